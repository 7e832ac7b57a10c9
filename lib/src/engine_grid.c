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
 * No RNG, no heap: the memory is hstpf_t.grid. docs/grid.md.
 *
 * Files: grid.h (the internal interface), grid_cdf.c (probabilities and
 * densities over cells), grid_acquire.c (placement from the fixes),
 * grid_box.c (step 1), grid_transport.c (step 2), grid_noise.c (step 3),
 * grid_measure.c (step 4); this file: the engine interface, estimates,
 * and the retry of a step that missed. */
#include <math.h>
#include <string.h>

#include "grid.h"
#include "refine.h"
#include "track.h"


/* Marginals of a model's cells into ms (with the mass at rest) and mv
 * (moving rows); returns the total mass. */
real hstpf__grid_marginals(hstpf_t *f, const real *p, const real *rest)
{
    real tot = 0;
    int i, j;
    for (i = 0; i < NS; ++i) {
        f->grid.ms[i] = rest[i]; /* the position marginal includes the mass at rest */
        tot += rest[i];
    }
    for (j = 0; j < NV; ++j) {
        const real *r = p + j * NS;
        const real rs = hstpf__grid_sum(r, NS);
        for (i = 0; i < NS; ++i) {
            f->grid.ms[i] += r[i];
        }
        f->grid.mv[j] = rs;
        tot += rs;
    }
    return tot;
}

/* qa[i & 7] += x[i]^2 for i < n, in blocks of eight (vector adds). */
static void sumsq_into(real *qa, const real *x, int n)
{
    int i, r;
    for (i = 0; i + 8 <= n; i += 8) {
        for (r = 0; r < 8; ++r) {
            qa[r] += x[i + r] * x[i + r];
        }
    }
    for (r = 0; i + r < n; ++r) {
        qa[r] += x[i + r] * x[i + r];
    }
}

/* Mean, variance (with the cells' own width) and effective cell count.
 * Two passes, about the mean and divided by the mass: positions reach
 * 1024 m from the origin, so the one-pass s2 - s1^2 of cells whose mass
 * sums to 1 only within float round-off (1e-7) was off by up to 0.1 m^2,
 * and a Case 2 posterior of millimetres published an sd of 0. */
void hstpf__grid_moments(hstpf_t *f, hstpf_model_t *m, uint16_t l)
{
    const real *p = f->grid.p[l], *g = f->grid.geom[l], *rest = f->grid.rest[l];
    double s1 = 0.0, s2 = 0.0, v1 = 0.0, v2 = 0.0, q2 = 0.0, moving = 0.0, tot, ms, mv;
    int i, j;
    tot = (double)hstpf__grid_marginals(f, p, rest);
    tot = tot > 0.0 ? tot : 1.0;
    for (i = 0; i < NS; ++i) {
        s1 += (double)f->grid.ms[i] * (((double)i + 0.5) * (double)g[1]);
    }
    for (j = 0; j < NV; ++j) {
        v1 += (double)f->grid.mv[j] * ((double)g[2] + ((double)j + 0.5) * (double)g[3]);
        moving += (double)f->grid.mv[j];
    }
    ms = s1 / tot; /* from the box's edge */
    mv = v1 / tot; /* the mass at rest counts at v = 0 */
    { /* the second pass in float (soft-float double on the M4F): about
       * the mean, from the box's edge, nothing large cancels */
        const real cs = (real)ms, cv = (real)(mv - (double)g[2]);
        real a2 = 0, b2 = 0;
        for (i = 0; i < NS; ++i) {
            const real d = ((real)i + (real)0.5) * g[1] - cs;
            a2 += f->grid.ms[i] * d * d;
        }
        for (j = 0; j < NV; ++j) {
            const real d = ((real)j + (real)0.5) * g[3] - cv;
            b2 += f->grid.mv[j] * d * d;
        }
        s2 = (double)a2;
        v2 = (double)b2 + (tot - moving > 0.0 ? tot - moving : 0.0) * mv * mv;
    }
    { /* sum of squares in float, eight partial sums: a double per cell is
       * soft-float on the M4F (a quarter of its grid step) */
        real qa[8] = {0, 0, 0, 0, 0, 0, 0, 0};
        sumsq_into(qa, p, NS * NV);
        sumsq_into(qa, rest, NS);
        q2 = (double)(((qa[0] + qa[1]) + (qa[2] + qa[3])) + ((qa[4] + qa[5]) + (qa[6] + qa[7])));
    }
    m->s_mean = (real)((double)g[0] + ms);
    m->v_mean = (real)mv;
    /* variances with each cell's own width (uniform within the cell) */
    m->s_var = (real)(s2 / tot + (double)g[1] * (double)g[1] / 12.0);
    m->v_var = (real)(v2 / tot + moving / tot * (double)g[3] * (double)g[3] / 12.0);
    m->ess = (real)(q2 > 0.0 ? 1.0 / q2 : 0.0);
}

