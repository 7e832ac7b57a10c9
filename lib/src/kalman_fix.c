/* A Gaussian filter's fix scored by the fix noise's real density (an
 * assumed-density update). The rows' Kalman filters on the grid engine are
 * the stand-ins of the rows without a grid and the continuous hypothesis'
 * yardstick; on the noise's moments a fix in a heavy tail (Student-t,
 * multipath) moves their likelihood ratios far more than the exact
 * densities do. So the predictive position N(s, pss) is cut into cells
 * over its +-6 sd, and over the noise's core where those cannot see it (a
 * prediction wider than the noise, a fix beyond the span), each weighted
 * by the fix noise integrated over it (the grid's own measurement,
 * grid_measure.c), which gives the likelihood, and the posterior
 * position's mean and variance, from which the rest of the state follows
 * by its regression on the position (docs/grid.md, "Rows on the grid"). */
#include <math.h>

#include "grid.h"
#include "refine.h"

#define FIX_CELLS 24     /* cells at least, over +-FIX_REACH sd of the prediction */
#define FIX_CELLS_MAX 96 /* at most: a prediction far wider than the noise (acquisition) */
#define FIX_REACH 6.0    /* the Gaussian's mass beyond: 2e-9 */
#define CORE_TAIL 1e-4   /* the noise's core: its 0.01 % .. 99.99 % quantiles around the fix */
#define CORE_GROW 1.1    /* the core's cells widen by this from its median outwards */
#define CORE_SIDE 48     /* cells at most on each side of it */

/* The sums over cells, relative to the largest log-weight so far, and the
 * position moments about that cell's midpoint (in float, moments about a
 * point far from the posterior would cancel: a fix 1 km from s). */
typedef struct {
    real lmax, piv, wsum, m1, m2;
    int floored; /* every cell so far within the prediction's span beyond the floor */
} fix_sum_t;

/* Cell [a, a + h] (from s) of the prediction N(0, sd): the fix noise over
 * it as the grid scores a cell, times the Gaussian at its midpoint times
 * h. */
static void add_cell(const hstpf_dist_t *de, real y, real sd, real a, real h, fix_sum_t *c)
{
    const real x = a + (real)0.5 * h, z = x / sd;
    const real li = hstpf__grid_cell_score(de, y - (a + h), y - a, y - x);
    real lw, w;
    c->floored = c->floored && (li <= de->floor || z < (real)-FIX_REACH || z > (real)FIX_REACH);
    lw = li - (real)0.5 * z * z;
    if (lw > c->lmax) {
        const real r = hstpf__exp_neg(c->lmax - lw), d = x - c->piv;
        c->wsum *= r;
        c->m1 *= r;
        c->m2 *= r;
        c->m2 += d * (d * c->wsum - (real)2 * c->m1);
        c->m1 -= d * c->wsum;
        c->lmax = lw;
        c->piv = x;
    }
    w = hstpf__exp_neg(lw - c->lmax) * h;
    c->wsum += w;
    c->m1 += w * (x - c->piv);
    c->m2 += w * (x - c->piv) * (x - c->piv);
}

/* Cells from c0 towards edge (either side), the first w0 wide, each
 * CORE_GROW times wider: fine where the noise's density is high, few in
 * its tail. They stop at edge, at CORE_SIDE cells, or where they would be
 * wider than wmax (the prediction's own cells are then as fine), unless
 * they must reach it (to_edge: the last cell then goes to it); returns
 * where they stopped. */
static real add_side(const hstpf_dist_t *de, real y, real sd, real c0, real edge, real w0, real wmax, int to_edge,
                     fix_sum_t *c)
{
    const real dir = edge > c0 ? (real)1 : (real)-1;
    real a = c0, w = w0;
    int k;
    for (k = 0; k < CORE_SIDE && (edge - a) * dir > (real)0 && (to_edge || w <= wmax); ++k) {
        real b = a + dir * w;
        b = (b - edge) * dir > (real)0 || (to_edge && k == CORE_SIDE - 1) ? edge : b;
        add_cell(de, y, sd, dir > (real)0 ? a : b, (b - a) * dir, c);
        a = b;
        w *= (real)CORE_GROW;
    }
    return a;
}

