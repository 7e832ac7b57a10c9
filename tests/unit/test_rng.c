/* RNG: xoshiro128** and splitmix64 against reference outputs of the
 * published algorithms; seeding, streams, uniform variates, errors. */
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

/* xoshiro128** 1.1 (Blackman & Vigna, 2018, xoshiro128starstar.c) from the
 * state {1, 2, 3, 4}. result = rotl(s[1] * 5, 7) * 9, then the state update
 *   t = s1 << 9; s2 ^= s0; s3 ^= s1; s1 ^= s2; s0 ^= s3; s2 ^= t; s3 = rotl(s3, 11).
 * By hand:
 *   1st: s1 = 2: 2*5 = 10, rotl(10, 7) = 1280, *9 = 11520.
 *        update: t = 1024; s2 = 3^1 = 2; s3 = 4^2 = 6; s1 = 2^2 = 0;
 *        s0 = 1^6 = 7; s2 = 2^1024 = 1026; s3 = rotl(6, 11) = 12288.
 *   2nd: s1 = 0 -> 0.
 *        update: t = 0; s2 = 1026^7 = 1029; s3 = 12288^0 = 12288; s1 = 0^1029 = 1029;
 *        s0 = 7^12288 = 12295; s2 = 1029; s3 = rotl(12288, 11) = 25165824.
 *   3rd: s1 = 1029: 1029*5 = 5145, rotl(5145, 7) = 658560, *9 = 5927040.
 * All ten values: the reference vector of the Rust crate rand_xoshiro,
 * "These values were produced with the reference implementation (v1.1):
 * http://xoshiro.di.unimi.it/xoshiro128starstar.c" (rust-random/rngs,
 * rand_xoshiro/src/xoshiro128starstar.rs, test `reference`). */
static void test_xoshiro_reference(void **state)
{
    static const uint32_t expected[10] = {11520u,      0u,          5927040u,    70819200u,
                                          2031721883u, 1637235492u, 1287239034u, 3734860849u,
                                          3729100597u, 4258142804u};
    const uint32_t s0[4] = {1u, 2u, 3u, 4u};
    hstpf_rng_t r;
    int i;
    (void)state;
    assert_int_equal(hstpf_rng_set_state(&r, s0), HSTPF_OK);
    for (i = 0; i < 10; ++i) {
        assert_int_equal(hstpf_rng_next(&r), expected[i]);
    }
}

/* splitmix64 (Vigna, splitmix64.c). Seed 0: 0xe220a8397b1dcdaf,
 * 0x6e789e6aa1b965f4, 0x06c45d188009454f, 0xf88bb8a8724c81ec (the published
 * test vector, reproduced in many independent test suites). Seed
 * 1477776061723855037: rand_xoshiro's reference vector "produced with the
 * reference implementation: http://xoshiro.di.unimi.it/splitmix64.c"
 * (rust-random/rngs, rand_xoshiro/src/splitmix64.rs, test `reference`,
 * first ten of fifty). The state is a Weyl sequence: + 0x9E3779B97F4A7C15
 * per call. */
static void test_splitmix64_reference(void **state)
{
    static const uint64_t seed0[4] = {UINT64_C(0xe220a8397b1dcdaf), UINT64_C(0x6e789e6aa1b965f4),
                                      UINT64_C(0x06c45d188009454f), UINT64_C(0xf88bb8a8724c81ec)};
    static const uint64_t rand_ref[10] = {
        UINT64_C(1985237415132408290),  UINT64_C(2979275885539914483),
        UINT64_C(13511426838097143398), UINT64_C(8488337342461049707),
        UINT64_C(15141737807933549159), UINT64_C(17093170987380407015),
        UINT64_C(16389528042912955399), UINT64_C(13177319091862933652),
        UINT64_C(10841969400225389492), UINT64_C(17094824097954834098)};
    uint64_t st = 0;
    int i;
    (void)state;
    for (i = 0; i < 4; ++i) {
        assert_true(hstpf_splitmix64(&st) == seed0[i]);
        assert_true(st == (uint64_t)(i + 1) * UINT64_C(0x9E3779B97F4A7C15));
    }
    st = UINT64_C(1477776061723855037);
    for (i = 0; i < 10; ++i) {
        assert_true(hstpf_splitmix64(&st) == rand_ref[i]);
    }
}

