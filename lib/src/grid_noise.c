/* Grid engine: the process noise as kernels of cell masses and their
 * convolution with the transported cells (step 3 of docs/grid.md). */
#include <math.h>
#include <string.h>

#include "grid.h"

/* Kernel of the noise scale * X on cells of width h: k[m - m0] = P(noise in
 * cell m) / P(noise within its tail quantiles), for the offsets m in
 * [m0, m0 + n) that lie within +-reach cells (farther ones cannot land on
 * the grid: their mass leaves it). Returns n >= 1; *m0 its first offset. */
/* The nearest cell offset to x cells, held within +-2^30: a noise spread
 * over more cells than that (a tiny cell, a huge scale) must not overflow
 * the cast; its kernel is clipped to the reach below anyway. 0 for a NaN
 * (a cell width gone non-finite, which the bank then resets; the cast of
 * a NaN is undefined: the fuzz harness) */
static int cell_index(real x)
{
    const double c = floor((double)(x + (real)0.5));
    if (!(c == c)) {
        return 0;
    }
    return c > 1073741824.0 ? 1073741824 : (c < -1073741824.0 ? -1073741824 : (int)c);
}

int hstpf__grid_kernel(const hstpf_dist_quantiles_t *d, real scale, real h, int reach, real tail, real *k, int *m0)
{
    const real lo = scale * hstpf__grid_tail_quantile(d, 0, tail) / h;
    const real hi = scale * hstpf__grid_tail_quantile(d, 1, tail) / h;
    const int cap = (HSTPF__GRID_K - 1) / 2;
    int a = cell_index(lo), b = cell_index(hi), m, n;
    real sum = 0, total, el, eh;
    reach = reach < cap ? reach : cap;
    total = scale > (real)0 ? hstpf__grid_prob_in(d, ((real)a - (real)0.5) * h / scale, ((real)b + (real)0.5) * h / scale)
                            : (real)0;
    a = a < -reach ? -reach : (a > reach ? reach : a);
    b = b > reach ? reach : (b < -reach ? -reach : b);
    n = b - a + 1;
    if (scale > (real)0) { /* each edge's CDF once: tap m's upper edge is tap m + 1's lower */
        hstpf__grid_cdf2(d, ((real)a - (real)0.5) * h / scale, &el, &eh);
        for (m = 0; m < n; ++m) {
            real ul, uh, p;
            hstpf__grid_cdf2(d, ((real)(a + m) + (real)0.5) * h / scale, &ul, &uh);
            p = eh < (real)0.5 ? eh - uh : ul - el; /* as hstpf__grid_prob_in */
            k[m] = p > (real)0 ? p : (real)0;
            sum += k[m];
            el = ul;
            eh = uh;
        }
    } else {
        for (m = 0; m < n; ++m) {
            k[m] = 0;
        }
    }
    if (!(sum > (real)0) || !(total > (real)0)) { /* no spread at this scale: a point mass at offset 0 */
        const int z = a > 0 ? 0 : (b < 0 ? n - 1 : -a);
        for (m = 0; m < n; ++m) {
            k[m] = m == z ? (real)1 : (real)0;
        }
        total = 1;
    }
    for (m = 0; m < n; ++m) {
        k[m] /= total;
    }
    *m0 = a;
    return n;
}

/* Position noise on one row, in place: o[i] = sum_k ks[k] x[i - m0s - k]
 * with x the row padded with zeros (pad: scratch of NS + nks - 1 values,
 * pad[t + m0s + nks - 1] = x[t], zeroed by the caller: every row writes the
 * same cells of it). The padding's terms add exact zeros, so
 * each sum is that of the taps that reach, in the same order, and the loop
 * over a whole row vectorises. */
static void conv_row(real *restrict o, real *restrict pad, const real *ks, int nks, int m0s)
{
    const int off = m0s + nks - 1;
    real acc[NS]; /* the row in registers across the taps */
    int i, k;
    for (i = 0; i < NS; ++i) { /* pad is zero outside these cells */
        if (i + off >= 0 && i + off < NS + nks - 1) {
            pad[i + off] = o[i];
        }
        acc[i] = 0;
    }
    for (k = 0; k < nks; ++k) {
        hstpf__grid_axpy_row(acc, pad + (nks - 1) - k, ks[k]);
    }
    memcpy(o, acc, sizeof acc);
}

