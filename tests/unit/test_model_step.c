/* One model step against hand-computed values.
 *
 * Two models (CRH3 and SS8, Table 1), 8 particles, process noise Gaussian
 * with sd 1e-9 (particles move deterministically to ~6e-9), measurement
 * noise N(0, 1 m), prior speed exactly 50 m/s (sd 0), no roughening, no
 * resampling (ESS threshold 1e-9), no gate. Particles are read back with
 * hstpf_particles(). Float tolerances: a quantity of size X computed in a
 * few float operations is within 4 eps X (eps = 1.2e-7).
 *
 * Hand computation (docs/model.md): xi = 9.81 / (1 + 0.06) / 1000
 * = 0.00925471698 (m/s^2)/(N/kN); V = 3.6 v = 180 km/h at v = 50 m/s;
 *   CRH3: W = 0.79 + 0.0064*180 + 0.000115*180^2 = 0.79 + 1.152 + 3.726
 *         = 5.668 N/kN; a = xi (20 - 5.668) = 0.00925471698 * 14.332
 *         = 0.132638604 m/s^2; T = 0.5 s: v' = 50 + 0.5 a = 50.0663193.
 *   SS8:  W = 1.02 + 0.0035*180 + 0.000426*32400 = 1.02 + 0.63 + 13.8024
 *         = 15.4524; a = xi * 4.5476 = 0.0420867509; v' = 50.0210434.
 *   s' = s + T v = s + 25 m for every particle.
 * With the track profile (i + 600/R: 2 + 0 = 2 N/kN from 100 m, 5 + 600/2000
 * = 5.3 N/kN from 1000.3 m, -3 from 5000 m):
 *   CRH3: a = xi (20 - 5.668 - 2) = 0.114129170, v' = 50.0570646;
 *         a = xi (20 - 5.668 - 5.3) = 0.0835886038, v' = 50.0417943;
 *   SS8:  a = xi (20 - 15.4524 - 2) = 0.0235773170, v' = 50.0117887;
 *         a = xi (20 - 15.4524 - 5.3) = -0.00696324906, v' = 49.9965184.
 * No reversal: v = 1 m/s, u = -200 N/kN, T = 1 s: W(1) (V = 3.6) for CRH3
 *   = 0.79 + 0.02304 + 0.00149040 = 0.8145304; a = -xi * 200.8145304 =
 *   -1.85848164; v + T a = -0.858 < 0, so v' = 0; s' = s + 1 m. */
#include <stdlib.h>
#include <string.h>

#include "testbuild.h"
#include "testutil.h"

#define NP 8
#define XI (9.81 / 1.06 / 1000.0)
#define SQRT_2PI 2.5066282746310002
/* log-density table error for N(0, sd): dx^2/8 / sd^2, dx = 16 sd / 511 */
#define LP_TABLE_ERR ((16.0 / 511.0) * (16.0 / 511.0) / 8.0)

static hstpf_t filt, filt2; /* ~200 kB each: static */

static hstpf_theta_t models[2];

static void base_config(hstpf_config_t *c)
{
    static const char *const names[2] = {"CRH3", "SS8"};
    tu_config_rows(c, models, names, 2);
    c->n_particles = NP;
    c->seed = 12345;
    c->engine = HSTPF_ENGINE_PARTICLE; /* this file checks the particle step */
    c->noise_s.sd = 1e-9;
    c->noise_v.sd = 1e-9;
    c->noise_e.sd = 1.0;
    c->init_speed_mps = 50.0;
    c->init_speed_sd = 1e-30; /* a point prior (0 would mean: from two fixes) */
    c->roughening_k = 0.0;
    c->resample = HSTPF_RESAMPLE_ESS;
    c->ess_threshold = 1e-9;
    c->gate_m = 0.0;
}

static void step(hstpf_t *f, double dt, double u, double y, int has_y)
{
    const hstpf_input_t in = tu_input(dt, u, y, has_y);
    const int32_t err = hstpf_step(f, &in);
    if (err != HSTPF_OK) {
        fail_msg("hstpf_step: %s", hstpf_strerror(err));
    }
}

