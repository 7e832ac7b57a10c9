/* Systematic resampling internals (lib/src/internal.h): invariants.
 *
 * Systematic resampling with offset u0 in [0, 1) places n pointers at
 * (j + u0) / n, j = 0..n-1, on the cumulative weights C_i = w_0 + .. + w_i;
 * particle i gets the pointers in [C_(i-1), C_i): exactly
 *   count_i = ceil(n C_i - u0) - ceil(n C_(i-1) - u0),
 * which is floor(n w_i) or ceil(n w_i), sums to n, and is 0 when w_i = 0.
 * The library sums C_i in float: the computed n C_i - u0 is within
 * Delta = n (n + 2) u of the exact value (recursive summation, u = eps/2,
 * plus the product and the subtraction), so a count may move past
 * floor/ceil by at most 2 Delta: that is the float allowance below. Arrays
 * are heap blocks of exactly n elements, so AddressSanitizer catches any
 * index out of range. */
#include <stdlib.h>
#include <string.h>

#include "internal.h"
#include "testutil.h"

typedef hstpf_real_t real;

static void *xalloc(size_t n, size_t size)
{
    void *p = calloc(n ? n : 1u, size);
    assert_non_null(p);
    return p;
}

/* Checks the counts for weights w (sum S, not necessarily exactly 1). */
static void check_counts(const real *w, uint16_t n, real u0, const uint16_t *cnt, const char *what)
{
    double s = 0.0, delta;
    uint32_t total = 0;
    uint16_t i;
    for (i = 0; i < n; ++i) {
        s += (double)w[i];
    }
    delta = (double)n * ((double)n + 2.0) * 0.5 * TU_REAL_EPS + (double)n * fabs(s - 1.0);
    for (i = 0; i < n; ++i) {
        const double nw = (double)n * (double)w[i] / s;
        total += cnt[i];
        if ((double)cnt[i] < floor(nw - 2.0 * delta) || (double)cnt[i] > ceil(nw + 2.0 * delta)) {
            fail_msg("%s: n = %u, u0 = %.9g: count[%u] = %u, n w = %.6f (allowance %.3g)", what, n, (double)u0, i,
                     cnt[i], nw, 2.0 * delta);
        }
        if (w[i] == (real)0 && cnt[i] != 0u) {
            fail_msg("%s: n = %u, u0 = %.9g: particle %u has weight 0 but %u copies (sum of w - 1 = %.3g)", what, n,
                     (double)u0, i, cnt[i], s - 1.0);
        }
    }
    if (total != n) {
        fail_msg("%s: n = %u, u0 = %.9g: counts sum to %u", what, n, (double)u0, total);
    }
}

static real offsets[8];

static void make_offsets(hstpf_rng_t *r)
{
    offsets[0] = 0;
    offsets[1] = (real)(1.0 / 16777216.0);
    offsets[2] = (real)0.5;
    offsets[3] = (real)(16777215.0 / 16777216.0); /* largest hstpf_rng_uniform */
    offsets[4] = (real)0.25;
    offsets[5] = hstpf_rng_uniform(r);
    offsets[6] = hstpf_rng_uniform(r);
    offsets[7] = hstpf_rng_uniform(r);
}

/* random weights normalised in the library's precision: their float sum
 * is 1 up to round-off; power > 1 skews them */
static void random_weights(hstpf_rng_t *r, real *w, uint16_t n, int power)
{
    real sum = 0;
    uint16_t i;
    int k;
    for (i = 0; i < n; ++i) {
        real x = hstpf_rng_uniform(r) + (real)1e-3;
        real y = x;
        for (k = 1; k < power; ++k) {
            y *= x;
        }
        w[i] = y;
        sum += y;
    }
    for (i = 0; i < n; ++i) {
        w[i] /= sum;
    }
}

static void test_counts_random(void **state)
{
    static const uint16_t ns[] = {1, 2, 3, 5, 7, 10, 64, 100, 255, 256, 1000, 4096};
    hstpf_rng_t r;
    size_t a;
    (void)state;
    (void)hstpf_rng_seed(&r, 2024, 0);
    for (a = 0; a < sizeof ns / sizeof ns[0]; ++a) {
        const uint16_t n = ns[a];
        real *w = xalloc(n, sizeof *w);
        uint16_t *cnt = xalloc(n, sizeof *cnt);
        int trial, o, power;
        for (trial = 0; trial < 4; ++trial) {
            for (power = 1; power <= 16; power *= 4) {
                random_weights(&r, w, n, power);
                make_offsets(&r);
                for (o = 0; o < 8; ++o) {
                    hstpf__resample_counts(w, n, offsets[o], cnt);
                    check_counts(w, n, offsets[o], cnt, "random weights");
                }
            }
        }
        free(w);
        free(cnt);
    }
}

