/* Grid engine: a model's cells placed from the acquisition fixes.
 * docs/grid.md, "Acquisition and standstill". */
#include <math.h>
#include <string.h>

#include "grid.h"


/* A model from the acquisition fixes. Position: s = y2 - e2, cell masses
 * from e's CDF. Speed, one fix (t12 = 0): N(v0, init_speed_sd) (a point
 * when the sd is 0). Two fixes t12 apart: by the model's Euler step from
 * s1 = y1 - e1, v = (s - y1 + e1 - mu_s)/t12 + t12 a + mu_v, so a speed
 * cell [w_j, w_j+1] at position s_i holds the probability of e1 in
 * [t12 (w_j - c) - s_i + y1 + mu_s, ...], c = t12 a + mu_v (a at the
 * two fixes' mean speed; the process noise over t12 is left out of the
 * spread, as in the other engines). Speeds below 0 are at rest. */
void hstpf__grid_place_one(hstpf_t *f, hstpf_model_t *m, const hstpf__acq_t *q)
{
    const uint16_t l = hstpf__grid_slot(f, m);
    const hstpf_config_t *c = &f->cfg;
    real *p = f->grid.p[l], *g = f->grid.geom[l], *rest = f->grid.rest[l];
    const real y2 = (real)q->y2, y1 = (real)q->y1, t = (real)q->t12;
    const real el = hstpf__grid_tail_quantile(&f->de.qt, 0, GRID_TAIL), eh = hstpf__grid_tail_quantile(&f->de.qt, 1, GRID_TAIL);
    real s_lo = y2 - eh, s_hi = y2 - el, v_lo, v_hi, tot = 0, cs = 0, mus = 0, sdv = 0;
    const real v0 = (real)q->v0;
    int i, j;
    if (t > (real)0) {
        const real sc = (real)sqrt(q->t12 / c->dt_nominal_s);
        const real vm = (real)((q->y2 - q->y1) / q->t12), vp = vm > (real)0 ? vm : (real)0;
        mus = sc * (real)f->noise_mom[0]; /* the noise's own mean (a Gamma spec's mean field is unused) */
        cs = t * ((real)q->xu - m->k0 - (m->k1 + m->k2 * vp) * vp) + sc * (real)f->noise_mom[2];
        v_lo = (s_lo - y1 + el - mus) / t + cs;
        v_hi = (s_hi - y1 + eh - mus) / t + cs;
    } else {
        sdv = (real)c->init_speed_sd;
        v_lo = v0 + sdv * hstpf__grid_tail_quantile(&f->unit, 0, GRID_TAIL);
        v_hi = v0 + sdv * hstpf__grid_tail_quantile(&f->unit, 1, GRID_TAIL);
    }
    v_lo = v_lo > (real)0 ? v_lo : (real)0;
    v_hi = v_hi > v_lo ? v_hi : v_lo;
    hstpf__grid_geometry(s_lo, s_hi, v_lo, v_hi, g);
    for (i = 0; i < NS; ++i) { /* e2 in [y2 - right edge, y2 - left edge] */
        const real x0 = g[0] + (real)i * g[1], sc_i = x0 + (real)0.5 * g[1];
        const real ps = hstpf__grid_prob_in(&f->de.qt, y2 - (x0 + g[1]), y2 - x0);
        real below;
        for (j = 0; j < NV; ++j) {
            const real w0 = g[2] + (real)j * g[3], w1 = w0 + g[3];
            real pv;
            if (t > (real)0) {
                pv = hstpf__grid_prob_in(&f->de.qt, t * (w0 - cs) - sc_i + y1 + mus, t * (w1 - cs) - sc_i + y1 + mus);
            } else if (sdv > (real)0) {
                pv = hstpf__grid_prob_in(&f->unit, (w0 - v0) / sdv, (w1 - v0) / sdv);
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
            below = hstpf__grid_prob_in(&f->de.qt, (real)-3e38, t * (-cs) - sc_i + y1 + mus);
        } else if (sdv > (real)0) {
            below = hstpf__grid_prob_in(&f->unit, (real)-3e38, -v0 / sdv);
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
    hstpf__grid_moments(f, m, l);
}
