/* Helpers shared by the unit tests: exact reference distribution functions
 * written independently of lib/ (so the tests do not check the library
 * against itself), Kolmogorov-Smirnov statistics, float-tolerance helpers.
 * Test framework: cmocka (replaces Unity, see tests/README.md). */
#ifndef HSTPF_TESTUTIL_H
#define HSTPF_TESTUTIL_H

/* cmocka 1.1 needs these before its header */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <float.h>
#include <math.h>

#include "hstpf/hstpf.h"

/* Machine epsilon of the library's arithmetic (float unless the library and
 * the test are built with HSTPF_USE_DOUBLE=1). */
#if defined(HSTPF_USE_DOUBLE) && HSTPF_USE_DOUBLE
#define TU_REAL_EPS DBL_EPSILON
#define TU_REAL_MIN DBL_MIN
#else
#define TU_REAL_EPS ((double)FLT_EPSILON)
#define TU_REAL_MIN ((double)FLT_MIN)
#endif

/* |actual - expected| <= tol, or the test fails with both values. */
#define TU_CLOSE(actual, expected, tol)                                                        \
    do {                                                                                       \
        const double tu_a_ = (double)(actual), tu_e_ = (double)(expected), tu_t_ = (tol);      \
        if (!(fabs(tu_a_ - tu_e_) <= tu_t_)) {                                                 \
            fail_msg("%s = %.10g, expected %.10g +- %.3g (off by %.3g)", #actual, tu_a_, tu_e_, \
                     tu_t_, fabs(tu_a_ - tu_e_));                                              \
        }                                                                                      \
    } while (0)

/* Standard normal CDF from erfc (C99 libm). */
double tu_norm_cdf(double z);

/* Regularised lower incomplete gamma P(k, x) by its power series
 *   P(k, x) = x^k e^-x / Gamma(k + 1) * sum_n x^n / ((k + 1) ... (k + n)),
 * all terms positive (no cancellation), for x >= 0; accurate to ~1e-14
 * absolute for the shapes and ranges the tests use (x <= 200). */
double tu_gamma_p(double k, double x);

/* x with 1 - P(k, x) = q, by bisection (q >= 1e-12). */
double tu_gamma_upper_quantile(double k, double q);

/* A CDF for the KS test: cdf(x, ctx). */
typedef double (*tu_cdf_fn)(double x, const void *ctx);

/* Sorts x[0..n-1] ascending. */
void tu_sort(double *x, size_t n);

/* One-sample KS distance sup_{x >= x_min} |F_n(x) - F(x)| of the sample x
 * (sorted in place). x_min = -HUGE_VAL gives the usual statistic; a finite
 * x_min leaves out values the float arithmetic cannot represent (the lower
 * tail of Gamma(0.02) below 1e-30): the restricted distance is a sup over a
 * subset, so the usual critical value still bounds it. */
double tu_ks_one_sample(double *x, size_t n, tu_cdf_fn cdf, const void *ctx, double x_min);

/* Two-sample KS distance (both sorted in place). */
double tu_ks_two_sample(double *a, size_t na, double *b, size_t nb);

/* Asymptotic KS critical value c(alpha) = sqrt(-ln(alpha / 2) / 2):
 * reject when sqrt(n) D > c(alpha) (one sample) or sqrt(n m / (n + m)) D >
 * c(alpha) (two samples). c(0.001) = 1.9495. */
double tu_ks_c(double alpha);

#endif
