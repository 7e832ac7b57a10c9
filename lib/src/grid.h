/* The grid engine's internal interface, shared by engine_grid.c and the
 * grid_*.c files (one file per step of docs/grid.md). Not part of the API.
 * The state is hstpf_t.grid (hstpf_grid_ws_t in hstpf.h); its cells p,
 * rest, work and save point into the caller's workspace. f->grid.work,
 * row, ms, mv, ks, kv, vimg, first, last and box are scratch passed from
 * one step to the next within one model's pass. */
#ifndef HSTPF_GRID_H
#define HSTPF_GRID_H

#include "dist_impl.h"
#include "engine.h"
#include "internal.h"

typedef hstpf_real_t real;

#define NS HSTPF_GRID_NS
#define NV HSTPF_GRID_NV
#define QN ((int)HSTPF_DIST_QN)
#define GRID_TAIL ((real)1e-5)  /* mass a box leaves out on each side */
#define WIDE_TAIL ((real)1e-9)  /* the same when a step is retried */
#define THETA_REACH 4.5         /* sd of theta's spread a box reaches (its 1e-5 tail is 4.3) */
#define PULL_SD 2.0            /* measurement beyond this many sd: keep that tail */
#define DS_MIN ((real)1e-3)     /* narrowest cell, m: float positions near 1 km */
#define DV_MIN ((real)1e-4)     /* narrowest cell, m/s */
#define MASS_MIN ((real)1e-30)  /* a cell below this is empty */
#define LATTICE_COARSEST ((real)1.5) /* cfg.grid_speed_lattice: widest cells, x the box's own */

/* Model m's grid (p, rest, geom, pred_mass): its slot. With cfg.grid_rows
 * only the rows that carry the most weight have one (engine_grid.c). */
static inline uint16_t hstpf__grid_slot(const hstpf_t *f, const hstpf_model_t *m)
{
    return (uint16_t)f->grid.slot[m - f->m];
}

/* The deterministic speed after one step (below 0: the train comes to
 * rest within the step; the caller moves that mass to rest). */
static inline real hstpf__grid_speed_map(const hstpf_model_t *m, real v, real dt, real acc)
{
    return v + dt * (acc - m->k0 - (m->k1 + m->k2 * v) * v);
}

/* x[0] + ... + x[n - 1] in eight partial sums: the grid's sums run over
 * thousands of cells, and one chain of dependent additions would cost the
 * adder's latency per cell. */
