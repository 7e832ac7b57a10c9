/* The simulator's truth physics (tools/sim/hstpf_sim.h), checked against
 * values derived by hand from the rule:
 *   held (v == 0, u - c0 - g <= 0): s' = s, v' = 0, no noise;
 *   else s' = s + T v + w_s, v' = max(0, v + T xi (u - W(v) - g) + w_v);
 * and a journey timetable's stops, dwells and reported holding brake. */
#include "hstpf_sim.h"
#include "testutil.h"

#include <math.h>
#include <string.h>

static double xi_of(double gamma) { return 9.81 / (1.0 + gamma) / 1000.0; }

static void test_held_rule(void **state)
{
    const hstpf_theta_t th = {"x", 1.0, 0.0, 0.0};
    (void)state;
    assert_true(hstpf_sim_held(&th, 0.0, HSTPF_SIM_HOLD_BRAKE, 0.0));
    assert_true(hstpf_sim_held(&th, 0.0, 0.0, 0.0));  /* u = 0 at a platform */
    assert_true(hstpf_sim_held(&th, 0.0, 1.0, 0.0));  /* exactly c0: cannot start */
    assert_false(hstpf_sim_held(&th, 0.0, 1.5, 0.0)); /* departs */
    assert_true(hstpf_sim_held(&th, 0.0, 1.5, 0.5));  /* uphill: c0 + g = 1.5 */
    assert_false(hstpf_sim_held(&th, 0.0, 0.0, -2.0)); /* downhill pulls it away */
    assert_false(hstpf_sim_held(&th, 1e-9, -50.0, 0.0)); /* moving: not held */
}

/* Noise-free coasting against c0 = 50 N/kN from 1 m/s: 1, 1 - d, 1 - 2d,
 * then 0 (clamped, d = 50 xi = 0.4627 m/s per step), then held. */
static void test_never_reverses_noise_free(void **state)
{
    static const hstpf_track_seg_t none[1] = {{0.0, 0.0, 0.0}};
    hstpf_sim_config_t c;
    hstpf_sim_t sim;
    hstpf_sim_sample_t smp;
    const double d = 50.0 * xi_of(0.06);
    int k;
    (void)state;
    hstpf_sim_default(&c);
    c.truth.c0 = 50.0;
    c.truth.c1 = 0.0;
    c.truth.c2 = 0.0;
    memset(&c.noise_s, 0, sizeof c.noise_s);
    memset(&c.noise_v, 0, sizeof c.noise_v);
    c.noise_s.kind = c.noise_v.kind = HSTPF_DIST_GAUSSIAN;
    c.profile = HSTPF_PROFILE_COAST_BRAKE;
    c.track = none;
    c.n_track = 1;
    hstpf_sim_init(&sim, &c);
    sim.t = 600.0; /* the coasting phase */
    sim.v = 1.0;
    {
        const double want[6] = {1.0, 1.0 - d, 1.0 - 2.0 * d, 0.0, 0.0, 0.0};
        const double s_want[6] = {0.0, 1.0, 2.0 - d, 3.0 - 3.0 * d, 3.0 - 3.0 * d, 3.0 - 3.0 * d};
        for (k = 0; k < 6; ++k) {
            hstpf_sim_next(&sim, &smp);
            TU_CLOSE(smp.v, want[k], 1e-12);
            TU_CLOSE(smp.s, s_want[k], 1e-12);
            TU_CLOSE(smp.u, 0.0, 0.0);
            assert_int_equal(smp.held, k >= 3);
        }
    }
}

/* With Case 1 noise a held train does not move at all, and a braking train
 * never goes below 0. */