/* Rows r0..r1 of p from the rows b0..b1 of w (the others hold no mass):
 * p row j = sum_k k[k] w row (j - m0 - k), the taps in order, each row
 * kept in a local array across the taps. */
static void speed_conv(real *p, const real *w, const real *k, int nk, int m0, int b0, int b1, int r0, int r1)
{
    int j, t, i;
    for (j = r0; j <= r1; ++j) {
        /* the taps whose source row lies in b0..b1 */
        const int t0 = j - m0 - b1 > 0 ? j - m0 - b1 : 0;
        const int t1 = j - m0 - b0 < nk - 1 ? j - m0 - b0 : nk - 1;
        real acc[NS];
        for (i = 0; i < NS; ++i) {
            acc[i] = 0;
        }
        for (t = t0; t <= t1; ++t) {
            const real c = k[t];
            if (c > (real)0) {
                hstpf__grid_axpy_row(acc, w + (j - m0 - t) * NS, c);
            }
        }
        memcpy(p + j * NS, acc, sizeof acc);
    }
}

/* The hypothesis' grid: its speeds spread by N(0, theta_sd^2) too (theta's
 * uncertainty, refine.c), and every grid's while the traction is unknown
 * (its acceleration's sd, bank.c), through work; what would go below or
 * above the box is dropped (it scores as mass the prediction lost): near
 * rest that is a speed cut at 0 and renormalised, not piled at 0, which
 * publishes 0.1-0.2 m/s more at a stop in a traction gap (a review's
 * measure; well within its sd). */
static void theta_spread(hstpf_t *f, real *p, const real *ng)
{
    int m0;
    const int nk = hstpf__grid_kernel(&f->unit, f->grid.theta_sd, ng[3], NV - 1, f->grid.tail, f->grid.kv, &m0);
    if (nk == 1 && m0 == 0) {
        return;
    }
    memcpy(f->grid.work, p, sizeof(real) * (size_t)(NS * NV));
    speed_conv(p, f->grid.work, f->grid.kv, nk, m0, 0, NV - 1, 0, NV - 1);
}

/* Step 3: speed noise from work into p (what it would take below 0 goes to
 * rest: a train never reverses), then position noise in place, also on the
 * mass that came to rest within the step; the held mass gets none. Only
 * the rows that can receive mass are computed, each as a whole row. */
void hstpf__grid_diffuse(hstpf_t *f, uint16_t l, real scale, const real *ng)
{
    real *p = f->grid.p[l], *w = f->grid.work, *kv = f->grid.kv, *ks = f->grid.ks;
    real *rest = f->grid.rest[l], *rpend = f->grid.rpend;
    int16_t *box = f->grid.box;
    int m0v, m0s, nkv, nks, j, k, i, r0 = 0, r1 = -1, c0 = 0, c1 = -1;
    nkv = hstpf__grid_kernel(&f->dv, scale, ng[3], NV - 1, f->grid.tail, kv, &m0v);
    nks = hstpf__grid_kernel(&f->ds, scale, ng[1], NS - 1, f->grid.tail, ks, &m0s);
    if (box[1] >= box[0]) {
        r0 = box[0] + m0v;
        r1 = box[1] + m0v + nkv - 1;
        r0 = r0 < 0 ? 0 : r0;
        r1 = r1 > NV - 1 ? NV - 1 : r1;
        c0 = box[2];
        c1 = box[3];
        speed_conv(p, w, kv, nkv, m0v, box[0], box[1], r0, r1);
        if (ng[2] <= (real)0) { /* the box starts at 0: what falls below is at rest */
            for (j = box[0]; j <= box[1]; ++j) {
                const real *r = w + j * NS;
                real c = 0;
                for (k = 0; k < nkv && j + m0v + k < 0; ++k) {
                    c += kv[k];
                }
                if (c > (real)0) {
                    for (i = c0; i <= c1; ++i) {
                        rpend[i] += c * r[i];
                    }
                }
            }
        }
    }
    if (r1 < r0) { /* no row receives mass */
        r0 = NV;
        r1 = NV - 1;
    }
    memset(p, 0, sizeof(real) * (size_t)(r0 * NS)); /* the rows below and above those computed */
    memset(p + (r1 + 1) * NS, 0, sizeof(real) * (size_t)((NV - 1 - r1) * NS));
    if (!(nks == 1 && m0s == 0)) { /* work is free now: the padded rows */
        memset(w, 0, sizeof(real) * (size_t)(NS + nks - 1));
        for (j = r0; j <= r1; ++j) {
            conv_row(p + j * NS, w, ks, nks, m0s);
        }
        conv_row(rpend, w, ks, nks, m0s);
    }
    if (f->grid.theta_sd > (real)0) {
        theta_spread(f, p, ng);
    }
    for (i = 0; i < NS; ++i) {
        rest[i] = f->grid.rnew[i] + rpend[i];
    }
}