static inline real hstpf__grid_sum(const real *x, int n)
{
    real a[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    int i, r;
    for (i = 0; i + 8 <= n; i += 8) { /* a[r] += x[i + r]: two vector adds */
        for (r = 0; r < 8; ++r) {
            a[r] += x[i + r];
        }
    }
    for (r = 0; i + r < n; ++r) {
        a[r] += x[i + r];
    }
    return ((a[0] + a[1]) + (a[2] + a[3])) + ((a[4] + a[5]) + (a[6] + a[7]));
}

/* Model l's whole mass: its moving cells and its cells at rest. */
static inline real hstpf__grid_mass(const hstpf_t *f, uint16_t l)
{
    return hstpf__grid_sum(f->grid.p[l], NS * NV) + hstpf__grid_sum(f->grid.rest[l], NS);
}

/* Model l's cells (moving and at rest) divided by tot > 0; returns whether
 * any holds mass after it: always, unless 1 / tot overflowed (its largest
 * cell is then >= 1 / (cells)), when they are summed again. */
static inline int hstpf__grid_normalise(hstpf_t *f, uint16_t l, real tot)
{
    const real inv = (real)1 / tot;
    real *p = f->grid.p[l], *rest = f->grid.rest[l];
    int i;
    for (i = 0; i < NS * NV; ++i) {
        p[i] *= inv;
    }
    for (i = 0; i < NS; ++i) {
        rest[i] *= inv;
    }
    return inv - inv == (real)0 || hstpf__grid_mass(f, l) > (real)0;
}

/* o += c r over a whole row. Columns outside the occupied ones hold exact
 * zeros in r, so the sums are those over the occupied columns; a length
 * known at compile time and rows that cannot overlap let the loop be
 * unrolled and vectorised without a variable range's run-time checks. */
static inline void hstpf__grid_axpy_row(real *restrict o, const real *restrict r, real c)
{
    int i;
    for (i = 0; i < NS; ++i) {
        o[i] += c * r[i];
    }
}

/* ---- grid_cdf.c: a built distribution over intervals ------------------ */

/* P(X <= x) into *lo and P(X > x) into *hi, each on its own side. */
void hstpf__grid_cdf2(const hstpf_dist_quantiles_t *d, real x, real *lo, real *hi);
/* P(a < X <= b), a <= b, from the quantile tables (the sampler's CDF). */
real hstpf__grid_prob_in(const hstpf_dist_quantiles_t *d, real a, real b);
/* The quantile at tail (upper = 0) or 1 - tail. */
real hstpf__grid_tail_quantile(const hstpf_dist_quantiles_t *d, int upper, real tail);
/* Log of the mean density of d over [a, b], a < b; -3e38 for zero. */
real hstpf__grid_cell_loglik(const hstpf_dist_t *d, real a, real b);
/* The same, scored as the grid scores a cell: beyond the floor, the floor
 * with its slope at mid (the cell's midpoint), as a particle there would
 * be (grid_measure.c, kalman_fix.c). */
static inline real hstpf__grid_cell_score(const hstpf_dist_t *d, real a, real b, real mid)
{
    const real lc = hstpf__grid_cell_loglik(d, a, b);
    real li = lc;
    if (lc < d->floor) {
        const real fl = hstpf__dist_logpdf(d, mid);
        li = fl < d->floor ? fl : d->floor;
        li = lc > li ? lc : li;
    }
    return li;
}

/* ---- grid_acquire.c ---------------------------------------------------- */

/* Model m's cells placed from the acquisition fixes q. */
void hstpf__grid_place_one(hstpf_t *f, hstpf_model_t *m, const hstpf__acq_t *q);

/* ---- grid_box.c: step 1 ------------------------------------------------ */

/* The new grid ng = (s0, ds, v0, dv) of model l for this step (with the
 * box tail f->grid.tail); sets f->grid.first/last and vimg. *tot and *rtot:
 * the model's mass and its mass at rest. Uses f->grid.work as scratch. */
/* grid_box.c: a box's geometry with the narrowest cells allowed */
void hstpf__grid_geometry(real s_lo, real s_hi, real v_lo, real v_hi, real *g);
void hstpf__grid_new_box(hstpf_t *f, const hstpf_model_t *m, uint16_t l, real dt, real acc, real scale, int has_y,
                         real yr, real *ng, real *tot, real *rtot);
/* cfg.grid_speed_lattice: ng's speed cells moved onto the lattice of the
 * old rows' images vimg (rows first[j] <= last[j] occupied), or left. */
void hstpf__grid_speed_lattice(const int16_t *first, const int16_t *last, const real *vimg, real *ng);

/* ---- grid_transport.c: step 2 ------------------------------------------ */

/* Input cells i0..i1, cell i covering [a + i w, a + (i + 1) w] in output
 * cells, added to out[0..n_out) in proportion to the overlap. */
void hstpf__grid_remap(const real *in, int i0, int i1, real a, real w, real *out, int n_out);
/* Model l's cells moved by the dynamics onto ng, into f->grid.work (and
 * rnew, rpend, box). Returns the fraction of the mass at rest after it. */
real hstpf__grid_transport(hstpf_t *f, const hstpf_model_t *m, uint16_t l, real dt, real acc, const real *ng, real tot,
                           real rtot);

/* ---- grid_noise.c: step 3 ---------------------------------------------- */

/* The cell masses of the noise scale * X on cells of width h, between its
 * tail quantiles and within +-reach cells: k[0..n), first offset *m0;
 * returns n. */
int hstpf__grid_kernel(const hstpf_dist_quantiles_t *d, real scale, real h, int reach, real tail, real *k, int *m0);
/* The process noise convolved into model l's cells from f->grid.work. */
void hstpf__grid_diffuse(hstpf_t *f, uint16_t l, real scale, const real *ng);
/* Grid k's positions spread by N(0, var) on a box widened to hold it (a
 * step in the fixes' reference, fix_step.c). */
void hstpf__grid_spread(hstpf_t *f, uint16_t k, double var);

/* ---- grid_measure.c: step 4 -------------------------------------------- */

/* Model l weighted by the measurement yr and normalised; returns the
 * log-likelihood increment, whether any cell holds mass in *has_mass, and
 * counts the floor hits of m. */
real hstpf__grid_measure(hstpf_t *f, hstpf_model_t *m, uint16_t l, real yr, int *has_mass);

/* ---- engine_grid.c ----------------------------------------------------- */

/* The marginals of cells p and rest into f->grid.ms and mv; the mass. */
real hstpf__grid_marginals(hstpf_t *f, const real *p, const real *rest);
/* Model l's means, variances and effective cell count into m. */
void hstpf__grid_moments(hstpf_t *f, hstpf_model_t *m, uint16_t l);

#endif