static void test_held_train_does_not_random_walk(void **state)
{
    static const hstpf_sim_leg_t legs[1] = {{100.0, 60.0, 600.0}};
    hstpf_sim_config_t c;
    hstpf_sim_t sim;
    hstpf_sim_sample_t smp;
    double s_rest = -1.0, t_rest = -1.0, t_dep = -1.0;
    int k;
    (void)state;
    hstpf_sim_default(&c);
    c.profile = HSTPF_PROFILE_JOURNEY;
    c.legs = legs;
    c.n_legs = 1;
    c.first_dwell_s = 30.0;
    c.seed = 7;
    hstpf_sim_init(&sim, &c);
    for (k = 0; k < 1000; ++k) {
        hstpf_sim_next(&sim, &smp);
        assert_true(smp.v >= 0.0);
        if (smp.t < 30.0) { /* the origin's dwell: at rest from t = 0 */
            assert_true(smp.held);
            TU_CLOSE(smp.s, 0.0, 0.0);
            TU_CLOSE(smp.u, HSTPF_SIM_HOLD_BRAKE, 0.0);
        } else if (smp.t == 30.0) {
            assert_false(smp.held); /* departs after exactly 30 s */
            assert_true(smp.u > c.truth.c0);
        } else if (smp.t > 40.0 && smp.v == 0.0 && t_rest < 0.0) {
            t_rest = smp.t;
            s_rest = smp.s;
        }
        if (t_rest >= 0.0 && smp.t >= t_rest && smp.t < t_rest + 600.0) {
            /* the last leg's stop: held for good (after its dwell too) */
            assert_true(smp.held);
            TU_CLOSE(smp.s, s_rest, 0.0);
            TU_CLOSE(smp.v, 0.0, 0.0);
            TU_CLOSE(smp.u, HSTPF_SIM_HOLD_BRAKE, 0.0);
        }
        if (t_rest >= 0.0 && t_dep < 0.0 && smp.v > 0.0) {
            t_dep = smp.t;
        }
    }
    /* run 60 s from t = 30 (reaching ~24 m/s at 0.4 m/s^2), brake at
     * 0.5 m/s^2 (~48 s): at rest near t = 140 s */
    assert_true(t_rest > 120.0 && t_rest < 160.0);
    assert_true(t_dep < 0.0); /* the last leg: no departure */
}

/* Two legs: the train stands dwell_s from the step it came to rest, then
 * departs with traction above c0. */
static void test_dwell_then_departure(void **state)
{
    static const hstpf_sim_leg_t legs[2] = {{200.0, 120.0, 120.0}, {200.0, 100.0, -1.0}};
    hstpf_sim_config_t c;
    hstpf_sim_t sim;
    hstpf_sim_sample_t smp;
    double t_rest = -1.0, t_dep = -1.0;
    int k;
    (void)state;
    hstpf_sim_default(&c);
    c.profile = HSTPF_PROFILE_JOURNEY;
    c.legs = legs;
    c.n_legs = 2;
    c.first_dwell_s = -1.0;
    c.v0_mps = 200.0 / 3.6; /* starts running at speed */
    c.seed = 3;
    hstpf_sim_init(&sim, &c);
    for (k = 0; k < 800; ++k) {
        hstpf_sim_next(&sim, &smp);
        if (k == 0) {
            TU_CLOSE(smp.v, 200.0 / 3.6, 0.0);
        }
        if (t_rest < 0.0 && smp.v == 0.0) {
            t_rest = smp.t;
        }
        if (t_rest >= 0.0 && t_dep < 0.0 && !smp.held) {
            t_dep = smp.t;
            assert_true(smp.u > c.truth.c0);
        }
    }
    assert_true(t_rest > 0.0);
    TU_CLOSE(t_dep - t_rest, 120.0, 0.0);
}

/* ---- heavy-tailed position noise (issue 13), against closed forms ------ */

static const double pi_ = 3.14159265358979323846;

/* t(3): F(t) = 1/2 + (atan(t / sqrt 3) + (t / sqrt 3) / (1 + t^2 / 3)) / pi */
static double t3_cdf(double t)
{
    const double r = t / sqrt(3.0);
    return 0.5 + (atan(r) + r / (1.0 + r * r)) / pi_;
}

static double phi_cdf(double z) { return 0.5 * erfc(-z / sqrt(2.0)); }

static double heavy_cdf(const hstpf_sim_heavy_t *h, double x)
{
    if (h->kind == HSTPF_SIM_HEAVY_T) {
        return t3_cdf(x / h->scale);
    }
    return (1.0 - h->p_wide) * phi_cdf(x / h->sd) + h->p_wide * phi_cdf(x / h->wide_sd);
}

/* Mass and second moment over [-R, R], by hand: t(3) (density
 * 6 sqrt3 / (pi (3 + t^2)^2)): 2 F(R') - 1 and
 * s^2 (6 sqrt3 / pi) (atan(R' / sqrt3) / sqrt3 - R' / (3 + R'^2)), R' = R / s
 * (3 s^2 as R -> inf); a Gaussian N(0, sd^2): erf(a / sqrt2) and
 * sd^2 (erf(a / sqrt2) - 2 a phi(a)), a = R / sd, mixed by the weights. */
