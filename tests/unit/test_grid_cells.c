/* The grid engine's cell arithmetic against independent references.
 *
 * - The conservative remap (hstpf__grid_remap, docs/grid.md step 2): every
 *   output cell gets each input cell's mass times the length of their
 *   overlap over the input cell's width, computed here in double straight
 *   from the intervals. Width ratios 1 (the box histogram's, which has its
 *   own vectorised path), below 1, between 1 and 2 and above 2; offsets
 *   near a whole cell (the floor's rounding), cells partly or wholly
 *   outside the output, empty cells and cells below MASS_MIN (skipped).
 *   Tolerance: the input edges a + i w are floats of magnitude up to ~25,
 *   so each edge is off by up to 2e-6 cells; 1e-4 of the mass is far above
 *   that and far below any share sent to a wrong cell.
 * - The CDF's tails (hstpf__grid_cdf2 on the tail tables, which a binary
 *   search now reads): at each tail node the probability is exactly the
 *   node's, 2^(k-32); it never decreases along a sweep; between nodes k
 *   and k + 1 it lies between theirs; a Gaussian's lies within a factor 2
 *   of erfc's.
 * - The moments (hstpf__grid_moments) of cells placed by hand 1000 m from
 *   the origin, a millimetre wide, whose mass sums to 1 + 4e-7 (float
 *   round-off is of that order): mean, variance (with each cell's width^2
 *   / 12) and the mass at rest counted at v = 0, derived by hand. The
 *   one-pass s2 - s1^2 about the origin gave a variance of 0 here.
 * - The speed lattice (cfg.grid_speed_lattice) on hand-made images: the
 *   width doubled, kept or halved and the origin on the lattice, derived by
 *   hand; ng left as it is in each of the cases the lattice does not apply.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "grid.h"
#include "testbuild.h"
#include "testutil.h"

#define NOUT 24

static uint32_t lcg(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return *s >> 8;
}

static double unit01(uint32_t *s)
{
    return (double)lcg(s) / 16777216.0;
}

static void remap_ref(const hstpf_real_t *in, int i0, int i1, double a, double w, double *ref)
{
    int i, k;
    for (k = 0; k < NOUT; ++k) {
        ref[k] = 0.0;
    }
    for (i = i0; i <= i1; ++i) {
        const double x0 = a + (double)i * w, x1 = x0 + w;
        if (!(in[i] > (hstpf_real_t)1e-30)) {
            continue;
        }
        for (k = 0; k < NOUT; ++k) {
            const double ov = fmin(x1, (double)(k + 1)) - fmax(x0, (double)k);
            if (ov > 0.0) {
                ref[k] += (double)in[i] * ov / w;
            }
        }
    }
}

static void test_remap_reference(void **state)
{
    /* width ratio, offset: w = 1 at and near whole offsets, narrower,
     * wider, partly outside on either side */
    static const double cases[][2] = {{1.0, 0.3},   {1.0, 3.999999}, {1.0, 2.0},   {1.0, -2.4}, {1.0, 6.5},
                                      {0.73, 1.2},  {0.5, 5.2},      {0.97, 0.01}, {1.37, 0.0}, {1.99, -0.7},
                                      {2.6, 1.1},   {1.0, 14.5},     {0.61, -3.3}, {1.05, 4.0}};
    uint32_t seed = 20261124u;
    size_t c;
    int rep, k;
    (void)state;
    for (c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        for (rep = 0; rep < 200; ++rep) {
            hstpf_real_t in[HSTPF_GRID_NS], out[NOUT];
            double ref[NOUT], mass = 0.0;
            const int i0 = (int)(lcg(&seed) % 4u), i1 = HSTPF_GRID_NS - 1 - (int)(lcg(&seed) % 4u);
            const hstpf_real_t w = (hstpf_real_t)cases[c][0];
            const hstpf_real_t a = (hstpf_real_t)(cases[c][1] + (rep % 2 ? 0.0 : 1e-3 * (unit01(&seed) - 0.5)));
            int i;
            for (i = 0; i < HSTPF_GRID_NS; ++i) {
                const uint32_t r = lcg(&seed) % 10u;
                in[i] = (hstpf_real_t)(r == 0 ? 0.0 : (r == 1 ? 1e-31 : unit01(&seed)));
                mass += in[i] > (hstpf_real_t)1e-30 ? (double)in[i] : 0.0;
            }
            for (k = 0; k < NOUT; ++k) {
                out[k] = (hstpf_real_t)(0.25 * (double)k); /* the remap adds to what is there */
            }
            hstpf__grid_remap(in, i0, i1, a, w, out, NOUT);
            remap_ref(in, i0, i1, (double)a, (double)w, ref);
            for (k = 0; k < NOUT; ++k) {
                const double got = (double)out[k] - 0.25 * (double)k;
                if (!(fabs(got - ref[k]) <= 1e-4 * mass + 1e-6)) {
                    fail_msg("w %g a %.7g rep %d cells %d..%d: output cell %d holds %.8g, reference %.8g", (double)w,
                             (double)a, rep, i0, i1, k, got, ref[k]);
                }
            }
        }
    }
}

