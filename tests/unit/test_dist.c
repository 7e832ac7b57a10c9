/* Noise distributions (dist.h): samples against the exact CDF (KS), moments,
 * log-density against the exact log-density inside and beyond the grid, the
 * floor, hard edges, hstpf_exp_neg, and every error of hstpf_dist_init.
 *
 * The exact functions are written here, independently of lib/src/dist.c:
 * Gaussian CDF by erfc, Gamma CDF by the power series of P(k, x) (checked
 * below against closed forms), the triangular table by its hand-derived
 * CDF. Tolerances (all stated in dist.h or derived from statistics):
 *  - sampler vs exact CDF, deterministic: KS distance of the table sampler,
 *    sup_u |F(Q^(u)) - u|, below 2e-3 (dist.h);
 *  - drawn samples: KS < c(0.001)/sqrt(N) + 2e-3 (alpha = 0.001 plus the
 *    table's stated accuracy), for three seeds;
 *  - log-density inside the grid: dx^2/8 * max|(log p)''| per cell (dist.h)
 *    plus float round-off computed from the magnitudes involved. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "dist_impl.h"
#include "testutil.h"
#ifdef HSTPF_TEST_HAVE_SIM
#include "hstpf_sim.h"
#endif

#define KS_TABLE_ACC 2e-3 /* dist.h: KS distance of the sampler below 2e-3 */
#define ALPHA 0.001
#define Z_ALPHA 3.2905 /* two-sided normal quantile for alpha = 0.001 */
#define LN (HSTPF_DIST_LN)

/* ---- the distributions under test -------------------------------------- */

/* Triangular table density, not normalised: p = 0 at -1, 2 at 0, 0 at 3.
 * Mass = 2 * 4 / 2 = 4, so the density is 0.5 (x + 1) on [-1, 0] and
 * (3 - x) / 6 on [0, 3]. CDF by hand: 0.25 (x + 1)^2 on [-1, 0] and
 * 1 - (3 - x)^2 / 12 on [0, 3] (both 0.25 at 0). Mean (a + b + c) / 3 = 2/3,
 * variance (a^2 + b^2 + c^2 - ab - ac - bc) / 18 = 13/18, kurtosis 2.4. */
static const double tri_x[3] = {-1.0, 0.0, 3.0};
static const double tri_p[3] = {0.0, 2.0, 0.0};

typedef struct {
    const char *name;
    hstpf_dist_spec_t spec;
    double mean, var, kurt; /* exact moments, by hand */
} dcase_t;

enum { NCASE = 7 };
static dcase_t cases[NCASE];

static void gauss_spec(hstpf_dist_spec_t *s, double m, double sd)
{
    memset(s, 0, sizeof *s);
    s->kind = HSTPF_DIST_GAUSSIAN;
    s->mean = m;
    s->sd = sd;
}

static void gamma_spec(hstpf_dist_spec_t *s, double k, double th, double loc)
{
    memset(s, 0, sizeof *s);
    s->kind = HSTPF_DIST_GAMMA;
    s->shape = k;
    s->scale = th;
    s->loc = loc;
}

static void make_cases(void)
{
    int i = 0;
    cases[i].name = "N(0,1)";
    gauss_spec(&cases[i].spec, 0.0, 1.0);
    cases[i].mean = 0.0, cases[i].var = 1.0, cases[i].kurt = 3.0, ++i;
    cases[i].name = "N(2,0.5)";
    gauss_spec(&cases[i].spec, 2.0, 0.5);
    cases[i].mean = 2.0, cases[i].var = 0.25, cases[i].kurt = 3.0, ++i;
    /* Gamma(k, th, loc): mean loc + k th, var k th^2, kurtosis 3 + 6 / k */
    cases[i].name = "Gamma(0.5,0.2)";
    gamma_spec(&cases[i].spec, 0.5, 0.2, 0.0);
    cases[i].mean = 0.1, cases[i].var = 0.02, cases[i].kurt = 15.0, ++i;
    cases[i].name = "Gamma(0.02,0.1)";
    gamma_spec(&cases[i].spec, 0.02, 0.1, 0.0);
    cases[i].mean = 0.002, cases[i].var = 0.0002, cases[i].kurt = 303.0, ++i;
    cases[i].name = "Gamma(0.1,0.05)";
    gamma_spec(&cases[i].spec, 0.1, 0.05, 0.0);
    cases[i].mean = 0.005, cases[i].var = 0.00025, cases[i].kurt = 63.0, ++i;
    cases[i].name = "Gamma(3,2,loc=-1)";
    gamma_spec(&cases[i].spec, 3.0, 2.0, -1.0);
    cases[i].mean = 5.0, cases[i].var = 12.0, cases[i].kurt = 5.0, ++i;
    cases[i].name = "Table(triangle -1,0,3)";
    memset(&cases[i].spec, 0, sizeof cases[i].spec);
    cases[i].spec.kind = HSTPF_DIST_TABLE;
    cases[i].spec.table_x = tri_x;
    cases[i].spec.table_p = tri_p;
    cases[i].spec.table_n = 3;
    cases[i].mean = 2.0 / 3.0, cases[i].var = 13.0 / 18.0, cases[i].kurt = 2.4;
}

/* exact CDF */
static double exact_cdf(double x, const void *ctx)
{
    const hstpf_dist_spec_t *s = (const hstpf_dist_spec_t *)ctx;
    switch (s->kind) {
    case HSTPF_DIST_GAUSSIAN:
        return tu_norm_cdf((x - s->mean) / s->sd);
    case HSTPF_DIST_GAMMA:
        return tu_gamma_p(s->shape, (x - s->loc) / s->scale);
    default: /* the triangle above */
        if (x <= -1.0) {
            return 0.0;
        }
        if (x <= 0.0) {
            return 0.25 * (x + 1.0) * (x + 1.0);
        }
        if (x < 3.0) {
            return 1.0 - (3.0 - x) * (3.0 - x) / 12.0;
        }
        return 1.0;
    }
}

/* exact log-density (-HUGE_VAL outside the support) */
static double exact_lp(const hstpf_dist_spec_t *s, double x)
{
    double z;
    switch (s->kind) {
    case HSTPF_DIST_GAUSSIAN:
        z = (x - s->mean) / s->sd;
        return -0.5 * z * z - log(s->sd) - 0.5 * log(2.0 * 3.14159265358979323846);
    case HSTPF_DIST_GAMMA:
        z = (x - s->loc) / s->scale;
        if (!(z > 0.0)) {
            return -HUGE_VAL;
        }
        return (s->shape - 1.0) * log(z) - z - log(s->scale) - lgamma(s->shape);
    default:
        if (x < -1.0 || x > 3.0) {
            return -HUGE_VAL;
        }
        return log(x <= 0.0 ? 0.5 * (x + 1.0) : (3.0 - x) / 6.0);
    }
}

/* |d/dx log p| and |d2/dx2 log p| at x (inside the support) */
static double exact_lp1(const hstpf_dist_spec_t *s, double x)
{
    switch (s->kind) {
    case HSTPF_DIST_GAUSSIAN:
        return fabs(x - s->mean) / (s->sd * s->sd);
    case HSTPF_DIST_GAMMA:
        return fabs((s->shape - 1.0) / (x - s->loc) - 1.0 / s->scale);
    default:
        return x <= 0.0 ? 1.0 / (x + 1.0) : 1.0 / (3.0 - x);
    }
}

static double exact_lp2(const hstpf_dist_spec_t *s, double x)
{
    switch (s->kind) {
    case HSTPF_DIST_GAUSSIAN:
        return 1.0 / (s->sd * s->sd);
    case HSTPF_DIST_GAMMA:
        return fabs(s->shape - 1.0) / ((x - s->loc) * (x - s->loc));
    default: /* log of a linear function a + b x: -(b / p)^2 */
        return x <= 0.0 ? 1.0 / ((x + 1.0) * (x + 1.0)) : 1.0 / ((3.0 - x) * (3.0 - x));
    }
}

/* Values below this are left out of the KS distances: a float cannot hold
 * the Gamma(0.02) quantiles below ~1e-38 (a quarter of its mass lies below
 * 1e-31); for double the bound is far below anything sampled. */