static void heavy_moments_by_hand(const hstpf_sim_heavy_t *h, double r, double *m0, double *m2)
{
    if (h->kind == HSTPF_SIM_HEAVY_T) {
        const double q = r / h->scale;
        *m0 = 2.0 * t3_cdf(q) - 1.0;
        *m2 = h->scale * h->scale * (6.0 * sqrt(3.0) / pi_) * (atan(q / sqrt(3.0)) / sqrt(3.0) - q / (3.0 + q * q));
    } else {
        const double a = r / h->sd, b = r / h->wide_sd;
        const double pa = exp(-0.5 * a * a) / sqrt(2.0 * pi_), pb = exp(-0.5 * b * b) / sqrt(2.0 * pi_);
        *m0 = (1.0 - h->p_wide) * erf(a / sqrt(2.0)) + h->p_wide * erf(b / sqrt(2.0));
        *m2 = (1.0 - h->p_wide) * h->sd * h->sd * (erf(a / sqrt(2.0)) - 2.0 * a * pa) +
              h->p_wide * h->wide_sd * h->wide_sd * (erf(b / sqrt(2.0)) - 2.0 * b * pb);
    }
}

static void heavy_setup(hstpf_sim_heavy_kind_t k, hstpf_sim_config_t *c, hstpf_sim_table_t *tab)
{
    hstpf_sim_default(c);
    hstpf_sim_heavy(c, k, tab);
    assert_int_equal(c->heavy_e.kind, k);
    assert_int_equal(c->noise_e.kind, HSTPF_DIST_TABLE);
    assert_int_equal(c->noise_s.kind, HSTPF_DIST_GAUSSIAN); /* Case 1 otherwise */
}

/* The scale of t(3) gives Case 1's quartiles, +-0.67449 sqrt(5) m; the
 * mixture's core is Case 1's sd and its wide part 10 times it at 5 %. */
static void test_heavy_parameters(void **state)
{
    hstpf_sim_config_t c;
    static hstpf_sim_table_t tab;
    (void)state;
    heavy_setup(HSTPF_SIM_HEAVY_T, &c, &tab);
    TU_CLOSE(t3_cdf(0.6744897501960817 * sqrt(5.0) / c.heavy_e.scale), 0.75, 1e-7);
    TU_CLOSE(c.heavy_e.nu, 3.0, 0.0);
    heavy_setup(HSTPF_SIM_HEAVY_MIX, &c, &tab);
    TU_CLOSE(c.heavy_e.sd, sqrt(5.0), 1e-15);
    TU_CLOSE(c.heavy_e.wide_sd, 10.0 * sqrt(5.0), 1e-14);
    TU_CLOSE(c.heavy_e.p_wide, 0.05, 0.0);
}

/* The simulator's density: Simpson's rule over [-200, 200] m (h = 1 mm)
 * against the closed forms above: mass to 1e-9, second moment to 1e-6
 * relative; and its tails outside the table, 2.1e-6 (t) and < 1e-15. */
static void test_heavy_density_mass_and_moments(void **state)
{
    static const hstpf_sim_heavy_kind_t kinds[2] = {HSTPF_SIM_HEAVY_T, HSTPF_SIM_HEAVY_MIX};
    int k;
    (void)state;
    for (k = 0; k < 2; ++k) {
        hstpf_sim_config_t c;
        static hstpf_sim_table_t tab;
        const double r = HSTPF_SIM_HEAVY_RANGE, h = 1e-3;
        const long n = (long)(2.0 * r / h + 0.5); /* even */
        double m0 = 0.0, m2 = 0.0, w0, w2;
        long i;
        heavy_setup(kinds[k], &c, &tab);
        for (i = 0; i <= n; ++i) {
            const double x = -r + h * (double)i, p = hstpf_sim_heavy_pdf(&c.heavy_e, x);
            const double wgt = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
            m0 += wgt * p;
            m2 += wgt * p * x * x;
        }
        m0 *= h / 3.0;
        m2 *= h / 3.0;
        heavy_moments_by_hand(&c.heavy_e, r, &w0, &w2);
        TU_CLOSE(m0, w0, 1e-9);
        TU_CLOSE(m2, w2, 1e-6 * w2);
        if (k == 0) {
            TU_CLOSE(1.0 - w0, 2.11e-6, 0.01e-6);
            TU_CLOSE(w2, 3.0 * c.heavy_e.scale * c.heavy_e.scale, 0.07 * w2); /* 6.6 / R' of 3 */
        } else {
            assert_true(1.0 - w0 < 1e-15);
            TU_CLOSE(w2, 0.95 * 5.0 + 0.05 * 500.0, 1e-9);
        }
    }
}

