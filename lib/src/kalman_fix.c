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

void hstpf__kalman_fix(const hstpf_t *f, double s, double pss, double yr, hstpf__fix_t *out)
{
    const hstpf_dist_t *de = &f->de;
    const real sd = (real)sqrt(pss > 0.0 ? pss : 0.0);
    /* cells no wider than a quarter of the noise's interquartile range, so
     * that a posterior narrowed by its core is resolved, up to
     * FIX_CELLS_MAX: a prediction wider than twice the range gets wider
     * cells, and a fix beyond +-FIX_REACH sd of it is seen from the last
     * cell (a filter that lost the train is placed again: engine.h) */
    const real iqr = hstpf__grid_tail_quantile(&de->qt, 1, (real)0.25) - hstpf__grid_tail_quantile(&de->qt, 0, (real)0.25);
    const real y = (real)(yr - s); /* the fix from the prediction: float keeps cm here */
    real h = (real)(2.0 * FIX_REACH) * sd / (real)FIX_CELLS, x0 = (real)-FIX_REACH * sd;
    real lmax = (real)-3e38, wsum = 0, m1 = 0, m2 = 0;
    int i, n = FIX_CELLS, all_floor = 1;
    out->ds = 0.0;
    out->var = pss;
    out->floored = 0;
    if (!(h > DS_MIN)) { /* a point: the density at it */
        const real l = hstpf__dist_logpdf(de, y);
        out->floored = l <= de->floor;
        out->loglik = (double)l;
        return;
    }
    if (h > (real)0.25 * iqr) {
        const real c = (real)(2.0 * FIX_REACH) * sd / ((real)0.25 * iqr);
        n = c < (real)(FIX_CELLS_MAX - 1) ? (int)c + 1 : FIX_CELLS_MAX;
        h = (real)(2.0 * FIX_REACH) * sd / (real)n;
    }
    for (i = 0; i < n; ++i) {
        /* the fix noise over cell i, with the grid's floor (grid_measure.c),
         * times the prediction's mass there (midpoint rule); the sums are
         * kept relative to the largest log-density so far */
        const real a = x0 + (real)i * h, x = a + (real)0.5 * h, z = x / sd; /* from s */
        const real l = hstpf__grid_cell_loglik(de, y - (a + h), y - a);
        real li = l, w;
        if (l < de->floor) {
            const real fl = hstpf__dist_logpdf(de, y - x);
            li = fl < de->floor ? fl : de->floor;
            li = l > li ? l : li;
        }
        all_floor = all_floor && li <= de->floor;
        if (li > lmax) {
            const real r = hstpf__exp_neg(lmax - li);
            wsum *= r;
            m1 *= r;
            m2 *= r;
            lmax = li;
        }
        w = hstpf__exp_neg((real)-0.5 * z * z + (li - lmax));
        wsum += w;
        m1 += w * x;
        m2 += w * x * x;
    }
    out->floored = all_floor;
    /* the Gaussian's density is 1 / (sd sqrt(2 pi)) at its centre: cells of h */
    out->loglik = (double)lmax + (wsum > (real)0 ? log((double)wsum * (double)h / (double)sd * 0.3989422804014327) : 0.0);
    if (all_floor || !(wsum > (real)0)) { /* every cell beyond the floor: the fix is not used */
        return;
    }
    m1 /= wsum;
    out->ds = (double)m1;
    out->var = (double)(m2 / wsum - m1 * m1); /* wider than pss after a fix far in a heavy tail: two modes */
    out->var = out->var > 0.0 ? out->var : 0.0;
}

int hstpf__fix_exact(const hstpf_t *f)
{
    return f->engine == (uint8_t)HSTPF_ENGINE_GRID && hstpf__process_gaussian(&f->cfg) &&
           f->cfg.noise_e.kind != HSTPF_DIST_GAUSSIAN;
}