static double ks_x_min(const hstpf_dist_spec_t *s)
{
    if (s->kind == HSTPF_DIST_GAMMA && s->shape < 1.0) {
        return s->loc + s->scale * TU_REAL_MIN * 1e8;
    }
    return -HUGE_VAL;
}

static void build(hstpf_dist_t *d, const hstpf_dist_spec_t *s)
{
    const int32_t err = hstpf_dist_init(d, s);
    if (err != HSTPF_OK) {
        fail_msg("hstpf_dist_init: %s", hstpf_strerror(err));
    }
}

/* ---- the reference functions themselves --------------------------------- */

/* tu_gamma_p against closed forms: P(1, x) = 1 - e^-x, P(1/2, x) = erf(sqrt x),
 * P(3, x) = 1 - e^-x (1 + x + x^2 / 2); small x: P(k, x) -> x^k / Gamma(k+1). */
static void test_reference_cdfs(void **state)
{
    static const double xs[] = {1e-6, 0.01, 0.3, 1.0, 2.5, 7.0, 20.0, 50.0};
    size_t i;
    (void)state;
    for (i = 0; i < sizeof xs / sizeof xs[0]; ++i) {
        const double x = xs[i];
        TU_CLOSE(tu_gamma_p(1.0, x), -expm1(-x), 1e-13);
        TU_CLOSE(tu_gamma_p(0.5, x), erf(sqrt(x)), 1e-13);
        TU_CLOSE(tu_gamma_p(3.0, x), 1.0 - exp(-x) * (1.0 + x + 0.5 * x * x), 1e-13);
    }
    TU_CLOSE(tu_gamma_p(0.02, 1e-20) / (pow(1e-20, 0.02) / tgamma(1.02)), 1.0, 1e-12);
    TU_CLOSE(tu_gamma_p(0.1, 1e-12) / (pow(1e-12, 0.1) / tgamma(1.1)), 1.0, 1e-11);
    TU_CLOSE(tu_norm_cdf(1.0), 0.8413447460685429, 1e-15);
    TU_CLOSE(tu_norm_cdf(-3.0), 0.0013498980316300946, 1e-17);
    /* the triangle's CDF is the integral of its density */
    {
        double c = 0.0, x;
        const double h = 1e-4;
        for (x = -1.0 + 0.5 * h; x < 3.0; x += h) {
            c += h * exp(exact_lp(&cases[6].spec, x));
            if (fabs(x - 1.23005) < 0.5 * h) {
                TU_CLOSE(c, exact_cdf(x + 0.5 * h, &cases[6].spec), 1e-6);
            }
        }
        TU_CLOSE(c, 1.0, 1e-6);
    }
}

/* ---- sampling ----------------------------------------------------------- */

/* The sampler maps r to u = r / 2^32 (tails: (t + 1) / 2^32 at nodes 2^k),
 * monotonically. Its CDF at Q^(u) is u, so the KS distance between the
 * sampled and the exact distribution is sup_u |F(Q^(u)) - u|: evaluated on
 * 256 points per body bin and every tail segment's ends and middle. */
static double sampler_ks(const hstpf_dist_t *d, const hstpf_dist_spec_t *s, uint32_t *nonmono)
{
    const double xmin = ks_x_min(s), fmin = exact_cdf(xmin, s);
    double dmax = 0.0, prev = -HUGE_VAL;
    uint32_t j;
    int k, side;
    *nonmono = 0;
    for (j = 0; j < 65536u; ++j) {
        const uint32_t r = j * 65536u + 32768u;
        const double u = ((double)r + 0.5) / 4294967296.0;
        const double x = (double)hstpf_dist_sample(d, r);
        const double dev = x >= xmin ? fabs(exact_cdf(x, s) - u) : (u > fmin ? u - fmin : 0.0);
        dmax = dev > dmax ? dev : dmax;
        /* non-decreasing, up to one rounding of the interpolation */
        if (x < prev - 4.0 * TU_REAL_EPS * fabs(prev)) {
            ++*nonmono;
        }
        prev = x;
    }
    for (side = 0; side < 2; ++side) {
        for (k = 0; k < 24; ++k) {
            const uint32_t pts[3] = {(1u << k) - 1u, (3u << k) / 2u - 1u, (2u << k) - 2u};
            int p;
            for (p = 0; p < 3; ++p) {
                const uint32_t t = pts[p];
                const uint32_t r = side ? ~t : t;
                const double tail = ((double)t + 1.0) / 4294967296.0;
                const double u = side ? 1.0 - tail : tail;
                const double x = (double)hstpf_dist_sample(d, r);
                double dev;
                if (x >= xmin) {
                    dev = fabs(exact_cdf(x, s) - u);
                    /* the upper tail: compare tail probabilities directly */
                    if (side && s->kind == HSTPF_DIST_GAUSSIAN) {
                        dev = fabs(0.5 * erfc((x - s->mean) / (s->sd * sqrt(2.0))) - tail);
                    }
                } else {
                    dev = u > fmin ? u - fmin : 0.0;
                }
                dmax = dev > dmax ? dev : dmax;
            }
        }
    }
    return dmax;
}

static void test_sampler_accuracy(void **state)
{
    int c;
    (void)state;
    for (c = 0; c < NCASE; ++c) {
        static hstpf_dist_t d;
        uint32_t nonmono;
        double ks;
        build(&d, &cases[c].spec);
        ks = sampler_ks(&d, &cases[c].spec, &nonmono);
        print_message("%-24s sampler KS distance %.2e (dist.h: < %.0e)\n", cases[c].name, ks,
                      KS_TABLE_ACC);
        if (!(ks < KS_TABLE_ACC)) {
            fail_msg("%s: sampler KS distance %g >= %g", cases[c].name, ks, KS_TABLE_ACC);
        }
        assert_int_equal(nonmono, 0);
        /* extremes reach the 2^-32 quantiles (Gaussian: 6.23 sd) */
        if (cases[c].spec.kind == HSTPF_DIST_GAUSSIAN) {
            const double z = 6.2302; /* Phi(-6.2302) = 2.33e-10 = 2^-32 */
            TU_CLOSE(((double)hstpf_dist_sample(&d, 0u) - cases[c].spec.mean) / cases[c].spec.sd, -z,
                     2e-3);
            TU_CLOSE(((double)hstpf_dist_sample(&d, 0xFFFFFFFFu) - cases[c].spec.mean) / cases[c].spec.sd,
                     z, 2e-3);
        }
    }
}

/* Exact mean and second moment of what the sampler implements: it is linear
 * in r on each body bin and tail segment, so each segment's points form an
 * arithmetic progression from its first to its last value. */
static void sampler_moments(const hstpf_dist_t *d, double *mean, double *var)
{
    const int qs = 32 - HSTPF_DIST_QBITS;
    double m1 = 0.0, m2 = 0.0;
    uint32_t b;
    int k, side;
    for (b = 1; b + 1u < HSTPF_DIST_QN; ++b) {
        const double n = (double)(1u << qs);
        const double x0 = (double)hstpf_dist_sample(d, b << qs);
        const double x1 = (double)hstpf_dist_sample(d, (b << qs) + ((1u << qs) - 1u));
        const double l = x1 - x0;
        m1 += n * 0.5 * (x0 + x1);
        m2 += n * (x0 * x0 + x0 * l + l * l * (2.0 * n - 1.0) / (6.0 * (n - 1.0)));
    }
    for (side = 0; side < 2; ++side) {
        for (k = 0; k <= qs; ++k) {
            /* t = m - 1 for m in [2^k, 2^(k+1)); k = qs: the single point m = 2^qs */
            const uint32_t t0 = (1u << k) - 1u, t1 = k < qs ? (2u << k) - 2u : t0;
            const double n = (double)(t1 - t0) + 1.0;
            const double x0 = (double)hstpf_dist_sample(d, side ? ~t0 : t0);
            const double x1 = (double)hstpf_dist_sample(d, side ? ~t1 : t1);
            const double l = x1 - x0;
            m1 += n * 0.5 * (x0 + x1);
            m2 += n * (x0 * x0 + x0 * l + (n > 1.0 ? l * l * (2.0 * n - 1.0) / (6.0 * (n - 1.0)) : 0.0));
        }
    }
    m1 /= 4294967296.0;
    m2 /= 4294967296.0;
    *mean = m1;
    *var = m2 - m1 * m1;
}

