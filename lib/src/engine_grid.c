/* Grid engine: a deterministic point-mass filter per model (Bucy & Senne;
 * Simandl, Kralovec & Soderstrom). The density of (s, v) lives on
 * HSTPF_GRID_NS x HSTPF_GRID_NV uniform cells that are placed again every
 * step around the predicted support. One step:
 *   1. the new grid is the box between the GRID_TAIL quantiles of the
 *      predicted marginals (the posterior's cells moved by the dynamics,
 *      convolved with the noise): asymmetric where the noise is; a step
 *      whose every cell misses the measurement is done again with
 *      WIDE_TAIL, so a truncated tail is told apart from a misfit;
 *   2. every cell is transported by the dynamics (positions by T v, speeds
 *      through v + T a(v) with the no-reversal clamp) and its mass is
 *      shared among the new cells it overlaps (conservative remap);
 *   3. the process noise is convolved in, speed then position, with
 *      kernels of cell masses taken from the noise's CDF (any density);
 *   4. each position cell is weighted by the measurement density
 *      integrated over the cell (exact for one-sided and unbounded
 *      densities), with the library's floor; the sum is the model's
 *      likelihood increment.
 * No RNG, no heap: the memory is hstpf_t.grid. docs/grid.md. */
#include <math.h>
#include <string.h>

#include "dist_impl.h"
#include "engine.h"
#include "internal.h"
#include "track.h"

typedef hstpf_real_t real;

#define NS HSTPF_GRID_NS
#define NV HSTPF_GRID_NV
#define QN ((int)HSTPF_DIST_QN)
#define GRID_TAIL ((real)1e-5)  /* mass a box leaves out on each side */
#define WIDE_TAIL ((real)1e-9)  /* the same when a step is retried */
#define PULL_SD 2.0            /* measurement beyond this many sd: keep that tail */
#define KERN_TAIL ((real)1e-7)  /* extent of the noise kernels and the prior */
#define DS_MIN ((real)1e-3)     /* narrowest cell, m: float positions near 1 km */
#define DV_MIN ((real)1e-4)     /* narrowest cell, m/s */
#define MASS_MIN ((real)1e-30)  /* a cell below this is empty */

/* ---- CDF of a built distribution, from its quantile tables ----------- */

/* 2^(k-32) for k in [0, 32] */
static real pow2m32(int k)
{
    return (real)ldexp(1.0, k - 32);
}

/* Tail probability at x between the nodes of a tail table (nodes at tail
 * probability 2^(k-32)), the inverse of hstpf__dist_tail's interpolation.
 * x is on the tail's side of tab[QSHIFT]; dir = +1 for the lower tail
 * (nodes increase), -1 for the upper. */
static real tail_prob(const real *tab, real x, int dir)
{
    int k;
    if ((real)dir * (x - tab[0]) < (real)0) {
        return 0;
    }
    for (k = 0; k < HSTPF__QSHIFT; ++k) {
        if ((real)dir * (x - tab[k + 1]) < (real)0) {
            const real w = tab[k + 1] - tab[k];
            const real fr = w != (real)0 ? (x - tab[k]) / w : (real)1;
            return pow2m32(k) * ((real)1 + fr);
        }
    }
    return pow2m32(HSTPF__QSHIFT);
}

/* P(X <= x) into *lo and P(X > x) into *hi, each computed on its own side
 * so that neither loses the small tail to round-off. Consistent with the
 * sampler: the exact probability at every quantile node, linear between. */
static void cdf2(const hstpf_dist_t *d, real x, real *lo, real *hi)
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
    while (b - a > 1) { /* q[a] <= x < q[b] */
        const int c = (a + b) / 2;
        if (x >= d->q[c]) {
            a = c;
        } else {
            b = c;
        }
    }
    u = d->q[b] > d->q[a] ? (x - d->q[a]) / (d->q[b] - d->q[a]) : (real)0;
    *lo = ((real)a + u) / (real)QN;
    *hi = ((real)(QN - a) - u) / (real)QN;
}

/* P(a < X <= b), a <= b. */
static real prob_in(const hstpf_dist_t *d, real a, real b)
{
    real la, ha, lb, hb, p;
    cdf2(d, a, &la, &ha);
    cdf2(d, b, &lb, &hb);
    p = ha < (real)0.5 ? ha - hb : lb - la;
    return p > (real)0 ? p : (real)0;
}

/* Quantile at probability KERN_TAIL (upper = 0) or 1 - KERN_TAIL: the
 * sampler's own inverse CDF at that point. */
