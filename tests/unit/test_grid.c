/* The grid engine (HSTPF_ENGINE_GRID), against independent references.
 *
 * - Gaussian noise: the exact Bayesian recursion is then (up to the EKF's
 *   linearisation of c2 V^2) the Kalman filter, so the grid's per-step
 *   log-likelihood increments must agree with the Kalman engine's over a
 *   whole Case 1 run (1800 s, the paper's three models), steps where
 *   either engine is at its likelihood floor left out (each has its own
 *   convention there): the true model's within 0.25 nats at every step
 *   and 0.015 on average (measured at 20 x 72: 0.21 and 0.012; at 48 x 48
 *   0.12 and 0.008: twenty position cells span the posterior's +-4.3 sd,
 *   and one step in 1781 differs by 0.2); every
 *   model's within 3 nats and 0.08 on average (measured 2.3 and 0.066: a
 *   model the measurements pull away from its prediction has its
 *   posterior in the predicted tails, which the box cuts at 1e-5 on the
 *   side away from the measurement, docs/grid.md).
 * - Case 2 (Gamma noise): a bootstrap particle filter written here in
 *   double with the exact Gamma densities (M = 20 000, resampled every
 *   step) gives each model's log-likelihood summed over the first 300 s
 *   (up to the step where its every particle has zero likelihood);
 *   REF_RUNS independent runs give its Monte Carlo standard error se. The
 *   grid's sums must lie within 4 se + 0.04 nats per step of the reference
 *   mean. The 0.04 is the grid's own bias, not Monte Carlo error: at
 *   20 x 72 the true model's sum is 0.009 nats per step below the
 *   reference (2.6 of 219 nats over 300 s; cells of a few millimetres
 *   under the unbounded Gamma(0.5) measurement density), CRH5's 0.003
 *   (0.019 and 0.008 while the kernels reached 1e-7, docs/grid.md).
 * - Bit-for-bit determinism: two instances with different seeds give
 *   identical estimates at every step (the grid has no RNG), and a reset
 *   run repeats the first.
 * - Standstill: at rest under braking every model is held (speed exactly
 *   0, position still, weights frozen, the estimate's standstill flag).
 * - Acquisition at 300 km/h from two fixes with the diffuse speed prior:
 *   every model's speed within 1 m/s and position within 3 m after 30 s.
 * - cfg.grid_rows: which rows have a grid, how the others score, and the
 *   same answer as every row on the grid (test_grid_rows).
 * - Mass: after every step the cells sum to 1 within 1e-5, none is
 *   negative or non-finite, and a prediction without a measurement keeps
 *   all but 1e-3 of the mass (measured: 2e-4; the box leaves 1e-5 out per side and
 *   dimension).
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hstpf_sim.h"
#include "testbuild.h"
#include "testutil.h"

#define XI (9.81 / 1.06 / 1000.0)

static hstpf_t fa, fb; /* static, as on a target */

static void models_of(int paper_case, hstpf_theta_t *m)
{
    static const char *c1[3] = {"SS1/SS3/SS4", "CRH3", "SS8"}, *c2[3] = {"CRH1", "CRH3", "CRH5"};
    int k;
    for (k = 0; k < 3; ++k) {
        const int32_t i = hstpf_train_type_find(paper_case == 1 ? c1[k] : c2[k]);
        assert_true(i >= 0);
        m[k] = hstpf_train_types[i];
    }
}

static void setup(int paper_case, uint64_t seed, hstpf_sim_config_t *sc, hstpf_config_t *c, hstpf_theta_t *m)
{
    hstpf_sim_default(sc);
    sc->seed = seed;
    if (paper_case == 2) {
        hstpf_sim_case2(sc);
    }
    models_of(paper_case, m);
    assert_int_equal(hstpf_config_default(c), HSTPF_OK);
    c->models = m;
    c->n_models = 3;
    c->noise_s = sc->noise_s;
    c->noise_v = sc->noise_v;
    c->noise_e = sc->noise_e;
    c->engine = HSTPF_ENGINE_GRID;
}

/* After every step the cells are a normalised density; after a step
 * without a measurement (pred = 1) the prediction kept all but 1e-3 of the
 * mass (with a measurement the box only holds the posterior, docs/grid.md,
 * so the prediction is cut where the likelihood is negligible). */
static void check_cells(const hstpf_t *f, int pred)
{
    uint16_t l;
    if (!f->have_fix) {
        return; /* not acquired yet (two fixes): no cells */
    }
    for (l = 0; l < f->cfg.n_models; ++l) {
        double sum = 0.0;
        int i;
        for (i = 0; i < HSTPF_GRID_NS * HSTPF_GRID_NV + HSTPF_GRID_NS; ++i) {
            const double p = (double)(i < HSTPF_GRID_NS * HSTPF_GRID_NV ? f->grid.p[l][i]
                                                                         : f->grid.rest[l][i - HSTPF_GRID_NS * HSTPF_GRID_NV]);
            if (!(isfinite(p) && p >= 0.0)) {
                fail_msg("model %u cell %d holds %g", l, i, p);
            }
            sum += p;
        }
        TU_CLOSE(sum, 1.0, 1e-5);
        if (pred && !((double)f->grid.pred_mass[l] > 1.0 - 1e-3 && (double)f->grid.pred_mass[l] < 1.0 + 1e-5)) {
            fail_msg("model %u kept mass %.9f in its prediction", l, (double)f->grid.pred_mass[l]);
        }
        assert_true(f->grid.geom[l][1] > 0 && f->grid.geom[l][3] > 0);
    }
}