/* Drawn samples (hstpf_dist_sample(d, hstpf_rng_next(&rng))), three seeds,
 * N = 1e5 each, every check at alpha = 0.001:
 *  - KS against the exact CDF: D < c(0.001)/sqrt(N) + 2e-3;
 *  - sample mean against d->qt.mean within 3.29 sd / sqrt(N), sample variance
 *    against d->qt.sd^2 within 3.29 sd^2 sqrt((kurtosis - 1) / N) (the
 *    standard error of a sample variance; kurtosis exact, by hand);
 *  - the same against the exact moments mu_T, var_T of what the sampler
 *    implements (above): a sharper check of the sampling path itself;
 *  - d->qt.mean and d->qt.sd equal the exact moments up to float rounding.
 * The table's own moment bias (mu_T - mean, sd_T / sd) is printed: dist.h
 * states no bound for it, so it is reported, not asserted. */
static void test_samples(void **state)
{
    enum { N = 100000 };
    static double x[N];
    static hstpf_dist_t d;
    const double ks_tol = tu_ks_c(ALPHA) / sqrt((double)N) + KS_TABLE_ACC;
    int c;
    uint64_t seed;
    (void)state;
    for (c = 0; c < NCASE; ++c) {
        const dcase_t *cs = &cases[c];
        const double sd = sqrt(cs->var);
        double mu_t, var_t;
        build(&d, &cs->spec);
        TU_CLOSE(d.qt.mean, cs->mean, 4.0 * TU_REAL_EPS * (fabs(cs->mean) + sd));
        TU_CLOSE(d.qt.sd, sd, 4.0 * TU_REAL_EPS * sd);
        sampler_moments(&d, &mu_t, &var_t);
        print_message("%-24s table sampler: mean bias %+.2e sd, sd ratio %.5f\n", cs->name,
                      (mu_t - cs->mean) / sd, sqrt(var_t) / sd);
        for (seed = 1; seed <= 3; ++seed) {
            hstpf_rng_t rng;
            double m = 0.0, v = 0.0, ks;
            int i;
            assert_int_equal(hstpf_rng_seed(&rng, seed, 7), HSTPF_OK);
            for (i = 0; i < N; ++i) {
                x[i] = (double)hstpf_dist_sample(&d, hstpf_rng_next(&rng));
                m += x[i];
            }
            m /= N;
            for (i = 0; i < N; ++i) {
                v += (x[i] - m) * (x[i] - m);
            }
            v /= (N - 1);
            TU_CLOSE(m, d.qt.mean, Z_ALPHA * sd / sqrt((double)N));
            TU_CLOSE(v, (double)d.qt.sd * (double)d.qt.sd, Z_ALPHA * cs->var * sqrt((cs->kurt - 1.0) / N));
            TU_CLOSE(m, mu_t, Z_ALPHA * sqrt(var_t / N));
            TU_CLOSE(v, var_t, Z_ALPHA * var_t * sqrt((cs->kurt - 1.0) / N));
            ks = tu_ks_one_sample(x, N, exact_cdf, &cs->spec, ks_x_min(&cs->spec));
            if (!(ks < ks_tol)) {
                fail_msg("%s seed %u: KS %g >= %g", cs->name, (unsigned)seed, ks, ks_tol);
            }
        }
    }
}

#ifdef HSTPF_TEST_HAVE_SIM
/* Two-sample KS of the table sampler against the simulator's exact
 * Marsaglia-Tsang sampler (tools/sim) for the paper's Case 2 shapes:
 * D < c(0.001) sqrt(2/N) + 2e-3; values below ks_x_min are censored there
 * in both samples. */
static void test_gamma_vs_exact_sampler(void **state)
{
    enum { N = 50000 };
    static double a[N], b[N];
    static hstpf_dist_t d;
    const double tol = tu_ks_c(ALPHA) * sqrt(2.0 / N) + KS_TABLE_ACC;
    int c;
    (void)state;
    for (c = 2; c <= 5; ++c) {
        const hstpf_dist_spec_t *s = &cases[c].spec;
        const double xmin = ks_x_min(s);
        uint64_t seed;
        build(&d, s);
        for (seed = 11; seed <= 13; ++seed) {
            hstpf_rng_t r1, r2;
            double ks;
            int i;
            (void)hstpf_rng_seed(&r1, seed, 1);
            (void)hstpf_rng_seed(&r2, seed, 2);
            for (i = 0; i < N; ++i) {
                a[i] = (double)hstpf_dist_sample(&d, hstpf_rng_next(&r1));
                b[i] = hstpf_sim_noise(&r2, s);
                a[i] = a[i] < xmin ? xmin : a[i];
                b[i] = b[i] < xmin ? xmin : b[i];
            }
            ks = tu_ks_two_sample(a, N, b, N);
            if (!(ks < tol)) {
                fail_msg("%s seed %u: two-sample KS %g >= %g", cases[c].name, (unsigned)seed, ks, tol);
            }
        }
    }
}
#endif

/* ---- log-density -------------------------------------------------------- */

/* The grid as documented: Gaussian mean +- 8 sd, Gamma loc to its 1 - 1e-9
 * quantile, table its own range; LN nodes. */
static void grid_of(const hstpf_dist_spec_t *s, double *lo, double *hi)
{
    switch (s->kind) {
    case HSTPF_DIST_GAUSSIAN:
        *lo = s->mean - 8.0 * s->sd;
        *hi = s->mean + 8.0 * s->sd;
        break;
    case HSTPF_DIST_GAMMA:
        *lo = s->loc;
        *hi = s->loc + s->scale * tu_gamma_upper_quantile(s->shape, 1e-9);
        break;
    default:
        *lo = s->table_x[0];
        *hi = s->table_x[s->table_n - 1u];
        break;
    }
}

/* Node value: the exact log-density, except the Gamma's first node for
 * shape < 1 (unbounded density): the average over the half cell, log(P(k,
 * dx/2/scale) / (dx/2)) (dist.h). */
static double node_lp(const hstpf_dist_spec_t *s, double lo, double dx, int j)
{
    if (j == 0 && s->kind == HSTPF_DIST_GAMMA && s->shape < 1.0) {
        return log(tu_gamma_p(s->shape, 0.5 * dx / s->scale) / (0.5 * dx));
    }
    return exact_lp(s, lo + dx * j);
}

static int in_kink_cell(const hstpf_dist_spec_t *s, double a, double b)
{
    uint16_t i;
    if (s->kind != HSTPF_DIST_TABLE) {
        return 0;
    }
    for (i = 1; i + 1u < s->table_n; ++i) {
        if (s->table_x[i] > a && s->table_x[i] < b) {
            return 1;
        }
    }
    return 0;
}

typedef struct {
    double lo, hi, dx, lpmax, floor, depth, sd;
    /* where the library's node j lies relative to ours: within
     * dlo + j * dnode (its own grid, found by its own quantile search, and
     * rounded to the library's precision; bounded in check_grid) */
    double dlo, dnode;
    /* the library's lp_max (and so its floor, and a Gamma's first node for
     * shape < 1, which is lp_max) relative to ours; bounded in check_grid */
    double dlp;
} grid_t;

static void check_grid(const hstpf_dist_t *d, const hstpf_dist_spec_t *s, double sd, grid_t *g)
{
    int j;
    grid_of(s, &g->lo, &g->hi);
    g->dx = (g->hi - g->lo) / (LN - 1);
    g->depth = s->floor_depth > 0.0 ? s->floor_depth : 30.0;
    g->sd = sd;
    /* the library's grid is the documented one */
    TU_CLOSE(d->lo, g->lo, 2.0 * TU_REAL_EPS * (fabs(g->lo) + g->hi - g->lo));
    TU_CLOSE(d->dx, g->dx, 1e-6 * g->dx + 2.0 * TU_REAL_EPS * g->dx);
    g->dlo = fabs((double)d->lo - g->lo) + TU_REAL_EPS * (fabs(g->lo) + g->dx);
    g->dnode = fabs((double)d->dx - g->dx) + TU_REAL_EPS * g->dx;
    g->lpmax = -HUGE_VAL;
    for (j = 0; j < LN; ++j) {
        const double v = node_lp(s, g->lo, g->dx, j);
        g->lpmax = v > g->lpmax ? v : g->lpmax;
    }
    g->floor = g->lpmax - g->depth;
    TU_CLOSE(d->lp_max, g->lpmax, 1e-6 * (1.0 + fabs(g->lpmax)));
    g->dlp = fabs((double)d->lp_max - g->lpmax);
    TU_CLOSE(d->floor, g->floor, 1e-6 * (1.0 + fabs(g->floor)));
}