/* The rows stepped on the grid: cfg.grid_rows of them where the process
 * noise is Gaussian (the rows' Kalman filters are then a fair stand-in
 * for the others), every row otherwise (docs/grid.md, "Rows on the
 * grid"). */
static uint16_t grid_rows(const hstpf_config_t *c)
{
    return c->grid_rows > 0u && c->grid_rows < c->n_models && hstpf__process_gaussian(c) ? c->grid_rows
                                                                                          : c->n_models;
}

/* The grid models: those rows, and the continuous hypothesis' if it has one. */
static uint16_t n_grids(const hstpf_config_t *c)
{
    return (uint16_t)(grid_rows(c) + (hstpf__refine_grid_cfg(c) ? 1u : 0u));
}

/* Some rows have no grid. */
static int screened(const hstpf_t *f)
{
    return grid_rows(&f->cfg) < f->cfg.n_models;
}

/* The models that have or may have a grid: the rows, and the hypothesis'. */
static uint16_t n_cells_models(const hstpf_t *f)
{
    return (uint16_t)(f->cfg.n_models + (hstpf__refine_on_grid(f) ? 1u : 0u));
}

/* Grid k's cells, cells at rest and geometry into f->grid.save (a step to
 * retry, a grid to hand on), and back into grid k. */
static void save_cells(hstpf_t *f, uint16_t k)
{
    memcpy(f->grid.save, f->grid.p[k], sizeof f->grid.p[k]);
    memcpy(f->grid.save + NS * NV, f->grid.rest[k], sizeof f->grid.rest[k]);
    memcpy(f->grid.save + NS * NV + NS, f->grid.geom[k], sizeof f->grid.geom[k]);
}

static void restore_cells(hstpf_t *f, uint16_t k)
{
    memcpy(f->grid.p[k], f->grid.save, sizeof f->grid.p[k]);
    memcpy(f->grid.rest[k], f->grid.save + NS * NV, sizeof f->grid.rest[k]);
    memcpy(f->grid.geom[k], f->grid.save + NS * NV + NS, sizeof f->grid.geom[k]);
}

/* Row a ranks above row b: a larger weight, or the same and a lower index
 * (a strict order, so the rows on the grid follow from the weights alone:
 * a reset run repeats the first). */
static int ranks_above(const hstpf_t *f, int a, int b)
{
    return f->m[a].logq > f->m[b].logq || (f->m[a].logq == f->m[b].logq && a < b);
}

/* The highest (lowest when lo) ranked row with a grid (want 1) or without
 * one (want 0); -1: none. */
static int ranked(const hstpf_t *f, int want, int lo)
{
    int best = -1;
    uint16_t l;
    for (l = 0; l < f->cfg.n_models; ++l) {
        if ((f->grid.slot[l] >= 0) == want && (best < 0 || ranks_above(f, lo ? best : (int)l, lo ? (int)l : best))) {
            best = (int)l;
        }
    }
    return best;
}

/* Grid k, a copy of row from's density, moved by the offset between the
 * two rows' Kalman means (what the models' different dynamics put between
 * them; the copy keeps the exact shape). A copy left where the leader is
 * cost a promoted true row 0.3-1 nat per fix until it had moved there:
 * stops-t, DFH3 seed 39, declared at 2061 s against 250 s with every row
 * on the grid (docs/grid.md, "Rows on the grid"). */
static void move_copy(hstpf_t *f, uint16_t k, const hstpf_model_t *to, const hstpf_model_t *from)
{
    real *g = f->grid.geom[k];
    const double ds = to->kx[0] - from->kx[0], dv = to->kx[1] - from->kx[1]; /* finite: finite_models */
    g[0] += (real)ds;
    /* no speed below 0: a box that starts at 0 keeps its speeds (the cells
     * would have to be remapped; measured small, docs/grid.md) */
    g[2] = g[2] + (real)dv > (real)0 ? g[2] + (real)dv : (real)0;
}

/* The grids go to the highest ranked rows: a row without one that ranks
 * above the lowest gridded row takes that row's grid. With copy, it starts
 * from the density of the gridded row that leads, which tracks the same
 * train (its own Kalman filter is a Gaussian, and the fixes' tails are
 * not), moved by the offset of its own filter's mean from the leader's. */