typedef struct {
    double s[NP];
    hstpf_real_t v[NP], w[NP];
} cloud_t;

static void read_cloud(const hstpf_t *f, uint16_t l, cloud_t *c)
{
    assert_int_equal(hstpf_particles(f, l, c->s, c->v, c->w), HSTPF_OK);
}

static double log_norm(double z) /* log N(z; 0, 1) */
{
    return -0.5 * z * z - log(SQRT_2PI);
}

static double eps4(double x)
{
    return 4.0 * TU_REAL_EPS * fabs(x);
}

/* Dynamics: s' = s + T v, v' = v + T xi (u - W(v)) with the literals above. */
static void test_dynamics(void **state)
{
    static const double v1[2] = {50.0663193019, 50.0210433755};
    hstpf_config_t c;
    cloud_t c0[2], c1[2];
    uint16_t l, i;
    (void)state;
    base_config(&c);
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&filt, sizeof filt, &c), HSTPF_OK);
    step(&filt, 1.0, 0.0, 1000.3, 1); /* first fix */
    for (l = 0; l < 2; ++l) {
        read_cloud(&filt, l, &c0[l]);
        for (i = 0; i < NP; ++i) {
            TU_CLOSE(c0[l].v[i], 50.0, 0.0);         /* prior sd 0 */
            TU_CLOSE(c0[l].w[i], 1.0 / NP, 1e-6);     /* uniform after the fix */
            TU_CLOSE(c0[l].s[i], 1000.3, 6.3 * 1.0); /* y - e, |e| <= 6.23 sd */
        }
    }
    step(&filt, 0.5, 20.0, 1025.4, 1);
    for (l = 0; l < 2; ++l) {
        read_cloud(&filt, l, &c1[l]);
        for (i = 0; i < NP; ++i) {
            TU_CLOSE(c1[l].s[i], c0[l].s[i] + 25.0, eps4(c1[l].s[i] - 1000.0) + 1e-8);
            TU_CLOSE(c1[l].v[i], v1[l], eps4(50.0) + 1e-8);
        }
    }
    /* the same particles, from the first fix's formula: both models were
     * drawn from their own streams, so their clouds differ */
    assert_true(memcmp(c0[0].s, c0[1].s, sizeof c0[0].s) != 0);
}

/* The track profile: i + 600/R at the particle's position at the start of
 * the step; hstpf_track_resistance at chosen positions. */
static void test_track(void **state)
{
    static const hstpf_track_seg_t track[3] = {{100.0, 2.0, 0.0}, {1000.3, 5.0, 2000.0}, {5000.0, -3.0, 0.0}};
    static const double v_lo[2] = {50.0570645849, 50.0117886585}; /* g = 2 */
    static const double v_hi[2] = {50.0417943019, 49.9965183755}; /* g = 5.3 */
    static const double pos[] = {-10.0, 99.99, 100.0, 1000.29, 1000.3, 4999.9, 5000.0, 1e7};
    static const double g_want[] = {0.0, 0.0, 2.0, 2.0, 5.3, 5.3, -3.0, -3.0};
    hstpf_config_t c;
    cloud_t c0[2], c1[2];
    uint16_t l, i;
    int lo = 0, hi = 0;
    size_t k;
    (void)state;
    base_config(&c);
    c.track = track;
    c.n_track = 3;
    c.noise_e.sd = 0.5; /* particles on both sides of 1000.3 m */
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&filt, sizeof filt, &c), HSTPF_OK);
    for (k = 0; k < sizeof pos / sizeof pos[0]; ++k) {
        double g = -99.0;
        assert_int_equal(hstpf_track_resistance(&filt, pos[k], &g), HSTPF_OK);
        TU_CLOSE(g, g_want[k], 1e-12);
    }
    step(&filt, 1.0, 0.0, 1000.3, 1);
    for (l = 0; l < 2; ++l) {
        read_cloud(&filt, l, &c0[l]);
    }
    step(&filt, 0.5, 20.0, 1025.3, 1);
    for (l = 0; l < 2; ++l) {
        read_cloud(&filt, l, &c1[l]);
        for (i = 0; i < NP; ++i) {
            if (fabs(c0[l].s[i] - 1000.3) < 1e-4) {
                continue; /* on the boundary to float precision */
            }
            if (c0[l].s[i] < 1000.3) {
                ++lo;
                TU_CLOSE(c1[l].v[i], v_lo[l], eps4(50.0) + 1e-8);
            } else {
                ++hi;
                TU_CLOSE(c1[l].v[i], v_hi[l], eps4(50.0) + 1e-8);
            }
            TU_CLOSE(c1[l].s[i], c0[l].s[i] + 25.0, eps4(c1[l].s[i] - 1000.0) + 1e-8);
        }
    }
    assert_true(lo > 0 && hi > 0); /* both segments were exercised */
}

