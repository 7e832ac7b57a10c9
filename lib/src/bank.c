/* The bank: life cycle and the step, with the standstill rule. The model
 * weights are weights.c's, the traction unknown traction_unknown.c's, the
 * lock lock.c's, the declaration declare.c's, the published estimate
 * estimate.c's; how each model's state and likelihood are computed is the
 * engine's (engine.h). */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "bank.h"
#include "dist_impl.h"
#include "engine.h"
#include "refine.h"
#include "rng_impl.h"
#include "track.h"

hstpf_engine_t hstpf__engine_resolve(const hstpf_config_t *cfg)
{
    if (cfg->engine == HSTPF_ENGINE_AUTO) {
        return hstpf__all_gaussian(cfg) ? HSTPF_ENGINE_KALMAN : HSTPF_ENGINE_GRID;
    }
    return cfg->engine;
}

/* The one place an engine is chosen. */
const hstpf__engine_t *hstpf__engine_for(hstpf_engine_t e)
{
    switch (e) {
    case HSTPF_ENGINE_KALMAN: return &hstpf__engine_kalman;
    case HSTPF_ENGINE_GRID: return &hstpf__engine_grid;
    default: return &hstpf__engine_particle;
    }
}

const hstpf__engine_t *hstpf__engine_of(const hstpf_t *f)
{
    return hstpf__engine_for((hstpf_engine_t)f->engine);
}

int32_t hstpf_workspace_size(const hstpf_config_t *cfg, size_t *bytes)
{
    int32_t err;
    if (cfg == NULL || bytes == NULL) {
        return HSTPF_E_NULL;
    }
    err = hstpf__config_check(cfg, NULL);
    if (err != HSTPF_OK) {
        return err;
    }
    *bytes = hstpf__engine_for(hstpf__engine_resolve(cfg))->ws_bytes(cfg);
    return HSTPF_OK;
}

/* No type declared, no hold running: status says why (a reset, or a
 * consist that changed under a declared type). */
static void clear_declaration(hstpf_t *f, hstpf_status_t status)
{
    f->status = status;
    f->declared = -1;
    f->leader = -1;
    f->held_s = 0.0;
    f->decision_time_s = -1.0;
    f->fit = HSTPF_FIT_UNKNOWN;
    f->fit_held_s = 0.0;
}

static void reset_state(hstpf_t *f)
{
    uint16_t l;
    const double q0 = f->rf.active ? f->cfg.refine_prior_q : 0.0;
    const double lq = log((1.0 - q0) / (double)f->cfg.n_models);
    f->rf.logq = f->rf.active ? log(q0) : 0.0;
    f->rf.placed = 0;
    f->rf.nis = 1.0;
    /* the hypothesis' state too: the estimate blends it in (a reset read the
     * last run's speed and spreads, a review found) */
    memset(f->rf.kz, 0, sizeof f->rf.kz);
    memset(f->rf.kp, 0, sizeof f->rf.kp);
    f->rf.loglik = 0.0;
    f->rf.held = 0;
    f->rf.floored = 0;
    memset(&f->rf.rest, 0, sizeof f->rf.rest);
    hstpf__trac_check_reset(f);
    clear_declaration(f, HSTPF_STATUS_UNDECIDED);
    /* the rows, and the slot of the hypothesis' grid model (unused without one) */
    for (l = 0; l <= f->cfg.n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        m->logq = lq;
        m->s_mean = m->v_mean = m->loglik = 0;
        m->s_var = m->v_var = 0;
        memset(m->kx, 0, sizeof m->kx);
        memset(m->kp, 0, sizeof m->kp);
        m->kll = 0.0;
        memset(&m->rest, 0, sizeof m->rest);
        m->held = 0;
        m->k_placed = 0;
        m->reacquired = 0;
        m->ess = (real)f->cfg.n_particles;
        m->floor_hits = 0;
        m->floor_run = 0;
        m->track_hint = 0;
    }
    hstpf__trac_check_snapshot(f);
    f->origin_m = 0.0;
    f->time_s = 0.0;
    f->steps = 0;
    f->have_fix = 0;
    f->have_pend = 0;
    f->ever_locked = 0;
    f->prior_lock = 0;
    f->fix_age_s = 0.0;
    f->fix_gap_s = 0.0;
    f->acquisitions = 0;
    f->nonfinite_resets = 0;
    f->backward = 0;
    f->top_m = -HUGE_VAL;
    memset(&f->pr, 0, sizeof f->pr);
    f->standstill = 0;
    f->weights_wait = 0;
    f->arrival_s = 0.0;
    f->stop_s = 0.0;
    f->mix_pending = 0;
    f->outlier_run = 0;
    f->lost_run = 0;
    f->outliers = 0;
    f->reacquired = 0;
    memset(&f->fs, 0, sizeof f->fs);
    f->fs.side = 2;
}