static void build(hstpf_dist_t *d, int gamma)
{
    hstpf_dist_spec_t s;
    memset(&s, 0, sizeof s);
    s.kind = gamma ? HSTPF_DIST_GAMMA : HSTPF_DIST_GAUSSIAN;
    if (gamma) {
        s.shape = 0.5;
        s.scale = 1.0;
    } else {
        s.sd = 1.0;
    }
    assert_int_equal(hstpf_dist_init(d, &s), HSTPF_OK);
}

static void test_cdf_tails(void **state)
{
    static hstpf_dist_t d;
    int g, k, side;
    (void)state;
    for (g = 0; g < 2; ++g) {
        build(&d, g);
        for (side = 0; side < 2; ++side) {
            const hstpf_real_t *tab = side ? d.qt.tail_hi : d.qt.tail_lo;
            hstpf_real_t prev = -1;
            for (k = 0; k < HSTPF__QSHIFT; ++k) {
                const double pk = ldexp(1.0, k - 32);
                hstpf_real_t lo, hi, p;
                int t;
                if (!(tab[k] != tab[k + 1])) {
                    continue; /* a tie: the node is not the first beyond */
                }
                hstpf__grid_cdf2(&d.qt, tab[k], &lo, &hi);
                p = side ? hi : lo;
                if (!((double)p == pk)) {
                    fail_msg("%s, %s tail node %d: %.9g, not 2^%d", g ? "Gamma(0.5)" : "N(0,1)",
                             side ? "upper" : "lower", k, (double)p, k - 32);
                }
                for (t = 1; t < 16; ++t) { /* between node k and node k + 1 */
                    const hstpf_real_t x = tab[k] + (tab[k + 1] - tab[k]) * ((hstpf_real_t)t / 16);
                    hstpf__grid_cdf2(&d.qt, x, &lo, &hi);
                    p = side ? hi : lo;
                    assert_true((double)p >= pk && (double)p <= 2.0 * pk);
                    /* along the sweep away from the tail p never decreases */
                    assert_true(p >= prev);
                    prev = p;
                    if (!g) { /* the normal's own tail probability, within the bracket's factor 2 */
                        const double e = 0.5 * erfc((side ? (double)x : -(double)x) / sqrt(2.0));
                        assert_true((double)p <= 2.0 * e && (double)p >= 0.5 * e);
                    }
                }
            }
            {
                hstpf_real_t lo, hi; /* beyond the outermost node: zero */
                hstpf__grid_cdf2(&d.qt, side ? tab[0] + 1 : tab[0] - 1, &lo, &hi);
                assert_true((side ? hi : lo) == 0);
            }
        }
    }
}

/* The speed lattice (cfg.grid_speed_lattice) on hand-made images: rows
 * 5..14 occupied, their images from a at a spacing w; the box ng asks for
 * dv cells from v0. Derived by hand: the lattice width is w 2^k, the
 * smallest with 71 cells >= 72 dv (the box's range), kept only if at most
 * 1.5 dv, with the origin a + floor((v0 - a) / h) h; else ng is left. */