/* Weights whose float sum is 1 + k ulp, k = -8..8 (scaled), and the extreme
 * float case 1/3 * 3 > 1. */
static void test_counts_roundoff(void **state)
{
    hstpf_rng_t r;
    uint16_t n;
    (void)state;
    (void)hstpf_rng_seed(&r, 7, 1);
    for (n = 2; n <= 300; n = (uint16_t)(n * 3 / 2 + 1)) {
        real *w = xalloc(n, sizeof *w);
        uint16_t *cnt = xalloc(n, sizeof *cnt);
        int k, o;
        for (k = -8; k <= 8; ++k) {
            uint16_t i;
            random_weights(&r, w, n, 2);
            for (i = 0; i < n; ++i) {
                w[i] *= (real)(1.0 + k * TU_REAL_EPS);
            }
            make_offsets(&r);
            for (o = 0; o < 8; ++o) {
                hstpf__resample_counts(w, n, offsets[o], cnt);
                check_counts(w, n, offsets[o], cnt, "sum 1 +- round-off");
            }
        }
        free(w);
        free(cnt);
    }
}

/* w = 1/n: every particle exactly once whenever u0 is farther than the
 * float allowance n (n + 2) u from 0 and 1 (for n <= 300: below 0.006, so
 * u0 in [0.01, 0.99]); at u0 = 0 the pointers sit exactly on the cumulative
 * boundaries and round-off may move one across, so only the sum and the
 * floor/ceil allowance apply there. */
static void test_counts_uniform(void **state)
{
    hstpf_rng_t r;
    uint16_t n;
    (void)state;
    (void)hstpf_rng_seed(&r, 99, 0);
    for (n = 1; n <= 300; ++n) {
        real *w = xalloc(n, sizeof *w);
        uint16_t *cnt = xalloc(n, sizeof *cnt);
        uint16_t i;
        int t;
        for (i = 0; i < n; ++i) {
            w[i] = (real)1 / (real)n;
        }
        for (t = 0; t < 20; ++t) {
            const real u0 = t == 0 ? (real)0.01 : t == 1 ? (real)0.99 : (real)0.01 + (real)0.98 * hstpf_rng_uniform(&r);
            hstpf__resample_counts(w, n, u0, cnt);
            for (i = 0; i < n; ++i) {
                if (cnt[i] != 1u) {
                    fail_msg("w = 1/%u, u0 = %.9g: count[%u] = %u, expected 1", n, (double)u0, i, cnt[i]);
                }
            }
        }
        hstpf__resample_counts(w, n, 0, cnt);
        check_counts(w, n, 0, cnt, "uniform, u0 = 0");
        free(w);
        free(cnt);
    }
}

/* a single weight 1 (first, middle, last): all n copies go to it */
static void test_counts_single(void **state)
{
    static const uint16_t ns[] = {1, 2, 3, 100, 256};
    hstpf_rng_t r;
    size_t a;
    (void)state;
    (void)hstpf_rng_seed(&r, 5, 0);
    for (a = 0; a < sizeof ns / sizeof ns[0]; ++a) {
        const uint16_t n = ns[a];
        real *w = xalloc(n, sizeof *w);
        uint16_t *cnt = xalloc(n, sizeof *cnt);
        const uint16_t where[3] = {0, (uint16_t)(n / 2), (uint16_t)(n - 1)};
        int p, o;
        for (p = 0; p < 3; ++p) {
            uint16_t i;
            for (i = 0; i < n; ++i) {
                w[i] = i == where[p] ? (real)1 : (real)0;
            }
            make_offsets(&r);
            for (o = 0; o < 8; ++o) {
                hstpf__resample_counts(w, n, offsets[o], cnt);
                for (i = 0; i < n; ++i) {
                    assert_int_equal(cnt[i], i == where[p] ? n : 0u);
                }
            }
        }
        free(w);
        free(cnt);
    }
}

/* Degenerate weights: zeros at both ends (as when the likelihood of far
 * particles underflows), the non-zero middle normalised in float so that
 * its sum is 1 - a few ulp or 1 + a few ulp. A particle of weight 0 must
 * never be copied, whatever u0 (also the largest, 1 - 2^-24). */