static void choose_rows(hstpf_t *f, int copy)
{
    const int src = ranked(f, 1, 0);
    int saved = 0;
    for (;;) {
        const int w = ranked(f, 1, 1), d = ranked(f, 0, 0);
        if (d < 0 || w < 0 || !ranks_above(f, d, w)) {
            return;
        }
        if (copy && !saved) { /* src's own grid may be the next one handed on */
            const uint16_t k = (uint16_t)f->grid.slot[src];
            save_cells(f, k);
            saved = 1;
        }
        f->grid.slot[d] = f->grid.slot[w];
        f->grid.slot[w] = -1;
        if (copy) {
            const uint16_t k = (uint16_t)f->grid.slot[d];
            restore_cells(f, k);
            move_copy(f, k, &f->m[d], &f->m[src]);
            f->grid.pred_mass[k] = 1;
        }
    }
}

/* A model placed from fixes: its cells if it has a grid, and its row's
 * Kalman filter where the rows run one (the continuous hypothesis'
 * yardstick, where lock.c places the hypothesis' EKF, refine.c; the rows
 * without a grid). */
static void place_one(hstpf_t *f, hstpf_model_t *m, const hstpf__acq_t *q)
{
    const int gridded = f->grid.slot[m - f->m] >= 0;
    if (gridded) {
        hstpf__grid_place_one(f, m, q);
    }
    if (f->rf.active || screened(f)) {
        hstpf__kalman_place(f, m, q);
    }
    if (!gridded) {
        hstpf__kalman_publish(f, m);
        m->loglik = 0;
        m->held = 0;
    }
}

static void place_all(hstpf_t *f, const hstpf__acq_t *q)
{
    uint16_t l;
    if (hstpf__refine_on_grid(f)) {
        hstpf__refine_grid_theta(f);
    }
    choose_rows(f, 0); /* each grid is placed below */
    for (l = 0; l < n_cells_models(f); ++l) {
        place_one(f, &f->m[l], q);
    }
}

/* Predict (and measure) one model with the box tail f->grid.tail; returns
 * whether it holds any mass. */
static int model_pass(hstpf_t *f, hstpf_model_t *m, const hstpf__step_t *st, real acc)
{
    const uint16_t l = hstpf__grid_slot(f, m);
    const real dt = (real)st->dt, scale = (real)st->scale;
    real ng[4], tot, rtot, held;
    real *g = f->grid.geom[l];
    int has_mass;
    hstpf__grid_new_box(f, m, l, dt, acc, scale, st->has_y, (real)st->yr, ng, &tot, &rtot);
    if (f->grid.theta_sd > (real)0) { /* the box reaches the Gaussian's tails too */
        const real w = (real)THETA_REACH * f->grid.theta_sd, hi = ng[2] + (real)NV * ng[3] + w;
        ng[2] = ng[2] - w > (real)0 ? ng[2] - w : (real)0;
        ng[3] = (hi - ng[2]) / (real)NV;
    }
    if (!(ng[1] > (real)0 && ng[3] > (real)0 && ng[0] - ng[0] == (real)0 && ng[2] - ng[2] == (real)0)) {
        /* cells narrower than float resolves where the box lies (a speed
         * noise of scale 1e9 put it at 2.8e8 m/s; a fuzz finding: NaN cell
         * indices): no mass, so the model is placed again (model_step) */
        return 0;
    }
    held = hstpf__grid_transport(f, m, l, dt, acc, ng, tot, rtot);
    hstpf__grid_diffuse(f, l, scale, ng);
    g[0] = ng[0];
    g[1] = ng[1];
    g[2] = ng[2];
    g[3] = ng[3];
    /* the whole posterior at rest: held, or come to rest within the step */
    m->held = (uint8_t)(held >= (real)(1.0 - 1e-6));
    tot = hstpf__grid_mass(f, l);
    f->grid.pred_mass[l] = tot;
    m->loglik = 0;
    if (st->has_y) {
        m->loglik = hstpf__grid_measure(f, m, l, (real)st->yr, &has_mass);
        return has_mass;
    }
    return tot > (real)0 && hstpf__grid_normalise(f, l, tot); /* a step without a fix */
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
    const uint16_t l = hstpf__grid_slot(f, m);
    const uint16_t run = m->floor_run;
    const uint32_t hits = m->floor_hits;
    const real v_was = m->v_mean;
    real acc = (real)hstpf__step_xu(f, m, st);
    int has_mass;
    if (f->cfg.n_track > 0u) {
        acc -= hstpf__track_acc(f, &m->track_hint, m->s_mean);
    }
    if (st->has_y) {
        save_cells(f, l);
    }
    f->grid.tail = GRID_TAIL;
    has_mass = model_pass(f, m, st, acc);
    if (st->has_y && ((run == 0u && m->floor_run > 0u) || !has_mass)) {
        restore_cells(f, l);
        m->floor_run = run;
        m->floor_hits = hits;
        f->grid.tail = WIDE_TAIL;
        has_mass = model_pass(f, m, st, acc);
    }
    if (!has_mass) {
        hstpf__acq_t q;
        memset(&q, 0, sizeof q);
        q.y2 = st->has_y ? st->yr : (double)m->s_mean;
        q.y1 = q.y2;
        q.v0 = (double)v_was;
        hstpf__grid_place_one(f, m, &q);
        m->loglik = st->has_y ? f->de.floor : (real)0;
        m->floor_hits = hits + (st->has_y ? 1u : 0u);
        m->floor_run = (uint16_t)(run + (st->has_y ? 1u : 0u));
        return;
    }
    hstpf__grid_moments(f, m, l);
}