static real tail_quantile(const hstpf_dist_t *d, int upper)
{
    const uint32_t r = (uint32_t)(KERN_TAIL * (real)4294967296.0);
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
static real cell_loglik(const hstpf_dist_t *d, real a, real b)
{
    const real pm = prob_in(d, a, b);
    real dens;
    if (pm > (real)1e-5) {
        return hstpf__log_pos(pm / (b - a));
    }
    dens = dens_int(d, a, b) / (b - a);
    return dens > (real)0 ? d->lp_max + hstpf__log_pos(dens) : (real)-3e38;
}

/* ---- grid pieces ------------------------------------------------------ */

static real *geom(hstpf_t *f, uint16_t l)
{
    return f->grid.geom[l];
}

/* The deterministic speed after one step (below 0: the train comes to
 * rest within the step; the caller moves that mass to rest). */
static real speed_map(const hstpf_model_t *m, real v, real dt, real acc)
{
    return v + dt * (acc - m->k0 - (m->k1 + m->k2 * v) * v);
}

/* Conservative remap: input cell i covers [a + i w, a + (i + 1) w] in units
 * of output cells; its mass goes to the output cells it overlaps, in
 * proportion. Mass beyond the output is dropped. */
static void remap(const real *in, int i0, int i1, real a, real w, real *out, int n_out)
{
    const real inv = (real)1 / w;
    int i;
    for (i = i0; i <= i1; ++i) {
        const real x0 = a + (real)i * w, x1 = x0 + w, m = in[i];
        int k;
        if (m <= MASS_MIN || x1 <= (real)0 || x0 >= (real)n_out) {
            continue;
        }
        k = (int32_t)x0;
        k -= (real)k > x0 ? 1 : 0; /* floor */
        if (x1 <= (real)(k + 1)) { /* inside one output cell */
            out[k] += m;
        } else if (w <= (real)1 || x1 <= (real)(k + 2)) { /* across one edge */
            const real fr = ((real)(k + 1) - x0) * inv;
            if (k >= 0) {
                out[k] += m * fr;
            }
            if (k + 1 < n_out) {
                out[k + 1] += m - m * fr;
            }
        } else {
            for (k = k > 0 ? k : 0; k < n_out && (real)k < x1; ++k) {
                const real lo = x0 > (real)k ? x0 : (real)k;
                const real hi = x1 < (real)(k + 1) ? x1 : (real)(k + 1);
                if (hi > lo) {
                    out[k] += m * (hi - lo) * inv;
                }
            }
        }
    }
}

/* Kernel of the noise scale * X on cells of width h: k[m - m0] = P(noise in
 * cell m) / P(noise within the KERN_TAIL quantiles), for the offsets m in
 * [m0, m0 + n) that lie within +-reach cells (farther ones cannot land on
 * the grid: their mass leaves it). Returns n >= 1; *m0 its first offset. */
static int kernel(const hstpf_dist_t *d, real scale, real h, int reach, real *k, int *m0)
{
    const real lo = scale * tail_quantile(d, 0) / h, hi = scale * tail_quantile(d, 1) / h;
    const int cap = (HSTPF__GRID_K - 1) / 2;
    int a = (int32_t)floor((double)(lo + (real)0.5)), b = (int32_t)floor((double)(hi + (real)0.5)), m, n;
    real sum = 0, total;
    reach = reach < cap ? reach : cap;
    total = scale > (real)0 ? prob_in(d, ((real)a - (real)0.5) * h / scale, ((real)b + (real)0.5) * h / scale)
                            : (real)0;
    a = a < -reach ? -reach : (a > reach ? reach : a);
    b = b > reach ? reach : (b < -reach ? -reach : b);
    n = b - a + 1;
    for (m = 0; m < n; ++m) {
        const real c = (real)(a + m);
        k[m] = scale > (real)0 ? prob_in(d, (c - (real)0.5) * h / scale, (c + (real)0.5) * h / scale) : (real)0;
        sum += k[m];
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

/* Marginals of a model's cells into ms (with the mass at rest) and mv
 * (moving rows); returns the total mass. */
static real marginals(hstpf_t *f, const real *p, const real *rest)
{
    real tot = 0;
    int i, j;
    for (i = 0; i < NS; ++i) {
        f->grid.ms[i] = rest[i]; /* the position marginal includes the mass at rest */
        tot += rest[i];
    }
    for (j = 0; j < NV; ++j) {
        const real *r = p + j * NS;
        real rs = 0;
        for (i = 0; i < NS; ++i) {
            rs += r[i];
            f->grid.ms[i] += r[i];
        }
        f->grid.mv[j] = rs;
        tot += rs;
    }
    return tot;
}

/* Mean, variance (with the cells' own width) and effective cell count. */
static void moments(hstpf_t *f, hstpf_model_t *m, uint16_t l)
{
    const real *p = f->grid.p[l], *g = geom(f, l), *rest = f->grid.rest[l];
    double s1 = 0.0, s2 = 0.0, v1 = 0.0, v2 = 0.0, q2 = 0.0, moving = 0.0;
    int i, j;
    (void)marginals(f, p, rest);
    for (i = 0; i < NS; ++i) {
        const double x = (double)g[0] + ((double)i + 0.5) * (double)g[1], w = (double)f->grid.ms[i];
        s1 += w * x;
        s2 += w * x * x;
    }
    for (j = 0; j < NV; ++j) {
        const double x = (double)g[2] + ((double)j + 0.5) * (double)g[3], w = (double)f->grid.mv[j];
        v1 += w * x;
        v2 += w * x * x;
        moving += w;
    }
    for (i = 0; i < NS * NV; ++i) {
        q2 += (double)p[i] * (double)p[i];
    }
    for (i = 0; i < NS; ++i) {
        q2 += (double)rest[i] * (double)rest[i];
    }
    m->s_mean = (real)s1;
    m->v_mean = (real)v1;
    /* variances with each cell's own width (uniform within the cell) */
    m->s_var = (real)fmax(s2 - s1 * s1 + (double)g[1] * (double)g[1] / 12.0, 0.0);
    m->v_var = (real)fmax(v2 - v1 * v1 + moving * (double)g[3] * (double)g[3] / 12.0, 0.0);
    m->ess = (real)(q2 > 0.0 ? 1.0 / q2 : 0.0);
}

/* ---- placement -------------------------------------------------------- */

/* A model from the acquisition fixes. Position: s = y2 - e2, cell masses
 * from e's CDF. Speed, one fix (t12 = 0): N(v0, init_speed_sd) (a point
 * when the sd is 0). Two fixes t12 apart: by the model's Euler step from
 * s1 = y1 - e1, v = (s - y1 + e1 - mu_s)/t12 + t12 a + mu_v, so a speed
 * cell [w_j, w_j+1] at position s_i holds the probability of e1 in
 * [t12 (w_j - c) - s_i + y1 + mu_s, ...], c = t12 a + mu_v (a at the
 * two fixes' mean speed; the process noise over t12 is left out of the
 * spread, as in the other engines). Speeds below 0 are at rest. */
static void place_one(hstpf_t *f, hstpf_model_t *m, const hstpf__acq_t *q)
{
    const uint16_t l = (uint16_t)(m - f->m);
    const hstpf_config_t *c = &f->cfg;
    real *p = f->grid.p[l], *g = geom(f, l), *rest = f->grid.rest[l];
    const real y2 = (real)q->y2, y1 = (real)q->y1, t = (real)q->t12;
    const real el = tail_quantile(&f->de, 0), eh = tail_quantile(&f->de, 1);
    real s_lo = y2 - eh, s_hi = y2 - el, v_lo, v_hi, tot = 0, cs = 0, mus = 0, sdv = 0;
    const real v0 = (real)q->v0;
    int i, j;
    if (t > (real)0) {
        const real sc = (real)sqrt(q->t12 / c->dt_nominal_s);
        const real vm = (real)((q->y2 - q->y1) / q->t12), vp = vm > (real)0 ? vm : (real)0;
        mus = sc * (real)c->noise_s.mean;
        cs = t * ((real)q->xu - m->k0 - (m->k1 + m->k2 * vp) * vp) + sc * (real)c->noise_v.mean;
        v_lo = (s_lo - y1 + el - mus) / t + cs;
        v_hi = (s_hi - y1 + eh - mus) / t + cs;
    } else {
        sdv = (real)c->init_speed_sd;
        v_lo = v0 + sdv * tail_quantile(&f->unit, 0);
        v_hi = v0 + sdv * tail_quantile(&f->unit, 1);
    }
    v_lo = v_lo > (real)0 ? v_lo : (real)0;
    v_hi = v_hi > v_lo ? v_hi : v_lo;
    if (s_hi - s_lo < DS_MIN * (real)NS) {
        s_lo = (real)0.5 * (s_lo + s_hi) - (real)0.5 * DS_MIN * (real)NS;
        s_hi = s_lo + DS_MIN * (real)NS;
    }
    if (v_hi - v_lo < DV_MIN * (real)NV) {
        v_lo = (real)0.5 * (v_lo + v_hi) - (real)0.5 * DV_MIN * (real)NV;
        v_lo = v_lo > (real)0 ? v_lo : (real)0;
        v_hi = v_lo + DV_MIN * (real)NV;
    }
    g[0] = s_lo;
    g[1] = (s_hi - s_lo) / (real)NS;
    g[2] = v_lo;
    g[3] = (v_hi - v_lo) / (real)NV;
    for (i = 0; i < NS; ++i) { /* e2 in [y2 - right edge, y2 - left edge] */
        const real x0 = g[0] + (real)i * g[1], sc_i = x0 + (real)0.5 * g[1];
        const real ps = prob_in(&f->de, y2 - (x0 + g[1]), y2 - x0);
        real below;
        for (j = 0; j < NV; ++j) {
            const real w0 = g[2] + (real)j * g[3], w1 = w0 + g[3];
            real pv;
            if (t > (real)0) {
                pv = prob_in(&f->de, t * (w0 - cs) - sc_i + y1 + mus, t * (w1 - cs) - sc_i + y1 + mus);
            } else if (sdv > (real)0) {
                pv = prob_in(&f->unit, (w0 - v0) / sdv, (w1 - v0) / sdv);
            } else {
                pv = (real)(v0 >= w0 && (v0 < w1 || j == NV - 1));
            }
            p[j * NS + i] = ps * pv;
            tot += p[j * NS + i];
        }
        /* speeds below the box's 0 edge: at rest */
        if (g[2] > (real)0) {
            below = 0;
        } else if (t > (real)0) {
            below = prob_in(&f->de, (real)-3e38, t * (-cs) - sc_i + y1 + mus);
        } else if (sdv > (real)0) {
            below = prob_in(&f->unit, (real)-3e38, -v0 / sdv);
        } else {
            below = (real)(v0 < (real)0);
        }
        rest[i] = ps * below;
        tot += rest[i];
    }
    if (!(tot > (real)0)) { /* a prior narrower than a cell: all in the middle */
        p[(NV / 2) * NS + NS / 2] = 1;
        tot = 1;
    }
    for (i = 0; i < NS * NV; ++i) {
        p[i] /= tot;
    }
    for (i = 0; i < NS; ++i) {
        rest[i] /= tot;
    }
    f->grid.pred_mass[l] = 1;
    m->loglik = 0;
    m->held = 0;
    moments(f, m, l);
}

static void place_all(hstpf_t *f, const hstpf__acq_t *q)
{
    uint16_t l;
    for (l = 0; l < f->cfg.n_models; ++l) {
        place_one(f, &f->m[l], q);
    }
}

/* ---- one step of one model --------------------------------------------- */

/* Bins of a histogram on [x0, x1] at spacing at least h0, so that at most
 * nmax bins and a noise of range r fits the kernel capacity. */
static real bin_width(real x0, real x1, real h0, real r, int nmax)
{
    real h = h0;
    const real hb = (x1 - x0) / (real)(nmax - 2), hk = r / (real)(HSTPF__GRID_K - 4);
    h = hb > h ? hb : h;
    return hk > h ? hk : h;
}

/* The cut_lo and 1 - cut_hi quantiles of a histogram (bins of width h from x0, n bins)
 * convolved with the noise scale * X: the support of a predicted marginal. */
static void noisy_quantiles(const real *hist, int n, real x0, real h, const hstpf_dist_t *d, real scale, real cut_lo,
                            real cut_hi, real *k, real *lo, real *hi)
{
    int m0, nk, b, kk;
    real c = 0;
    nk = kernel(d, scale, h, HSTPF__GRID_K, k, &m0);
    /* output bin b (0 .. n + nk - 2) holds sum_kk k[kk] hist[b - kk] and
     * covers x0 + (b + m0) h .. + h */
    for (b = 0; b < n + nk - 1; ++b) {
        real o = 0;
        for (kk = 0; kk < nk; ++kk) {
            o += (b - kk >= 0 && b - kk < n) ? k[kk] * hist[b - kk] : (real)0;
        }
        c += o;
        if (c > cut_lo) {
            break;
        }
    }
    *lo = x0 + (real)(b + m0) * h;
    c = 0;
    for (b = n + nk - 2; b >= 0; --b) {
        real o = 0;
        for (kk = 0; kk < nk; ++kk) {
            o += (b - kk >= 0 && b - kk < n) ? k[kk] * hist[b - kk] : (real)0;
        }
        c += o;
        if (c > cut_hi) {
            break;
        }
    }
    *hi = x0 + (real)(b + m0 + 1) * h;
    if (*hi <= *lo) {
        *hi = *lo + h;
    }
}

/* With a measurement, the position box only needs to hold the posterior:
 * the predicted position marginal (hist convolved with the noise) times the
 * measurement density over each bin, cut at GRID_TAIL per side. Predicted
 * mass left outside then carries at most 2 GRID_TAIL of the likelihood, so
 * the increment changes by less than 3e-5 nats, while the cells shrink to
 * the posterior's width (Case 2: centimetres inside a metre-wide
 * prediction, whose width is the Gamma(0.02) noise's rare long jumps).
 * Nothing changes when the measurement misses the prediction (the retry
 * and the reach to the measurement handle that). */
static void posterior_box(hstpf_t *f, const real *hist, int n, real x0, real h, real scale, real yr, real *s_lo,
                          real *s_hi)
{
    real *out = f->grid.work + NS * NV / 2, *k = f->grid.ks;
    const real lfloor = hstpf__exp_neg(f->de.floor - f->de.lp_max);
    real sum = 0, cut, c;
    int m0, nk, b, kk, nb, bl, bh;
    nk = kernel(&f->ds, scale, h, HSTPF__GRID_K, k, &m0);
    nb = n + nk - 1;
    for (b = 0; b < nb; ++b) { /* bin b covers x0 + (b + m0) h .. + h */
        const real x = x0 + (real)(b + m0) * h;
        real o = 0, lik;
        for (kk = 0; kk < nk; ++kk) {
            o += (b - kk >= 0 && b - kk < n) ? k[kk] * hist[b - kk] : (real)0;
        }
        lik = o > (real)0 ? cell_loglik(&f->de, yr - (x + h), yr - x) - f->de.lp_max : (real)-3e38;
        lik = lik > (real)-80 ? hstpf__exp_neg(lik < (real)0 ? lik : (real)0) : (real)0;
        out[b] = lik > lfloor ? o * lik : (real)0;
        sum += out[b];
    }
    if (!(sum > (real)0)) {
        return;
    }
    cut = GRID_TAIL * sum;
    for (bl = 0, c = 0; bl < nb - 1 && c + out[bl] <= cut; ++bl) {
        c += out[bl];
    }
    for (bh = nb - 1, c = 0; bh > bl && c + out[bh] <= cut; --bh) {
        c += out[bh];
    }
    *s_lo = x0 + (real)(bl + m0) * h;
    *s_hi = x0 + (real)(bh + m0 + 1) * h;
}

/* The box of the predicted density: the f->grid.tail quantiles of its two
 * marginals, from the occupied cells (f->grid.first/last, vimg) moved by the
 * dynamics and convolved with the noise. On entry *s_lo.. hold the bounding
 * box of the moved cells. Uses f->grid.work as scratch. Quantiles, not mean
 * +- k sd: a one-sided noise's spike stays inside. */
static void predicted_box(hstpf_t *f, uint16_t l, real dt, real scale, real tot, int has_y, real yr, real mid,
                          real rest_v, real *s_lo, real *s_hi, real *v_lo, real *v_hi)
{
    const real *p = f->grid.p[l], *g = f->grid.geom[l], *rest = f->grid.rest[l];
    const int nmax = NS * NV / 4;
    real *hist = f->grid.work;
    const real rs = scale * (tail_quantile(&f->ds, 1) - tail_quantile(&f->ds, 0));
    const real rv = scale * (tail_quantile(&f->dv, 1) - tail_quantile(&f->dv, 0));
    real h, x0;
    int n, j, b, pull = 0;
    /* positions: each occupied row shifted by T times its centre speed */
    x0 = *s_lo;
    h = bin_width(*s_lo, *s_hi, g[1], rs, nmax);
    {
        const real nn = (*s_hi - *s_lo) / h; /* NaN-safe: never more than nmax bins */
        n = nn >= (real)0 && nn < (real)(nmax - 2) ? (int)nn + 2 : nmax;
    }
    memset(hist, 0, (size_t)n * sizeof *hist);
    for (j = 0; j < NV; ++j) {
        const real sh = dt * (g[2] + ((real)j + (real)0.5) * g[3]);
        if (f->grid.first[j] <= f->grid.last[j]) {
            remap(p + j * NS, f->grid.first[j], f->grid.last[j], (g[0] + sh - x0) / h, g[1] / h, hist, n);
        }
    }
    remap(rest, 0, NS - 1, (g[0] - x0) / h, g[1] / h, hist, n); /* at rest: no shift */
    {
        /* the side the measurement lies on keeps its tail to WIDE_TAIL: a
         * model the measurements pull away from its prediction has its
         * posterior there (cutting it would bias every misfit model) */
        real cut_lo = f->grid.tail * tot, cut_hi = cut_lo;
        if (has_y) {
            double m1 = 0.0, m2 = 0.0, sd;
            for (b = 0; b < n; ++b) {
                const double x = (double)x0 + ((double)b + 0.5) * (double)h;
                m1 += (double)hist[b] * x;
                m2 += (double)hist[b] * x * x;
            }
            m1 /= (double)tot;
            sd = sqrt(fmax(m2 / (double)tot - m1 * m1, 0.0) + (double)(scale * f->ds.sd) * (double)(scale * f->ds.sd));
            m1 += (double)(scale * f->ds.mean);
            if ((double)mid > m1 + PULL_SD * sd) {
                cut_hi = WIDE_TAIL * tot;
                pull = 1;
            } else if ((double)mid < m1 - PULL_SD * sd) {
                cut_lo = WIDE_TAIL * tot;
                pull = -1;
            }
        }
        noisy_quantiles(hist, n, x0, h, &f->ds, scale, cut_lo, cut_hi, f->grid.ks, s_lo, s_hi);
        if (has_y && f->grid.tail > WIDE_TAIL) {
            posterior_box(f, hist, n, x0, h, scale, yr, s_lo, s_hi);
        }
    }
    /* speeds: each occupied row spread over its image [vimg_j, vimg_j+1] */
    x0 = *v_lo;
    h = bin_width(*v_lo, *v_hi, g[3], rv, nmax);
    {
        const real nn = (*v_hi - *v_lo) / h;
        n = nn >= (real)0 && nn < (real)(nmax - 2) ? (int)nn + 2 : nmax;
    }
    memset(hist, 0, (size_t)n * sizeof *hist);
    for (j = 0; j < NV; ++j) {
        real ta, tb, rm = 0;
        int i;
        if (f->grid.first[j] > f->grid.last[j]) {
            continue;
        }
        for (i = f->grid.first[j]; i <= f->grid.last[j]; ++i) {
            rm += p[j * NS + i];
        }
        ta = ((f->grid.vimg[j] > (real)0 ? f->grid.vimg[j] : (real)0) - x0) / h;
        tb = ((f->grid.vimg[j + 1] > (real)0 ? f->grid.vimg[j + 1] : (real)0) - x0) / h;
        if (ta > tb) {
            const real t = ta;
            ta = tb;
            tb = t;
        }
        if (tb - ta < (real)1e-6) {
            b = ta > (real)0 ? (int32_t)ta : 0;
            hist[b < n ? b : n - 1] += rm;
            continue;
        }
        remap(&rm, 0, 0, ta, tb - ta, hist, n);
    }
    if (rest_v >= (real)0) { /* the mass at rest starts moving */
        real rm = 0;
        for (j = 0; j < NS; ++j) {
            rm += rest[j];
        }
        b = (int32_t)((rest_v - x0) / h);
        b = b < 0 ? 0 : (b > n - 1 ? n - 1 : b);
        hist[b] += rm;
    }
    /* the pull moves the speed the same way (through the s-v correlation) */
    noisy_quantiles(hist, n, x0, h, &f->dv, scale, (pull < 0 ? WIDE_TAIL : f->grid.tail) * tot,
                    (pull > 0 ? WIDE_TAIL : f->grid.tail) * tot, f->grid.kv, v_lo, v_hi);
}

/* Steps 1-2: the new box from the transported support plus the noise
 * quantiles, and the cells transported into f->grid.work. A cell is
 * occupied when it holds more than KERN_TAIL / cells of the mass, so that
 * at most KERN_TAIL is left behind; the box is the bounding box of the
 * occupied cells after the dynamics (each row moved by T times its centre
 * speed), so a correlated posterior does not inflate it. */
static real transport(hstpf_t *f, hstpf_model_t *m, uint16_t l, real dt, real acc, real scale, int has_y, real yr,
                      real *ng)
{
    const real *p = f->grid.p[l], *g = geom(f, l), *rest = f->grid.rest[l];
    real *w = f->grid.work, *vimg = f->grid.vimg, *row = f->grid.row;
    int16_t *first = f->grid.first, *last = f->grid.last, *box = f->grid.box;
    real tot = 0, rtot = 0, thr, held = 0, s_lo = (real)3e38, s_hi = (real)-3e38, v_lo = (real)3e38,
         v_hi = (real)-3e38;
    const real mid = yr - hstpf__dist_sample(&f->de, 0x80000000u); /* y less e's median */
    const real a0 = acc - m->k0;                                   /* net acceleration at rest */
    const real rest_v = a0 > (real)0 ? dt * a0 : (real)-1;         /* < 0: the rest mass is held */
    int i, j, any = 0;
    for (i = 0; i < NS * NV; ++i) {
        tot += p[i];
    }
    for (i = 0; i < NS; ++i) {
        rtot += rest[i];
    }
    tot += rtot;
    thr = KERN_TAIL * tot / (real)(NS * NV);
    for (j = 0; j < NV; ++j) {
        const real *r = p + j * NS, sh = dt * (g[2] + ((real)j + (real)0.5) * g[3]);
        int a = 0, b = NS - 1;
        while (a <= b && r[a] <= thr) {
            ++a;
        }
        while (b >= a && r[b] <= thr) {
            --b;
        }
        first[j] = (int16_t)a;
        last[j] = (int16_t)b;
        if (a > b) {
            continue;
        }
        any = 1;
        vimg[j] = speed_map(m, g[2] + (real)j * g[3], dt, acc);
        vimg[j + 1] = speed_map(m, g[2] + (real)(j + 1) * g[3], dt, acc);
        s_lo = g[0] + (real)a * g[1] + sh < s_lo ? g[0] + (real)a * g[1] + sh : s_lo;
        s_hi = g[0] + (real)(b + 1) * g[1] + sh > s_hi ? g[0] + (real)(b + 1) * g[1] + sh : s_hi;
        for (i = j; i <= j + 1; ++i) {
            const real vi = vimg[i] > (real)0 ? vimg[i] : (real)0; /* never below 0 */
            v_lo = vi < v_lo ? vi : v_lo;
            v_hi = vi > v_hi ? vi : v_hi;
        }
    }
    if (rtot > thr) { /* the mass at rest: no shift; it starts at rest_v if it moves */
        int a = 0, b = NS - 1;
        while (a < b && rest[a] <= thr) {
            ++a;
        }
        while (b > a && rest[b] <= thr) {
            --b;
        }
        s_lo = g[0] + (real)a * g[1] < s_lo ? g[0] + (real)a * g[1] : s_lo;
        s_hi = g[0] + (real)(b + 1) * g[1] > s_hi ? g[0] + (real)(b + 1) * g[1] : s_hi;
        v_lo = rest_v > (real)0 && rest_v < v_lo ? rest_v : (v_lo < (real)3e38 ? v_lo : (real)0);
        v_hi = rest_v > v_hi ? rest_v : (v_hi > (real)-3e38 ? v_hi : (real)0);
        any = 1;
    }
    if (!any) { /* cannot happen (normalised mass); keep the old box */
        s_lo = g[0];
        s_hi = g[0] + (real)NS * g[1];
        v_lo = g[2];
        v_hi = g[2] + (real)NV * g[3];
    } else {
        predicted_box(f, l, dt, scale, tot, has_y, yr, mid, rtot > (real)0 ? rest_v : (real)-1, &s_lo, &s_hi, &v_lo,
                      &v_hi);
    }
    if (has_y) {
        /* a measurement whose middle lies beyond the predicted box pulls
         * the posterior out of it: the box reaches to the measurement's
         * 1 %..99 % range, or the model could never catch up */
        if (mid < s_lo || mid > s_hi) {
            const real e_hi = hstpf__dist_sample(&f->de, 0xFD70A3D7u), e_lo = hstpf__dist_sample(&f->de, 0x028F5C29u);
            s_lo = yr - e_hi < s_lo ? yr - e_hi : s_lo;
            s_hi = yr - e_lo > s_hi ? yr - e_lo : s_hi;
        }
    }
    v_lo = v_lo > (real)0 ? v_lo : (real)0; /* a train never reverses: the box starts at 0 at most */
    if (s_hi - s_lo < DS_MIN * (real)NS) {
        s_lo = (real)0.5 * (s_lo + s_hi) - (real)0.5 * DS_MIN * (real)NS;
        s_hi = s_lo + DS_MIN * (real)NS;
    }
    if (v_hi - v_lo < DV_MIN * (real)NV) {
        v_lo = (real)0.5 * (v_lo + v_hi) - (real)0.5 * DV_MIN * (real)NV;
        v_lo = v_lo > (real)0 ? v_lo : (real)0;
        v_hi = v_lo + DV_MIN * (real)NV;
    }
    ng[0] = s_lo;
    ng[1] = (s_hi - s_lo) / (real)NS;
    ng[2] = v_lo;
    ng[3] = (v_hi - v_lo) / (real)NV;
    memset(w, 0, sizeof f->grid.work);
    memset(f->grid.rnew, 0, sizeof f->grid.rnew);
    memset(f->grid.rpend, 0, sizeof f->grid.rpend);
    box[0] = NV; /* rows, then columns, of work that receive mass */
    box[1] = -1;
    box[2] = NS;
    box[3] = -1;
    for (j = 0; j < NV; ++j) {
        real lo_v, hi_v, f0 = 0, rm = 0, ta, tb;
        const real a = (g[0] + dt * (g[2] + ((real)j + (real)0.5) * g[3]) - ng[0]) / ng[1];
        int k, c0, c1;
        if (first[j] > last[j]) {
            continue;
        }
        lo_v = vimg[j] < vimg[j + 1] ? vimg[j] : vimg[j + 1];
        hi_v = vimg[j] < vimg[j + 1] ? vimg[j + 1] : vimg[j];
        if (hi_v <= (real)0) { /* the whole row comes to rest within the step */
            f0 = 1;
        } else if (lo_v < (real)0) {
            f0 = -lo_v / (hi_v - lo_v);
            lo_v = 0;
        }
        /* columns this row reaches */
        c0 = (int)(a + (real)first[j] * g[1] / ng[1]);
        c1 = (int)(a + (real)(last[j] + 1) * g[1] / ng[1]);
        c0 = c0 < 0 ? 0 : (c0 > NS - 1 ? NS - 1 : c0);
        c1 = c1 < 0 ? 0 : (c1 > NS - 1 ? NS - 1 : c1);
        for (i = c0; i <= c1; ++i) {
            row[i] = 0;
        }
        remap(p + j * NS, first[j], last[j], a, g[1] / ng[1], row, NS);
        if (f0 > (real)0) { /* s' = s + T v, v' = 0: to rest, position noise to come */
            for (i = c0; i <= c1; ++i) {
                f->grid.rpend[i] += f0 * row[i];
                rm += row[i];
            }
            held += f0 * rm;
            if (f0 >= (real)1) {
                continue;
            }
        }
        box[2] = (int16_t)(c0 < box[2] ? c0 : box[2]);
        box[3] = (int16_t)(c1 > box[3] ? c1 : box[3]);
        ta = (lo_v - ng[2]) / ng[3];
        tb = (hi_v - ng[2]) / ng[3];
        if (tb - ta < (real)1e-6) { /* the whole row maps to one speed */
            ta = tb = ta < (real)0 ? (real)0 : (ta > (real)(NV - 1) ? (real)(NV - 1) : ta);
        }
        for (k = ta > (real)0 ? (int32_t)ta : 0; k < NV && (k == (int32_t)ta || (real)k < tb); ++k) {
            const real lo = ta > (real)k ? ta : (real)k, hi = tb < (real)(k + 1) ? tb : (real)(k + 1);
            const real frac = (tb > ta ? (hi - lo) / (tb - ta) : (real)1) * ((real)1 - f0);
            real *o = w + k * NS;
            if (frac > (real)0) {
                for (i = c0; i <= c1; ++i) {
                    o[i] += frac * row[i];
                }
                box[0] = (int16_t)(k < box[0] ? k : box[0]);
                box[1] = (int16_t)(k > box[1] ? k : box[1]);
            }
        }
    }
    if (rtot > (real)0) { /* the mass at rest, on the new position cells */
        memset(row, 0, sizeof f->grid.row);
        remap(rest, 0, NS - 1, (g[0] - ng[0]) / ng[1], g[1] / ng[1], row, NS);
        if (rest_v < (real)0) { /* held: s' = s, v' = 0, no process noise */
            for (i = 0; i < NS; ++i) {
                f->grid.rnew[i] += row[i];
            }
            held += rtot;
        } else { /* starts moving: v' = T a0 + noise */
            int k = (int32_t)((rest_v - ng[2]) / ng[3]);
            k = k < 0 ? 0 : (k > NV - 1 ? NV - 1 : k);
            for (i = 0; i < NS; ++i) {
                w[k * NS + i] += row[i];
            }
            box[0] = (int16_t)(k < box[0] ? k : box[0]);
            box[1] = (int16_t)(k > box[1] ? k : box[1]);
            box[2] = 0;
            box[3] = NS - 1;
        }
    }
    return tot > (real)0 ? held / tot : (real)0;
}

/* Step 3: speed noise from work into p, then position noise in place; only
 * the rows and columns that can receive mass are visited. */
/* Position noise on one row, in place over [c0, c1] -> [o0, o1]. */
static void conv_row(real *o, real *row, int c0, int c1, const real *ks, int nks, int m0s)
{
    const int o0 = c0 + m0s < 0 ? 0 : c0 + m0s, o1 = c1 + m0s + nks - 1 > NS - 1 ? NS - 1 : c1 + m0s + nks - 1;
    int i, k;
    for (i = c0; i <= c1; ++i) {
        row[i] = o[i];
        o[i] = 0;
    }
    for (i = o0; i <= o1; ++i) { /* gather: cell i from i - m0s - k */
        const int ka = i - m0s - c1 > 0 ? i - m0s - c1 : 0;
        const int kb = i - m0s - c0 < nks - 1 ? i - m0s - c0 : nks - 1;
        const real *src = row + (i - m0s);
        real acc = 0;
        for (k = ka; k <= kb; ++k) {
            acc += ks[k] * src[-k];
        }
        o[i] = acc;
    }
}

/* Step 3: speed noise from work into p (what it would take below 0 goes to
 * rest: a train never reverses), then position noise in place, also on the
 * mass that came to rest within the step; the held mass gets none. Only
 * the rows and columns that can receive mass are visited. */
static void diffuse(hstpf_t *f, uint16_t l, real scale, const real *ng)
{
    real *p = f->grid.p[l], *w = f->grid.work, *row = f->grid.row, *kv = f->grid.kv, *ks = f->grid.ks;
    real *rest = f->grid.rest[l], *rpend = f->grid.rpend;
    int16_t *box = f->grid.box;
    int m0v, m0s, nkv, nks, j, k, i, r0 = 0, r1 = -1, c0 = 0, c1 = -1;
    nkv = kernel(&f->dv, scale, ng[3], NV - 1, kv, &m0v);
    nks = kernel(&f->ds, scale, ng[1], NS - 1, ks, &m0s);
    memset(p, 0, sizeof f->grid.p[l]);
    if (box[1] >= box[0]) {
        r0 = box[0] + m0v;
        r1 = box[1] + m0v + nkv - 1;
        r0 = r0 < 0 ? 0 : r0;
        r1 = r1 > NV - 1 ? NV - 1 : r1;
        c0 = box[2];
        c1 = box[3];
        for (j = r0; j <= r1; ++j) { /* p row j = sum_k kv[k] w row (j - m0v - k) */
            real *o = p + j * NS;
            for (k = 0; k < nkv; ++k) {
                const int src = j - m0v - k;
                const real c = kv[k];
                const real *r;
                if (src < box[0] || src > box[1] || c <= (real)0) {
                    continue;
                }
                r = w + src * NS;
                for (i = c0; i <= c1; ++i) {
                    o[i] += c * r[i];
                }
            }
        }
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
    if (!(nks == 1 && m0s == 0)) {
        for (j = r0; j <= r1; ++j) {
            conv_row(p + j * NS, row, c0, c1, ks, nks, m0s);
        }
        conv_row(rpend, row, 0, NS - 1, ks, nks, m0s);
    }
    for (i = 0; i < NS; ++i) {
        rest[i] = f->grid.rnew[i] + rpend[i];
    }
}

/* Step 4: the measurement update; returns the log-likelihood increment. */
static real measure(hstpf_t *f, hstpf_model_t *m, uint16_t l, real yr)
{
    const hstpf_dist_t *de = &f->de;
    real *p = f->grid.p[l], *g = geom(f, l), *ll = f->grid.row;
    real lmax = (real)-3e38, sum = 0, inv;
    int i, j, all_floor = 1;
    (void)marginals(f, p, f->grid.rest[l]);
    for (i = 0; i < NS; ++i) {
        const real x0 = g[0] + (real)i * g[1];
        const real lc = cell_loglik(de, yr - (x0 + g[1]), yr - x0);
        const real fl = hstpf__dist_logpdf(de, yr - (x0 + (real)0.5 * g[1]));
        real li = (fl < de->floor ? fl : de->floor);
        li = lc > li ? lc : li;
        ll[i] = li;
        if (f->grid.ms[i] > MASS_MIN) {
            lmax = li > lmax ? li : lmax;
            all_floor = all_floor && li <= de->floor;
        }
    }
    if (all_floor) {
        ++m->floor_hits;
        ++m->floor_run;
    } else {
        m->floor_run = 0;
    }
    for (i = 0; i < NS; ++i) {
        ll[i] = hstpf__exp_neg(ll[i] - lmax);
    }
    for (j = 0; j < NV; ++j) {
        real *r = p + j * NS;
        for (i = 0; i < NS; ++i) {
            r[i] *= ll[i];
            sum += r[i];
        }
    }
    for (i = 0; i < NS; ++i) {
        f->grid.rest[l][i] *= ll[i];
        sum += f->grid.rest[l][i];
    }
    if (!(sum > (real)0)) { /* every cell underflowed: keep the prediction */
        return lmax;
    }
    inv = (real)1 / sum;
    for (i = 0; i < NS * NV; ++i) {
        p[i] *= inv;
    }
    for (i = 0; i < NS; ++i) {
        f->grid.rest[l][i] *= inv;
    }
    return lmax + (real)log((double)sum);
}

static real mass_of(const hstpf_t *f, uint16_t l)
{
    real t = 0;
    int i;
    for (i = 0; i < NS * NV; ++i) {
        t += f->grid.p[l][i];
    }
    for (i = 0; i < NS; ++i) {
        t += f->grid.rest[l][i];
    }
    return t;
}

/* Predict (and measure) one model with the box tail f->grid.tail. */
static void model_pass(hstpf_t *f, hstpf_model_t *m, const hstpf__step_t *st, real acc)
{
    const uint16_t l = (uint16_t)(m - f->m);
    const real dt = (real)st->dt, scale = (real)st->scale;
    real ng[4], tot, held;
    real *p = f->grid.p[l], *g = geom(f, l);
    int i;
    held = transport(f, m, l, dt, acc, scale, st->has_y, (real)st->yr, ng);
    diffuse(f, l, scale, ng);
    g[0] = ng[0];
    g[1] = ng[1];
    g[2] = ng[2];
    g[3] = ng[3];
    /* the whole posterior at rest: held, or come to rest within the step */
    m->held = (uint8_t)(held >= (real)(1.0 - 1e-6));
    tot = mass_of(f, l);
    f->grid.pred_mass[l] = tot;
    m->loglik = 0;
    if (st->has_y) {
        m->loglik = measure(f, m, l, (real)st->yr);
    } else if (tot > (real)0) {
        const real inv = (real)1 / tot;
        for (i = 0; i < NS * NV; ++i) {
            p[i] *= inv;
        }
        for (i = 0; i < NS; ++i) {
            f->grid.rest[l][i] *= inv;
        }
    }
}

/* One model's step. A model that was tracking and now misses the
 * measurement with every cell may only have cut off the tail the truth
 * was in (the box leaves GRID_TAIL out, and with a measurement it holds
 * only the posterior): the step is done again from the saved cells with
 * the predicted box that leaves out WIDE_TAIL. A model that still misses
 * is a misfit (its dynamics cannot reach the measurement). A grid left
 * without mass (cannot happen but by round-off) is placed again at the
 * measurement with the model's speed, and scores the floor. */
static void model_step(hstpf_t *f, hstpf_model_t *m, const hstpf__step_t *st)
{
    const uint16_t l = (uint16_t)(m - f->m);
    const uint16_t run = m->floor_run;
    const uint32_t hits = m->floor_hits;
    const real v_was = m->v_mean;
    real acc = (real)st->xu;
    if (f->cfg.n_track > 0u) {
        acc -= hstpf__track_acc(f, &m->track_hint, m->s_mean);
    }
    if (st->has_y) {
        memcpy(f->grid.save, f->grid.p[l], sizeof f->grid.p[l]);
        memcpy(f->grid.save + NS * NV, f->grid.rest[l], sizeof f->grid.rest[l]);
        memcpy(f->grid.save + NS * NV + NS, f->grid.geom[l], sizeof f->grid.geom[l]);
    }
    f->grid.tail = GRID_TAIL;
    model_pass(f, m, st, acc);
    if (st->has_y && ((run == 0u && m->floor_run > 0u) || !(mass_of(f, l) > (real)0))) {
        memcpy(f->grid.p[l], f->grid.save, sizeof f->grid.p[l]);
        memcpy(f->grid.rest[l], f->grid.save + NS * NV, sizeof f->grid.rest[l]);
        memcpy(f->grid.geom[l], f->grid.save + NS * NV + NS, sizeof f->grid.geom[l]);
        m->floor_run = run;
        m->floor_hits = hits;
        f->grid.tail = WIDE_TAIL;
        model_pass(f, m, st, acc);
    }
    if (!(mass_of(f, l) > (real)0)) {
        hstpf__acq_t q;
        memset(&q, 0, sizeof q);
        q.y2 = st->has_y ? st->yr : (double)m->s_mean;
        q.y1 = q.y2;
        q.v0 = (double)v_was;
        place_one(f, m, &q);
        m->loglik = st->has_y ? f->de.floor : (real)0;
        m->floor_hits = hits + (st->has_y ? 1u : 0u);
        m->floor_run = (uint16_t)(run + (st->has_y ? 1u : 0u));
        return;
    }
    moments(f, m, l);
}

/* When every model misses the measurement, it is the measurement (or the
 * reference) that is off, not the models: no model's weight moves. */
static void predict_update(hstpf_t *f, const hstpf__step_t *st)
{
    uint16_t l, missed = 0;
    for (l = 0; l < f->cfg.n_models; ++l) {
        const uint32_t hits = f->m[l].floor_hits;
        model_step(f, &f->m[l], st);
        missed = (uint16_t)(missed + (f->m[l].floor_hits != hits));
    }
    if (st->has_y && missed == f->cfg.n_models) {
        for (l = 0; l < f->cfg.n_models; ++l) {
            f->m[l].loglik = 0;
        }
    }
}

static void shift(hstpf_t *f, real d)
{
    uint16_t l;
    for (l = 0; l < f->cfg.n_models; ++l) {
        f->grid.geom[l][0] -= d;
        f->m[l].s_mean -= d;
    }
}

const hstpf__engine_t hstpf__engine_grid = {place_all, place_one, predict_update, NULL, shift};