static void gaussian_vs_kalman(uint8_t lattice)
{
    hstpf_sim_config_t sc;
    hstpf_config_t c;
    hstpf_theta_t m[3];
    hstpf_sim_t sim;
    hstpf_sim_sample_t smp;
    hstpf_input_t in = {0};
    double max_true = 0.0, max_all = 0.0, sum_true = 0.0, sum_all = 0.0;
    uint32_t hits_g[3] = {0, 0, 0}, hits_k[3] = {0, 0, 0};
    int k, n = 0, floored = 0;
    setup(1, 1, &sc, &c, m);
    c.grid_speed_lattice = lattice;
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&fa, sizeof fa, &c), HSTPF_OK);
    c.engine = HSTPF_ENGINE_KALMAN;
    tu_workspace(&c, 1);
    assert_int_equal(hstpf_init(&fb, sizeof fb, &c), HSTPF_OK);
    hstpf_sim_init(&sim, &sc);
    for (k = 0; k <= 1800; ++k) {
        hstpf_estimate_t eg, ek;
        uint16_t l;
        hstpf_sim_next_input(&sim, &smp, &in);
        assert_int_equal(hstpf_step(&fa, &in), HSTPF_OK);
        assert_int_equal(hstpf_step(&fb, &in), HSTPF_OK);
        (void)hstpf_estimate(&fa, &eg);
        (void)hstpf_estimate(&fb, &ek);
        if (k < 20 || !in.has_position) { /* after the acquisition's first 20 s */
            continue;
        }
        for (l = 0; l < 3; ++l) {
            const double d = fabs((double)eg.model[l].loglik - (double)ek.model[l].loglik);
            /* beyond the floor each engine has its own convention */
            if (eg.model[l].floor_hits != hits_g[l] || ek.model[l].floor_hits != hits_k[l]) {
                hits_g[l] = eg.model[l].floor_hits;
                hits_k[l] = ek.model[l].floor_hits;
                ++floored;
                continue;
            }
            if (d > 0.3 && getenv("GRID_DEBUG") != NULL) {
                print_message("t %d model %u: grid %.3f kalman %.3f\n", k, l, (double)eg.model[l].loglik,
                              (double)ek.model[l].loglik);
            }
            max_all = d > max_all ? d : max_all;
            sum_all += d / 3.0;
            if (l == 1) {
                max_true = d > max_true ? d : max_true;
                sum_true += d;
            }
        }
        ++n;
    }
    print_message("grid%s vs Kalman, |d loglik| over %d steps: true model max %.4f mean %.4f; all max %.4f mean %.4f"
                  " (%d model-steps at a floor left out)\n",
                  lattice ? " (speed lattice)" : "", n, max_true, sum_true / n, max_all, sum_all / n, floored);
    assert_true(floored < 100);
    assert_true(n > 1700);
    assert_true(max_true <= 0.25);
    assert_true(sum_true / n <= 0.015);
    assert_true(max_all <= 3.0);
    assert_true(sum_all / n <= 0.08);
}

static void test_gaussian_vs_kalman(void **state)
{
    (void)state;
    gaussian_vs_kalman(0);
}

/* The same bounds with cfg.grid_speed_lattice (measured: true model 0.175
 * and 0.012, every model 1.46 and 0.035: the mismatched models' smear is
 * what the option removes) */
static void test_gaussian_vs_kalman_lattice(void **state)
{
    (void)state;
    gaussian_vs_kalman(1);
}

/* cfg.grid_speed_lattice does what it says: after each step of a paper
 * Case 2 run the new speed cells lie on the lattice of the old cells'
 * images under the model's map, v -> v + T (a - k0 - (k1 + k2 v) v),
 * computed here from the old geometry: the new origin is the image of an
 * old edge (or of the half or a multiple of the images' spacing) to 2 %
 * of a cell, and the new width is the images' width times a power of two
 * (the map's slope varies by 1e-5 across a box; the images are floats near
 * 56 m/s, each rounded by 4e-6: to 1e-5 plus four roundings over the
 * width). Where the new cells are not on it, the lattice's would have been
 * coarser than 1.5 x the box's own (LATTICE_COARSEST). Mass and sign as
 * everywhere (check_cells). */