/* The rows' Kalman filters on the noises' moments, each increment kept in
 * m->kll: the continuous hypothesis' yardstick (refine.c), and the rows
 * without a grid, whose rest is their filter's. */
static void rows_kalman_step(hstpf_t *f, const hstpf__step_t *st)
{
    uint16_t l;
    for (l = 0; l < f->cfg.n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        uint8_t held;
        int floored;
        m->kll = hstpf__kalman_step(f, m, st, &held, &floored);
        if (f->grid.slot[l] < 0) {
            m->held = held;
            m->loglik = 0;
            m->floor_run = (uint16_t)(st->has_y && floored); /* until rows_without_grid */
        }
    }
}

/* Row m's Kalman filter at mean (s, v), covariance (pss, psv, pvv). */
static void kalman_set(hstpf_model_t *m, double s, double v, double pss, double psv, double pvv)
{
    m->kx[0] = s;
    m->kx[1] = v;
    m->kp[0] = pss;
    m->kp[1] = psv;
    m->kp[2] = pvv;
    m->rest.zp = 0; /* a stop's unclamped speed is of the state replaced */
    m->rest.zc = 0;
}

/* A gridded row's Kalman filter that has lost the train (hstpf__kalman_lost)
 * is placed again at its grid's moments, and k_placed says so: this step's
 * ratios against it (the rows without a grid, the hypothesis' yardstick)
 * are then taken against the grid's exact increment. */
static void anchor_lost(hstpf_t *f)
{
    uint16_t l;
    for (l = 0; l < f->cfg.n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        m->k_placed = (uint8_t)(f->grid.slot[l] >= 0 && hstpf__kalman_lost(m, m->kx[0], m->kx[1], m->kp[0], m->kp[2]));
        if (m->k_placed) {
            kalman_set(m, (double)m->s_mean, (double)m->v_mean, (double)m->s_var, 0.0, (double)m->v_var);
        }
    }
}

/* A row without a grid scores against the leading row: the leader's exact
 * increment plus the log ratio of their Kalman filters, within +-1 nat (a
 * fix in a heavy tail puts that Gaussian ratio far beyond the exact
 * densities'). It publishes the leader's state, which the grid has exactly
 * under the fixes' real noise, and the leader's floor counts (so a fix
 * every weighted model misses is still told, weights.c, hstpf__all_lost); whether it
 * is held at rest stays its own filter's (the leader's gave larger weight
 * moves across stops: stops-t TV max 0.13 against 0.024, 5 seeds); a filter of
 * its own that missed the fix or lost the train (hstpf__kalman_lost, against
 * the leader's grid) is placed again at the leader's, and when lost scores
 * the leader's increment. */
static void rows_without_grid(hstpf_t *f, const hstpf__step_t *st)
{
    const hstpf_model_t *lead = &f->m[ranked(f, 1, 0)];
    uint16_t l;
    for (l = 0; l < f->cfg.n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        if (f->grid.slot[l] >= 0) {
            continue;
        }
        const int lost = hstpf__kalman_lost(lead, m->kx[0], m->kx[1], m->kp[0], m->kp[2]);
        if (st->has_y) { /* its own filter lost: no ratio; the leader's placed again: against its exact increment */
            const double r = lost ? 0.0 : m->kll - (lead->k_placed ? (double)lead->loglik : lead->kll);
            m->loglik = (real)((double)lead->loglik + (r < -1.0 ? -1.0 : (r > 1.0 ? 1.0 : r)));
        }
        if (m->floor_run > 0u || lost) { /* its own filter missed this fix, or is far from the train */
            kalman_set(m, lead->kx[0], lead->kx[1], lead->kp[0], lead->kp[1], lead->kp[2]);
        }
        m->floor_run = lead->floor_run;
        m->floor_hits += (uint32_t)(st->has_y && lead->floor_run > 0u);
        m->s_mean = lead->s_mean;
        m->v_mean = lead->v_mean;
        m->s_var = lead->s_var;
        m->v_var = lead->v_var;
        m->ess = lead->ess;
    }
}