/* Inside the grid: at nodes the exact value (or the floor) up to float
 * round-off; between nodes within dx^2/8 max|(log p)''| of the cell; cells
 * whose nodes are at the floor or the Gamma's first cell (documented
 * cell-average) or a table's kink: never below the floor. */
static void check_inside(const hstpf_dist_t *d, const hstpf_dist_spec_t *s, const grid_t *g)
{
    static const double fr[] = {0.0, 0.1234, 0.5, 0.8765};
    const double eps = TU_REAL_EPS;
    int j;
    uint32_t checked = 0;
    for (j = 0; j < LN - 1; ++j) {
        const double a = g->lo + g->dx * j, b = a + g->dx;
        const double na = node_lp(s, g->lo, g->dx, j), nb = node_lp(s, g->lo, g->dx, j + 1);
        const int floor_cell = !(na > g->floor) || !(nb > g->floor);
        const int edge_cell = j == 0 && s->kind == HSTPF_DIST_GAMMA;
        size_t p;
        for (p = 0; p < sizeof fr / sizeof fr[0]; ++p) {
            const hstpf_real_t xr = (hstpf_real_t)(a + fr[p] * g->dx);
            const double x = (double)xr;
            const double got = (double)hstpf_dist_logpdf(d, xr);
            /* float: t = (x - lo) / dx is found within 1.5 eps |x - lo| (three
             * roundings), so x within 2 eps (|x| + |lo|); the node values and
             * the interpolation are rounded within a few eps of their size */
            /* near a node the point may fall on either side of it: the
             * previous cell's chord slope counts too */
            const double chord_prev = j > 0 ? fabs(na - fmax(node_lp(s, g->lo, g->dx, j - 1), g->floor)) / g->dx : 0.0;
            const double slope = floor_cell || edge_cell
                                     ? 0.0
                                     : fmax(fmax(exact_lp1(s, a), exact_lp1(s, b)), fr[p] == 0.0 ? chord_prev : 0.0);
            const double fl_tol = g->dlp + slope * (2.0 * eps * (fabs(x) + fabs(g->lo)) + g->dlo + (j + 1) * g->dnode) +
                                  4.0 * eps * (1.0 + fabs(na > g->floor ? na : g->floor) +
                                               fabs(nb > g->floor ? nb : g->floor));
            assert_true(isfinite(got));
            if (!(got >= g->floor - g->dlp - 4.0 * eps * (1.0 + fabs(g->floor)))) {
                fail_msg("%s: log-density %g at %g below the floor %g", "inside", got, x, g->floor);
            }
            if (floor_cell || edge_cell || in_kink_cell(s, a, b) || x < a || x >= b) {
                continue;
            }
            {
                const double interp = g->dx * g->dx / 8.0 * fmax(exact_lp2(s, a), exact_lp2(s, b));
                const double want = fr[p] == 0.0 ? na : exact_lp(s, x);
                const double tol = (fr[p] == 0.0 ? 0.0 : interp) + fl_tol;
                if (!(fabs(got - want) <= tol)) {
                    fail_msg("cell %d x = %.9g: log-density %.9g, exact %.9g, tolerance %.3g", j, x, got,
                             want, tol);
                }
                ++checked;
            }
        }
    }
    assert_true(checked > 3u * (LN / 4));
}

/* Beyond the grid: max(continuation, sloping floor), where the floor is
 * lp_max - depth at the grid's edge and falls 1 nat per sd beyond it; the
 * continuation is the exact quadratic for the Gaussian (from the edge node),
 * the end slope for the Gamma's right tail, and at a hard edge a Gaussian of
 * width edge_soft from the edge node (none when edge_soft = 0). */
static double expected_beyond(const hstpf_dist_spec_t *s, const grid_t *g, double x)
{
    const int left = x < g->lo;
    const double dd = left ? g->lo - x : x - g->hi;
    const double fl = g->floor - dd / g->sd;
    const double edge_raw = node_lp(s, g->lo, g->dx, left ? 0 : LN - 1);
    const double edge = edge_raw > g->floor ? edge_raw : g->floor;
    double cont = -HUGE_VAL;
    if (s->kind == HSTPF_DIST_GAUSSIAN) {
        cont = edge + dd * (-8.0 / s->sd - 0.5 * dd / (s->sd * s->sd));
    } else if (s->kind == HSTPF_DIST_GAMMA && !left) {
        cont = edge + dd * ((s->shape - 1.0) / (g->hi - g->lo) - 1.0 / s->scale);
    } else if (s->edge_soft > 0.0) {
        cont = edge - 0.5 * dd * dd / (s->edge_soft * s->edge_soft);
    }
    return cont > fl ? cont : fl;
}

static void check_beyond(const hstpf_dist_t *d, const hstpf_dist_spec_t *s, const grid_t *g)
{
    static const double k_sd[] = {0.01, 0.1, 0.5, 1.0, 3.0, 6.0, 10.0, 100.0, 1000.0};
    int side;
    size_t i;
    for (side = 0; side < 2; ++side) {
        double prev = HUGE_VAL;
        for (i = 0; i < sizeof k_sd / sizeof k_sd[0]; ++i) {
            const double dd = k_sd[i] * g->sd;
            const hstpf_real_t xr = (hstpf_real_t)(side ? g->hi + dd : g->lo - dd);
            const double x = (double)xr;
            const double got = (double)hstpf_dist_logpdf(d, xr);
            const double want = expected_beyond(s, g, x);
            /* float: position within 3 eps (|x| + |edge|), values within
             * 8 eps of their magnitude; slope below 8 + dd/sd nats per sd */
            const double slope = (8.0 + fabs(x - (side ? g->hi : g->lo)) / g->sd) / g->sd +
                                 fabs(s->kind == HSTPF_DIST_GAMMA ? 1.0 / s->scale : 0.0) +
                                 (s->edge_soft > 0.0 ? dd / (s->edge_soft * s->edge_soft) : 0.0);
            const double tol = g->dlp + slope * (3.0 * TU_REAL_EPS * (fabs(x) + fabs(g->hi) + fabs(g->lo)) + g->dlo +
                                        (side ? (LN - 1) * g->dnode : 0.0)) +
                               8.0 * TU_REAL_EPS * (1.0 + fabs(want));
            if (!(fabs(got - want) <= tol)) {
                fail_msg("%s side, %g sd beyond: log-density %.9g, expected %.9g +- %.3g", side ? "right" : "left",
                         k_sd[i], got, want, tol);
            }
            /* never flat: farther is lower */
            assert_true(got < prev);
            prev = got;
        }
    }
}

static void check_extremes(const hstpf_dist_t *d, const grid_t *g)
{
    static const double xs[] = {1e6, -1e6, 1e15, -1e15, 1e30, -1e30};
    size_t i;
    const hstpf_real_t nan = (hstpf_real_t)NAN;
    /* NaN returns the floor */
    TU_CLOSE(hstpf_dist_logpdf(d, nan), g->floor, 1e-6 * (1.0 + fabs(g->floor)));
    for (i = 0; i < sizeof xs / sizeof xs[0]; ++i) {
        const double v = (double)hstpf_dist_logpdf(d, (hstpf_real_t)xs[i]);
        if (!isfinite(v) || v > g->floor) {
            fail_msg("log-density at %g = %g: must be finite and at most the floor %g", xs[i], v, g->floor);
        }
    }
}

