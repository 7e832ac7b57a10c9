/* A Gaussian filter's fix scored by the fix noise's real density (an
 * assumed-density update). The rows' Kalman filters on the grid engine are
 * the stand-ins of the rows without a grid and the continuous hypothesis'
 * yardstick; on the noise's moments a fix in a heavy tail (Student-t,
 * multipath) moves their likelihood ratios far more than the exact
 * densities do. So the predictive position N(s, pss) is cut into cells,
 * each weighted by the fix noise integrated over it (the grid's own
 * measurement, grid_measure.c), which gives the likelihood, and the
 * posterior position's mean and variance, from which the rest of the state
 * follows by its regression on the position (docs/grid.md, "Rows on the
 * grid"). */
#include <math.h>

#include "grid.h"
#include "refine.h"

#define FIX_CELLS 24     /* cells at least, over +-FIX_REACH sd of the prediction */
#define FIX_CELLS_MAX 96 /* at most: a prediction far wider than the noise (acquisition) */
#define FIX_REACH 6.0    /* the Gaussian's mass beyond: 2e-9 */
#define CORE_TAIL 1e-4   /* the noise's core: its 0.01 % .. 99.99 % quantiles */
#define CORE_CELLS 48    /* at most, over the core */

/* The sums over cells, relative to the largest log-weight so far, and
 * the position moments about that cell's midpoint (in float, moments about
 * a point far from the posterior would cancel: a fix 1 km from s). */
typedef struct {
    real lmax, piv, wsum, m1, m2;
    int all_floor;  /* every cell so far beyond the noise's floor */
    int span_floor; /* every cell so far within the prediction's span beyond it */
} fix_sum_t;

/* Cell [a, a + h] (from s) of the prediction N(0, sd): the fix noise over
 * it, with the grid's floor (grid_measure.c), times the Gaussian at its
 * midpoint times h. */
static void add_cell(const hstpf_dist_t *de, real y, real sd, real a, real h, fix_sum_t *c)
{
    const real x = a + (real)0.5 * h, z = x / sd;
    const int in_span = z >= (real)-FIX_REACH && z <= (real)FIX_REACH;
    const real l = hstpf__grid_cell_loglik(de, y - (a + h), y - a);
    real li = l, lw, w;
    if (l < de->floor) {
        const real fl = hstpf__dist_logpdf(de, y - x);
        li = fl < de->floor ? fl : de->floor;
        li = l > li ? l : li;
    }
    c->all_floor = c->all_floor && li <= de->floor;
    c->span_floor = c->span_floor && (li <= de->floor || !in_span);
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

/* [lo, hi] in cells no wider than hmax, at most nmax of them. */
static void add_span(const hstpf_dist_t *de, real y, real sd, real lo, real hi, real hmax, fix_sum_t *c)
{
    const real k = (hi - lo) / hmax;
    const int n = k < (real)(CORE_CELLS - 1) ? (int)k + 1 : CORE_CELLS;
    const real h = (hi - lo) / (real)n;
    int i;
    for (i = 0; i < n; ++i) {
        add_cell(de, y, sd, lo + (real)i * h, h, c);
    }
}

void hstpf__kalman_fix(const hstpf_t *f, double s, double pss, double yr, hstpf__fix_t *out)
{
    const hstpf_dist_t *de = &f->de;
    const real sd = (real)sqrt(pss > 0.0 ? pss : 0.0), reach = (real)FIX_REACH * sd;
    /* cells no wider than a quarter of the noise's interquartile range, so
     * that a posterior narrowed by its core is resolved, up to
     * FIX_CELLS_MAX over the prediction's +-FIX_REACH sd */
    const real iqr = hstpf__grid_tail_quantile(&de->qt, 1, (real)0.25) - hstpf__grid_tail_quantile(&de->qt, 0, (real)0.25);
    const real hmax = (real)0.25 * iqr;
    const real y = (real)(yr - s); /* the fix from the prediction: float keeps cm here */
    real h = (real)2.0 * reach / (real)FIX_CELLS;
    fix_sum_t c;
    int i, n = FIX_CELLS;
    out->ds = 0.0;
    out->var = pss;
    out->floored = 0;
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
    c.lmax = (real)-3e38;
    c.piv = c.wsum = c.m1 = c.m2 = 0;
    c.all_floor = c.span_floor = 1;
    {
        /* The noise's core (the positions at which the fix noise is within
         * its CORE_TAIL quantiles) gets cells of its own where the
         * prediction's cells cannot see it: cells wider than hmax (a
         * prediction far wider than the noise: the core's cells replace
         * them there), or a core centred beyond +-FIX_REACH sd (a filter
         * far from the fix, whose posterior lies at the fix all the same
         * when the noise's tail is lighter than the prediction's). */
        const real nlo = y - hstpf__grid_tail_quantile(&de->qt, 1, (real)CORE_TAIL);
        const real nhi = y - hstpf__grid_tail_quantile(&de->qt, 0, (real)CORE_TAIL);
        const real nmid = y - hstpf__grid_tail_quantile(&de->qt, 0, (real)0.5);
        const int coarse = h > hmax, far = nmid < -reach || nmid > reach;
        for (i = 0; i < n; ++i) {
            const real a = -reach + (real)i * h, b = a + h;
            if (!coarse || b <= nlo || a >= nhi) {
                add_cell(de, y, sd, a, h, &c);
                continue;
            }
            if (a < nlo) {
                add_cell(de, y, sd, a, nlo - a, &c);
            }
            if (b > nhi) {
                add_cell(de, y, sd, nhi, b - nhi, &c);
            }
        }
        if (coarse) {
            add_span(de, y, sd, nlo, nhi, hmax, &c);
        } else if (far) { /* the core beyond the span (a heavy tail's core reaches into it: cells there are the span's) */
            if (nlo < -reach) {
                add_span(de, y, sd, nlo, nhi < -reach ? nhi : -reach, hmax, &c);
            }
            if (nhi > reach) {
                add_span(de, y, sd, nlo > reach ? nlo : reach, nhi, hmax, &c);
            }
        }
    }
    out->floored = c.span_floor; /* the prediction missed the fix */
    /* the Gaussian's density is 1 / (sd sqrt(2 pi)) at its centre */
    out->loglik = (double)c.lmax + (c.wsum > (real)0 ? log((double)c.wsum / (double)sd * 0.3989422804014327) : 0.0);
    if (c.all_floor || !(c.wsum > (real)0)) { /* every cell beyond the floor: the fix is not used */
        return;
    }
    c.m1 /= c.wsum;
    out->ds = (double)c.piv + (double)c.m1;
    out->var = (double)(c.m2 / c.wsum - c.m1 * c.m1); /* wider than pss after a fix far in a heavy tail: two modes */
    out->var = out->var > 0.0 ? out->var : 0.0;
}

int hstpf__fix_exact(const hstpf_t *f)
{
    return f->engine == (uint8_t)HSTPF_ENGINE_GRID && hstpf__process_gaussian(&f->cfg) &&
           f->cfg.noise_e.kind != HSTPF_DIST_GAUSSIAN;
}