/* When every gridded row misses the measurement, it is the measurement (or
 * the reference) that is off, not the models: no model's weight moves. The
 * hypothesis' grid steps at the EKF's theta of the step before, so that
 * its likelihood is a prediction (refine.c). */
static void predict_update(hstpf_t *f, const hstpf__step_t *st)
{
    uint16_t l, missed = 0;
    if (screened(f)) {
        choose_rows(f, 1);
    }
    if (hstpf__refine_yardstick(f) || screened(f)) {
        rows_kalman_step(f, st);
    }
    /* the traction unknown: the speeds spread by its Gaussian, as theta's
     * uncertainty spreads the hypothesis' (grid_noise.c) */
    f->grid.theta_sd = (real)sqrt(st->acc_var);
    for (l = 0; l < f->cfg.n_models; ++l) {
        if (f->grid.slot[l] >= 0) {
            const uint32_t hits = f->m[l].floor_hits;
            model_step(f, &f->m[l], st);
            missed = (uint16_t)(missed + (f->m[l].floor_hits != hits));
        }
    }
    if (hstpf__refine_on_grid(f)) {
        const uint32_t hits = f->m[l].floor_hits;
        double tsd;
        hstpf__refine_grid_theta(f);
        tsd = hstpf__refine_theta_sd(f, st);
        f->grid.theta_sd = (real)(st->acc_var > 0.0 ? sqrt(tsd * tsd + st->acc_var) : tsd);
        model_step(f, &f->m[l], st);
        if (f->m[l].floor_hits == hits) {
            missed = 0; /* it fits a fix every row misses: the rows are off */
        }
    }
    f->grid.theta_sd = 0;
    if (hstpf__refine_yardstick(f) || screened(f)) {
        anchor_lost(f);
    }
    if (screened(f)) {
        rows_without_grid(f, st);
    }
    if (st->has_y && missed == grid_rows(&f->cfg)) {
        for (l = 0; l < n_cells_models(f); ++l) {
            f->m[l].loglik = 0;
        }
    }
}

static void shift(hstpf_t *f, real d)
{
    uint16_t l;
    for (l = 0; l < n_cells_models(f); ++l) {
        f->m[l].s_mean -= d;
        f->m[l].kx[0] -= (double)d; /* the Kalman filter's, if it runs */
        f->m[l].rest.s -= d;
    }
    for (l = 0; l < n_grids(&f->cfg); ++l) {
        f->grid.geom[l][0] -= d;
    }
}

static void spread(hstpf_t *f, double var)
{
    uint16_t k;
    for (k = 0; k < n_grids(&f->cfg); ++k) {
        hstpf__grid_spread(f, k, var);
    }
}

static size_t ws_bytes(const hstpf_config_t *c)
{
    return HSTPF_GRID_WS_BYTES(n_grids(c));
}

/* The layout HSTPF_GRID_WS_BYTES counts: each grid's cells, the
 * transported grid, the saved cells, each model's mass at rest. */
static void attach(hstpf_t *f, void *ws)
{
    const size_t nm = n_grids(&f->cfg);
    real *r = (real *)ws;
    uint16_t l;
    for (l = 0; l < f->cfg.n_models; ++l) { /* the first rows; choose_rows hands them on */
        f->grid.slot[l] = (int16_t)(l < grid_rows(&f->cfg) ? l : -1);
    }
    f->grid.slot[f->cfg.n_models] = (int16_t)grid_rows(&f->cfg); /* the hypothesis', if it has one */
    f->grid.p = (real(*)[NS * NV])(void *)r;
    r += nm * NS * NV;
    f->grid.work = r;
    r += NS * NV;
    f->grid.save = r;
    r += NS * NV + NS + 4;
    f->grid.rest = (real(*)[NS])(void *)r;
}

const hstpf__engine_t hstpf__engine_grid = {place_all, place_one, predict_update, NULL, shift, spread, ws_bytes,
                                             attach};