static void test_speed_lattice(void **state)
{
    hstpf_sim_config_t sc;
    hstpf_config_t c;
    hstpf_theta_t m[3];
    hstpf_sim_t sim;
    hstpf_sim_sample_t smp;
    hstpf_input_t in = {0};
    int k, on = 0, off = 0;
    (void)state;
    setup(2, 3, &sc, &c, m);
    c.grid_speed_lattice = 1;
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&fa, sizeof fa, &c), HSTPF_OK);
    hstpf_sim_init(&sim, &sc);
    for (k = 0; k < 300; ++k) {
        double g[3][4];
        uint16_t l;
        hstpf_sim_next_input(&sim, &smp, &in);
        for (l = 0; l < 3; ++l) {
            int i;
            for (i = 0; i < 4; ++i) {
                g[l][i] = (double)fa.grid.geom[l][i];
            }
        }
        assert_int_equal(hstpf_step(&fa, &in), HSTPF_OK);
        check_cells(&fa, !in.has_position);
        if (k < 5) {
            continue; /* acquisition: the cells are placed, not moved */
        }
        for (l = 0; l < 3; ++l) {
            const hstpf_model_t *mo = &fa.m[l];
            const double a = fa.xi * in.traction, v0 = g[l][2], dv = g[l][3];
            const double slope = 1.0 - in.dt_s * ((double)mo->k1 + 2.0 * (double)mo->k2 * (v0 + 36.0 * dv));
            const double img0 = v0 + in.dt_s * (a - (double)mo->k0 - ((double)mo->k1 + (double)mo->k2 * v0) * v0);
            const double nv0 = (double)fa.grid.geom[l][2], ndv = (double)fa.grid.geom[l][3];
            const double r = log2(ndv / (dv * slope)), x = (nv0 - img0) / (dv * slope);
            /* the images are computed in hstpf_real_t: a width between two
             * of them is off by up to two roundings at the speed */
            const double tol = 1e-5 + 4.0 * (v0 + 40.0 * dv) * (sizeof(hstpf_real_t) == 4 ? FLT_EPSILON : DBL_EPSILON) / dv;
            if (v0 < 1.0) {
                continue; /* near rest the box may keep its quantiles */
            }
            if (fabs(r - floor(r + 0.5)) > tol) {
                /* not on the lattice: then its cells would have been
                 * coarser than LATTICE_COARSEST (1.5) x the box's own */
                const double need = (double)HSTPF_GRID_NV * ndv, w = dv * slope;
                const double hl = w * pow(2.0, ceil(log2(need / ((double)(HSTPF_GRID_NV - 1) * w)) - 1e-12));
                if (!(hl > 1.5 * ndv * (1.0 - tol))) {
                    fail_msg("step %d model %u: width %.9g off the lattice, whose cells %.9g were within 1.5 x", k, l,
                             ndv, hl);
                }
                ++off;
                continue;
            }
            { /* the origin on the lattice of the finer of the two spacings */
                const double step = r < 0.0 ? pow(2.0, floor(r + 0.5)) : 1.0;
                const double xx = x / step;
                if (fabs(xx - floor(xx + 0.5)) > 0.02 + 2.0 * tol) {
                    fail_msg("step %d model %u: new origin %.9g is %.4f spacings from the image %.9g", k, l, nv0,
                             xx, img0);
                }
            }
            ++on;
        }
    }
    print_message("speed lattice: %d model-steps on it, %d off it (its cells too coarse)\n", on, off);
    assert_true(on > 3 * off); /* the lattice on most model-steps */
}

/* The same on a hilly track that both filters know (grades of +-12 per
 * mille every few km, curves): the grid takes the gradient at each
 * model's mean position, the Kalman engine at its mean; the true model's
 * increments must agree as on the flat line. */
static void test_track_vs_kalman(void **state)
{
    static const hstpf_track_seg_t track[] = {
        {0.0, 0.0, 0.0},        {3000.0, 12.0, 0.0},     {9000.0, 3.0, 7000.0},
        {14000.0, -12.0, 0.0},  {20000.0, 8.0, 5500.0},  {28000.0, 12.0, 0.0},
        {36000.0, -6.0, 0.0},   {44000.0, 10.0, 8000.0}, {54000.0, -12.0, 0.0},
    };
    hstpf_sim_config_t sc;
    hstpf_config_t c;
    hstpf_theta_t m[3];
    hstpf_sim_t sim;
    hstpf_sim_sample_t smp;
    hstpf_input_t in = {0};
    double mx = 0.0, sum = 0.0;
    int k, n = 0;
    (void)state;
    setup(1, 2, &sc, &c, m);
    sc.track = track;
    sc.n_track = (uint16_t)(sizeof track / sizeof track[0]);
    c.track = track;
    c.n_track = sc.n_track;
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&fa, sizeof fa, &c), HSTPF_OK);
    c.engine = HSTPF_ENGINE_KALMAN;
    tu_workspace(&c, 1);
    assert_int_equal(hstpf_init(&fb, sizeof fb, &c), HSTPF_OK);
    hstpf_sim_init(&sim, &sc);
    for (k = 0; k <= 900; ++k) {
        hstpf_estimate_t eg, ek;
        double d;
        hstpf_sim_next_input(&sim, &smp, &in);
        assert_int_equal(hstpf_step(&fa, &in), HSTPF_OK);
        assert_int_equal(hstpf_step(&fb, &in), HSTPF_OK);
        (void)hstpf_estimate(&fa, &eg);
        (void)hstpf_estimate(&fb, &ek);
        if (k < 20) {
            continue;
        }
        d = fabs((double)eg.model[1].loglik - (double)ek.model[1].loglik);
        mx = d > mx ? d : mx;
        sum += d;
        ++n;
    }
    print_message("hilly track, true model |d loglik|: max %.4f mean %.4f over %d steps\n", mx, sum / n, n);
    assert_true(mx <= 0.25);
    assert_true(sum / n <= 0.015);
}

/* ---- the particle reference for Case 2, double, exact densities -------- */

#define REF_M 20000
#define REF_RUNS 4
#define REF_STEPS 300

static double rs[REF_M], rv[REF_M], rw[REF_M], ts[REF_M], tv[REF_M];

static double gamma_logpdf(double x, double k, double th)
{
    return x > 0.0 ? (k - 1.0) * log(x) - x / th - lgamma(k) - k * log(th) : -HUGE_VAL;
}

/* cum[k] = sum over steps 1..k of log p(y_j | y_1:j-1) for model th, up to
 * the step before the first one where every particle has zero likelihood
 * (a model with less drag than the truth runs ahead of a one-sided
 * measurement: a true zero). Returns the last step with a finite sum. */