/* rng.h: stream k of seed is the (2k)-th and (2k+1)-th splitmix64 outputs,
 * low word first. For seed 0, stream 0 and 1 come from the published
 * vector above. */
static void test_seed_layout(void **state)
{
    hstpf_rng_t r;
    uint64_t st;
    uint32_t k;
    (void)state;
    assert_int_equal(hstpf_rng_seed(&r, 0, 0), HSTPF_OK);
    assert_true(r.s[0] == 0x7b1dcdafu && r.s[1] == 0xe220a839u);
    assert_true(r.s[2] == 0xa1b965f4u && r.s[3] == 0x6e789e6au);
    assert_int_equal(hstpf_rng_seed(&r, 0, 1), HSTPF_OK);
    assert_true(r.s[0] == 0x8009454fu && r.s[1] == 0x06c45d18u);
    assert_true(r.s[2] == 0x724c81ecu && r.s[3] == 0xf88bb8a8u);
    /* any seed and stream: by the documented rule */
    for (k = 0; k < 20; ++k) {
        uint64_t a, b, j;
        const uint64_t seed = UINT64_C(0x123456789abcdef) * (k + 1u);
        st = seed;
        for (j = 0; j < 2u * k; ++j) {
            (void)hstpf_splitmix64(&st);
        }
        a = hstpf_splitmix64(&st);
        b = hstpf_splitmix64(&st);
        assert_int_equal(hstpf_rng_seed(&r, seed, k), HSTPF_OK);
        assert_true(r.s[0] == (uint32_t)a && r.s[1] == (uint32_t)(a >> 32));
        assert_true(r.s[2] == (uint32_t)b && r.s[3] == (uint32_t)(b >> 32));
    }
}

/* Same seed and stream: same sequence; other streams and seeds differ, and
 * two streams are uncorrelated (|r| < 4.5 / sqrt(n): 4.5 sd of the sample
 * correlation of independent variables, over 17 x 16 / 2 = 136 pairs, a
 * false alarm has probability below 136 x 7e-6 = 1e-3). */
static void test_streams(void **state)
{
    enum { N = 20000, NS = 17 };
    static double u[NS][N];
    hstpf_rng_t a, b;
    uint32_t s, t;
    int i;
    (void)state;
    for (s = 0; s < NS; ++s) {
        assert_int_equal(hstpf_rng_seed(&a, 42, s), HSTPF_OK);
        assert_int_equal(hstpf_rng_seed(&b, 42, s), HSTPF_OK);
        for (i = 0; i < 1000; ++i) {
            assert_true(hstpf_rng_next(&a) == hstpf_rng_next(&b));
        }
        assert_int_equal(hstpf_rng_seed(&a, 42, s), HSTPF_OK);
        for (i = 0; i < N; ++i) {
            u[s][i] = (double)hstpf_rng_uniform(&a) - 0.5;
        }
    }
    for (s = 0; s < NS; ++s) {
        for (t = s + 1u; t < NS; ++t) {
            double sab = 0, saa = 0, sbb = 0, r;
            int same = 0;
            for (i = 0; i < N; ++i) {
                sab += u[s][i] * u[t][i];
                saa += u[s][i] * u[s][i];
                sbb += u[t][i] * u[t][i];
                same += u[s][i] == u[t][i];
            }
            r = sab / sqrt(saa * sbb);
            if (!(fabs(r) < 4.5 / sqrt((double)N))) {
                fail_msg("streams %u and %u correlated: r = %g", s, t, r);
            }
            assert_true(same < N / 100);
        }
    }
    /* other seeds, same stream: different sequences */
    assert_int_equal(hstpf_rng_seed(&a, 1, 0), HSTPF_OK);
    assert_int_equal(hstpf_rng_seed(&b, 2, 0), HSTPF_OK);
    {
        int same = 0;
        for (i = 0; i < 1000; ++i) {
            same += hstpf_rng_next(&a) == hstpf_rng_next(&b);
        }
        assert_true(same < 10);
    }
}

