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
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "grid.h"
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
            const hstpf_real_t *tab = side ? d.tail_hi : d.tail_lo;
            hstpf_real_t prev = -1;
            for (k = 0; k < HSTPF__QSHIFT; ++k) {
                const double pk = ldexp(1.0, k - 32);
                hstpf_real_t lo, hi, p;
                int t;
                if (!(tab[k] != tab[k + 1])) {
                    continue; /* a tie: the node is not the first beyond */
                }
                hstpf__grid_cdf2(&d, tab[k], &lo, &hi);
                p = side ? hi : lo;
                if (!((double)p == pk)) {
                    fail_msg("%s, %s tail node %d: %.9g, not 2^%d", g ? "Gamma(0.5)" : "N(0,1)",
                             side ? "upper" : "lower", k, (double)p, k - 32);
                }
                for (t = 1; t < 16; ++t) { /* between node k and node k + 1 */
                    const hstpf_real_t x = tab[k] + (tab[k + 1] - tab[k]) * ((hstpf_real_t)t / 16);
                    hstpf__grid_cdf2(&d, x, &lo, &hi);
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
                hstpf__grid_cdf2(&d, side ? tab[0] + 1 : tab[0] - 1, &lo, &hi);
                assert_true((side ? hi : lo) == 0);
            }
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_remap_reference),
        cmocka_unit_test(test_cdf_tails),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