static void lattice_case(double a, double w, double v0, double dv, int any, double want_v0, double want_h)
{
    int16_t first[HSTPF_GRID_NV], last[HSTPF_GRID_NV];
    hstpf_real_t vimg[HSTPF_GRID_NV + 1], ng[4];
    int j;
    for (j = 0; j < HSTPF_GRID_NV; ++j) {
        const int occ = any && j >= 5 && j < 15;
        first[j] = (int16_t)(occ ? 0 : HSTPF_GRID_NS);
        last[j] = (int16_t)(occ ? HSTPF_GRID_NS - 1 : -1);
    }
    for (j = 0; j <= HSTPF_GRID_NV; ++j) {
        vimg[j] = (hstpf_real_t)(a + (double)(j - 5) * w);
    }
    ng[0] = 100;
    ng[1] = (hstpf_real_t)0.01;
    ng[2] = (hstpf_real_t)v0;
    ng[3] = (hstpf_real_t)dv;
    hstpf__grid_speed_lattice(first, last, vimg, ng);
    assert_true(ng[0] == 100 && ng[1] == (hstpf_real_t)0.01); /* position untouched */
    { /* the images are hstpf_real_t near a: a width between two is off by two roundings */
        const double tol = 4.0 * (fabs(a) + 1.0) * (sizeof(hstpf_real_t) == 4 ? FLT_EPSILON : DBL_EPSILON);
        TU_CLOSE((double)ng[2], want_v0, 40.0 * tol + 1e-6);
        TU_CLOSE((double)ng[3], want_h, tol);
    }
}

static void test_speed_lattice_by_hand(void **state)
{
    (void)state;
    /* w 0.01, dv 0.008: 71 x 0.01 = 0.71 >= 0.576, and not 0.355; 0.01 <= 0.012;
     * origin 10 + floor(23.45) 0.01 */
    lattice_case(10.0, 0.01, 10.2345, 0.008, 1, 10.23, 0.01);
    /* w 0.004, dv 0.006: doubled once (0.284 < 0.432 <= 0.568); 0.008 <= 0.009 */
    lattice_case(10.0, 0.004, 10.2345, 0.006, 1, 10.0 + 29.0 * 0.008, 0.008);
    /* w 0.02, dv 0.0075: halved once (0.71 >= 0.54, 0.355 < 0.54); 0.01 <= 0.01125 */
    lattice_case(10.0, 0.02, 10.2345, 0.0075, 1, 10.23, 0.01);
    /* left as they are: */
    lattice_case(10.0, 0.01, 10.2345, 0.005, 1, 10.2345, 0.005);   /* 0.01 > 1.5 x 0.005 */
    lattice_case(10.0, 0.01, 10.2345, 0.008, 0, 10.2345, 0.008);   /* no row occupied */
    lattice_case(0.005, 0.01, 0.0, 0.008, 1, 0.0, 0.008);          /* the origin -0.005 < 0 */
    lattice_case(10.0, 2e-5, 10.0, 2e-5, 1, 10.0, 2e-5);           /* 4e-5 < DV_MIN */
    lattice_case(10.0, 0.0, 10.2345, 0.008, 1, 10.2345, 0.008);    /* images of width 0 */
    lattice_case(10.0, 1e-9, 10.2345, 0.008, 1, 10.2345, 0.008);   /* 16 doublings fall short of DV_MIN */
    lattice_case(10.0, 1e-6, 10.2345, 0.1, 1, 10.2345, 0.1);       /* of the range: 71 x 0.066 < 7.2 */
    lattice_case(10.0, 1.0, 10.2345, 1e-6, 1, 10.2345, 1e-6);      /* 16 halvings: 1.5e-5 < DV_MIN */
}

static hstpf_t gf; /* static, as on a target */

/* A grid-engine instance of three rows, grid 0's cells emptied: its
 * moving cells, its row at rest and its geometry into *p, *rest, *g. */
static void grid_empty(hstpf_real_t **p, hstpf_real_t **rest, hstpf_real_t **g)
{
    static const char *const names[] = {"CRH1", "CRH3", "CRH5"};
    static hstpf_theta_t rows[3];
    hstpf_config_t c;
    tu_config_rows(&c, rows, names, 3);
    c.engine = HSTPF_ENGINE_GRID;
    tu_workspace(&c, 0);
    assert_int_equal(hstpf_init(&gf, sizeof gf, &c), HSTPF_OK);
    *p = gf.grid.p[0];
    *rest = gf.grid.rest[0];
    *g = gf.grid.geom[0];
    memset(*p, 0, sizeof(hstpf_real_t) * HSTPF_GRID_NS * HSTPF_GRID_NV);
    memset(*rest, 0, sizeof(hstpf_real_t) * HSTPF_GRID_NS);
}