#define SPREAD_REACH 4.5 /* sd of a step's spread the widened box reaches each side */

void hstpf__grid_spread(hstpf_t *f, uint16_t k, double var)
{
    real *g = f->grid.geom[k], *p = f->grid.p[k], *w = f->grid.work, *sh = f->grid.row, *rest = f->grid.rest[k];
    real *rw = f->grid.rnew; /* free outside a step, as work is */
    const double sd = sqrt(var), ds = ((double)NS * (double)g[1] + 2.0 * SPREAD_REACH * sd) / (double)NS;
    /* the kernel's own variance: the cells' masses at their centres gain
     * ds^2 / 12 from the kernel's cells and ds^2 / 12 from the moments'
     * uniform cells, and lose the old cells' ds_old^2 / 12, so that the
     * moments' variance grows by var */
    const double kv = var - ds * ds / 6.0 + (double)g[1] * (double)g[1] / 12.0;
    const real ks = (real)sqrt(kv > 0.25 * var ? kv : 0.25 * var);
    /* the new cells: the old box widened by SPREAD_REACH sd each side,
     * centred on it */
    const real s0 = g[0] + (real)0.5 * (real)NS * (g[1] - (real)ds);
    int i, c, j;
    if (!(sd > 0.0 && g[1] > (real)0 && ds - ds == 0.0 && s0 - s0 == (real)0)) {
        return;
    }
    memset(w, 0, sizeof(real) * NS * NV);
    memset(rw, 0, sizeof f->grid.rnew);
    for (c = 0; c < NS; ++c) {
        /* sh[i]: the share of old cell c, taken at its centre, that the
         * kernel moves into new cell i; they sum to 1, so the mass stays */
        const real x = g[0] + ((real)c + (real)0.5) * g[1];
        real el, eh, sum = 0;
        hstpf__grid_cdf2(&f->unit, (s0 - x) / ks, &el, &eh);
        for (i = 0; i < NS; ++i) {
            real ul, uh, q;
            hstpf__grid_cdf2(&f->unit, (s0 + (real)(i + 1) * (real)ds - x) / ks, &ul, &uh);
            q = eh < (real)0.5 ? eh - uh : ul - el; /* as hstpf__grid_prob_in */
            sh[i] = q > (real)0 ? q : (real)0;
            sum += sh[i];
            el = ul;
            eh = uh;
        }
        for (i = 0; i < NS; ++i) {
            sh[i] = sum > (real)0 ? sh[i] / sum : (real)(i == NS / 2);
        }
        for (j = 0; j < NV; ++j) {
            if (p[j * NS + c] > (real)0) {
                hstpf__grid_axpy_row(w + j * NS, sh, p[j * NS + c]);
            }
        }
        if (rest[c] > (real)0) {
            hstpf__grid_axpy_row(rw, sh, rest[c]);
        }
    }
    memcpy(p, w, sizeof(real) * NS * NV);
    memcpy(rest, rw, sizeof f->grid.rnew);
    g[0] = s0;
    g[1] = (real)ds;
}