static int ref_loglik(const hstpf_theta_t *th, const hstpf_sim_sample_t *ys, const double *us, uint64_t seed,
                      double *cum)
{
    hstpf_rng_t r;
    const double k0 = XI * th->c0, k1 = XI * th->c1 * 3.6, k2 = XI * th->c2 * 12.96;
    int i, k;
    (void)hstpf_rng_seed(&r, seed, 0);
    cum[0] = 0.0;
    for (i = 0; i < REF_M; ++i) {
        rs[i] = ys[0].y - hstpf_sim_gamma(&r, 0.5) * 0.2;
        rv[i] = hstpf_sim_gauss(&r); /* init_speed 0, sd 1 */
    }
    for (k = 1; k <= REF_STEPS; ++k) {
        double mx = -HUGE_VAL, sum = 0.0, c = 0.0, u0;
        int j = 0;
        for (i = 0; i < REF_M; ++i) {
            const double v = rv[i];
            double vd = v + (us[k - 1] * XI - k0 - (k1 + k2 * v) * v);
            if (v >= 0.0 && vd < 0.0) {
                vd = 0.0;
            }
            rs[i] = rs[i] + v + hstpf_sim_gamma(&r, 0.02) * 0.1;
            rv[i] = vd + hstpf_sim_gamma(&r, 0.1) * 0.05;
            rw[i] = gamma_logpdf(ys[k].y - rs[i], 0.5, 0.2);
            mx = rw[i] > mx ? rw[i] : mx;
        }
        if (!isfinite(mx)) {
            return k - 1;
        }
        for (i = 0; i < REF_M; ++i) {
            rw[i] = exp(rw[i] - mx);
            sum += rw[i];
        }
        cum[k] = cum[k - 1] + mx + log(sum / REF_M);
        /* systematic resampling */
        u0 = (double)(hstpf_rng_next(&r) >> 8) / 16777216.0;
        for (i = 0; i < REF_M; ++i) {
            c += rw[i] / sum * REF_M;
            while (j < REF_M && (double)j + u0 < c) {
                ts[j] = rs[i];
                tv[j] = rv[i];
                ++j;
            }
        }
        for (; j < REF_M; ++j) {
            ts[j] = rs[REF_M - 1];
            tv[j] = rv[REF_M - 1];
        }
        memcpy(rs, ts, sizeof rs);
        memcpy(rv, tv, sizeof rv);
    }
    return REF_STEPS;
}

static void test_case2_vs_particle_reference(void **state)
{
    hstpf_sim_config_t sc;
    hstpf_config_t c;
    hstpf_theta_t m[3];
    hstpf_sim_t sim;
    static hstpf_sim_sample_t ys[REF_STEPS + 1];
    static double us[REF_STEPS + 1], gl[3][REF_STEPS + 1], cum[REF_RUNS][REF_STEPS + 1];
    int k, l, run, n_cov = 0, cov_s = 0, cov_v = 0;
    (void)state;
    setup(2, 3, &sc, &c, m);
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&fa, sizeof fa, &c), HSTPF_OK);
    hstpf_sim_init(&sim, &sc);
    for (k = 0; k <= REF_STEPS; ++k) {
        hstpf_input_t in = {0};
        hstpf_estimate_t e;
        hstpf_sim_next_input(&sim, &ys[k], &in);
        assert_true(in.has_position && in.dt_s == 1.0);
        /* the input's traction is the one of the step just ended */
        if (k > 0) {
            us[k - 1] = in.traction;
        }
        assert_int_equal(hstpf_step(&fa, &in), HSTPF_OK);
        (void)hstpf_estimate(&fa, &e);
        for (l = 0; l < 3; ++l) {
            gl[l][k] = k > 0 ? gl[l][k - 1] + (double)e.model[l].loglik : 0.0;
        }
        if (k >= 30) { /* the published 95 % intervals, once the weights settled */
            ++n_cov;
            cov_s += fabs(e.position_m - ys[k].s) <= 1.96 * e.position_sd_m;
            cov_v += fabs((double)e.speed_mps - ys[k].v) <= 1.96 * (double)e.speed_sd_mps;
        }
    }
    /* intervals of millimetres: they cover the truth in 94-98 % of steps
     * 30-300 (`hstpf-mc --scenario paper2 --trace`, seeds 1-6); 0.85 leaves
     * room for one run's correlated steps. While the variance was taken in
     * one pass about the origin they covered 20 % and 31 %. */
    print_message("95 %% intervals cover the truth: position %.3f, speed %.3f of %d steps\n", (double)cov_s / n_cov,
                  (double)cov_v / n_cov, n_cov);
    assert_true(cov_s >= 0.85 * n_cov && cov_v >= 0.85 * n_cov);
    { /* the continuous hypothesis (cfg.refine, the default; on its own grid
       * under Gamma speed noise) keeps little weight for a row's train, and
       * the rows keep their spread in the band: a declared row's theta_cov
       * is diag(refine_spread x its coefficients)^2 */
        hstpf_estimate_t e;
        (void)hstpf_estimate(&fa, &e);
        assert_true(e.declared >= 0 && e.q_offtable > 0 && e.q_offtable < 0.05f);
        TU_CLOSE((double)e.theta_cov[0], pow(c.refine_spread * m[e.declared].c0, 2), 1e-6 * e.theta_cov[0]);
        TU_CLOSE((double)e.theta_cov[3], pow(c.refine_spread * m[e.declared].c1, 2), 1e-6 * e.theta_cov[3]);
        TU_CLOSE((double)e.theta_cov[5], pow(c.refine_spread * m[e.declared].c2, 2), 1e-6 * e.theta_cov[5]);
        assert_true(e.theta_cov[1] == 0 && e.theta_cov[2] == 0 && e.theta_cov[4] == 0);
    }
    for (l = 0; l < 3; ++l) {
        double s1 = 0.0, s2 = 0.0, mean, se;
        int kmin = REF_STEPS;
        for (run = 0; run < REF_RUNS; ++run) {
            const int kl = ref_loglik(&m[l], ys, us, 100u + (uint64_t)run, cum[run]);
            kmin = kl < kmin ? kl : kmin;
        }
        for (run = 0; run < REF_RUNS; ++run) {
            s1 += cum[run][kmin];
            s2 += cum[run][kmin] * cum[run][kmin];
        }
        mean = s1 / REF_RUNS;
        se = sqrt(fmax(s2 / REF_RUNS - mean * mean, 0.0) / (REF_RUNS - 1));
        print_message("%s: steps 1..%d: grid %.3f, reference %.3f +- %.3f (se)\n", m[l].name, kmin, gl[l][kmin], mean,
                      se);
        assert_true(kmin >= 30);
        TU_CLOSE(gl[l][kmin], mean, 4.0 * se + 0.04 * kmin);
        if (kmin < REF_STEPS) { /* not asserted: the reference degenerates there too */
            print_message("  step %d: the reference's every particle at zero; grid %.2f nats\n", kmin + 1,
                          gl[l][kmin + 1] - gl[l][kmin]);
        }
    }
}