static void test_moments_by_hand(void **state)
{
    hstpf_real_t *p, *rest, *g;
    const hstpf_real_t h = (hstpf_real_t)0.5 * (hstpf_real_t)(1.0 + 4e-7);
    (void)state;
    grid_empty(&p, &rest, &g);
    g[0] = 1000; /* positions from 1000 m, cells of 1 mm; speeds from 80 m/s, 2 mm/s */
    g[1] = (hstpf_real_t)0.001;
    g[2] = 80;
    g[3] = (hstpf_real_t)0.002;
    /* half the mass at (s, v) cell (5, 10), half at (6, 11): centres
     * 1000.0055 / 1000.0065 m and 80.021 / 80.023 m/s */
    p[10 * HSTPF_GRID_NS + 5] = h;
    p[11 * HSTPF_GRID_NS + 6] = h;
    hstpf__grid_moments(&gf, &gf.m[0], 0);
    /* mean 1000.006 m and 80.022 m/s; variance 0.0005^2 + width^2 / 12 */
    TU_CLOSE((double)gf.m[0].s_mean, 1000.006, 1e-4); /* the float's ulp at 1000 m is 6e-5 */
    TU_CLOSE((double)gf.m[0].s_var, 0.25e-6 + 1e-6 / 12.0, 1e-9);
    TU_CLOSE((double)gf.m[0].v_mean, 80.022, 1e-5);
    TU_CLOSE((double)gf.m[0].v_var, 1e-6 + 4e-6 / 12.0, 1e-9);
    TU_CLOSE((double)gf.m[0].ess, 2.0, 1e-5);
    /* a quarter of the mass at rest instead (v = 0, position cell 6):
     * v's mean 0.75 x 80.022, its variance the mixture's */
    p[11 * HSTPF_GRID_NS + 6] = (hstpf_real_t)0.25;
    rest[6] = (hstpf_real_t)0.25;
    hstpf__grid_moments(&gf, &gf.m[0], 0);
    {
        const double tot = (double)h + 0.5, w1 = (double)h / tot, w2 = 0.25 / tot, w0 = 0.25 / tot;
        const double vm = w1 * 80.021 + w2 * 80.023, sm = 1000.0 + w1 * 0.0055 + (w2 + w0) * 0.0065;
        const double vv = w1 * 80.021 * 80.021 + w2 * 80.023 * 80.023 - vm * vm + (w1 + w2) * 4e-6 / 12.0;
        const double sv = w1 * 0.0055 * 0.0055 + (w2 + w0) * 0.0065 * 0.0065 - (sm - 1000.0) * (sm - 1000.0);
        TU_CLOSE((double)gf.m[0].v_mean, vm, 1e-4);
        TU_CLOSE((double)gf.m[0].v_var, vv, 1e-3 * vv);
        TU_CLOSE((double)gf.m[0].s_mean, sm, 1e-4);
        TU_CLOSE((double)gf.m[0].s_var, sv + 1e-6 / 12.0, 1e-9);
    }
}

/* A step in the fixes' reference spreads a grid's positions by N(0, v)
 * (hstpf__grid_spread, fix_step.c), onto cells of the old box widened by
 * 4.5 sd each side. Expected by hand: the mass stays (each old cell's
 * shares are normalised); so do the mean and the speeds' moments; the
 * position variance grows by v: the kernel's variance is v less what the
 * cells add (the new cells' width^2 / 12 twice: the kernel's cell masses,
 * Sheppard, and the moments' uniform cells; plus the old cells' width^2 /
 * 12 the old moments counted), which Sheppard's correction gives to
 * within the aliasing of a Gaussian sampled at 1.7 of its sd or finer:
 * 2 exp(-2 pi^2 / 1.7^2) = 2e-3 of v. Two boxes: a train at rest known to
 * millimetres, and cells as wide as the step's sd (a review found the mean
 * moved by half a cell and the variance 27 % too large there when each
 * old cell went to the new ones as a point with the kernel of v). */