/* The quantile part of spec's tables into q, built in de's place (its
 * log-density is not kept: nothing evaluates this noise's density). */
static void init_quantiles(hstpf_t *f, hstpf_dist_quantiles_t *q, const hstpf_dist_spec_t *spec)
{
    (void)hstpf_dist_init(&f->de, spec);
    *q = f->de.qt;
}

/* Noise tables; the specs were checked, so these cannot fail. */
static void init_tables(hstpf_t *f, const hstpf_config_t *cfg)
{
    const int particles = f->engine == (uint8_t)HSTPF_ENGINE_PARTICLE;
    hstpf_dist_spec_t unit;
    memset(&unit, 0, sizeof unit);
    unit.kind = HSTPF_DIST_GAUSSIAN;
    unit.sd = 1.0;
    init_quantiles(f, &f->ds, &cfg->noise_s);
    init_quantiles(f, &f->dv, &cfg->noise_v);
    init_quantiles(f, &f->unit, &unit);
    if (cfg->e_blur_sd > 0.0 && particles && cfg->noise_e.kind == HSTPF_DIST_GAUSSIAN) {
        /* a blurred Gaussian is a wider Gaussian (the first fix draws from it too) */
        hstpf_dist_spec_t e2 = cfg->noise_e;
        e2.sd = sqrt(e2.sd * e2.sd + cfg->e_blur_sd * cfg->e_blur_sd);
        (void)hstpf_dist_init(&f->de, &e2);
    } else {
        (void)hstpf_dist_init(&f->de, &cfg->noise_e);
        if (cfg->e_blur_sd > 0.0 && particles) {
            (void)hstpf__dist_blur(&f->de, &cfg->noise_e, cfg->e_blur_sd);
        }
    }
    { /* the moments the Kalman filters use: exact for every kind */
        const hstpf_dist_spec_t *sp[3] = {&cfg->noise_s, &cfg->noise_v, &cfg->noise_e};
        const hstpf_dist_quantiles_t *d[3] = {&f->ds, &f->dv, &f->de.qt};
        int i;
        for (i = 0; i < 3; ++i) {
            const int g = sp[i]->kind == HSTPF_DIST_GAUSSIAN;
            f->noise_mom[2 * i] = g ? sp[i]->mean : (double)d[i]->mean;
            f->noise_mom[2 * i + 1] = g ? sp[i]->sd : (double)d[i]->sd;
        }
    }
}