static void run_case(hstpf_t *f, const hstpf_config_t *c, int paper_case, uint64_t seed, int steps, int check,
                     hstpf_estimate_t *trace)
{
    hstpf_sim_config_t sc;
    hstpf_config_t cc;
    hstpf_theta_t m[3];
    hstpf_sim_t sim;
    hstpf_sim_sample_t smp;
    hstpf_input_t in = {0};
    int k;
    setup(paper_case, seed, &sc, &cc, m);
    hstpf_sim_init(&sim, &sc);
    (void)c;
    for (k = 0; k < steps; ++k) {
        hstpf_sim_next_input(&sim, &smp, &in);
        if (k % 7 == 3) {
            in.has_position = 0; /* some steps predict only */
        }
        assert_int_equal(hstpf_step(f, &in), HSTPF_OK);
        if (check) {
            check_cells(f, !in.has_position);
        }
        if (trace != NULL) {
            (void)hstpf_estimate(f, &trace[k]);
        }
    }
}

static void test_deterministic(void **state)
{
    static hstpf_estimate_t a[400], b[400];
    hstpf_sim_config_t sc;
    hstpf_config_t c;
    hstpf_theta_t m[3];
    int k;
    (void)state;
    setup(2, 5, &sc, &c, m);
    c.seed = 1;
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&fa, sizeof fa, &c), HSTPF_OK);
    c.seed = 987654321;
    tu_workspace(&c, 1);
    assert_int_equal(hstpf_init(&fb, sizeof fb, &c), HSTPF_OK);
    run_case(&fa, &c, 2, 5, 400, 0, a);
    run_case(&fb, &c, 2, 5, 400, 0, b);
    for (k = 0; k < 400; ++k) {
        if (memcmp(&a[k], &b[k], sizeof a[k]) != 0) {
            fail_msg("step %d differs: position %.9g / %.9g, q1 %.9g / %.9g", k, a[k].position_m, b[k].position_m,
                     (double)a[k].model[1].q, (double)b[k].model[1].q);
        }
    }
    assert_int_equal(hstpf_reset(&fb), HSTPF_OK);
    run_case(&fb, &c, 2, 5, 400, 0, b);
    for (k = 0; k < 400; ++k) { /* the counters go on across a reset; the estimates repeat */
        int l;
        assert_memory_equal(&a[k].position_m, &b[k].position_m, sizeof a[k].position_m);
        assert_memory_equal(&a[k].speed_mps, &b[k].speed_mps, sizeof a[k].speed_mps);
        for (l = 0; l < 3; ++l) {
            assert_memory_equal(&a[k].model[l], &b[k].model[l], sizeof a[k].model[l]);
        }
    }
}

static void test_mass_and_sign(void **state)
{
    hstpf_sim_config_t sc;
    hstpf_config_t c;
    hstpf_theta_t m[3];
    int cs;
    (void)state;
    for (cs = 1; cs <= 4; ++cs) { /* Case 1 and 2, then both with cfg.grid_speed_lattice */
        setup(cs > 2 ? cs - 2 : cs, 11, &sc, &c, m);
        c.grid_speed_lattice = (uint8_t)(cs > 2);
        tu_workspace(&c, 0);
        assert_int_equal(hstpf_init(&fa, sizeof fa, &c), HSTPF_OK);
        run_case(&fa, &c, cs > 2 ? cs - 2 : cs, 11, 600, 1, NULL);
    }
}

/* Inputs at the edges of their ranges: long steps, full braking and
 * traction, a jump of the position inside the gate, a table density. */
static void test_extremes(void **state)
{
    static const double tx[4] = {-1.0, -0.2, 0.5, 2.0}, tp[4] = {0.0, 1.0, 0.3, 0.0};
    hstpf_sim_config_t sc;
    hstpf_config_t c;
    hstpf_theta_t m[3];
    hstpf_input_t in = {0};
    int k;
    (void)state;
    setup(2, 1, &sc, &c, m);
    c.noise_e.kind = HSTPF_DIST_TABLE;
    c.noise_e.table_x = tx;
    c.noise_e.table_p = tp;
    c.noise_e.table_n = 4;
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&fa, sizeof fa, &c), HSTPF_OK);
    memset(&in, 0, sizeof in);
    for (k = 0; k < 300; ++k) {
        in.dt_s = (k % 50 == 49) ? 30.0 : 1.0;
        in.traction = (k / 40) % 2 ? -HSTPF_U_MAX : 60.0;
        in.has_position = 1;
        in.position_m = 1000.0 + 20.0 * k + ((k % 97 == 96) ? 500.0 : 0.0);
        (void)hstpf_step(&fa, &in);
        check_cells(&fa, 0);
    }
}