static void spread_case(double cell, double v)
{
    hstpf_real_t *p, *rest, *g;
    double s_mean, s_var, v_mean, v_var, width;
    grid_empty(&p, &rest, &g);
    g[0] = 1000;
    g[1] = (hstpf_real_t)cell;
    g[2] = 0;
    g[3] = (hstpf_real_t)0.002;
    p[2 * HSTPF_GRID_NS + 5] = (hstpf_real_t)0.25;
    p[3 * HSTPF_GRID_NS + 9] = (hstpf_real_t)0.125;
    p[3 * HSTPF_GRID_NS + 10] = (hstpf_real_t)0.125;
    rest[7] = (hstpf_real_t)0.5;
    hstpf__grid_moments(&gf, &gf.m[0], 0);
    s_mean = (double)gf.m[0].s_mean;
    s_var = (double)gf.m[0].s_var;
    v_mean = (double)gf.m[0].v_mean;
    v_var = (double)gf.m[0].v_var;
    hstpf__grid_spread(&gf, 0, v);
    width = (double)g[1];
    TU_CLOSE(width, (20.0 * cell + 9.0 * sqrt(v)) / 20.0, 1e-5 * width);
    TU_CLOSE((double)hstpf__grid_mass(&gf, 0), 1.0, 1e-5);
    TU_CLOSE((double)hstpf__grid_sum(rest, HSTPF_GRID_NS), 0.5, 1e-5);
    hstpf__grid_moments(&gf, &gf.m[0], 0);
    TU_CLOSE((double)gf.m[0].s_mean, s_mean, 1e-3 * sqrt(v) + 1e-4); /* + the float's ulp at 1 km */
    TU_CLOSE((double)gf.m[0].s_var - s_var, v, 5e-3 * v);
    TU_CLOSE((double)gf.m[0].v_mean, v_mean, 1e-6);
    TU_CLOSE((double)gf.m[0].v_var, v_var, 1e-8);
    print_message("cells %.3f m spread by %.2f m^2: variance %.4f -> %.4f m^2, mean moved %.2g m (new cells %.3f m)\n",
                  cell, v, s_var, (double)gf.m[0].s_var, (double)gf.m[0].s_mean - s_mean, width);
}

static void test_spread_by_hand(void **state)
{
    (void)state;
    spread_case(0.001, 2.5);
    spread_case(sqrt(2.5), 2.5);
    spread_case(0.5, 10.0);
}

/* The fix noises of the filters' reference: a Gaussian (closed form), and
 * as tables (linear between points 1 m apart) hstpf-mc's heavy-mix (95 %
 * N(0, 2.24 m), 5 % N(0, 22.4 m)) and heavy-t (Student-t, 3 degrees of
 * freedom, scale 1.97 m). */
#define MIX_N 241
static double mix_x[MIX_N], mix_p[2][MIX_N];

/* The library's density of a built noise, as its grid scores cells: from
 * its CDF in the core (0.1 m cells), from its log-density table in the
 * tails, where a CDF difference would cancel. */
static double lib_pdf(double e)
{
    const double p = (double)hstpf__grid_prob_in(&gf.de.qt, (hstpf_real_t)(e - 0.05), (hstpf_real_t)(e + 0.05));
    return p > 1e-5 ? p / 0.1 : exp((double)hstpf__dist_logpdf(&gf.de, (hstpf_real_t)e));
}

/* The sums of the trapezoid rule over [lo, hi] in steps of at most h. */
static void fix_ref_span(double sm, double pss, double y, double lo, double hi, double h, double acc[3])
{
    const long n = (long)ceil((hi - lo) / h);
    const double d = (hi - lo) / (double)n;
    long i;
    for (i = 0; i <= n; ++i) {
        const double x = lo + (double)i * d;
        const double w = (i == 0 || i == n ? 0.5 : 1.0) * d * exp(-0.5 * (x - sm) * (x - sm) / pss) /
                         (sqrt(pss) * 2.5066282746310002) * lib_pdf(y - x);
        acc[0] += w;
        acc[1] += w * x;
        acc[2] += w * x * x;
    }
}

/* log p(y), posterior mean and variance of s under N(s; sm, pss) times
 * the fix noise at y - s, by the trapezoid rule in double over +-10 sd of
 * the prediction and +-130 m of the fix (the noises' tables end at 120 m),
 * in steps of 1 cm or 1/4000 sd, whichever is finer. */