/* No reversal: from 1 m/s under full braking the speed stops at 0. */
static void test_no_reversal(void **state)
{
    hstpf_config_t c;
    cloud_t c0[2], c1[2];
    uint16_t l, i;
    (void)state;
    base_config(&c);
    c.init_speed_mps = 1.0;
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&filt, sizeof filt, &c), HSTPF_OK);
    step(&filt, 1.0, 0.0, 500.0, 1);
    for (l = 0; l < 2; ++l) {
        read_cloud(&filt, l, &c0[l]);
    }
    step(&filt, 1.0, -200.0, 501.0, 1);
    for (l = 0; l < 2; ++l) {
        read_cloud(&filt, l, &c1[l]);
        for (i = 0; i < NP; ++i) {
            TU_CLOSE(c1[l].v[i], 0.0, 1e-8); /* 0 + w_v, |w_v| <= 6.3e-9 */
            TU_CLOSE(c1[l].s[i], c0[l].s[i] + 1.0, eps4(c1[l].s[i] - 500.0) + 1e-8);
        }
    }
    /* a moderate braking that does not reach 0 is applied in full:
     * u = -50: a = -xi (50 + 0.8145304) = -0.470274, v' = 0.529726 (CRH3) */
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&filt, sizeof filt, &c), HSTPF_OK);
    step(&filt, 1.0, 0.0, 500.0, 1);
    step(&filt, 1.0, -50.0, 501.0, 1);
    read_cloud(&filt, 0, &c1[0]);
    for (i = 0; i < NP; ++i) {
        TU_CLOSE(c1[0].v[i], 1.0 - XI * 50.8145304, eps4(1.0) + 1e-8);
    }
}

/* Model weights: with Gaussian measurement noise, the log-likelihood
 * increment of model l is log sum_i W_i N(y - s'_i; 0, 1) with the weights
 * W before the step (1/n after the fix); q_l = q_l,prev exp(inc_l) / sum.
 * Computed here from the particle positions with the exact Gaussian.
 * Tolerance on inc: the table's log-density error 1.23e-4 nats (dist.h)
 * bounds the error of a log of a weighted mean of densities; exp_neg's
 * relative error (1e-5 allowed) and float sums add 2e-5. On q: dq =
 * q (1 - q) d(inc_l - inc_other) <= q (1 - q) 2 tol. */
