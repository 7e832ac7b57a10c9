/* Grid engine: the measurement update (step 4 of docs/grid.md). */
#include <math.h>
#include <string.h>

#include "grid.h"

/* Step 4: the measurement update; returns the log-likelihood increment,
 * and in *has_mass whether any cell holds mass after it (the sum of
 * non-negative cells is > 0 whatever their order: the caller need not sum
 * them again). */
real hstpf__grid_measure(hstpf_t *f, hstpf_model_t *m, uint16_t l, real yr, int *has_mass)
{
    const hstpf_dist_t *de = &f->de;
    real *p = f->grid.p[l], *g = f->grid.geom[l], *ll = f->grid.row;
    real lmax = (real)-3e38, sum = 0;
    int i, j, all_floor = 1;
    (void)hstpf__grid_marginals(f, p, f->grid.rest[l]);
    for (i = 0; i < NS; ++i) {
        const real x0 = g[0] + (real)i * g[1];
        const real li = hstpf__grid_cell_score(de, yr - (x0 + g[1]), yr - x0, yr - (x0 + (real)0.5 * g[1]));
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
        }
    }
    sum = hstpf__grid_sum(p, NS * NV);
    for (i = 0; i < NS; ++i) {
        f->grid.rest[l][i] *= ll[i];
        sum += f->grid.rest[l][i];
    }
    if (!(sum > (real)0)) { /* every cell underflowed: keep the prediction */
        *has_mass = 0;
        return lmax;
    }
    *has_mass = hstpf__grid_normalise(f, l, sum);
    return lmax + (real)log((double)sum);
}