/* The filter's model of it: the table built by the library has the
 * truncated density's sd (the exact moments of the piecewise-linear table,
 * 0.5 %), mean 0, quartiles +-1.508 m for t(3) (the library's own
 * quantile table, 0.5 %), and its log-density at 0 within 0.05 nats (the
 * 512-node log grid over 400 m: dx^2 / 8 |(log p)''| = 0.026 nats for t(3)). */
static void test_heavy_table_is_the_density(void **state)
{
    static const hstpf_sim_heavy_kind_t kinds[2] = {HSTPF_SIM_HEAVY_T, HSTPF_SIM_HEAVY_MIX};
    int k;
    (void)state;
    for (k = 0; k < 2; ++k) {
        hstpf_sim_config_t c;
        static hstpf_sim_table_t tab;
        static hstpf_dist_t d;
        double w0, w2;
        heavy_setup(kinds[k], &c, &tab);
        assert_int_equal(hstpf_dist_init(&d, &c.noise_e), HSTPF_OK);
        heavy_moments_by_hand(&c.heavy_e, HSTPF_SIM_HEAVY_RANGE, &w0, &w2);
        TU_CLOSE((double)d.qt.sd, sqrt(w2 / w0), 0.005 * sqrt(w2 / w0));
        TU_CLOSE((double)d.qt.mean, 0.0, 1e-3);
        TU_CLOSE((double)hstpf_dist_logpdf(&d, 0.0f), log(hstpf_sim_heavy_pdf(&c.heavy_e, 0.0)), 0.05);
        if (k == 0) {
            TU_CLOSE((double)hstpf_dist_sample(&d, 0xC0000000u), 0.6744897501960817 * sqrt(5.0), 0.0075);
            TU_CLOSE((double)hstpf_dist_sample(&d, 0x40000000u), -0.6744897501960817 * sqrt(5.0), 0.0075);
        }
    }
}

/* The simulator's sampler: 100 000 draws in 18 bins against the closed-form
 * CDF; Pearson's statistic below 40.79, the 99.9 % point of chi-square
 * with 17 degrees of freedom (fixed seed: a pass is reproducible). */
static void test_heavy_sampler_chi_square(void **state)
{
    static const double edges_t[17] = {-10, -5, -3, -2, -1.5, -1, -0.5, -0.25, 0, 0.25, 0.5, 1, 1.5, 2, 3, 5, 10};
    static const double edges_m[17] = {-30, -20, -10, -5, -3, -2, -1, -0.5, 0, 0.5, 1, 2, 3, 5, 10, 20, 30};
    static const hstpf_sim_heavy_kind_t kinds[2] = {HSTPF_SIM_HEAVY_T, HSTPF_SIM_HEAVY_MIX};
    const long n = 100000;
    int k;
    (void)state;
    for (k = 0; k < 2; ++k) {
        hstpf_sim_config_t c;
        static hstpf_sim_table_t tab;
        hstpf_rng_t rng;
        const double *ed = k == 0 ? edges_t : edges_m;
        long count[18] = {0};
        double chi2 = 0.0, unit;
        long i;
        int b;
        heavy_setup(kinds[k], &c, &tab);
        unit = k == 0 ? c.heavy_e.scale : c.heavy_e.sd;
        assert_int_equal(hstpf_rng_seed(&rng, 12345u + (uint64_t)k, 7u), HSTPF_OK);
        for (i = 0; i < n; ++i) {
            const double x = hstpf_sim_heavy_draw(&rng, &c.heavy_e) / unit;
            for (b = 0; b < 17 && x >= ed[b]; ++b) {
            }
            ++count[b];
        }
        for (b = 0; b < 18; ++b) {
            const double lo = b == 0 ? 0.0 : heavy_cdf(&c.heavy_e, ed[b - 1] * unit);
            const double hi = b == 17 ? 1.0 : heavy_cdf(&c.heavy_e, ed[b] * unit);
            const double e = (double)n * (hi - lo);
            assert_true(e > 5.0);
            chi2 += ((double)count[b] - e) * ((double)count[b] - e) / e;
        }
        print_message("heavy kind %d: chi-square %.2f (17 dof)\n", (int)kinds[k], chi2);
        assert_true(chi2 < 40.79);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_held_rule),
        cmocka_unit_test(test_never_reverses_noise_free),
        cmocka_unit_test(test_held_train_does_not_random_walk),
        cmocka_unit_test(test_dwell_then_departure),
        cmocka_unit_test(test_heavy_parameters),
        cmocka_unit_test(test_heavy_density_mass_and_moments),
        cmocka_unit_test(test_heavy_table_is_the_density),
        cmocka_unit_test(test_heavy_sampler_chi_square),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