int32_t hstpf_init(hstpf_t *f, size_t f_size, const hstpf_config_t *cfg)
{
    const hstpf__engine_t *eng;
    size_t need;
    int32_t err;
    uint16_t l;
    if (f == NULL || cfg == NULL) {
        return HSTPF_E_NULL;
    }
    if (f_size != sizeof(hstpf_t)) {
        return HSTPF_E_ABI;
    }
    err = hstpf__config_check(cfg, NULL);
    if (err != HSTPF_OK) {
        return err;
    }
    eng = hstpf__engine_for(hstpf__engine_resolve(cfg));
    need = eng->ws_bytes(cfg);
    if (need > 0 && cfg->workspace == NULL) {
        return HSTPF_E_NULL;
    }
    if (need > 0 && (cfg->workspace_size < need || (uintptr_t)cfg->workspace % HSTPF_WORKSPACE_ALIGN != 0)) {
        return HSTPF_E_SIZE;
    }
    memset(f, 0, sizeof *f);
    f->cfg = *cfg;
    f->cfg.models = NULL; /* copied below: the caller's arrays need not live on */
    f->cfg.track = NULL;
    if (need > 0) {
        memset(cfg->workspace, 0, need); /* runs repeat bit for bit whatever was there */
        eng->attach(f, cfg->workspace);
    }
    f->xi = HSTPF_G_ACC / (1.0 + cfg->gamma_rot) / 1000.0;
    f->engine = (uint8_t)hstpf__engine_resolve(cfg);
    /* Kalman: the rows' likelihoods are its own kind. Grid: through the
     * rows' Kalman yardstick under Gaussian process noise, on a grid of its
     * own otherwise (or with refine = 2; refine.h, docs/model.md
     * "Engines"). Particles: Monte Carlo likelihoods, no. */
    f->rf.active = (uint8_t)(cfg->refine && cfg->refine_prior_q > 0.0 &&
                             (f->engine == (uint8_t)HSTPF_ENGINE_KALMAN || f->engine == (uint8_t)HSTPF_ENGINE_GRID));
    for (l = 0; l < cfg->n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        f->theta[l] = cfg->models[l];
        hstpf__model_set_theta(f, m, cfg->models[l].c0, cfg->models[l].c1, cfg->models[l].c2);
        (void)hstpf_rng_seed(&m->rng, cfg->seed, l);
    }
    (void)hstpf_rng_seed(&f->rng, cfg->seed, HSTPF_MAX_MODELS);
    hstpf__track_init(f, cfg->track, cfg->n_track);
    init_tables(f, cfg);
    reset_state(f);
    f->magic = HSTPF_MAGIC;
    return HSTPF_OK;
}

int32_t hstpf_reset(hstpf_t *f)
{
    if (f == NULL) {
        return HSTPF_E_NULL;
    }
    if (f->magic != HSTPF_MAGIC) {
        return HSTPF_E_INIT;
    }
    reset_state(f);
    return HSTPF_OK;
}

int32_t hstpf_consist_changed(hstpf_t *f)
{
    if (f == NULL) {
        return HSTPF_E_NULL;
    }
    if (f->magic != HSTPF_MAGIC) {
        return HSTPF_E_INIT;
    }
    hstpf__consist_mix(f, 1.0); /* the traction check's snapshot too: the prior */
    clear_declaration(f, f->declared >= 0 ? HSTPF_STATUS_WITHDRAWN : HSTPF_STATUS_UNDECIDED);
    f->stop_s = 0.0;
    f->mix_pending = 0;
    return HSTPF_OK;
}

/* Every state, variance and log weight finite and physically possible:
 * one sum of their magnitudes, NaN or infinite if any is, and beyond
 * HSTPF__STATE_MAX when a state ran away while still finite (the blend of
 * a huge double state would publish infinity; fuzz regression). */
static int finite_models(const hstpf_t *f)
{
    double z = fabs(f->rf.logq);
    uint16_t l;
    int i;
    for (l = 0; l < f->cfg.n_models; ++l) {
        const hstpf_model_t *m = &f->m[l];
        z += fabs((double)m->s_mean) + fabs((double)m->v_mean) + fabs((double)m->s_var) +
             fabs((double)m->v_var) + fabs(m->logq);
        if (f->engine == (uint8_t)HSTPF_ENGINE_GRID) { /* the rows' Kalman filters too (zero when unused) */
            z += fabs(m->kx[0]) + fabs(m->kx[1]) + fabs(m->kp[0]) + fabs(m->kp[2]);
        }
    }
    if (hstpf__refine_on_grid(f)) {
        const hstpf_model_t *m = &f->m[f->cfg.n_models];
        z += fabs((double)m->s_mean) + fabs((double)m->v_mean) + fabs((double)m->s_var) + fabs((double)m->v_var);
    }
    for (i = 0; i < HSTPF_REFINE_NZ; ++i) { /* zero while the hypothesis is off */
        z += fabs(f->rf.kz[i]) + fabs(f->rf.kp[i * (HSTPF_REFINE_NZ + 1)]);
    }
    return z <= HSTPF__STATE_MAX;
}

/* Time passes without a lock: only the pending fix ages. */
static void advance_time(hstpf_t *f, double dt)
{
    f->time_s += dt;
    f->pend_age_s += dt;
    ++f->steps;
}