/* Inputs of a train at constant speed v (traction balancing the truth's
 * resistance), Gaussian position noise of sd 1 m from the simulator's
 * sampler, or at rest under braking when v == 0. */
static void constant_run(hstpf_t *f, double v, int steps, uint64_t seed, hstpf_estimate_t *last)
{
    const hstpf_theta_t *crh3 = &hstpf_train_types[2];
    hstpf_rng_t r;
    hstpf_input_t in = {0};
    int k;
    (void)hstpf_rng_seed(&r, seed, 0);
    memset(&in, 0, sizeof in);
    for (k = 0; k < steps; ++k) {
        in.dt_s = 1.0;
        in.traction = v > 0.0 ? hstpf_resistance(crh3, v) : -20.0;
        in.has_position = 1;
        in.position_m = 5000.0 + v * k + hstpf_sim_gauss(&r);
        assert_int_equal(hstpf_step(f, &in), HSTPF_OK);
        check_cells(f, 0);
        (void)hstpf_estimate(f, last);
    }
}

static void config_unit_noise(hstpf_config_t *c, hstpf_theta_t *m)
{
    hstpf_sim_config_t sc;
    setup(1, 1, &sc, c, m);
    c->noise_e.sd = 1.0;
}

/* At rest under braking, the whole posterior is held: every model's speed
 * is exactly 0, its position does not move, the weights do not change
 * (the bank sees every model held) and the estimate says standstill. */
static void test_standstill(void **state)
{
    hstpf_config_t c;
    hstpf_theta_t m[3];
    hstpf_estimate_t e0, e1;
    uint16_t l;
    (void)state;
    config_unit_noise(&c, m);
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&fa, sizeof fa, &c), HSTPF_OK);
    constant_run(&fa, 0.0, 60, 3, &e0);
    constant_run(&fa, 0.0, 60, 4, &e1);
    assert_int_equal(e1.standstill, 1);
    for (l = 0; l < 3; ++l) {
        assert_true(fa.m[l].held);
        assert_true(e1.model[l].speed_mps == 0);
        TU_CLOSE(e1.model[l].q, e0.model[l].q, 1e-6);
        TU_CLOSE(e1.model[l].position_m, 5000.0, 1.0);
    }
}

/* At rest under Case 2's one-sided Gamma(0.5) fixes (y = s + e, e > 0), a
 * held train's posterior lies below every fix, and the exact posterior's
 * width is the lowest e (about 0.05 mm after 90 fixes). The grid's cells
 * are at least 1 mm and a cell's mass is spread evenly over the cells it
 * is re-gridded onto, so mass may reach a cell or so above the lowest fix:
 * from the tenth step (all held) none lies 10 mm above it, and after 90
 * fixes the estimate is within 2 mm of the truth with an sd under 2 mm.
 * Measured: 5.3 mm, 0.1 mm, 0.7 mm; before the held box kept its cells
 * (docs/grid.md, pitfall 5), 43.8 mm, 4.3 mm and 9.4 mm: the box was
 * placed from the noisy prediction and reached to the measurement at
 * every fix. */
static void test_standstill_gamma(void **state)
{
    hstpf_sim_config_t sc;
    hstpf_config_t c;
    hstpf_theta_t m[3];
    hstpf_estimate_t e;
    hstpf_rng_t r;
    hstpf_input_t in = {0};
    double ymin = 1e300, worst = -1.0;
    int k, i;
    uint16_t l;
    (void)state;
    setup(2, 1, &sc, &c, m);
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&fa, sizeof fa, &c), HSTPF_OK);
    (void)hstpf_rng_seed(&r, 77, 0);
    memset(&in, 0, sizeof in);
    for (k = 0; k < 90; ++k) {
        in.dt_s = 1.0;
        in.traction = -50.0; /* the holding brake */
        in.has_position = 1;
        in.position_m = 5000.0 + 0.2 * hstpf_sim_gamma(&r, 0.5);
        assert_int_equal(hstpf_step(&fa, &in), HSTPF_OK);
        check_cells(&fa, 0);
        if (k < 10) {
            continue;
        }
        ymin = in.position_m < ymin ? in.position_m : ymin;
        for (l = 0; l < 3; ++l) {
            const hstpf_real_t *g = fa.grid.geom[l];
            assert_true(fa.m[l].held);
            for (i = 0; i < HSTPF_GRID_NS; ++i) {
                const double lo = fa.origin_m + (double)g[0] + (double)i * (double)g[1];
                double mass = fa.grid.rest[l][i];
                int j;
                for (j = 0; j < HSTPF_GRID_NV; ++j) {
                    mass += fa.grid.p[l][j * HSTPF_GRID_NS + i];
                }
                if (mass > 0 && lo - ymin > worst) {
                    worst = lo - ymin;
                }
            }
        }
    }
    (void)hstpf_estimate(&fa, &e);
    print_message("held at rest, Gamma fixes: mass up to %.4f m above the lowest fix; estimate %.4f m, sd %.4f m\n",
                  worst, e.position_m - 5000.0, e.position_sd_m);
    assert_true(worst < 0.01);
    for (l = 0; l < 3; ++l) {
        TU_CLOSE(e.model[l].position_m, 5000.0, 0.002);
    }
    assert_true(e.position_sd_m < 0.002);
}