static void fix_ref(double sm, double pss, double y, double *ll, double *mean, double *var)
{
    const double sd = sqrt(pss), h = fmin(0.01, sd / 4000.0);
    const double lo1 = sm - 10.0 * sd, hi1 = sm + 10.0 * sd, lo2 = y - 130.0, hi2 = y + 130.0;
    double acc[3] = {0.0, 0.0, 0.0};
    if (lo2 < hi1 && lo1 < hi2) {
        fix_ref_span(sm, pss, y, fmin(lo1, lo2), fmax(hi1, hi2), h, acc);
    } else {
        fix_ref_span(sm, pss, y, lo1, hi1, h, acc);
        fix_ref_span(sm, pss, y, lo2, hi2, h, acc);
    }
    *ll = log(acc[0]);
    *mean = acc[1] / acc[0];
    *var = acc[2] / acc[0] - *mean * *mean;
}

/* hstpf__kalman_fix (kalman_fix.c), the rows' filters' fix under a
 * non-Gaussian fix noise: against the closed-form Kalman update for a
 * Gaussian fix noise, and against the trapezoid rule above on the
 * library's densities of the three noises, at predicted sd 0.5 to 200 m
 * (from far narrower than the noise to far wider: its core then gets cells
 * of its own) and fixes 0, 2, -4, 8 and 25 sd of the innovation away.
 * Tolerances, wherever the filter takes the fix: 0.06 nats, 3 % of the
 * posterior's sd for its mean and 5 % for its variance. The filter's cells
 * are half an sd of the prediction or a quarter of the noise's
 * interquartile range, and its midpoint rule is off where both densities
 * are steep across a cell (0.043 nats at the Gaussian's 4 sd innovation);
 * errors that matter move a row's score by a nat. The Gaussian is also
 * checked against the closed-form Kalman update, within its tables' 0.07
 * nats 4 sd out. A fix far in a heavy tail leaves a posterior wider than
 * the prediction (two modes), as the reference has it. A fix beyond the
 * floor of every cell of the prediction's +-6 sd is not taken: the filter
 * stays, and the fix scores below the floor. */