/* dist.h: "finite for every finite x". The largest finite inputs. */
static void test_logpdf_finite_everywhere(void **state)
{
    int c;
    (void)state;
    for (c = 0; c < NCASE; ++c) {
        static hstpf_dist_t d;
#if defined(HSTPF_USE_DOUBLE) && HSTPF_USE_DOUBLE
        const hstpf_real_t big = DBL_MAX;
#else
        const hstpf_real_t big = FLT_MAX;
#endif
        double hi, lo;
        build(&d, &cases[c].spec);
        hi = (double)hstpf_dist_logpdf(&d, big);
        lo = (double)hstpf_dist_logpdf(&d, -big);
        if (!isfinite(hi) || !isfinite(lo)) {
            fail_msg("%s: log-density at +-max finite = %g, %g (must be finite)", cases[c].name, hi, lo);
        }
    }
}

static void run_logpdf_case(const hstpf_dist_spec_t *spec, double sd)
{
    static hstpf_dist_t d;
    grid_t g;
    build(&d, spec);
    check_grid(&d, spec, sd, &g);
    check_inside(&d, spec, &g);
    check_beyond(&d, spec, &g);
    check_extremes(&d, &g);
}

static void test_logpdf(void **state)
{
    int c;
    (void)state;
    for (c = 0; c < NCASE; ++c) {
        print_message("log-density: %s\n", cases[c].name);
        run_logpdf_case(&cases[c].spec, sqrt(cases[c].var));
    }
}

/* A deeper floor (100 nats) exposes the Gaussian's exact quadratic beyond
 * +-8 sd (it meets the sloping floor 6.6 sd beyond the grid); soft edges. */
static void test_logpdf_options(void **state)
{
    hstpf_dist_spec_t s;
    (void)state;
    gauss_spec(&s, 2.0, 0.5);
    s.floor_depth = 100.0;
    run_logpdf_case(&s, 0.5);
    s = cases[0].spec;
    s.floor_depth = 5.0; /* shallow floor: most of the grid at the floor */
    run_logpdf_case(&s, 1.0);
    s = cases[2].spec; /* Gamma(0.5, 0.2), soft edge 0.05 */
    s.edge_soft = 0.05;
    run_logpdf_case(&s, sqrt(cases[2].var));
    s = cases[5].spec; /* Gamma(3, 2, -1), soft edge 0.5 */
    s.edge_soft = 0.5;
    run_logpdf_case(&s, sqrt(cases[5].var));
    s = cases[6].spec; /* the table with soft edges */
    s.edge_soft = 0.1;
    run_logpdf_case(&s, sqrt(cases[6].var));
}

/* Exact checks, spelled out: the standard normal at its mean and at 1 sd is
 * -0.5 log(2 pi) = -0.9189385 and -1.4189385 (node error only); left of a
 * Gamma's location the floor falls 1 nat per sd. */
static void test_logpdf_spot_values(void **state)
{
    static hstpf_dist_t d;
    (void)state;
    build(&d, &cases[0].spec);
    TU_CLOSE(hstpf_dist_logpdf(&d, 0.0f), -0.91893853320467274, 1.3e-4);
    TU_CLOSE(hstpf_dist_logpdf(&d, 1.0f), -1.41893853320467274, 1.3e-4);
    TU_CLOSE(hstpf_dist_logpdf(&d, -2.0f), -2.91893853320467274, 1.3e-4);
    /* 9 sd: the floor lp_max - 30 minus 1 nat for the 1 sd beyond the grid;
     * lp_max is the largest node, within dx^2/8 = 1.23e-4 of the maximum */
    TU_CLOSE(hstpf_dist_logpdf(&d, 9.0f), -0.91893853320467274 - 30.0 - 1.0, 2e-4);
    /* Gamma(3, 2, -1): left of -1 the floor falls by 1 nat per sd sqrt(12) */
    build(&d, &cases[5].spec);
    TU_CLOSE((double)hstpf_dist_logpdf(&d, -1.5f) - (double)hstpf_dist_logpdf(&d, -1.0f - (float)sqrt(12.0) - 0.5f),
             1.0, 1e-4);
}

/* ---- exp_neg ------------------------------------------------------------ */

/* Relative error below 1e-6 against libm exp over [-100, 0] wherever the
 * result is a normal number of the library's precision (below it a float
 * cannot hold 1e-6 relative: the check there is 0 <= result <= smallest
 * normal); 1 for x >= 0, 0 below -100. */
static void test_exp_neg(void **state)
{
    double worst = 0.0, worst_x = 0.0;
    int i;
    (void)state;
    for (i = 0; i <= 1000000; ++i) {
        const hstpf_real_t xr = (hstpf_real_t)(-100.0 * i / 1000000.0);
        const double x = (double)xr, want = exp(x), got = (double)hstpf_exp_neg(xr);
        if (want >= TU_REAL_MIN) {
            const double rel = fabs(got / want - 1.0);
            if (rel > worst) {
                worst = rel;
                worst_x = x;
            }
        } else {
            assert_true(got >= 0.0 && got <= TU_REAL_MIN);
        }
    }
    print_message("exp_neg: worst relative error %.3g at x = %.6f\n", worst, worst_x);
    if (!(worst < 1e-6)) {
        fail_msg("exp_neg relative error %g at x = %.9g (dist.h: below 1e-6)", worst, worst_x);
    }
}

static void test_exp_neg_edges(void **state)
{
    (void)state;
    TU_CLOSE(hstpf_exp_neg(0.0f), 1.0, 0.0);
    TU_CLOSE(hstpf_exp_neg(-0.0f), 1.0, 0.0);
    TU_CLOSE(hstpf_exp_neg(1e-30f), 1.0, 0.0);
    TU_CLOSE(hstpf_exp_neg(5.0f), 1.0, 0.0);
    TU_CLOSE(hstpf_exp_neg((hstpf_real_t)INFINITY), 1.0, 0.0);
    TU_CLOSE(hstpf_exp_neg(-1e-30f), 1.0, 1e-6);
    TU_CLOSE(hstpf_exp_neg(-100.001f), 0.0, 0.0);
    TU_CLOSE(hstpf_exp_neg(-1e30f), 0.0, 0.0);
    TU_CLOSE(hstpf_exp_neg((hstpf_real_t)-INFINITY), 0.0, 0.0);
    {
        const double v = (double)hstpf_exp_neg((hstpf_real_t)NAN);
        assert_true(v >= 0.0 && v <= 1.0);
    }
    /* at the table's joints: x = -k ln2 / 512 */
    {
        int k;
        for (k = 0; k <= 2048; ++k) {
            const hstpf_real_t xr = (hstpf_real_t)(-k * 0.69314718055994531 / 512.0);
            TU_CLOSE(hstpf_exp_neg(xr) / exp((double)xr), 1.0, 1e-6);
        }
    }
}

/* ---- hstpf_dist_init errors ---------------------------------------------- */

static void expect_init(const hstpf_dist_spec_t *s, int32_t want, const char *what)
{
    static hstpf_dist_t d, copy;
    int32_t got;
    memset(&d, 0xA5, sizeof d);
    copy = d;
    got = hstpf_dist_init(&d, s);
    if (got != want) {
        fail_msg("%s: hstpf_dist_init returned %d (%s), expected %d (%s)", what, got, hstpf_strerror(got), want,
                 hstpf_strerror(want));
    }
    if (want != HSTPF_OK && memcmp(&d, &copy, sizeof d) != 0) {
        fail_msg("%s: *d changed on error", what);
    }
}