void hstpf__kalman_fix(const hstpf_t *f, double s, double pss, double yr, hstpf__fix_t *out)
{
    const hstpf_dist_t *de = &f->de;
    const real sd = (real)sqrt(pss > 0.0 ? pss : 0.0), reach = (real)FIX_REACH * sd;
    /* cells no wider than a quarter of the noise's interquartile range, so
     * that a posterior narrowed by its core is resolved, up to
     * FIX_CELLS_MAX over the prediction's +-FIX_REACH sd */
    const real iqr = hstpf__grid_tail_quantile(&de->qt, 1, (real)0.25) - hstpf__grid_tail_quantile(&de->qt, 0, (real)0.25);
    const real hmax = (real)0.25 * iqr > DS_MIN ? (real)0.25 * iqr : DS_MIN;
    const real y = (real)(yr - s); /* the fix from the prediction: float keeps cm here */
    const real nmid = y - hstpf__grid_tail_quantile(&de->qt, 0, (real)0.5); /* where the noise's median puts s */
    real h = (real)2.0 * reach / (real)FIX_CELLS, cl = nmid, ch = nmid; /* the core's cells in the span */
    fix_sum_t c;
    int i, n = FIX_CELLS, coarse, far;
    out->ds = 0.0;
    out->var = pss;
    out->floored = 0;
    if (!(pss < 1e30) || !(yr - s < 1e30 && yr - s > -1e30)) { /* not finite: nothing to take */
        out->floored = 1;
        out->loglik = (double)de->floor;
        return;
    }
    if (!(h > DS_MIN)) { /* a point: the density at it */
        const real l = hstpf__dist_logpdf(de, y);
        out->floored = l <= de->floor;
        out->loglik = (double)l;
        return;
    }
    if (h > hmax) {
        const real k = (real)2.0 * reach / hmax;
        n = k < (real)(FIX_CELLS_MAX - 1) ? (int)k + 1 : FIX_CELLS_MAX;
        h = (real)2.0 * reach / (real)n;
    }
    /* The noise's core gets cells of its own where the prediction's cells
     * cannot see it: cells wider than hmax (a prediction far wider than
     * the noise; the core's cells replace them where these are finer), or
     * a median beyond the span (a filter far from the fix, whose posterior
     * may lie at the fix or between: the core's cells reach back to the
     * span's edge, and on into the span while its cells are coarser). The
     * core's cells run on past its quantiles while they are finer than
     * the span's. */
    coarse = h > hmax;
    far = nmid > reach || nmid < -reach;
    c.lmax = (real)-3e38;
    c.piv = c.wsum = c.m1 = c.m2 = 0;
    c.floored = 1;
    if (far) {
        /* the core's far end: where the noise's CORE_TAIL quantile puts s */
        const real e = nmid > reach ? reach : -reach;
        const real end = y - hstpf__grid_tail_quantile(&de->qt, nmid > reach ? 0 : 1, (real)CORE_TAIL);
        add_side(de, y, sd, nmid, end, hmax, (real)3e38, 1, &c);
        add_side(de, y, sd, nmid, e, hmax, (real)3e38, 1, &c);
        if (coarse) { /* the core's part inside the span: cells up to h from its edge */
            cl = ch = e;
            if (nmid > reach) {
                cl = add_side(de, y, sd, e, (real)-3e38, hmax, h, 0, &c);
            } else {
                ch = add_side(de, y, sd, e, (real)3e38, hmax, h, 0, &c);
            }
        }
    } else if (coarse) {
        ch = add_side(de, y, sd, nmid, (real)3e38, hmax, h, 0, &c);
        cl = add_side(de, y, sd, nmid, (real)-3e38, hmax, h, 0, &c);
    }
    for (i = 0; i < n; ++i) { /* the span, without the core's cells [cl, ch] */
        const real a = -reach + (real)i * h, b = a + h;
        if (!coarse || b <= cl || a >= ch) {
            add_cell(de, y, sd, a, h, &c);
            continue;
        }
        if (a < cl) {
            add_cell(de, y, sd, a, cl - a, &c);
        }
        if (b > ch) {
            add_cell(de, y, sd, ch, b - ch, &c);
        }
    }
    /* the Gaussian's density is 1 / (sd sqrt(2 pi)) at its centre */
    out->loglik = (double)c.lmax + (c.wsum > (real)0 ? log((double)c.wsum / (double)sd * 0.3989422804014327) : 0.0);
    /* the prediction missed the fix: every cell of its span beyond the
     * floor, and the core's beyond it do not lift the fix above it */
    out->floored = c.floored && out->loglik <= (double)de->floor;
    if (out->floored || !(c.wsum > (real)0)) { /* the fix is not used (a filter that lost the train: engine.h) */
        return;
    }
    c.m1 /= c.wsum;
    out->ds = (double)c.piv + (double)c.m1;
    out->var = (double)(c.m2 / c.wsum - c.m1 * c.m1); /* wider than pss after a fix far in a heavy tail: two modes */
    out->var = out->var > 0.0 ? out->var : 0.0;
}

void hstpf__fix_moments(const hstpf_t *f, double s, double pss, double yr, hstpf__fixm_t *out)
{
    const double *nm = f->noise_mom;
    const double depth = (double)(f->de.lp_max - f->de.floor), zf = sqrt(2.0 * depth);
    double az, ll;
    out->sy = pss + nm[5] * nm[5];
    out->sd = sqrt(out->sy);
    out->z = (yr - nm[4] - s) / out->sd;
    az = fabs(out->z);
    out->floored = az > zf;
    if (!out->floored) {
        ll = -0.5 * out->z * out->z;
    } else {
        ll = -depth - ((az < 1e4 ? az : 1e4) - zf);
        out->z = out->z > 0.0 ? zf : -zf;
    }
    out->loglik = ll - 0.5 * log(6.283185307179586 * out->sy);
}

int hstpf__fix_exact(const hstpf_t *f)
{
    return f->engine == (uint8_t)HSTPF_ENGINE_GRID && hstpf__process_gaussian(&f->cfg) &&
           f->cfg.noise_e.kind != HSTPF_DIST_GAUSSIAN;
}