static void test_counts_zeros_at_ends(void **state)
{
    static const uint16_t ns[] = {4, 10, 100, 256};
    hstpf_rng_t r;
    size_t a;
    int below = 0, above = 0;
    (void)state;
    (void)hstpf_rng_seed(&r, 3, 0);
    for (a = 0; a < sizeof ns / sizeof ns[0]; ++a) {
        const uint16_t n = ns[a];
        real *w = xalloc(n, sizeof *w);
        uint16_t *cnt = xalloc(n, sizeof *cnt);
        int trial, o;
        for (trial = 0; trial < 40; ++trial) {
            const uint16_t z0 = (uint16_t)(n / 4), z1 = (uint16_t)(n / 4); /* zeros at each end */
            const uint16_t m = (uint16_t)(n - z0 - z1);
            double s = 0.0;
            uint16_t i;
            memset(w, 0, n * sizeof *w);
            random_weights(&r, w + z0, m, 3);
            for (i = 0; i < n; ++i) {
                s += (double)w[i];
            }
            below += s < 1.0;
            above += s > 1.0;
            make_offsets(&r);
            for (o = 0; o < 8; ++o) {
                hstpf__resample_counts(w, n, offsets[o], cnt);
                check_counts(w, n, offsets[o], cnt, "zeros at the ends");
            }
        }
        free(w);
        free(cnt);
    }
    /* the trials did exercise both signs of the round-off */
    assert_true(below > 0 && above > 0);
}

/* replicate: the multiset after equals the one the counts imply; each
 * survivor keeps its slot; s, v and lw move together; counts unchanged. */
static void test_replicate(void **state)
{
    static const uint16_t ns[] = {1, 2, 3, 7, 100, 256, 1000};
    hstpf_rng_t r;
    size_t a;
    (void)state;
    (void)hstpf_rng_seed(&r, 11, 0);
    for (a = 0; a < sizeof ns / sizeof ns[0]; ++a) {
        const uint16_t n = ns[a];
        real *w = xalloc(n, sizeof *w), *s = xalloc(n, sizeof *s), *v = xalloc(n, sizeof *v);
        real *lw = xalloc(n, sizeof *lw);
        uint16_t *cnt = xalloc(n, sizeof *cnt), *before = xalloc(n, sizeof *before);
        uint32_t *seen = xalloc(n, sizeof *seen);
        int trial;
        for (trial = 0; trial < 12; ++trial) {
            uint16_t i;
            const int with_lw = trial % 2;
            random_weights(&r, w, n, 1 + 4 * (trial % 4));
            if (trial == 11) {
                for (i = 0; i < n; ++i) {
                    w[i] = i == n - 1u ? (real)1 : (real)0; /* everything to the last */
                }
            }
            hstpf__resample_counts(w, n, hstpf_rng_uniform(&r), cnt);
            memcpy(before, cnt, n * sizeof *cnt);
            for (i = 0; i < n; ++i) {
                s[i] = (real)i;
                v[i] = (real)(-(double)i - 0.5);
                lw[i] = (real)((double)i * 0.25);
                seen[i] = 0;
            }
            hstpf__replicate(s, v, with_lw ? lw : NULL, cnt, n);
            assert_memory_equal(cnt, before, n * sizeof *cnt);
            for (i = 0; i < n; ++i) {
                const double si = (double)s[i];
                const uint32_t idx = (uint32_t)si;
                assert_true(si >= 0.0 && si < (double)n && si == (double)idx);
                assert_true((double)v[i] == -si - 0.5);
                assert_true((double)lw[i] == (with_lw ? si * 0.25 : (double)i * 0.25));
                ++seen[idx];
                if (before[i] > 0u) {
                    assert_true(idx == i); /* a survivor keeps its slot */
                }
            }
            for (i = 0; i < n; ++i) {
                if (seen[i] != before[i]) {
                    fail_msg("n = %u: particle %u appears %u times, counts say %u", n, i, seen[i], before[i]);
                }
            }
        }
        free(w);
        free(s);
        free(v);
        free(lw);
        free(cnt);
        free(before);
        free(seen);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_counts_random),  cmocka_unit_test(test_counts_roundoff),
        cmocka_unit_test(test_counts_uniform), cmocka_unit_test(test_counts_single),
        cmocka_unit_test(test_counts_zeros_at_ends), cmocka_unit_test(test_replicate),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