/* One step of every model and of the continuous hypothesis. */
static void engines_substep(hstpf_t *f, const hstpf__engine_t *e, const hstpf__step_t *st)
{
    e->predict_update(f, st);
    if (f->rf.active) {
        hstpf__refine_update(f, st);
        if (hstpf__refine_yardstick(f)) {
            hstpf__refine_anchor(f, st);
        } else if (hstpf__refine_on_grid(f)) {
            hstpf__refine_from_grid(f, st);
        }
    }
}

/* The model steps s' = s + T v (paper Eq. 6), written for steps of about
 * dt_nominal_s: over a longer one it drops T^2 a / 2, 210 m for a 29 s
 * step braking at 0.5 m/s^2, and a departure from rest moves nothing for
 * the whole step (a review: a 29 s gap while braking from 300 km/h, one
 * step, declared a wrong type in 585 of 850 runs, speeds 26 m/s off at
 * 33 sd). Such a step is predicted in hstpf__substeps() equal parts
 * with its traction, as the model's own train would run, and the fix is
 * taken at the last; a step up to 1.5 dt_nominal_s is one part, as before. */
uint32_t hstpf__substeps(const hstpf_t *f, double dt)
{
    const double r = dt / f->cfg.dt_nominal_s;
    if (!(r > HSTPF__SUBSTEP_RATIO)) {
        return 1u;
    }
    return r < (double)HSTPF_SUBSTEPS_MAX ? (uint32_t)ceil(r) : HSTPF_SUBSTEPS_MAX;
}

hstpf__step_t hstpf__step_part(const hstpf_t *f, const hstpf__step_t *st, uint32_t n)
{
    hstpf__step_t sub = *st;
    sub.dt = st->dt / (double)n;
    sub.scale = (double)(real)sqrt(sub.dt / f->cfg.dt_nominal_s);
    sub.acc_var = st->acc_var / (double)n;
    sub.has_y = 0;
    return sub;
}

static void engines_step(hstpf_t *f, const hstpf__engine_t *e, const hstpf__step_t *st)
{
    const uint32_t n = hstpf__substeps(f, st->dt);
    hstpf__step_t sub = *st;
    uint32_t i;
    if (n > 1u) {
        sub = hstpf__step_part(f, st, n);
        for (i = 1; i < n; ++i) {
            engines_substep(f, e, &sub);
        }
        sub.has_y = st->has_y;
    }
    engines_substep(f, e, &sub);
}

/* Two fixes in a row after a lock from the configured speed prior are
 * gated, or beyond every weighted model's floor: the prior was wrong (a
 * unit configured for a power-up at rest that started while the train
 * runs published 0 +- 1 m/s valid at 300 km/h: hstpf-mc --scenario
 * start300-prior). The fix in pend_y (the prior's, aged since; or the
 * first gated one) and this one place the models again. Time has
 * advanced; free_run: the traction is not to be used. */
static void prior_replace(hstpf_t *f, const hstpf_input_t *in, int free_run)
{
    const double t = f->pend_age_s, v = t > 0.0 ? (in->position_m - f->pend_y) / t : 0.0;
    ++f->reacquired;
    hstpf__drop_lock(f, 0);
    f->have_pend = 1;
    (void)hstpf__acquire(f, in->position_m, free_run ? hstpf__free_xu(f, v > 0.0 ? v : 0.0) : f->xi * in->traction);
}

