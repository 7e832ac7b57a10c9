/* Inline table look-ups for the hot loop; dist.c exposes them as functions. */
#ifndef HSTPF_DIST_IMPL_H
#define HSTPF_DIST_IMPL_H

#include <string.h>

#include "hstpf/dist.h"

#define HSTPF__QSHIFT (32 - HSTPF_DIST_QBITS)
#define HSTPF__EXP_N 512

#define HSTPF__LOG_N 256
#define HSTPF__DIST_FLOOR_DEPTH 30.0 /* nats below the peak, unless the spec says */
#define HSTPF__GAMMA_TOP_TAIL 1e-9   /* the Gamma's log-density grid ends at this tail */

/* dist.c, for dist_blur.c (init time, double): the quantile of a spec
 * (upper: from the right tail), and the range checks of a spread. */
double hstpf__dist_quantile(const hstpf_dist_spec_t *sp, double mass, double prob, int upper);
int hstpf__dist_finite(double x);
int hstpf__dist_spread_ok(double spread, double offset);
/* 2^(-j/512), j = 0..512 */
extern const hstpf_real_t hstpf__exp2_tab[HSTPF__EXP_N + 1];
/* log2(1 + j/256), j = 0..256 */
extern const hstpf_real_t hstpf__log2_tab[HSTPF__LOG_N + 1];

static inline int hstpf__log2u(uint32_t m) /* m > 0 */
{
#if defined(__GNUC__) || defined(__clang__)
    return 31 - __builtin_clz(m);
#else
    int k = 0;
    while (m >>= 1) {
        ++k;
    }
    return k;
#endif
}

/* Tail bin: t in [0, 2^QSHIFT) maps to tail probability (t + 1) / 2^32,
 * interpolated between nodes at powers of two. */
static inline hstpf_real_t hstpf__dist_tail(const hstpf_real_t *tab, uint32_t t)
{
    const uint32_t m = t + 1u;
    const int k = hstpf__log2u(m);
    const uint32_t base = 1u << k;
    hstpf_real_t frac;
    if (k >= HSTPF__QSHIFT) {
        return tab[HSTPF__QSHIFT];
    }
    frac = (hstpf_real_t)(m - base) / (hstpf_real_t)base;
    return tab[k] + frac * (tab[k + 1] - tab[k]);
}

/* The width between the tail nodes k, F^-1(1 - 2^(k - 32)) - F^-1(2^(k - 32)):
 * how far two draws lie apart but rarely (the lock's and the step rule's
 * ranges). */
static inline double hstpf__dist_range(const hstpf_dist_quantiles_t *d, int k)
{
    return (double)d->tail_hi[k] - (double)d->tail_lo[k];
}

static inline hstpf_real_t hstpf__dist_sample(const hstpf_dist_quantiles_t *d, uint32_t r)
{
    const uint32_t b = r >> HSTPF__QSHIFT;
    hstpf_real_t f;
    if (b == 0u) {
        return hstpf__dist_tail(d->tail_lo, r);
    }
    if (b == HSTPF_DIST_QN - 1u) {
        return hstpf__dist_tail(d->tail_hi, ~r);
    }
    f = (hstpf_real_t)(r & ((1u << HSTPF__QSHIFT) - 1u)) *
        (hstpf_real_t)(1.0 / (double)(1u << HSTPF__QSHIFT));
    return d->q[b] + f * (d->q[b + 1u] - d->q[b]);
}

static inline hstpf_real_t hstpf__dist_logpdf(const hstpf_dist_t *d, hstpf_real_t x)
{
    const hstpf_real_t t = (x - d->lo) * d->inv_dx;
    hstpf_real_t dd, v, edge;
    int side;
    if (t >= (hstpf_real_t)0 && t < (hstpf_real_t)(HSTPF_DIST_LN - 1)) {
        const int32_t j = (int32_t)t;
        const hstpf_real_t f = t - (hstpf_real_t)j;
        return d->lp[j] + f * (d->lp[j + 1] - d->lp[j]);
    }
    if (t < (hstpf_real_t)0) {
        side = 0;
        dd = -t * d->dx;
        edge = d->lp[0];
    } else if (t >= (hstpf_real_t)(HSTPF_DIST_LN - 1)) {
        side = 1;
        dd = (t - (hstpf_real_t)(HSTPF_DIST_LN - 1)) * d->dx;
        edge = d->lp[HSTPF_DIST_LN - 1];
    } else {
        return d->floor; /* NaN */
    }
    /* beyond this the value is astronomically low anyway: cap the distance
     * so that the quadratic cannot overflow to -inf */
    dd = dd < d->dd_max ? dd : d->dd_max;
    {
        /* beyond the grid the floor slopes: finite, yet never flat, so a
         * cloud that lost the measurement is still pulled back to it */
        const hstpf_real_t fl = d->floor - dd * d->floor_slope;
        if (d->hard[side] && d->tail_c[side] == (hstpf_real_t)0) {
            return fl;
        }
        v = edge + dd * (d->tail_b[side] + d->tail_c[side] * dd);
        return v > fl ? v : fl;
    }
}