static void test_model_weights(void **state)
{
    const double tol = LP_TABLE_ERR + 2e-5;
    const double ys[3] = {1000.3, 1025.9, 1076.6};
    const double dts[3] = {1.0, 0.5, 1.0};
    hstpf_config_t c;
    cloud_t cl[2];
    double wprev[2][NP], q[2] = {0.5, 0.5};
    uint16_t l, i;
    int k;
    (void)state;
    base_config(&c);
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&filt, sizeof filt, &c), HSTPF_OK);
    step(&filt, dts[0], 20.0, ys[0], 1);
    for (l = 0; l < 2; ++l) {
        for (i = 0; i < NP; ++i) {
            wprev[l][i] = 1.0 / NP;
        }
    }
    for (k = 1; k < 3; ++k) {
        hstpf_estimate_t est;
        double inc[2], qn[2], zsum = 0.0, pos = 0.0, th0 = 0.0;
        step(&filt, dts[k], 20.0, ys[k], 1);
        assert_int_equal(hstpf_estimate(&filt, &est), HSTPF_OK);
        for (l = 0; l < 2; ++l) {
            double mx = -HUGE_VAL, sum = 0.0, lp[NP], wn[NP], ms = 0.0, sw2 = 0.0;
            read_cloud(&filt, l, &cl[l]);
            for (i = 0; i < NP; ++i) {
                lp[i] = log(wprev[l][i]) + log_norm(ys[k] - cl[l].s[i]);
                mx = lp[i] > mx ? lp[i] : mx;
            }
            for (i = 0; i < NP; ++i) {
                sum += exp(lp[i] - mx);
            }
            inc[l] = mx + log(sum);
            TU_CLOSE(est.model[l].loglik, inc[l], tol + eps4(inc[l]));
            /* the new normalised weights, their ESS and the posterior mean */
            for (i = 0; i < NP; ++i) {
                wn[i] = exp(lp[i] - inc[l]);
                TU_CLOSE(cl[l].w[i], wn[i], wn[i] * 2.0 * tol + 1e-7);
                ms += wn[i] * cl[l].s[i];
                sw2 += wn[i] * wn[i];
                wprev[l][i] = wn[i];
            }
            TU_CLOSE(est.model[l].position_m, ms, 2e-3);
            TU_CLOSE(est.model[l].ess, 1.0 / sw2, (1.0 / sw2) * 4.0 * tol + 1e-4);
        }
        for (l = 0; l < 2; ++l) {
            qn[l] = q[l] * exp(inc[l] - inc[0]);
            zsum += qn[l];
        }
        for (l = 0; l < 2; ++l) {
            qn[l] /= zsum;
            TU_CLOSE(est.model[l].q, qn[l], qn[l] * (1.0 - qn[l]) * 2.0 * tol + 1e-6);
            q[l] = qn[l];
            pos += qn[l] * est.model[l].position_m;
            th0 += qn[l] * models[l].c0;
        }
        /* blended outputs: sum_l q_l x_l, theta = sum_l q_l theta_l */
        TU_CLOSE(est.position_m, pos, 1e-3);
        TU_CLOSE(est.theta[0], th0, 1e-5);
        assert_int_equal(est.step, (uint32_t)(k + 1));
        TU_CLOSE(est.time_s, k == 1 ? 1.5 : 2.5, 1e-12);
    }
}

/* The paper's Eq. 13 option: inc = log N(y - s_mean_l; 0, 1) with the
 * model's posterior mean. */
static void test_paper_weight(void **state)
{
    hstpf_config_t c;
    hstpf_estimate_t est;
    uint16_t l;
    (void)state;
    base_config(&c);
    c.weight_method = HSTPF_WEIGHT_PAPER;
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&filt, sizeof filt, &c), HSTPF_OK);
    step(&filt, 1.0, 20.0, 1000.3, 1);
    step(&filt, 0.5, 20.0, 1025.9, 1);
    assert_int_equal(hstpf_estimate(&filt, &est), HSTPF_OK);
    for (l = 0; l < 2; ++l) {
        const double want = log_norm(1025.9 - est.model[l].position_m);
        TU_CLOSE(est.model[l].loglik, want, LP_TABLE_ERR + 1e-4);
    }
}

