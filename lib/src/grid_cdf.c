/* Grid engine: probabilities and densities of a built distribution over
 * intervals (cells), from the same tables the sampler uses: the CDF from
 * the quantile tables, the density from the log-density table.
 * docs/grid.md, steps 3 and 4. */
#include <math.h>
#include <string.h>

#include "grid.h"

/* ---- CDF of a built distribution, from its quantile tables ----------- */

/* 2^(k-32) for k in [0, 31], exactly, without double arithmetic (soft-float
 * on the M4F) */
static real pow2m32(int k)
{
    return (real)((uint32_t)1u << k) * (real)(1.0 / 4294967296.0);
}

/* Tail probability at x between the nodes of a tail table (nodes at tail
 * probability 2^(k-32)), the inverse of hstpf__dist_tail's interpolation.
 * x is on the tail's side of tab[QSHIFT]; dir = +1 for the lower tail
 * (nodes increase), -1 for the upper. */
static real tail_prob(const real *tab, real x, int dir)
{
    /* the first node j in [1, QSHIFT] beyond x (QSHIFT + 1: none), by a
     * binary search without a branch on the comparison: a kernel's tail taps
     * each scanned up to 24 nodes one by one */
    const real *base = tab + 1;
    int len = HSTPF__QSHIFT, j, k;
    if ((real)dir * (x - tab[0]) < (real)0) {
        return 0;
    }
    while (len > 1) {
        const int half = len / 2;
        base = (real)dir * (x - base[half - 1]) < (real)0 ? base : base + half;
        len -= half;
    }
    j = (int)(base - tab) + ((real)dir * (x - *base) < (real)0 ? 0 : 1);
    if (j > HSTPF__QSHIFT) {
        return pow2m32(HSTPF__QSHIFT);
    }
    k = j - 1;
    {
        const real w = tab[k + 1] - tab[k];
        const real fr = w != (real)0 ? (x - tab[k]) / w : (real)1;
        return pow2m32(k) * ((real)1 + fr);
    }
}

/* P(X <= x) into *lo and P(X > x) into *hi, each computed on its own side
 * so that neither loses the small tail to round-off. Consistent with the
 * sampler: the exact probability at every quantile node, linear between. */
void hstpf__grid_cdf2(const hstpf_dist_quantiles_t *d, real x, real *lo, real *hi)
{
    int a = 1, b = QN - 1;
    real u;
    if (!(x >= d->q[1])) {
        *lo = tail_prob(d->tail_lo, x, 1);
        *hi = (real)1 - *lo;
        return;
    }
    if (x >= d->q[QN - 1]) {
        *hi = tail_prob(d->tail_hi, x, -1);
        *lo = (real)1 - *hi;
        return;
    }
    { /* the last a in [1, QN - 2] with q[a] <= x (q[1] <= x < q[QN - 1]); no
       * branch on the comparison */
        const real *base = d->q + 1;
        int len = QN - 2;
        while (len > 1) {
            const int half = len / 2;
            base = base[half] <= x ? base + half : base;
            len -= half;
        }
        a = (int)(base - d->q);
        b = a + 1;
    }
    u = d->q[b] > d->q[a] ? (x - d->q[a]) / (d->q[b] - d->q[a]) : (real)0;
    *lo = ((real)a + u) / (real)QN;
    *hi = ((real)(QN - a) - u) / (real)QN;
}

/* P(a < X <= b), a <= b. */
real hstpf__grid_prob_in(const hstpf_dist_quantiles_t *d, real a, real b)
{
    real la, ha, lb, hb, p;
    hstpf__grid_cdf2(d, a, &la, &ha);
    hstpf__grid_cdf2(d, b, &lb, &hb);
    p = ha < (real)0.5 ? ha - hb : lb - la;
    return p > (real)0 ? p : (real)0;
}

/* Quantile at probability tail (upper = 0) or 1 - tail: the sampler's own
 * inverse CDF at that point. */
real hstpf__grid_tail_quantile(const hstpf_dist_quantiles_t *d, int upper, real tail)
{
    const uint32_t r = (uint32_t)(tail * (real)4294967296.0);
    return hstpf__dist_sample(d, upper ? ~r : r);
}

/* ---- densities integrated over cells ---------------------------------- */

/* Mean of exp over a segment on which the log-density is linear from l0 to
 * l1 (both <= 0). */
static real mean_exp(real l0, real l1)
{
    const real dl = l1 - l0;
    if (dl > (real)1e-3 || dl < (real)-1e-3) {
        return (hstpf__exp_neg(l1) - hstpf__exp_neg(l0)) / dl;
    }
    return hstpf__exp_neg((real)0.5 * (l0 + l1));
}

/* Integral of exp(logpdf(x) - lp_max) over [a, b], a <= b: the table's own
 * piecewise log-linear density inside its range, midpoints outside it. */
static real dens_int(const hstpf_dist_t *d, real a, real b)
{
    const real top = d->lo + (real)(HSTPF_DIST_LN - 1) * d->dx;
    real sum = 0, t0, t1;
    if (a < d->lo) {
        const real x1 = b < d->lo ? b : d->lo;
        sum += (x1 - a) * hstpf__exp_neg(hstpf__dist_logpdf(d, (real)0.5 * (a + x1)) - d->lp_max);
    }
    if (b > top) {
        const real x0 = a > top ? a : top;
        sum += (b - x0) * hstpf__exp_neg(hstpf__dist_logpdf(d, (real)0.5 * (x0 + b)) - d->lp_max);
    }
    t0 = ((a > d->lo ? a : d->lo) - d->lo) * d->inv_dx;
    t1 = ((b < top ? b : top) - d->lo) * d->inv_dx;
    t1 = t1 < (real)(HSTPF_DIST_LN - 1) ? t1 : (real)(HSTPF_DIST_LN - 1); /* round-off */
    while (t0 < t1) {
        int32_t j = (int32_t)t0;
        real te, l0, l1;
        j = j > HSTPF_DIST_LN - 2 ? HSTPF_DIST_LN - 2 : j;
        te = (real)(j + 1) < t1 ? (real)(j + 1) : t1;
        if (!(te > t0)) {
            break;
        }
        l0 = d->lp[j] + (t0 - (real)j) * (d->lp[j + 1] - d->lp[j]) - d->lp_max;
        l1 = d->lp[j] + (te - (real)j) * (d->lp[j + 1] - d->lp[j]) - d->lp_max;
        sum += (te - t0) * d->dx * mean_exp(l0 > 0 ? 0 : l0, l1 > 0 ? 0 : l1);
        t0 = te;
    }
    return sum;
}

/* Log of the mean density of d over [a, b], a < b (absolute, nats). Where
 * the interval holds a fair share of the probability it is taken from the
 * CDF (the quantile tables: exact at their nodes, which resolve a Gamma's
 * unbounded peak, where the log-density table's first interval holds only
 * an average); in the tails from the log-density table, whose relative
 * accuracy holds where a CDF difference would cancel. -3e38 for zero. */
real hstpf__grid_cell_loglik(const hstpf_dist_t *d, real a, real b)
{
    const real pm = hstpf__grid_prob_in(&d->qt, a, b);
    real dens;
    if (pm > (real)1e-5) {
        return hstpf__log_pos(pm / (b - a));
    }
    dens = dens_int(d, a, b) / (b - a);
    return dens > (real)0 ? d->lp_max + hstpf__log_pos(dens) : (real)-3e38;
}