/* exp(x), x <= 0: 2^-(n+f) with f from the table, 2^-n built in the exponent. */
static inline hstpf_real_t hstpf__exp_neg(hstpf_real_t x)
{
    hstpf_real_t t, g, v;
    int32_t n, j;
    if (!(x < (hstpf_real_t)0)) {
        return x >= (hstpf_real_t)0 ? (hstpf_real_t)1 : (hstpf_real_t)0;
    }
    if (x < (hstpf_real_t)-100) {
        return (hstpf_real_t)0;
    }
    /* Cody-Waite: n ln2 is subtracted in two parts (ln2_hi has 12 bits, so
     * n * ln2_hi is exact) and the remainder keeps full precision */
    n = (int32_t)(-x * (hstpf_real_t)1.4426950408889634);
    t = ((-x - (hstpf_real_t)n * (hstpf_real_t)0.693145751953125) -
         (hstpf_real_t)n * (hstpf_real_t)1.4286067653302e-06) *
        (hstpf_real_t)1.4426950408889634;
    if (t < (hstpf_real_t)0) {
        t += (hstpf_real_t)1;
        --n;
    } else if (t >= (hstpf_real_t)1) {
        t -= (hstpf_real_t)1;
        ++n;
    }
    g = t * (hstpf_real_t)HSTPF__EXP_N;
    j = (int32_t)g;
    g -= (hstpf_real_t)j;
    v = hstpf__exp2_tab[j] + g * (hstpf__exp2_tab[j + 1] - hstpf__exp2_tab[j]);
#if defined(HSTPF_USE_DOUBLE) && HSTPF_USE_DOUBLE
    {
        const uint64_t bits = (uint64_t)(1023 - n) << 52;
        double p;
        memcpy(&p, &bits, sizeof p);
        return v * p;
    }
#else
    if (n > 126) { /* n >= 0: x < 0 and t >= 0 when n is 0 */
        return 0.0f;
    }
    {
        const uint32_t bits = (uint32_t)(127 - n) << 23;
        float p;
        memcpy(&p, &bits, sizeof p);
        return v * p;
    }
#endif
}

/* log(x) for x > 0 (normal numbers): exponent from the bits, log2 of the
 * mantissa from the table; absolute error below 2e-6. x <= 0 gives -1e30. */
static inline hstpf_real_t hstpf__log_pos(hstpf_real_t x)
{
    hstpf_real_t m, t;
    int32_t e, j;
    if (!(x > (hstpf_real_t)0)) {
        return (hstpf_real_t)-1e30;
    }
#if defined(HSTPF_USE_DOUBLE) && HSTPF_USE_DOUBLE
    {
        uint64_t b;
        memcpy(&b, &x, sizeof b);
        e = (int32_t)((b >> 52) & 0x7FFu) - 1023;
        b = (b & 0x000FFFFFFFFFFFFFull) | 0x3FF0000000000000ull;
        memcpy(&m, &b, sizeof m);
    }
#else
    {
        uint32_t b;
        memcpy(&b, &x, sizeof b);
        e = (int32_t)((b >> 23) & 0xFFu) - 127;
        b = (b & 0x007FFFFFu) | 0x3F800000u;
        memcpy(&m, &b, sizeof m);
    }
#endif
    t = (m - (hstpf_real_t)1) * (hstpf_real_t)HSTPF__LOG_N; /* [0, 256) */
    j = (int32_t)t;
    t -= (hstpf_real_t)j;
    return ((hstpf_real_t)e + hstpf__log2_tab[j] + t * (hstpf__log2_tab[j + 1] - hstpf__log2_tab[j])) *
           (hstpf_real_t)0.69314718055994531;
}

/* Replaces the log-density of a built Gamma distribution by that of the
 * variate plus N(0, sd), sd a spread (HSTPF_DIST_SPREAD_MIN..MAX); the
 * sampling tables are kept. A blur below 1/4088 of the grid's span (the
 * Gamma's 1 - 1e-9 quantile) is widened to it: it could not show between
 * two nodes. Init-time cost bounded whatever scale / sd: per node at most
 * 256 + 289 exp/pow (see docs/quality.md for the measured worst case).
 * HSTPF_E_DIST for any other kind or an invalid spec. */
int32_t hstpf__dist_blur(hstpf_dist_t *d, const hstpf_dist_spec_t *spec, double sd);

/* Validates a specification without building it (used by hstpf_init). */
int32_t hstpf__dist_check(const hstpf_dist_spec_t *spec);

#endif
