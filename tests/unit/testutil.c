#include "testutil.h"

#include <stdlib.h>

double tu_norm_cdf(double z)
{
    return 0.5 * erfc(-z / sqrt(2.0));
}

double tu_gamma_p(double k, double x)
{
    double term, sum, lead;
    int n;
    if (!(x > 0.0)) {
        return 0.0;
    }
    lead = exp(k * log(x) - x - lgamma(k + 1.0));
    term = 1.0;
    sum = 1.0;
    for (n = 1; n < 100000; ++n) {
        term *= x / (k + (double)n);
        sum += term;
        if (term < sum * 1e-17) {
            break;
        }
    }
    {
        const double p = lead * sum;
        return p < 1.0 ? p : 1.0;
    }
}

double tu_gamma_upper_quantile(double k, double q)
{
    double a = 0.0, b = 1.0;
    int i;
    while (1.0 - tu_gamma_p(k, b) > q) {
        b *= 2.0;
    }
    for (i = 0; i < 200; ++i) {
        const double m = 0.5 * (a + b);
        if (1.0 - tu_gamma_p(k, m) > q) {
            a = m;
        } else {
            b = m;
        }
    }
    return 0.5 * (a + b);
}

static int cmp_double(const void *pa, const void *pb)
{
    const double a = *(const double *)pa, b = *(const double *)pb;
    return (a > b) - (a < b);
}

void tu_sort(double *x, size_t n)
{
    qsort(x, n, sizeof *x, cmp_double);
}

double tu_ks_one_sample(double *x, size_t n, tu_cdf_fn cdf, const void *ctx, double x_min)
{
    double d = 0.0;
    size_t i, first = n;
    tu_sort(x, n);
    for (i = 0; i < n; ++i) {
        if (x[i] >= x_min) {
            const double f = cdf(x[i], ctx);
            const double hi = (double)(i + 1u) / (double)n - f; /* F_n at x_i vs F */
            const double lo = f - (double)i / (double)n;        /* F_n just below x_i */
            if (first == n) {
                first = i;
            }
            d = hi > d ? hi : d;
            d = lo > d ? lo : d;
        }
    }
    if (x_min > -HUGE_VAL) {
        /* F_n is constant on [x_min, first sample above it) */
        const double dm = fabs((double)first / (double)n - cdf(x_min, ctx));
        d = dm > d ? dm : d;
    }
    return d;
}

double tu_ks_two_sample(double *a, size_t na, double *b, size_t nb)
{
    size_t i = 0, j = 0;
    double d = 0.0;
    tu_sort(a, na);
    tu_sort(b, nb);
    while (i < na && j < nb) {
        const double x = a[i] < b[j] ? a[i] : b[j];
        double diff;
        while (i < na && a[i] <= x) {
            ++i;
        }
        while (j < nb && b[j] <= x) {
            ++j;
        }
        diff = fabs((double)i / (double)na - (double)j / (double)nb);
        d = diff > d ? diff : d;
    }
    return d;
}

double tu_ks_c(double alpha)
{
    return sqrt(-0.5 * log(0.5 * alpha));
}