static void test_init_errors(void **state)
{
    static double tx[HSTPF_DIST_TABLE_MAX + 1], tp[HSTPF_DIST_TABLE_MAX + 1];
    static hstpf_dist_t d;
    const double nan = NAN, inf = INFINITY;
    hstpf_dist_spec_t g, m, t, s;
    int i;
    (void)state;
    gauss_spec(&g, 0.0, 1.0);
    gamma_spec(&m, 2.0, 1.0, 0.0);
    t = cases[6].spec;

    assert_int_equal(hstpf_dist_init(NULL, &g), HSTPF_E_NULL);
    expect_init(NULL, HSTPF_E_NULL, "spec NULL");
    s = t, s.table_x = NULL, expect_init(&s, HSTPF_E_NULL, "table_x NULL");
    s = t, s.table_p = NULL, expect_init(&s, HSTPF_E_NULL, "table_p NULL");

    /* NaN and Inf in every parameter of each kind */
    for (i = 0; i < 2; ++i) {
        const double bad = i ? inf : nan;
        s = g, s.mean = bad, expect_init(&s, HSTPF_E_NONFINITE, "gaussian mean");
        s = g, s.sd = bad, expect_init(&s, HSTPF_E_NONFINITE, "gaussian sd");
        s = g, s.floor_depth = bad, expect_init(&s, HSTPF_E_NONFINITE, "floor_depth");
        s = m, s.edge_soft = bad, expect_init(&s, HSTPF_E_NONFINITE, "edge_soft");
        s = m, s.shape = bad, expect_init(&s, HSTPF_E_NONFINITE, "gamma shape");
        s = m, s.scale = bad, expect_init(&s, HSTPF_E_NONFINITE, "gamma scale");
        s = m, s.loc = -bad, expect_init(&s, HSTPF_E_NONFINITE, "gamma loc");
        {
            double x2[3] = {-1.0, 0.0, 3.0}, p2[3] = {0.0, 2.0, 0.0};
            x2[1] = bad;
            s = t, s.table_x = x2, expect_init(&s, HSTPF_E_NONFINITE, "table x");
            x2[1] = 0.0;
            p2[2] = bad;
            s = t, s.table_p = p2, expect_init(&s, HSTPF_E_NONFINITE, "table p");
        }
    }
    /* sizes */
    s = t, s.table_n = 0, expect_init(&s, HSTPF_E_SIZE, "table_n 0");
    s = t, s.table_n = 1, expect_init(&s, HSTPF_E_SIZE, "table_n 1");
    for (i = 0; i <= HSTPF_DIST_TABLE_MAX; ++i) {
        tx[i] = i * 0.5;
        tp[i] = 1.0 + (i % 3);
    }
    s = t, s.table_x = tx, s.table_p = tp;
    s.table_n = HSTPF_DIST_TABLE_MAX + 1, expect_init(&s, HSTPF_E_SIZE, "table_n max + 1");
    s.table_n = HSTPF_DIST_TABLE_MAX, expect_init(&s, HSTPF_OK, "table_n max");
    s.table_n = 2, expect_init(&s, HSTPF_OK, "table_n 2");
    /* invalid values */
    s = g, s.sd = 0.0, expect_init(&s, HSTPF_E_DIST, "sd 0");
    s = g, s.sd = -1.0, expect_init(&s, HSTPF_E_DIST, "sd < 0");
    s = m, s.scale = 0.0, expect_init(&s, HSTPF_E_DIST, "scale 0");
    s = m, s.scale = -2.0, expect_init(&s, HSTPF_E_DIST, "scale < 0");
    s = m, s.shape = 0.0, expect_init(&s, HSTPF_E_DIST, "shape 0");
    s = m, s.shape = 0.999e-3, expect_init(&s, HSTPF_E_DIST, "shape < 1e-3");
    s = m, s.shape = 1.0001e4, expect_init(&s, HSTPF_E_DIST, "shape > 1e4");
    s = m, s.shape = -1.0, expect_init(&s, HSTPF_E_DIST, "shape < 0");
    s = m, s.shape = 1e-3, expect_init(&s, HSTPF_OK, "shape 1e-3");
    s = m, s.shape = 1e4, expect_init(&s, HSTPF_OK, "shape 1e4");
    {
        double x2[3] = {-1.0, 0.0, 3.0}, p2[3] = {0.0, 2.0, 0.0};
        x2[2] = 0.0; /* not strictly increasing */
        s = t, s.table_x = x2, expect_init(&s, HSTPF_E_DIST, "table x repeated");
        x2[2] = -2.0;
        s = t, s.table_x = x2, expect_init(&s, HSTPF_E_DIST, "table x decreasing");
        x2[2] = 3.0;
        p2[1] = -1e-9;
        s = t, s.table_p = p2, expect_init(&s, HSTPF_E_DIST, "negative density");
        p2[1] = 0.0;
        s = t, s.table_p = p2, expect_init(&s, HSTPF_E_DIST, "zero mass");
    }
    s = g, s.floor_depth = -1.0, expect_init(&s, HSTPF_E_DIST, "floor_depth < 0");
    s = m, s.edge_soft = -0.1, expect_init(&s, HSTPF_E_DIST, "edge_soft < 0");
    s = g, s.kind = (hstpf_dist_kind_t)3, expect_init(&s, HSTPF_E_DIST, "unknown kind");
    /* only the members of the kind are read */
    s = g, s.shape = nan, s.scale = -1.0, s.table_x = NULL, expect_init(&s, HSTPF_OK, "gaussian ignores others");
    s = m, s.mean = nan, s.sd = -1.0, expect_init(&s, HSTPF_OK, "gamma ignores others");
    /* and a good init after errors works */
    assert_int_equal(hstpf_dist_init(&d, &g), HSTPF_OK);
    TU_CLOSE(d.qt.sd, 1.0, 1e-6);
}

/* ---- ranges and bounded work (issue 11) -------------------------------- */

/* Every member of a built distribution is a finite number. */
static void assert_all_finite(const hstpf_dist_t *d, const char *what)
{
    unsigned i;
    const hstpf_real_t one[] = {d->lo, d->dx, d->inv_dx, d->tail_b[0], d->tail_b[1], d->tail_c[0],
                                d->tail_c[1], d->floor, d->floor_slope, d->dd_max, d->lp_max, d->qt.mean, d->qt.sd};
    for (i = 0; i < sizeof one / sizeof one[0]; ++i) {
        if (!isfinite((double)one[i])) {
            fail_msg("%s: member %u is %g", what, i, (double)one[i]);
        }
    }
    for (i = 0; i <= HSTPF_DIST_QN; ++i) {
        if (!isfinite((double)d->qt.q[i])) {
            fail_msg("%s: q[%u] = %g", what, i, (double)d->qt.q[i]);
        }
    }
    for (i = 0; i < HSTPF_DIST_TAILN; ++i) {
        if (!isfinite((double)d->qt.tail_lo[i]) || !isfinite((double)d->qt.tail_hi[i])) {
            fail_msg("%s: tail %u not finite", what, i);
        }
    }
    for (i = 0; i < LN; ++i) {
        if (!isfinite((double)d->lp[i])) {
            fail_msg("%s: lp[%u] = %g", what, i, (double)d->lp[i]);
        }
    }
    {
        static const double xs[] = {0.0, 1.0, -1.0, 1e9, -1e9, 1e30, -1e30, 3e38, -3e38};
        static const uint32_t rs[] = {0u, 1u, 0x7FFFFFFFu, 0x80000000u, 0xFFFFFFFEu, 0xFFFFFFFFu};
        for (i = 0; i < sizeof xs / sizeof xs[0]; ++i) {
            const double v = (double)hstpf_dist_logpdf(d, (hstpf_real_t)xs[i]);
            if (!isfinite(v)) {
                fail_msg("%s: logpdf(%g) = %g", what, xs[i], v);
            }
        }
        for (i = 0; i < sizeof rs / sizeof rs[0]; ++i) {
            const double v = (double)hstpf_dist_sample(d, rs[i]);
            if (!isfinite(v)) {
                fail_msg("%s: sample(%u) = %g", what, (unsigned)rs[i], v);
            }
        }
    }
}

/* Offsets, spreads and floors outside the documented ranges are refused;
 * the extremes inside them build tables of finite numbers only. */