/* Acquisition at 300 km/h: from the first two fixes every model's speed is
 * found (diffuse speed prior, the default), within 1 m/s after 30 s, and
 * the position within 3 m, with no step rejected. */
static void test_acquire_300(void **state)
{
    const double v = 300.0 / 3.6;
    hstpf_config_t c;
    hstpf_theta_t m[3];
    hstpf_estimate_t e;
    uint16_t l;
    (void)state;
    config_unit_noise(&c, m);
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&fa, sizeof fa, &c), HSTPF_OK);
    constant_run(&fa, v, 30, 5, &e);
    for (l = 0; l < 3; ++l) {
        TU_CLOSE(e.model[l].speed_mps, v, 1.0);
        TU_CLOSE(e.model[l].position_m, 5000.0 + v * 29.0, 3.0);
    }
}

/* cfg.grid_rows under Gaussian process noise (Case 1 inputs, all 17 rows,
 * the truth ND2, which Case 1 identifies among 17): after each step the
 * rows with a grid are exactly the grid_rows highest ranked by the weights
 * before it (larger weight, then lower index); a row without one scores
 * the leading gridded row's increment plus its Kalman filter's log ratio to
 * the leader's, within +-1 nat, and publishes the leader's state; the
 * workspace holds grid_rows grids. Against every row on the grid (0) on
 * the same inputs: the same type declared, positions within 1 m RMS of
 * each other (each tracks the train within about 1.4 m, the fix noise's
 * 2 m scaled by the filter); a row given a grid scores its next five fixes
 * within 0.05 nats (mean |difference| of their sum) of its own grid in
 * the other run (0.007 measured; 0.16 when the copy of the leader's
 * density was not moved to the row's own mean). Under Case 2's Gamma
 * process noise the option is ignored: every row has a grid. */
static double rows_ll[2][1801][HSTPF_N_TRAIN_TYPES]; /* each row's increment per step: run a (0), run b (1) */
static int8_t rows_new[1801][HSTPF_N_TRAIN_TYPES];  /* run a: the row was given a grid before this step */

static void rows_run(hstpf_t *f, const hstpf_config_t *c, hstpf_estimate_t *last, double *pos, int check, double jump,
                     int steps)
{
    hstpf_sim_config_t sc;
    hstpf_sim_t sim;
    hstpf_sim_sample_t smp;
    hstpf_input_t in = {0};
    int k;
    hstpf_sim_default(&sc);
    sc.seed = 3;
    sc.truth = hstpf_train_types[hstpf_train_type_find("ND2")];
    hstpf_sim_init(&sim, &sc);
    for (k = 0; k < steps; ++k) {
        double lq[HSTPF_N_TRAIN_TYPES];
        int16_t slot[HSTPF_N_TRAIN_TYPES];
        uint16_t l, n_grid = 0;
        for (l = 0; l < c->n_models; ++l) {
            lq[l] = f->m[l].logq;
            slot[l] = f->grid.slot[l];
        }
        hstpf_sim_next_input(&sim, &smp, &in);
        in.position_m += k >= 60 ? jump : 0.0; /* the fixes' reference moves (within the gate) at 60 s */
        assert_int_equal(hstpf_step(f, &in), HSTPF_OK);
        (void)hstpf_estimate(f, last);
        pos[k] = last->position_m;
        for (l = 0; l < c->n_models; ++l) {
            rows_ll[check ? 0 : 1][k][l] = in.has_position ? (double)f->m[l].loglik : 0.0;
            if (check) {
                rows_new[k][l] = (int8_t)(slot[l] < 0 && f->grid.slot[l] >= 0);
            }
        }
        if (!check || !f->have_fix) {
            continue;
        }
        for (l = 0; l < c->n_models; ++l) {
            uint16_t above = 0, j;
            for (j = 0; j < c->n_models; ++j) {
                above = (uint16_t)(above + (lq[j] > lq[l] || (lq[j] == lq[l] && j < l)));
            }
            if ((f->grid.slot[l] >= 0) != (above < c->grid_rows)) {
                fail_msg("t %d: row %u ranked %u has slot %d", k, l, above, f->grid.slot[l]);
            }
            n_grid = (uint16_t)(n_grid + (f->grid.slot[l] >= 0));
        }
        assert_int_equal(n_grid, c->grid_rows);
        if (in.has_position && k > 2) {
            int lead = -1;
            for (l = 0; l < c->n_models; ++l) {
                if (f->grid.slot[l] >= 0 && (lead < 0 || lq[l] > lq[lead])) {
                    lead = (int)l;
                }
            }
            for (l = 0; l < c->n_models; ++l) {
                if (f->grid.slot[l] < 0) {
                    const double r = f->m[l].kll - f->m[lead].kll;
                    const double want = (double)f->m[lead].loglik + (r > 1.0 ? 1.0 : (r < -1.0 ? -1.0 : r));
                    TU_CLOSE((double)f->m[l].loglik, want, 1e-4);
                    assert_true(f->m[l].s_mean == f->m[lead].s_mean && f->m[l].v_mean == f->m[lead].v_mean);
                }
            }
        }
    }
}