static void test_fix_reference(void **state)
{
    static const char *const names[] = {"CRH1", "CRH3", "CRH5"};
    static const double sds[7] = {0.5, 2.0, 4.0, 8.0, 10.0, 50.0, 200.0}, offs[5] = {0.0, 2.0, -4.0, 8.0, 25.0};
    hstpf_theta_t rows[3];
    hstpf_config_t c;
    int noise, a, b, j, taken = 0, checked = 0, far = 0;
    (void)state;
    for (j = 0; j < MIX_N; ++j) {
        const double e = -120.0 + (double)j, t = e / 1.971787;
        mix_x[j] = e;
        mix_p[0][j] = 0.95 * exp(-0.5 * (e / 2.24) * (e / 2.24)) / 2.24 + 0.05 * exp(-0.5 * (e / 22.4) * (e / 22.4)) / 22.4;
        mix_p[1][j] = pow(1.0 + t * t / 3.0, -2.0);
    }
    for (noise = 0; noise < 3; ++noise) {
        tu_config_rows(&c, rows, names, 3);
        c.engine = HSTPF_ENGINE_GRID;
        if (noise) {
            memset(&c.noise_e, 0, sizeof c.noise_e);
            c.noise_e.kind = HSTPF_DIST_TABLE;
            c.noise_e.table_x = mix_x;
            c.noise_e.table_p = mix_p[noise - 1];
            c.noise_e.table_n = MIX_N;
        } else {
            c.noise_e.kind = HSTPF_DIST_GAUSSIAN;
            c.noise_e.mean = 0.3;
            c.noise_e.sd = 2.0;
        }
        tu_workspace(&c, 0);
        assert_int_equal(hstpf_init(&gf, sizeof gf, &c), HSTPF_OK);
        assert_int_equal(hstpf__fix_exact(&gf), noise > 0); /* the Gaussian keeps the closed form */
        if (!noise) { /* a fix 7.6 sd from a 10 m prediction: the prediction's cells all beyond the floor, but the
                       * cells at the fix lift it above: taken, as the reference (72.8 +- 2 m past s) */
            double ll, mean, var;
            hstpf__fix_t fx;
            hstpf__kalman_fix(&gf, 500.0, 100.0, 576.0, &fx);
            fix_ref(500.0, 100.0, 576.0, &ll, &mean, &var);
            assert_false(fx.floored);
            assert_true(fx.loglik > (double)gf.de.floor);
            TU_CLOSE(fx.loglik, ll, 0.06);
            TU_CLOSE(500.0 + fx.ds, mean, 0.1 * sqrt(var));
        }
        for (a = 0; a < 7; ++a) {
            for (b = 0; b < 5; ++b) {
                const double sm = 500.0, pss = sds[a] * sds[a], y = sm + offs[b] * sqrt(pss + 5.0);
                double ll, mean, var;
                hstpf__fix_t fx;
                hstpf__kalman_fix(&gf, sm, pss, y, &fx);
                assert_true(isfinite(fx.loglik) && isfinite(fx.ds) && isfinite(fx.var));
                fix_ref(sm, pss, y, &ll, &mean, &var);
                if (!noise && ll > (double)gf.de.floor + 1.0) { /* hand-derived: the Kalman update, within
                                                                 * the Gaussian's tables (0.07 nats 4 sd out) */
                    const double r = 4.0, sy = pss + r, inn = y - 0.3 - sm;
                    TU_CLOSE(fx.loglik, -0.5 * inn * inn / sy - 0.5 * log(6.283185307179586 * sy), 0.1);
                    TU_CLOSE(sm + fx.ds, sm + pss / sy * inn, 0.05 * sqrt(pss * r / sy));
                    TU_CLOSE(fx.var, pss * r / sy, 0.05 * pss * r / sy);
                }
                if (fx.floored) { /* not taken, and scored below the floor */
                    assert_true(fx.ds == 0.0 && fx.var == pss);
                    assert_true(fx.loglik <= (double)gf.de.floor);
                    continue;
                }
                ++taken;
                if (ll < (double)gf.de.floor + 1.0) { /* the floor's own slope: no noise to compare */
                    continue;
                }
                {
                    /* where the reference reads the density's log table (its
                     * 0.1 m mass below 1e-5) and the cells its CDF, the two
                     * forms of a table's tail differ (0.21 nats, 9 % of the
                     * variance, at most, in these cases) */
                    const int tail = (double)hstpf__grid_prob_in(&gf.de.qt, (hstpf_real_t)(y - sm - 0.05),
                                                                 (hstpf_real_t)(y - sm + 0.05)) <= 1e-5;
                    TU_CLOSE(fx.loglik, ll, tail ? 0.25 : 0.06);
                    TU_CLOSE(sm + fx.ds, mean, (tail ? 0.1 : 0.03) * sqrt(var));
                    TU_CLOSE(fx.var, var, (tail ? 0.1 : 0.05) * var);
                }
                ++checked;
                far += fabs(offs[b]) * sqrt(pss + 5.0) > 6.0 * sds[a];
            }
        }
    }
    print_message("fix taken in %d of 105 cases, %d checked against the reference, %d of them beyond the prediction's 6 sd\n",
                  taken, checked, far);
    /* a prediction or a fix that is not finite: not taken */
    {
        static const double bad[3][2] = {{INFINITY, 501.0}, {NAN, 501.0}, {4.0, NAN}};
        for (j = 0; j < 3; ++j) {
            hstpf__fix_t fx;
            hstpf__kalman_fix(&gf, 500.0, bad[j][0], bad[j][1], &fx);
            assert_true(fx.floored && isfinite(fx.loglik) && fx.ds == 0.0);
        }
    }
    /* a prediction with no spread: the density at the point */
    {
        hstpf__fix_t fx;
        hstpf__kalman_fix(&gf, 500.0, 0.0, 501.0, &fx);
        TU_CLOSE(fx.loglik, (double)hstpf__dist_logpdf(&gf.de, 1.0f), 1e-6);
        assert_true(fx.ds == 0.0 && fx.var == 0.0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_remap_reference),
        cmocka_unit_test(test_cdf_tails),
        cmocka_unit_test(test_moments_by_hand),
        cmocka_unit_test(test_spread_by_hand),
        cmocka_unit_test(test_speed_lattice_by_hand),
        cmocka_unit_test(test_fix_reference),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