static void test_spec_ranges(void **state)
{
    static hstpf_dist_t d;
    hstpf_dist_spec_t s;
    double x2[2] = {0.0, 1.0}, p2[2] = {1.0, 1.0};
    const double X = HSTPF_DIST_X_MAX, SMIN = HSTPF_DIST_SPREAD_MIN, SMAX = HSTPF_DIST_SPREAD_MAX;
    const double R = HSTPF_DIST_REL_MIN;
    (void)state;
    /* refused: beyond float range, or below what float tables resolve */
    gauss_spec(&s, 1e38, 1.0), expect_init(&s, HSTPF_E_DIST, "gaussian mean 1e38");
    gauss_spec(&s, 2.0 * X, 1e5), expect_init(&s, HSTPF_E_DIST, "gaussian mean 2e9");
    gauss_spec(&s, 0.0, 3.5e38), expect_init(&s, HSTPF_E_DIST, "gaussian sd 3.5e38");
    gauss_spec(&s, 0.0, 2.0 * SMAX), expect_init(&s, HSTPF_E_DIST, "gaussian sd 2e9");
    gauss_spec(&s, 0.0, 1e-30), expect_init(&s, HSTPF_E_DIST, "gaussian sd 1e-30");
    gauss_spec(&s, 0.0, 0.5 * SMIN), expect_init(&s, HSTPF_E_DIST, "gaussian sd below min");
    gauss_spec(&s, 1e3, 0.5 * R * 1e3), expect_init(&s, HSTPF_E_DIST, "gaussian sd below rel min");
    gamma_spec(&s, 1.0, 3.5e38, 0.0), expect_init(&s, HSTPF_E_DIST, "gamma scale 3.5e38");
    gamma_spec(&s, 1.0, 1e-30, 0.0), expect_init(&s, HSTPF_E_DIST, "gamma scale 1e-30");
    gamma_spec(&s, 1.0, 1.0, -2.0 * X), expect_init(&s, HSTPF_E_DIST, "gamma loc -2e9");
    gamma_spec(&s, 1.0, 0.5 * R * 1e6, 1e6), expect_init(&s, HSTPF_E_DIST, "gamma scale below rel min");
    gauss_spec(&s, 0.0, 1.0), s.floor_depth = HSTPF_DIST_FLOOR_MAX * 1.01,
                              expect_init(&s, HSTPF_E_DIST, "floor_depth beyond max");
    gamma_spec(&s, 1.0, 1.0, 0.0), s.edge_soft = 1e-30, expect_init(&s, HSTPF_E_DIST, "edge_soft 1e-30");
    gamma_spec(&s, 1.0, 1.0, 0.0), s.edge_soft = 1e30, expect_init(&s, HSTPF_E_DIST, "edge_soft 1e30");
    memset(&s, 0, sizeof s);
    s.kind = HSTPF_DIST_TABLE;
    s.table_x = x2;
    s.table_p = p2;
    s.table_n = 2;
    x2[1] = 1e-12, expect_init(&s, HSTPF_E_DIST, "table support 1e-12");
    x2[0] = 1e8, x2[1] = 1e8 + 1.0, expect_init(&s, HSTPF_E_DIST, "table support 1 m at 1e8 m");
    x2[0] = -1e38, x2[1] = 1e38, expect_init(&s, HSTPF_E_DIST, "table points 1e38");
    x2[0] = 0.0, x2[1] = 1e9, p2[0] = p2[1] = 1e300, expect_init(&s, HSTPF_E_DIST, "table mass infinite");

    /* accepted: the extremes, every member finite */
    p2[0] = p2[1] = 1.0;
    x2[0] = 0.0, x2[1] = SMIN, expect_init(&s, HSTPF_OK, "table support min");
    assert_int_equal(hstpf_dist_init(&d, &s), HSTPF_OK), assert_all_finite(&d, "table support min");
    x2[0] = -X, x2[1] = -X + SMAX, expect_init(&s, HSTPF_OK, "table widest at -X");
    assert_int_equal(hstpf_dist_init(&d, &s), HSTPF_OK), assert_all_finite(&d, "table widest at -X");
    x2[0] = -X, x2[1] = X, expect_init(&s, HSTPF_E_DIST, "table wider than the widest spread");
    x2[0] = X - R * X, x2[1] = X, p2[0] = 1e300, p2[1] = 0.0;
    assert_int_equal(hstpf_dist_init(&d, &s), HSTPF_OK), assert_all_finite(&d, "table narrow at X");
    {
        static const double gm[][2] = {{0.0, 1e-9}, {0.0, 1e9}, {1e9, 1e9}, {-1e9, 1e4}, {1e4, 0.1}};
        static const double ga[][3] = {{1e-3, 1e-9, 0.0}, {1e4, 1e-9, 0.0}, {1e-3, 1e9, -1e9},
                                       {1e4, 1e9, 1e9},   {1.0, 1e4, -1e9}, {0.5, 1e-4, 10.0}};
        unsigned i;
        char what[96];
        for (i = 0; i < sizeof gm / sizeof gm[0]; ++i) {
            gauss_spec(&s, gm[i][0], gm[i][1]);
            s.floor_depth = HSTPF_DIST_FLOOR_MAX;
            (void)snprintf(what, sizeof what, "N(%g, %g)", gm[i][0], gm[i][1]);
            expect_init(&s, HSTPF_OK, what);
            assert_int_equal(hstpf_dist_init(&d, &s), HSTPF_OK);
            assert_all_finite(&d, what);
        }
        for (i = 0; i < sizeof ga / sizeof ga[0]; ++i) {
            gamma_spec(&s, ga[i][0], ga[i][1], ga[i][2]);
            s.edge_soft = SMIN;
            (void)snprintf(what, sizeof what, "Gamma(%g, %g, %g)", ga[i][0], ga[i][1], ga[i][2]);
            expect_init(&s, HSTPF_OK, what);
            assert_int_equal(hstpf_dist_init(&d, &s), HSTPF_OK);
            assert_all_finite(&d, what);
        }
    }
}

/* The Gamma's quantiles for scales below 1: the bisection's bracket is in
 * scales (it was in scale^2 and collapsed for small scales). Gamma(2):
 * P(2, x) = 1 - e^-x (1 + x), median 1.678346990 (solved by hand below);
 * Gamma(1e4): median k - 1/3 + 8 / (405 k). */
static void test_gamma_small_scale(void **state)
{
    static hstpf_dist_t d;
    hstpf_dist_spec_t s;
    double a = 0.0, b = 10.0;
    int i;
    (void)state;
    for (i = 0; i < 200; ++i) {
        const double m = 0.5 * (a + b);
        if (1.0 - exp(-m) * (1.0 + m) < 0.5) {
            a = m;
        } else {
            b = m;
        }
    }
    gamma_spec(&s, 2.0, 1e-3, 0.0);
    assert_int_equal(hstpf_dist_init(&d, &s), HSTPF_OK);
    TU_CLOSE(d.qt.q[HSTPF_DIST_QN / 2], 1e-3 * a, 1e-3 * a * 1e-5);
    gamma_spec(&s, 1e4, 1e-3, 5.0);
    assert_int_equal(hstpf_dist_init(&d, &s), HSTPF_OK);
    TU_CLOSE(d.qt.q[HSTPF_DIST_QN / 2], 5.0 + 1e-3 * (1e4 - 1.0 / 3.0 + 8.0 / 4.05e6), 1e-5);
}

/* The blur's quadrature: bounded time and finite tables whatever scale /
 * sd (once unbounded: 15 s at 1e4 / 0.01, a float-to-int overflow beyond
 * 1e8; all -inf for shape 1e4), and right where an exact value is known. */