int32_t hstpf_step(hstpf_t *f, const hstpf_input_t *in)
{
    int has_y = (in != NULL && in->has_position) ? 1 : 0, gated = 0, weigh, free_run, trac_known;
    double xu;
    const hstpf__engine_t *e;
    hstpf__step_t st;
    if (f == NULL || in == NULL) {
        return HSTPF_E_NULL;
    }
    if (f->magic != HSTPF_MAGIC) {
        return HSTPF_E_INIT;
    }
    free_run = in->traction_unknown != 0; /* traction is then not read */
    if (!hstpf__fin(in->dt_s) || (!free_run && !hstpf__fin(in->traction)) ||
        (has_y && !hstpf__fin(in->position_m))) {
        return HSTPF_E_NONFINITE;
    }
    if (!(in->dt_s > 0.0 && in->dt_s <= HSTPF_DT_MAX_S)) {
        return HSTPF_E_DT;
    }
    if ((!free_run && fabs(in->traction) > HSTPF_U_MAX) || (has_y && fabs(in->position_m) > HSTPF_POS_MAX_M)) {
        return HSTPF_E_RANGE;
    }
    if (f->have_fix && in->dt_s > f->cfg.max_gap_s) {
        hstpf__drop_lock(f, 0); /* too long to predict across: re-acquire */
        f->have_pend = 0;
    }
    if (!f->have_fix) {
        advance_time(f, in->dt_s);
        if (has_y) {
            /* unknown traction: the pair's own speed sets the balance */
            const double t = f->pend_age_s, v = f->have_pend && t > 0.0 ? (in->position_m - f->pend_y) / t : 0.0;
            (void)hstpf__acquire(f, in->position_m, free_run ? hstpf__free_xu(f, v > 0.0 ? v : 0.0) : f->xi * in->traction);
        }
        f->standstill = 0;
        f->weights_wait = 0;
        hstpf__update_declaration(f, in->dt_s, 0);
        return HSTPF_OK;
    }
    if (has_y && f->cfg.gate_m > 0.0 && hstpf__fix_gate(f, in->position_m, in->dt_s)) {
        if (f->prior_lock && f->outlier_run > 0u) {
            /* a second gated fix in a row after the prior's lock: pairs
             * with the first (kept in pend_y by the gated path below) */
            advance_time(f, in->dt_s);
            prior_replace(f, in, free_run);
            hstpf__update_declaration(f, in->dt_s, 0);
            return HSTPF_OK;
        }
        if (f->cfg.reacquire_after == 0u || f->outlier_run < f->cfg.reacquire_after) {
            ++f->outliers;
            f->outlier_run = (uint16_t)(f->outlier_run + (f->outlier_run < UINT16_MAX)); /* saturates: 0 means valid */
            /* the step goes on without its fix; the fix is remembered: a
             * run of these may be the new reference */
            gated = 1;
            f->have_pend = 1;
            f->pend_y = in->position_m;
            f->pend_age_s = -in->dt_s; /* aged to 0 at the end of this step */
        } else {
            /* the reference really moved: acquire again from the gated fixes */
            ++f->reacquired;
            hstpf__drop_lock(f, 1);
            advance_time(f, in->dt_s);
            (void)hstpf__acquire(f, in->position_m, free_run ? hstpf__free_xu(f, -1.0) : f->xi * in->traction);
            hstpf__update_declaration(f, in->dt_s, 0);
            return HSTPF_OK;
        }
    }
    if (has_y && !gated) {
        f->outlier_run = 0;
    }
    has_y = has_y && !gated;
    /* all checks passed: from here on the step cannot fail */
    e = hstpf__engine_of(f);
    hstpf__trac_check_begin(f, !free_run, free_run ? 0.0 : f->xi * in->traction, in->dt_s);
    trac_known = !free_run && !f->tc.release;
    /* a traction that cannot be right is not used, nor one that holds a train that moves */
    free_run = free_run || f->tc.fault || f->tc.release;
    xu = free_run ? 0.0 : f->xi * in->traction; /* free: each model's own balance (hstpf__step_xu) */
    st.dt = in->dt_s;
    st.xu = xu;
    st.yr = has_y ? in->position_m - f->origin_m : 0.0;
    st.scale = (double)(real)sqrt(in->dt_s / f->cfg.dt_nominal_s);
    st.has_y = has_y;
    st.free_run = free_run;
    if (free_run) {
        st.acc_var = hstpf__free_acc_var(f, in->dt_s, has_y);
    } else {
        st.acc_var = 0.0;
        f->free_s = 0.0;
    }
    engines_step(f, e, &st);
    {
        const int hold = hstpf__weights_hold(f, in->dt_s, has_y);
        f->standstill = (uint8_t)(hold == 2);
        f->weights_wait = (uint8_t)(hold != 0);
        /* one standstill's length; when one of HSTPF_CONSIST_STOP_S ends,
         * the next weighted step mixes the consist's prior */
        if (f->standstill) {
            f->stop_s += in->dt_s;
        } else if (!f->weights_wait) {
            f->mix_pending = (uint8_t)(f->mix_pending || f->stop_s >= HSTPF_CONSIST_STOP_S);
            f->stop_s = 0.0;
        }
    }
    if (has_y) {
        /* every model that carries weight put this fix beyond its floor:
         * the fixes and the estimate disagree (a train moving although
         * held, a time base that broke); a run of these re-acquires */
        f->lost_run = hstpf__all_lost(f) ? (uint16_t)(f->lost_run + (f->lost_run < UINT16_MAX)) : 0u;
    }
    {
        /* a step whose traction is unknown, a lone outlier and a lock on
         * probation test nothing. At a
         * standstill each fix counts for at most 1 nat: a train held a few
         * metres from where it stopped fits the fixes worse than the shadow
         * while they pull it there (hstpf-mc --scenario gain5, DFH3 seed 45:
         * the CUSUM reached 24.8 of 25 nats at a stop; 10.3 now), but a
         * traction whose sign is swapped holds the models while the train
         * departs, which only these steps show (not tested at all, tracsign
         * published 12 % more wrong steps) */
        hstpf__trac_check_end(f, &st, trac_known && f->lost_run != 1u && !f->pr.active, f->standstill);
    }
    /* The first such fix after fixes they fitted is taken for an outlier
     * (a heavy-tailed noise's): it moves no weight. Otherwise a model at
     * the weight floor that happens to lie near it would take all the
     * weight for that step. A second one in a row moves them as usual. */
    weigh = has_y && !f->weights_wait && f->lost_run != 1u && !f->pr.active && !free_run && !f->tc.fault &&
            !f->tc.doubt;
    if (weigh) {
        if (f->mix_pending && f->cfg.consist_change_p > 0.0) {
            hstpf__consist_mix(f, f->cfg.consist_change_p); /* the first evidence after a long stop */
        }
        f->mix_pending = 0;
        hstpf__update_model_weights(f);
    }
    if (has_y && f->cfg.model_reacquire_after > 0u) {
        hstpf__models_reacquire(f, (real)st.yr);
    }
    if (e->after_weights != NULL) {
        e->after_weights(f, &st);
    }
    advance_time(f, in->dt_s);
    if (!finite_models(f)) {
        hstpf__nonfinite_reset(f);
        hstpf__update_declaration(f, in->dt_s, 0);
        return gated ? HSTPF_E_OUTLIER : HSTPF_OK;
    }
    hstpf__update_declaration(f, in->dt_s, weigh);
    {
        const double rel = hstpf__blended_position(f, 0.0, NULL, NULL); /* one blend for both (soft-float exp on the M4F) */
        const double s_m = f->origin_m + rel;
        hstpf__rebase(f, rel);
        if (has_y && hstpf__ran_backwards(f, s_m, in->position_m)) {
            return gated ? HSTPF_E_OUTLIER : HSTPF_OK;
        }
        if (has_y && (f->pr.active || f->pr.timed)) {
            hstpf__probation(f, s_m, in->position_m);
        }
    }
    if (has_y && f->prior_lock) {
        /* two fixes in a row beyond every weighted model's floor: the
         * prior was wrong; one may be an outlier (a lone 40 m fix at a
         * platform re-placed the models at 39 m/s, valid: a review) */
        if (f->lost_run >= 2u) {
            prior_replace(f, in, free_run);
            return HSTPF_OK;
        }
        f->prior_lock = (uint8_t)(f->lost_run != 0u); /* 0: the prior's speed confirmed by a fix */
    }
    if (f->cfg.reacquire_after > 0u && (f->lost_run >= f->cfg.reacquire_after ||
                                         (f->engine != (uint8_t)HSTPF_ENGINE_PARTICLE && !f->weights_wait &&
                                          f->lost_run >= HSTPF__LOST_REACQUIRE))) {
        /* this fix pairs with the next; after the early two
         * (HSTPF__LOST_REACQUIRE) it may be an outlier (a multipath burst:
         * paired with the next good fix it gave a speed 17 m/s low), so the
         * next two pair */
        const int early = f->lost_run < f->cfg.reacquire_after;
        ++f->reacquired;
        f->lost_run = 0;
        hstpf__drop_lock(f, 0);
        f->have_pend = (uint8_t)!early;
        f->pend_y = in->position_m;
        f->pend_age_s = 0.0;
    }
    return gated ? HSTPF_E_OUTLIER : HSTPF_OK;
}