/* Noise scaling: samples are scaled by sqrt(T / dt_nominal). With w_s ~
 * N(0, 0.3), dt_nominal 2.7 s and T = 4 s (one part: a step over 1.5
 * dt_nominal is predicted in parts, bank.c), s' - s - T v has sd 0.3
 * sqrt(4 / 2.7): the sample sd over 2 x 256 particles within 3.29 /
 * sqrt(2 N) relative (alpha = 0.001), mean within 3.29 sd / sqrt(N). */
static void test_noise_scaling(void **state)
{
    static double s0[2][HSTPF_MAX_PARTICLES], s1[HSTPF_MAX_PARTICLES];
    static hstpf_real_t v0[2][HSTPF_MAX_PARTICLES], v1[HSTPF_MAX_PARTICLES];
    hstpf_config_t c;
    double sum = 0.0, sum2 = 0.0, sd;
    const int n = HSTPF_MAX_PARTICLES * 2;
    uint16_t l, i;
    (void)state;
    base_config(&c);
    c.n_particles = HSTPF_MAX_PARTICLES;
    c.noise_s.sd = 0.3;
    c.dt_nominal_s = 2.7;
    tu_workspace(&c, 1);
    assert_int_equal(hstpf_init(&filt2, sizeof filt2, &c), HSTPF_OK);
    step(&filt2, 1.0, 0.0, 2000.0, 1);
    for (l = 0; l < 2; ++l) {
        assert_int_equal(hstpf_particles(&filt2, l, s0[l], v0[l], NULL), HSTPF_OK);
    }
    step(&filt2, 4.0, 0.0, 0.0, 0); /* predict only: no weighting, no resampling */
    for (l = 0; l < 2; ++l) {
        assert_int_equal(hstpf_particles(&filt2, l, s1, v1, NULL), HSTPF_OK);
        for (i = 0; i < HSTPF_MAX_PARTICLES; ++i) {
            const double d = s1[i] - s0[l][i] - 4.0 * (double)v0[l][i];
            sum += d;
            sum2 += d * d;
        }
    }
    sd = sqrt(sum2 / n - (sum / n) * (sum / n));
    TU_CLOSE(sum / n, 0.0, 3.29 * 0.3 * sqrt(4.0 / 2.7) / sqrt((double)n));
    TU_CLOSE(sd, 0.3 * sqrt(4.0 / 2.7), 0.3 * sqrt(4.0 / 2.7) * 3.29 / sqrt(2.0 * n));
}

/* A step without a position predicts only: weights unchanged, loglik 0,
 * q unchanged. */
static void test_predict_only(void **state)
{
    hstpf_config_t c;
    hstpf_estimate_t e0, e1;
    cloud_t a, b;
    uint16_t i;
    (void)state;
    base_config(&c);
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&filt, sizeof filt, &c), HSTPF_OK);
    step(&filt, 1.0, 20.0, 1000.3, 1);
    step(&filt, 1.0, 20.0, 1050.0, 1);
    assert_int_equal(hstpf_estimate(&filt, &e0), HSTPF_OK);
    read_cloud(&filt, 0, &a);
    step(&filt, 1.0, 20.0, 0.0, 0);
    assert_int_equal(hstpf_estimate(&filt, &e1), HSTPF_OK);
    read_cloud(&filt, 0, &b);
    for (i = 0; i < NP; ++i) {
        TU_CLOSE(b.w[i], a.w[i], 1e-6 * a.w[i] + 1e-9);
        TU_CLOSE(b.s[i], a.s[i] + (double)a.v[i], eps4(b.s[i] - 1000.0) + 1e-8);
    }
    TU_CLOSE(e1.model[0].loglik, 0.0, 0.0);
    TU_CLOSE(e1.model[0].q, e0.model[0].q, 1e-7);
    TU_CLOSE(e1.time_s, e0.time_s + 1.0, 1e-12);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dynamics),      cmocka_unit_test(test_track),
        cmocka_unit_test(test_no_reversal),   cmocka_unit_test(test_model_weights),
        cmocka_unit_test(test_paper_weight),  cmocka_unit_test(test_noise_scaling),
        cmocka_unit_test(test_predict_only),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