static void test_blur_bounded(void **state)
{
    static hstpf_dist_t d;
    static const double shapes[] = {1e-3, 0.5, 1.0, 2.0, 143.0, 1e4};
    static const double scale_sd[][2] = {{1e9, 1e-9}, {1e-9, 1e9}, {1.0, 1.0}, {1e3, 1e-6}, {1e-3, 1e3}, {1.0, 1e-9}};
    hstpf_dist_spec_t s;
    double worst = 0.0;
    unsigned i, j;
    char what[96];
    (void)state;
    for (i = 0; i < sizeof shapes / sizeof shapes[0]; ++i) {
        for (j = 0; j < sizeof scale_sd / sizeof scale_sd[0]; ++j) {
            clock_t t0;
            double cpu;
            gamma_spec(&s, shapes[i], scale_sd[j][0], 0.0);
            (void)snprintf(what, sizeof what, "Gamma(%g, %g) + N(0, %g)", shapes[i], scale_sd[j][0], scale_sd[j][1]);
            assert_int_equal(hstpf_dist_init(&d, &s), HSTPF_OK);
            t0 = clock();
            assert_int_equal(hstpf__dist_blur(&d, &s, scale_sd[j][1]), HSTPF_OK);
            cpu = (double)(clock() - t0) / CLOCKS_PER_SEC;
            worst = cpu > worst ? cpu : worst;
            if (cpu > 2.0) { /* measured below 0.02 s (docs/quality.md) */
                fail_msg("%s: %.2f s", what, cpu);
            }
            assert_all_finite(&d, what);
        }
    }
    print_message("blur: slowest of %u cases %.3f s CPU\n",
                  (unsigned)(sizeof shapes / sizeof shapes[0] * sizeof scale_sd / sizeof scale_sd[0]), worst);
    /* a blur far below the grid: the Gamma's own density, log p = log(x) - x/th - 2 log th */
    gamma_spec(&s, 2.0, 1e3, 0.0);
    assert_int_equal(hstpf_dist_init(&d, &s), HSTPF_OK);
    assert_int_equal(hstpf__dist_blur(&d, &s, 1e-6), HSTPF_OK);
    TU_CLOSE(hstpf_dist_logpdf(&d, 2000.0f), log(2000.0) - 2.0 - 2.0 * log(1e3), 1e-2);
    TU_CLOSE(hstpf_dist_logpdf(&d, 500.0f), log(500.0) - 0.5 - 2.0 * log(1e3), 1e-2);
    {
        double mass = 0.0, x;
        for (x = 0.5; x < 60000.0; x += 1.0) {
            mass += exp((double)hstpf_dist_logpdf(&d, (hstpf_real_t)x));
        }
        TU_CLOSE(mass, 1.0, 2e-3);
    }
    /* shape 1e4: the Gamma's exact density at its mean (blur var 1 of 1e4) */
    gamma_spec(&s, 1e4, 1.0, 0.0);
    assert_int_equal(hstpf_dist_init(&d, &s), HSTPF_OK);
    assert_int_equal(hstpf__dist_blur(&d, &s, 1.0), HSTPF_OK);
    TU_CLOSE(hstpf_dist_logpdf(&d, 10000.0f), 9999.0 * log(1e4) - 1e4 - lgamma(1e4), 1e-2);
    /* a blur far wider than the Gamma: N(0, sd) */
    gamma_spec(&s, 1e4, 1e-9, 0.0);
    assert_int_equal(hstpf_dist_init(&d, &s), HSTPF_OK);
    assert_int_equal(hstpf__dist_blur(&d, &s, 1e9), HSTPF_OK);
    TU_CLOSE(hstpf_dist_logpdf(&d, 0.0f), -log(1e9 * sqrt(2.0 * 3.14159265358979)), 1e-3);
    TU_CLOSE(hstpf_dist_logpdf(&d, 1e9f), -log(1e9 * sqrt(2.0 * 3.14159265358979)) - 0.5, 1e-3);
    /* refused: blurs outside the spreads' range, and NaN */
    gamma_spec(&s, 0.5, 0.2, 0.0);
    assert_int_equal(hstpf_dist_init(&d, &s), HSTPF_OK);
    assert_int_equal(hstpf__dist_blur(&d, &s, 3.5e38), HSTPF_E_DIST);
    assert_int_equal(hstpf__dist_blur(&d, &s, 1e-30), HSTPF_E_DIST);
    assert_int_equal(hstpf__dist_blur(&d, &s, NAN), HSTPF_E_DIST);
    assert_int_equal(hstpf__dist_blur(&d, &s, INFINITY), HSTPF_E_DIST);
    s.scale = -1.0; /* an invalid Gamma is refused by the blur as by init */
    assert_int_equal(hstpf__dist_blur(&d, &s, 0.1), HSTPF_E_DIST);
    /* its own floor depth */
    s.scale = 0.2;
    s.floor_depth = 12.0;
    assert_int_equal(hstpf__dist_blur(&d, &s, 0.1), HSTPF_OK);
    TU_CLOSE(d.floor, (double)d.lp_max - 12.0, 1e-4);
}

static int setup(void **state)
{
    (void)state;
    make_cases();
    return 0;
}

/* Blurred log-density (hstpf__dist_blur, cfg.e_blur_sd): Gamma(0.5, 0.2) + N(0, 0.1)
 * against an independent quadrature (g = u^2 removes the edge singularity:
 * p(x) = int 2 exp(-u^2/th) / sqrt(pi th) phi((x - u^2)/sd) / sd du), its
 * mass and mean; other kinds and sd <= 0 are refused. */
static double blur_ref(double x, double th, double sd)
{
    const int n = 200000;
    const double umax = sqrt(40.0 * th + x + 10.0 * sd > 0.0 ? 40.0 * th + x + 10.0 * sd : 1.0);
    double acc = 0.0;
    int j;
    for (j = 0; j < n; ++j) {
        const double u = umax * (j + 0.5) / n, z = (x - u * u) / sd;
        acc += 2.0 * exp(-u * u / th) / sqrt(3.14159265358979 * th) * exp(-0.5 * z * z) /
               (sd * 2.5066282746310002) * (umax / n);
    }
    return acc;
}

static void test_logpdf_blur(void **state)
{
    hstpf_dist_spec_t s;
    hstpf_dist_t d, g;
    double mass = 0.0, m1 = 0.0, x;
    const double dx = 1e-3;
    static const double xs[] = {-0.3, -0.1, 0.0, 0.02, 0.1, 0.3, 1.0, 2.0};
    unsigned i;
    (void)state;
    memset(&s, 0, sizeof s);
    s.kind = HSTPF_DIST_GAMMA;
    s.shape = 0.5;
    s.scale = 0.2;
    assert_int_equal(hstpf_dist_init(&d, &s), HSTPF_OK);
    assert_int_equal(hstpf__dist_blur(&d, &s, 0.1), HSTPF_OK);
    for (i = 0; i < sizeof xs / sizeof xs[0]; ++i) {
        const double ref = log(blur_ref(xs[i], 0.2, 0.1));
        const double got = (double)hstpf_dist_logpdf(&d, (hstpf_real_t)xs[i]);
        if (fabs(got - ref) > 5e-3) {
            fail_msg("blurred Gamma at %g: %g, reference %g", xs[i], got, ref);
        }
    }
    for (x = -1.0; x < 6.0; x += dx) {
        const double p = exp((double)hstpf_dist_logpdf(&d, (hstpf_real_t)x));
        mass += p * dx;
        m1 += x * p * dx;
    }
    assert_true(fabs(mass - 1.0) < 2e-3);
    assert_true(fabs(m1 - 0.1) < 2e-3);
    /* left of the edge it falls, never below the floor, finite */
    assert_true(hstpf_dist_logpdf(&d, -0.5f) < hstpf_dist_logpdf(&d, -0.2f));
    assert_true(hstpf_dist_logpdf(&d, -1e6f) >= d.floor - d.dd_max * d.floor_slope);

    /* only Gamma: a blurred Gaussian is a wider Gaussian, built by the
     * filter itself (test_errors checks the configuration errors) */
    gauss_spec(&s, 1.0, 0.3);
    assert_int_equal(hstpf_dist_init(&g, &s), HSTPF_OK);
    assert_int_equal(hstpf__dist_blur(&g, &s, 0.4), HSTPF_E_DIST);
    assert_int_equal(hstpf__dist_blur(&d, &cases[6].spec, 0.1), HSTPF_E_DIST); /* table */
    s.kind = HSTPF_DIST_GAMMA;
    s.shape = 0.5;
    s.scale = 0.2;
    assert_int_equal(hstpf__dist_blur(&d, &s, 0.0), HSTPF_E_DIST);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_logpdf_blur),
        cmocka_unit_test(test_reference_cdfs),
        cmocka_unit_test(test_sampler_accuracy),
        cmocka_unit_test(test_samples),
#ifdef HSTPF_TEST_HAVE_SIM
        cmocka_unit_test(test_gamma_vs_exact_sampler),
#endif
        cmocka_unit_test(test_logpdf),
        cmocka_unit_test(test_logpdf_options),
        cmocka_unit_test(test_logpdf_spot_values),
        cmocka_unit_test(test_logpdf_finite_everywhere),
        cmocka_unit_test(test_exp_neg),
        cmocka_unit_test(test_exp_neg_edges),
        cmocka_unit_test(test_init_errors),
        cmocka_unit_test(test_spec_ranges),
        cmocka_unit_test(test_gamma_small_scale),
        cmocka_unit_test(test_blur_bounded),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