static uint32_t inv_odd(uint32_t a) /* multiplicative inverse mod 2^32 */
{
    uint32_t x = a; /* correct to 3 bits; Newton doubles the bits */
    int i;
    for (i = 0; i < 5; ++i) {
        x *= 2u - a * x;
    }
    return x;
}

static uint32_t rotr(uint32_t x, int k)
{
    return (x >> k) | (x << (32 - k));
}

/* uniform = (next >> 8) / 2^24: in [0, 1), exactly the top 24 bits. The
 * extremes are forced by choosing s[1] so that the output is 0 or
 * 0xFFFFFFFF: s1 = rotr(out * 9^-1, 7) * 5^-1. KS against U(0,1) at
 * alpha = 0.001 for three seeds, tolerance c(0.001)/sqrt(n). */
static void test_uniform(void **state)
{
    enum { N = 200000 };
    static double x[N];
    hstpf_rng_t r, twin;
    uint64_t seed;
    int i;
    (void)state;
    {
        const uint32_t s1 = rotr(0xFFFFFFFFu * inv_odd(9u), 7) * inv_odd(5u);
        const uint32_t st[4] = {1u, s1, 0u, 0u};
        const uint32_t st0[4] = {1u, 0u, 0u, 0u};
        assert_int_equal(hstpf_rng_set_state(&r, st), HSTPF_OK);
        twin = r;
        assert_true(hstpf_rng_next(&twin) == 0xFFFFFFFFu);
        TU_CLOSE(hstpf_rng_uniform(&r), 16777215.0 / 16777216.0, 0.0);
        assert_true(hstpf_rng_uniform(&r) < 1.0f); /* whatever comes next */
        assert_int_equal(hstpf_rng_set_state(&r, st0), HSTPF_OK);
        TU_CLOSE(hstpf_rng_uniform(&r), 0.0, 0.0);
    }
    for (seed = 1; seed <= 3; ++seed) {
        double mean = 0.0, d;
        assert_int_equal(hstpf_rng_seed(&r, seed, 0), HSTPF_OK);
        twin = r;
        for (i = 0; i < N; ++i) {
            const double u = (double)hstpf_rng_uniform(&r);
            assert_true(u >= 0.0 && u < 1.0);
            TU_CLOSE(u, (double)(hstpf_rng_next(&twin) >> 8) / 16777216.0, 0.0);
            x[i] = u;
            mean += u;
        }
        mean /= N;
        /* mean of U(0,1): 1/2 +- 3.29 sqrt(1/12/N) (alpha = 0.001) */
        TU_CLOSE(mean, 0.5, 3.29 * sqrt(1.0 / 12.0 / N));
        tu_sort(x, N);
        d = 0.0;
        for (i = 0; i < N; ++i) {
            const double a = (double)(i + 1) / N - x[i], b = x[i] - (double)i / N;
            d = a > d ? a : d;
            d = b > d ? b : d;
        }
        assert_true(d < tu_ks_c(0.001) / sqrt((double)N));
    }
}

static void test_errors(void **state)
{
    const uint32_t zero[4] = {0u, 0u, 0u, 0u};
    const uint32_t one[4] = {0u, 0u, 0u, 1u};
    hstpf_rng_t r, copy;
    (void)state;
    assert_int_equal(hstpf_rng_seed(NULL, 1, 0), HSTPF_E_NULL);
    assert_int_equal(hstpf_rng_seed(&r, 7, 3), HSTPF_OK);
    copy = r;
    assert_int_equal(hstpf_rng_set_state(NULL, one), HSTPF_E_NULL);
    assert_int_equal(hstpf_rng_set_state(&r, NULL), HSTPF_E_NULL);
    assert_memory_equal(&r, &copy, sizeof r);
    assert_int_equal(hstpf_rng_set_state(&r, zero), HSTPF_E_RANGE);
    assert_memory_equal(&r, &copy, sizeof r);
    /* a single non-zero word is enough */
    assert_int_equal(hstpf_rng_set_state(&r, one), HSTPF_OK);
    assert_true(r.s[3] == 1u && r.s[0] == 0u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_xoshiro_reference), cmocka_unit_test(test_splitmix64_reference),
        cmocka_unit_test(test_seed_layout),       cmocka_unit_test(test_streams),
        cmocka_unit_test(test_uniform),           cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