static void test_grid_rows(void **state)
{
    static double pa[1801], pb[1801];
    hstpf_sim_config_t sc;
    hstpf_config_t c, c0;
    hstpf_estimate_t ea, eb;
    size_t ws;
    double ss = 0.0;
    int k;
    uint16_t l;
    (void)state;
    hstpf_sim_default(&sc);
    assert_int_equal(hstpf_config_default(&c), HSTPF_OK);
    assert_int_equal(c.grid_rows, 3);
    c.models = hstpf_train_types;
    c.n_models = HSTPF_N_TRAIN_TYPES;
    c.noise_s = sc.noise_s;
    c.noise_v = sc.noise_v;
    c.noise_e = sc.noise_e;
    c.engine = HSTPF_ENGINE_GRID;
    assert_int_equal(hstpf_workspace_size(&c, &ws), HSTPF_OK);
    assert_int_equal(ws, HSTPF_GRID_WS_BYTES(3));
    c0 = c;
    c0.grid_rows = 0;
    assert_int_equal(hstpf_workspace_size(&c0, &ws), HSTPF_OK);
    assert_int_equal(ws, HSTPF_GRID_WS_BYTES(HSTPF_N_TRAIN_TYPES));
    tu_workspace(&c, 0);
    tu_workspace(&c0, 1);
    assert_int_equal(hstpf_init(&fa, sizeof fa, &c), HSTPF_OK);
    assert_int_equal(hstpf_init(&fb, sizeof fb, &c0), HSTPF_OK);
    rows_run(&fa, &c, &ea, pa, 1, 0.0, 1801);
    rows_run(&fb, &c0, &eb, pb, 0, 0.0, 1801);
    for (k = 0; k <= 1800; ++k) {
        ss += (pa[k] - pb[k]) * (pa[k] - pb[k]);
    }
    print_message("grid_rows 3 vs every row: declared %d / %d, position RMS difference %.3f m\n", ea.declared,
                  eb.declared, sqrt(ss / 1801.0));
    assert_int_equal(ea.declared, hstpf_train_type_find("ND2"));
    assert_int_equal(eb.declared, ea.declared);
    assert_true(sqrt(ss / 1801.0) < 1.0);
    { /* a row given a grid scores the next fixes as its own grid would have
       * (the copy of the leader's density moved to the row's own mean) */
        double dev = 0.0;
        int n = 0, j;
        for (k = 0; k + 5 <= 1800; ++k) {
            for (l = 0; l < c.n_models; ++l) {
                double da = 0.0;
                if (!rows_new[k][l]) {
                    continue;
                }
                for (j = k; j < k + 5; ++j) {
                    da += rows_ll[0][j][l] - rows_ll[1][j][l];
                }
                dev += fabs(da);
                ++n;
            }
        }
        print_message("rows given a grid: %d, mean |difference| of their next 5 increments' sum %.4f nats\n", n,
                      n ? dev / n : 0.0);
        assert_true(n > 0);
        assert_true(dev / n < 0.05);
    }
    /* which rows have a grid follows from the weights alone: a reset run repeats the first, bit for bit */
    assert_int_equal(hstpf_reset(&fa), HSTPF_OK);
    rows_run(&fa, &c, &eb, pb, 0, 0.0, 1801);
    assert_memory_equal(pa, pb, sizeof pa);
    /* a fix every row misses is told as with every row on the grid (the rows
     * without one carry the leader's floor counts): a reference that moves by
     * 300 m at 60 s, while rows without a grid still carry weight, is
     * acquired again (with their own filters' counts it was not) */
    assert_int_equal(hstpf_init(&fa, sizeof fa, &c), HSTPF_OK);
    assert_int_equal(hstpf_init(&fb, sizeof fb, &c0), HSTPF_OK);
    rows_run(&fa, &c, &ea, pa, 0, 300.0, 400);
    rows_run(&fb, &c0, &eb, pb, 0, 300.0, 400);
    print_message("after a 300 m jump: acquisitions %u / %u, re-acquisitions %u / %u\n", ea.acquisitions,
                  eb.acquisitions, ea.reacquired, eb.reacquired);
    assert_int_equal(ea.reacquired, eb.reacquired);
    assert_true(ea.reacquired >= 1u);
    assert_true(fabs(pa[399] - pb[399]) < 5.0);
    /* Case 2: every row (and the hypothesis) on the grid whatever grid_rows says */
    hstpf_sim_case2(&sc);
    c.noise_s = sc.noise_s;
    c.noise_v = sc.noise_v;
    c.noise_e = sc.noise_e;
    assert_int_equal(hstpf_workspace_size(&c, &ws), HSTPF_OK);
    assert_int_equal(ws, HSTPF_GRID_WS_BYTES(HSTPF_N_TRAIN_TYPES + 1));
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&fa, sizeof fa, &c), HSTPF_OK);
    for (l = 0; l < c.n_models; ++l) {
        assert_true(fa.grid.slot[l] == (int16_t)l);
    }
    c.grid_rows = HSTPF_MAX_MODELS + 1;
    assert_int_equal(hstpf_init(&fa, sizeof fa, &c), HSTPF_E_CONFIG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gaussian_vs_kalman),
        cmocka_unit_test(test_gaussian_vs_kalman_lattice),
        cmocka_unit_test(test_speed_lattice),
        cmocka_unit_test(test_track_vs_kalman),
        cmocka_unit_test(test_case2_vs_particle_reference),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_mass_and_sign),
        cmocka_unit_test(test_extremes),
        cmocka_unit_test(test_standstill),
        cmocka_unit_test(test_standstill_gamma),
        cmocka_unit_test(test_acquire_300),
        cmocka_unit_test(test_grid_rows),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
