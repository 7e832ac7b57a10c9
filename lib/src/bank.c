/* The bank: life cycle, the step, the model weights (paper Eq. 14), the
 * declaration (Table 2) and the blended estimate. How each model's state and
 * likelihood are computed is the engine's (engine.h). */
#include <math.h>
#include <string.h>

#include "dist_impl.h"
#include "engine.h"
#include "internal.h"
#include "refine.h"
#include "rng_impl.h"
#include "track.h"

#define REBASE_M 1024.0 /* re-centre the float positions past this distance */

typedef hstpf_real_t real;

static int fin(double x)
{
    return isfinite(x) ? 1 : 0;
}

hstpf_engine_t hstpf__engine_resolve(const hstpf_config_t *cfg)
{
    if (cfg->engine == HSTPF_ENGINE_AUTO) {
        return hstpf__all_gaussian(cfg) ? HSTPF_ENGINE_KALMAN : HSTPF_ENGINE_GRID;
    }
    return cfg->engine;
}

/* The one place an engine is chosen. */
const hstpf__engine_t *hstpf__engine_of(const hstpf_t *f)
{
    switch ((hstpf_engine_t)f->engine) {
    case HSTPF_ENGINE_KALMAN: return &hstpf__engine_kalman;
    case HSTPF_ENGINE_GRID: return &hstpf__engine_grid;
    default: return &hstpf__engine_particle;
    }
}

/* log q of hypothesis i: the rows, then the continuous one. */
static double *logq_of(hstpf_t *f, uint16_t i)
{
    return i < f->cfg.n_models ? &f->m[i].logq : &f->rf.logq;
}

static uint16_t n_hyp(const hstpf_t *f)
{
    return (uint16_t)(f->cfg.n_models + f->rf.active);
}

static void reset_state(hstpf_t *f)
{
    uint16_t l;
    const double q0 = f->rf.active ? f->cfg.refine_prior_q : 0.0;
    const double lq = log((1.0 - q0) / (double)f->cfg.n_models);
    f->rf.logq = f->rf.active ? log(q0) : 0.0;
    f->rf.placed = 0;
    f->rf.nis = 1.0;
    f->fit = HSTPF_FIT_UNKNOWN;
    f->fit_held_s = 0.0;
    for (l = 0; l < f->cfg.n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        m->logq = lq;
        m->s_mean = m->v_mean = m->loglik = 0;
        m->ess = (real)f->cfg.n_particles;
        m->floor_hits = 0;
        m->floor_run = 0;
        m->track_hint = 0;
    }
    f->origin_m = 0.0;
    f->time_s = 0.0;
    f->held_s = 0.0;
    f->decision_time_s = -1.0;
    f->steps = 0;
    f->leader = -1;
    f->declared = -1;
    f->status = HSTPF_STATUS_UNDECIDED;
    f->have_fix = 0;
    f->have_pend = 0;
    f->ever_locked = 0;
    f->acquisitions = 0;
    f->nonfinite_resets = 0;
    f->standstill = 0;
    f->outlier_run = 0;
    f->lost_run = 0;
}

/* Noise tables; the specs were checked, so these cannot fail. */
static void init_tables(hstpf_t *f, const hstpf_config_t *cfg)
{
    const int particles = f->engine == (uint8_t)HSTPF_ENGINE_PARTICLE;
    hstpf_dist_spec_t unit;
    memset(&unit, 0, sizeof unit);
    unit.kind = HSTPF_DIST_GAUSSIAN;
    unit.sd = 1.0;
    (void)hstpf_dist_init(&f->ds, &cfg->noise_s);
    (void)hstpf_dist_init(&f->dv, &cfg->noise_v);
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
    (void)hstpf_dist_init(&f->unit, &unit);
}

int32_t hstpf_init(hstpf_t *f, size_t f_size, const hstpf_config_t *cfg)
{
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
    memset(f, 0, sizeof *f);
    f->cfg = *cfg;
    f->cfg.models = NULL; /* copied below: the caller's arrays need not live on */
    f->cfg.track = NULL;
    f->xi = HSTPF_G_ACC / (1.0 + cfg->gamma_rot) / 1000.0;
    f->engine = (uint8_t)hstpf__engine_resolve(cfg);
    f->rf.active = (uint8_t)(cfg->refine && cfg->refine_prior_q > 0.0 &&
                             f->engine == (uint8_t)HSTPF_ENGINE_KALMAN);
    for (l = 0; l < cfg->n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        f->theta[l] = cfg->models[l];
        /* a = xi u - k0 - k1 v - k2 v^2 with v in m/s */
        m->k0 = (real)(f->xi * cfg->models[l].c0);
        m->k1 = (real)(f->xi * cfg->models[l].c1 * 3.6);
        m->k2 = (real)(f->xi * cfg->models[l].c2 * 12.96);
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

/* Lock from fixes: with a configured speed prior the first fix starts the
 * filter; otherwise a fix waits for the next one (at most max_gap_s later,
 * with a speed that is physically possible) and both place the models. The
 * model weights and the declaration are kept. Returns 1 when locked now. */
static int acquire(hstpf_t *f, double y, double xu)
{
    hstpf__acq_t q;
    q.xu = xu;
    q.v0 = f->cfg.init_speed_mps;
    q.t12 = 0.0;
    if (f->cfg.init_speed_sd <= 0.0) {
        const double t = f->pend_age_s; /* >= this step's dt > 0: time advanced first */
        if (!f->have_pend || !(t <= f->cfg.max_gap_s) ||
            fabs(y - f->pend_y) > HSTPF_SPEED_MAX * t) {
            f->have_pend = 1;
            f->pend_y = y;
            f->pend_age_s = 0.0;
            return 0;
        }
        q.t12 = t;
    }
    f->origin_m = floor(y);
    hstpf__track_rebase(f);
    q.y1 = f->pend_y - f->origin_m;
    q.y2 = y - f->origin_m;
    hstpf__engine_of(f)->place_all(f, &q);
    if (f->rf.active) {
        /* (s, v) as the rows' filters have them; theta from the prior the
         * first time, kept from what was learnt afterwards */
        const hstpf_model_t *m0 = &f->m[0];
        if (!f->rf.placed) {
            hstpf__refine_place(f, m0->kx[0], m0->kx[1], m0->kp[0], m0->kp[1], m0->kp[2]);
            f->rf.placed = 1;
        } else {
            hstpf__refine_replace_sv(f, m0->kx[0], m0->kx[1], m0->kp[0], m0->kp[1], m0->kp[2]);
        }
    }
    f->have_pend = 0;
    f->have_fix = 1;
    f->ever_locked = 1;
    f->outlier_run = 0;
    ++f->acquisitions;
    return 1;
}

/* Drops the lock; the next fixes acquire again. keep_pend: the last fix
 * (a gated one) belongs to the new time base and may pair with the next. */
static void drop_lock(hstpf_t *f, int keep_pend)
{
    f->have_fix = 0;
    if (!keep_pend) {
        f->have_pend = 0;
    }
    f->standstill = 0;
    f->lost_run = 0;
}

static void update_model_weights(hstpf_t *f)
{
    const uint16_t nh = n_hyp(f);
    const double lfloor = f->cfg.q_floor > 0.0 ? log(f->cfg.q_floor) : -HUGE_VAL;
    double mx = -HUGE_VAL, sum = 0.0, lsum;
    uint16_t l;
    int pass;
    for (l = 0; l < f->cfg.n_models; ++l) {
        f->m[l].logq += (double)f->m[l].loglik;
    }
    if (f->rf.active) {
        f->rf.logq += f->rf.loglik;
    }
    /* Eq. 14 by log-sum-exp; then the floor, and normalise again */
    for (pass = 0; pass < 2; ++pass) {
        mx = -HUGE_VAL;
        sum = 0.0;
        for (l = 0; l < nh; ++l) {
            mx = *logq_of(f, l) > mx ? *logq_of(f, l) : mx;
        }
        for (l = 0; l < nh; ++l) {
            sum += exp(*logq_of(f, l) - mx);
        }
        lsum = mx + log(sum);
        for (l = 0; l < nh; ++l) {
            double *lq = logq_of(f, l);
            *lq -= lsum;
            if (pass == 0 && *lq < lfloor) {
                *lq = lfloor;
            }
        }
    }
}

/* What is off when no row fits, from the continuous hypothesis against the
 * nearest row in W(v) over 0-350 km/h: a gain k credibly away from 1; a
 * difference that is mostly constant in v (c0-like: gradient, offset); or
 * the coefficients in general. */
static uint8_t off_what(const hstpf_t *f)
{
    const hstpf_refine_t *r = &f->rf;
    double th[3], cov[9], best = HUGE_VAL, d0 = 0.0, dall = 0.0;
    uint16_t l, lb = 0;
    int k;
    uint8_t bits = 0;
    hstpf__refine_theta(f, th, cov);
    for (l = 0; l < f->cfg.n_models; ++l) {
        double e = 0.0;
        for (k = 0; k <= 7; ++k) {
            const double v = 50.0 * k;
            const double d = (th[0] - f->theta[l].c0) + (th[1] - f->theta[l].c1) * v +
                             (th[2] - f->theta[l].c2) * v * v;
            e += d * d;
        }
        if (e < best) {
            best = e;
            lb = l;
        }
    }
    for (k = 0; k <= 7; ++k) {
        const double v = 50.0 * k;
        const double dc0 = th[0] - f->theta[lb].c0;
        const double d = dc0 + (th[1] - f->theta[lb].c1) * v + (th[2] - f->theta[lb].c2) * v * v;
        d0 += (d - dc0) * (d - dc0); /* what is left once the c0 offset is removed */
        dall += d * d;
    }
    if (fabs(r->kz[5] - 1.0) > 3.0 * sqrt(r->kp[HSTPF_REFINE_NZ * HSTPF_REFINE_NZ - 1])) {
        bits |= HSTPF_OFF_GAIN;
    }
    if (d0 < 0.25 * dall) { /* dall = 0 makes d0 = 0: COEF */
        bits |= HSTPF_OFF_C0;
    } else {
        bits |= HSTPF_OFF_COEF;
    }
    if (r->nis > 3.0) {
        bits |= HSTPF_OFF_INNOV;
    }
    return bits;
}

/* "No table type fits": the continuous hypothesis held above
 * declare_threshold as long as a declaration needs; it ends when its weight
 * falls below withdraw_threshold. */
static void update_fit(hstpf_t *f, double dt, int evidence)
{
    if (!f->rf.active) {
        f->fit = (uint8_t)(f->declared >= 0 ? HSTPF_FIT_TABLE : HSTPF_FIT_UNKNOWN);
        return;
    }
    if (exp(f->rf.logq) > f->cfg.declare_threshold) {
        f->fit_held_s += evidence ? dt : 0.0;
    } else {
        f->fit_held_s = 0.0;
    }
    if (f->fit_held_s >= f->cfg.declare_hold_s && f->fit_held_s > 0.0) {
        f->fit = HSTPF_FIT_NONE;
    } else if (f->fit == HSTPF_FIT_NONE && exp(f->rf.logq) >= f->cfg.withdraw_threshold) {
        /* stays until the weight says otherwise */
    } else {
        f->fit = (uint8_t)(f->declared >= 0 ? HSTPF_FIT_TABLE : HSTPF_FIT_UNKNOWN);
    }
}

/* The declaration state machine of hstpf.h. The hold timer runs only on
 * steps that carry evidence: not at standstill, not without a fix. */
static void update_declaration(hstpf_t *f, double dt, int evidence)
{
    int16_t best = 0;
    uint16_t l;
    for (l = 1; l < f->cfg.n_models; ++l) {
        if (f->m[l].logq > f->m[best].logq) {
            best = (int16_t)l;
        }
    }
    if (f->declared >= 0 && exp(f->m[f->declared].logq) < f->cfg.withdraw_threshold) {
        f->declared = -1;
        f->status = HSTPF_STATUS_WITHDRAWN;
        f->decision_time_s = -1.0;
    }
    if (exp(f->m[best].logq) > f->cfg.declare_threshold) {
        if (best == f->leader) {
            f->held_s += evidence ? dt : 0.0;
        } else {
            f->leader = best;
            f->held_s = 0.0;
        }
    } else {
        f->leader = -1;
        f->held_s = 0.0;
    }
    if (f->leader >= 0 && f->held_s >= f->cfg.declare_hold_s && f->leader != f->declared) {
        f->status = f->declared < 0 ? HSTPF_STATUS_DECLARED : HSTPF_STATUS_CHANGED;
        f->declared = f->leader;
        f->decision_time_s = f->time_s;
    }
    update_fit(f, dt, evidence);
}

/* Weights for blended estimates: q less the floor, normalised, for the
 * rows (wb[0..n-1]) and the continuous hypothesis (wb[n], 0 when off). The
 * floor keeps a model able to recover; it must not let a model that lost
 * the train pull the estimates. */
static void blend_weights(const hstpf_t *f, double *wb)
{
    const uint16_t n = f->cfg.n_models, nh = n_hyp(f);
    double sum = 0.0;
    uint16_t l;
    wb[n] = 0.0;
    for (l = 0; l < nh; ++l) {
        const double q = exp(l < n ? f->m[l].logq : f->rf.logq) - f->cfg.q_floor;
        wb[l] = q > 0.0 ? q : 0.0;
        sum += wb[l];
    }
    for (l = 0; l < nh; ++l) {
        wb[l] = sum > 0.0 ? wb[l] / sum : 1.0 / (double)nh;
    }
}

static double blended_position(const hstpf_t *f, double dt_ahead)
{
    double s = 0.0, wb[HSTPF_MAX_MODELS + 1];
    uint16_t l;
    blend_weights(f, wb);
    for (l = 0; l < f->cfg.n_models; ++l) {
        const hstpf_model_t *m = &f->m[l];
        s += wb[l] * ((double)m->s_mean + dt_ahead * (double)m->v_mean);
    }
    s += wb[f->cfg.n_models] * (f->rf.kz[0] + dt_ahead * f->rf.kz[1]);
    return s;
}

/* Keep float positions small: shift the origin by whole metres. */
static void rebase(hstpf_t *f)
{
    const double rel = blended_position(f, 0.0);
    real d;
    if (fabs(rel) < REBASE_M) {
        return;
    }
    d = (real)floor(rel);
    hstpf__engine_of(f)->shift(f, d);
    f->rf.kz[0] -= (double)d;
    f->origin_m += (double)d;
    hstpf__track_rebase(f);
}

/* A model whose every particle has been at the floor for
 * model_reacquire_after measurements has lost the train (its dynamics are
 * wrong, or the train changed): it is placed again at the fix, with the
 * blended speed, so that it can recover if it becomes right. Its weight is
 * kept. */
static void models_reacquire(hstpf_t *f, real yr)
{
    const hstpf__engine_t *e = hstpf__engine_of(f);
    double wb[HSTPF_MAX_MODELS + 1], vb = 0.0;
    uint16_t l;
    blend_weights(f, wb);
    for (l = 0; l < f->cfg.n_models; ++l) {
        vb += wb[l] * (double)f->m[l].v_mean;
    }
    for (l = 0; l < f->cfg.n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        if (m->floor_run >= f->cfg.model_reacquire_after) {
            hstpf__acq_t q;
            q.y1 = q.y2 = (double)yr;
            q.t12 = 0.0;
            q.xu = 0.0;
            q.v0 = vb;
            e->place_one(f, m, &q);
            m->floor_run = 0;
            ++m->reacquired;
        }
    }
}

int32_t hstpf_reacquire(hstpf_t *f)
{
    if (f == NULL) {
        return HSTPF_E_NULL;
    }
    if (f->magic != HSTPF_MAGIC) {
        return HSTPF_E_INIT;
    }
    drop_lock(f, 0);
    return HSTPF_OK;
}

/* Every state, variance and log weight finite. x * 0 is 0 for a finite x
 * and NaN for a NaN or an infinity, so one sum tells (no overflow). */
static int finite_models(const hstpf_t *f)
{
    double z = 0.0;
    uint16_t l;
    int i;
    for (l = 0; l < f->cfg.n_models; ++l) {
        const hstpf_model_t *m = &f->m[l];
        z += (double)m->s_mean * 0.0 + (double)m->v_mean * 0.0 + (double)m->s_var * 0.0 +
             (double)m->v_var * 0.0 + m->logq * 0.0;
    }
    for (i = 0; i < HSTPF_REFINE_NZ; ++i) { /* zero while the hypothesis is off */
        z += f->rf.kz[i] * 0.0 + f->rf.kp[i * (HSTPF_REFINE_NZ + 1)] * 0.0;
    }
    return z + f->rf.logq * 0.0 == 0.0;
}

/* A filter that went non-finite starts again from the next fixes: uniform
 * weights if those are lost too. Counted in nonfinite_resets. */
static void nonfinite_reset(hstpf_t *f)
{
    uint16_t l;
    const uint16_t nh = n_hyp(f);
    for (l = 0; l < nh; ++l) {
        if (!fin(*logq_of(f, l))) {
            for (l = 0; l < nh; ++l) {
                *logq_of(f, l) = -log((double)nh);
            }
            break;
        }
    }
    f->rf.placed = 0; /* its theta too may be what went non-finite */
    ++f->nonfinite_resets;
    drop_lock(f, 0);
}

/* Standstill: every model that carries weight is held at rest. The data
 * then say nothing about W(v) (docs/model.md), so no model weight moves. */
static int at_standstill(const hstpf_t *f)
{
    double wb[HSTPF_MAX_MODELS + 1];
    uint16_t l;
    blend_weights(f, wb);
    for (l = 0; l < f->cfg.n_models; ++l) {
        if (wb[l] > 0.0 && !f->m[l].held) {
            return 0;
        }
    }
    return !(wb[f->cfg.n_models] > 0.0 && !f->rf.held);
}

static int all_lost(const hstpf_t *f)
{
    double wb[HSTPF_MAX_MODELS + 1];
    uint16_t l;
    blend_weights(f, wb);
    for (l = 0; l < f->cfg.n_models; ++l) {
        if (wb[l] > 0.0 && f->m[l].floor_run == 0u) {
            return 0;
        }
    }
    return 1;
}

/* Time passes without a lock: only the pending fix ages. */
static void advance_time(hstpf_t *f, double dt)
{
    f->time_s += dt;
    f->pend_age_s += dt;
    ++f->steps;
}

int32_t hstpf_step(hstpf_t *f, const hstpf_input_t *in)
{
    int has_y = (in != NULL && in->has_position) ? 1 : 0, gated = 0;
    const hstpf__engine_t *e;
    hstpf__step_t st;
    if (f == NULL || in == NULL) {
        return HSTPF_E_NULL;
    }
    if (f->magic != HSTPF_MAGIC) {
        return HSTPF_E_INIT;
    }
    if (!fin(in->dt_s) || !fin(in->traction) || (has_y && !fin(in->position_m))) {
        return HSTPF_E_NONFINITE;
    }
    if (!(in->dt_s > 0.0 && in->dt_s <= HSTPF_DT_MAX_S)) {
        return HSTPF_E_DT;
    }
    if (fabs(in->traction) > HSTPF_U_MAX || (has_y && fabs(in->position_m) > HSTPF_POS_MAX_M)) {
        return HSTPF_E_RANGE;
    }
    if (f->have_fix && in->dt_s > f->cfg.max_gap_s) {
        drop_lock(f, 0); /* too long to predict across: re-acquire */
        f->have_pend = 0;
    }
    if (!f->have_fix) {
        advance_time(f, in->dt_s);
        if (has_y) {
            (void)acquire(f, in->position_m, f->xi * in->traction);
        }
        f->standstill = 0;
        update_declaration(f, in->dt_s, 0);
        return HSTPF_OK;
    }
    if (has_y && f->cfg.gate_m > 0.0 &&
        fabs(in->position_m - f->origin_m - blended_position(f, in->dt_s)) > f->cfg.gate_m) {
        if (f->cfg.reacquire_after == 0u || f->outlier_run < f->cfg.reacquire_after) {
            ++f->outliers;
            ++f->outlier_run;
            /* the step goes on without its fix; the fix is remembered: a
             * run of these may be the new reference */
            gated = 1;
            f->have_pend = 1;
            f->pend_y = in->position_m;
            f->pend_age_s = -in->dt_s; /* aged to 0 at the end of this step */
        } else {
            /* the reference really moved: acquire again from the gated fixes */
            ++f->reacquired;
            drop_lock(f, 1);
            advance_time(f, in->dt_s);
            (void)acquire(f, in->position_m, f->xi * in->traction);
            update_declaration(f, in->dt_s, 0);
            return HSTPF_OK;
        }
    }
    if (has_y && !gated) {
        f->outlier_run = 0;
    }
    has_y = has_y && !gated;
    /* all checks passed: from here on the step cannot fail */
    e = hstpf__engine_of(f);
    st.dt = in->dt_s;
    st.xu = f->xi * in->traction;
    st.yr = has_y ? in->position_m - f->origin_m : 0.0;
    st.scale = (double)(real)sqrt(in->dt_s / f->cfg.dt_nominal_s);
    st.has_y = has_y;
    e->predict_update(f, &st);
    if (f->rf.active) {
        hstpf__refine_update(f, &st);
    }
    f->standstill = (uint8_t)at_standstill(f);
    if (has_y) {
        /* every model that carries weight put this fix beyond its floor:
         * the fixes and the estimate disagree (a train moving although
         * held, a time base that broke); a run of these re-acquires */
        f->lost_run = all_lost(f) ? (uint16_t)(f->lost_run + 1u) : 0u;
    }
    if (has_y && !f->standstill) {
        update_model_weights(f);
    }
    if (has_y && f->cfg.model_reacquire_after > 0u) {
        models_reacquire(f, (real)st.yr);
    }
    if (e->after_weights != NULL) {
        e->after_weights(f, &st);
    }
    advance_time(f, in->dt_s);
    if (!finite_models(f)) {
        nonfinite_reset(f);
        update_declaration(f, in->dt_s, 0);
        return gated ? HSTPF_E_OUTLIER : HSTPF_OK;
    }
    update_declaration(f, in->dt_s, has_y && !f->standstill);
    rebase(f);
    if (f->cfg.reacquire_after > 0u && f->lost_run >= f->cfg.reacquire_after) {
        ++f->reacquired;
        f->lost_run = 0;
        drop_lock(f, 0);
        f->have_pend = 1; /* this fix pairs with the next */
        f->pend_y = in->position_m;
        f->pend_age_s = 0.0;
    }
    return gated ? HSTPF_E_OUTLIER : HSTPF_OK;
}

/* Every published value finite and within the header's ranges. */
static int in_ranges(const hstpf_estimate_t *o)
{
    const double vals[] = {o->position_m, (double)o->speed_mps, o->position_sd_m, (double)o->speed_sd_mps,
                           (double)o->theta[0], (double)o->theta[1], (double)o->theta[2],
                           (double)o->resistance};
    uint32_t i;
    for (i = 0; i < sizeof vals / sizeof vals[0]; ++i) {
        if (!fin(vals[i])) {
            return 0;
        }
    }
    /* (the sds are square roots of values clamped at 0: never negative) */
    return fabs(o->position_m) <= HSTPF_POS_MAX_M && o->speed_mps >= (real)0 &&
           (double)o->speed_mps <= HSTPF_SPEED_MAX && o->theta[0] >= (real)0 && o->theta[1] >= (real)0 &&
           o->theta[2] >= (real)0;
}

/* The published theta and its covariance: the mixture of the rows (points)
 * and the continuous hypothesis (Gaussian); a declared row is a point. */
static void theta_mixture(const hstpf_t *f, const double *wb, double *th, double *cov)
{
    const uint16_t n = f->cfg.n_models;
    double rth[3] = {0.0, 0.0, 0.0}, rcov[9];
    uint16_t l;
    int i, j;
    memset(cov, 0, sizeof(double) * 9);
    th[0] = th[1] = th[2] = 0.0;
    if (f->declared >= 0) {
        /* Table 2, State A(2): the declared type's own coefficients */
        th[0] = f->theta[f->declared].c0;
        th[1] = f->theta[f->declared].c1;
        th[2] = f->theta[f->declared].c2;
        return;
    }
    if (f->rf.active) {
        hstpf__refine_theta(f, rth, rcov);
    }
    for (l = 0; l < n; ++l) {
        th[0] += wb[l] * f->theta[l].c0;
        th[1] += wb[l] * f->theta[l].c1;
        th[2] += wb[l] * f->theta[l].c2;
    }
    for (i = 0; i < 3; ++i) {
        th[i] += wb[n] * rth[i];
    }
    for (l = 0; l <= n; ++l) {
        const double d[3] = {(l < n ? f->theta[l].c0 : rth[0]) - th[0],
                             (l < n ? f->theta[l].c1 : rth[1]) - th[1],
                             (l < n ? f->theta[l].c2 : rth[2]) - th[2]};
        if (!(wb[l] > 0.0)) {
            continue;
        }
        for (i = 0; i < 3; ++i) {
            for (j = 0; j < 3; ++j) {
                cov[3 * i + j] += wb[l] * (d[i] * d[j] + (l < n ? 0.0 : rcov[3 * i + j]));
            }
        }
    }
}

int32_t hstpf_resistance_band(const hstpf_estimate_t *e, double v_mps, double *w, double *sd)
{
    double h[3], var = 0.0;
    const double *c;
    double cv[6];
    int i, j;
    static const uint8_t idx[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
    if (e == NULL || w == NULL || sd == NULL) {
        return HSTPF_E_NULL;
    }
    if (!fin(v_mps)) {
        return HSTPF_E_NONFINITE;
    }
    h[0] = 1.0;
    h[1] = 3.6 * v_mps;
    h[2] = h[1] * h[1];
    for (i = 0; i < 6; ++i) {
        cv[i] = (double)e->theta_cov[i];
    }
    c = cv;
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) {
            var += h[i] * h[j] * c[idx[i][j]];
        }
    }
    *w = (double)e->theta[0] + (double)e->theta[1] * h[1] + (double)e->theta[2] * h[2];
    *sd = sqrt(var > 0.0 ? var : 0.0);
    return HSTPF_OK;
}

int32_t hstpf_estimate(const hstpf_t *f, hstpf_estimate_t *out)
{
    uint16_t l;
    double s = 0.0, v = 0.0, vs = 0.0, vv = 0.0, th[3] = {0.0, 0.0, 0.0}, cov[9];
    double wb[HSTPF_MAX_MODELS + 1];
    int16_t best = 0;
    if (f == NULL || out == NULL) {
        return HSTPF_E_NULL;
    }
    if (f->magic != HSTPF_MAGIC) {
        return HSTPF_E_INIT;
    }
    memset(out, 0, sizeof *out);
    out->step = f->steps;
    out->time_s = f->time_s;
    out->n_models = f->cfg.n_models;
    blend_weights(f, wb);
    for (l = 0; l < f->cfg.n_models; ++l) {
        const hstpf_model_t *m = &f->m[l];
        hstpf_model_out_t *o = &out->model[l];
        o->q = (real)exp(m->logq);
        o->position_m = f->origin_m + (double)m->s_mean;
        o->speed_mps = m->v_mean;
        o->ess = m->ess;
        o->loglik = m->loglik;
        o->floor_hits = m->floor_hits;
        o->reacquired = m->reacquired;
        s += wb[l] * (double)m->s_mean;
        v += wb[l] * (double)m->v_mean;
        if (m->logq > f->m[best].logq) {
            best = (int16_t)l;
        }
    }
    s += wb[f->cfg.n_models] * f->rf.kz[0];
    v += wb[f->cfg.n_models] * f->rf.kz[1];
    /* the mixture's variance: within each model plus between the models */
    for (l = 0; l < f->cfg.n_models; ++l) {
        const hstpf_model_t *m = &f->m[l];
        const double ds = (double)m->s_mean - s, dv = (double)m->v_mean - v;
        vs += wb[l] * ((double)m->s_var + ds * ds);
        vv += wb[l] * ((double)m->v_var + dv * dv);
    }
    if (f->rf.active) {
        const double wr = wb[f->cfg.n_models], ds = f->rf.kz[0] - s, dv = f->rf.kz[1] - v;
        vs += wr * (f->rf.kp[0] + ds * ds);
        vv += wr * (f->rf.kp[HSTPF_REFINE_NZ + 1] + dv * dv);
        out->q_offtable = (real)exp(f->rf.logq);
        out->gain = (real)f->rf.kz[5];
        out->gain_sd = (real)sqrt(f->rf.kp[HSTPF_REFINE_NZ * HSTPF_REFINE_NZ - 1]);
    } else {
        out->gain = 1;
    }
    theta_mixture(f, wb, th, cov);
    out->theta_cov[0] = (real)cov[0];
    out->theta_cov[1] = (real)cov[1];
    out->theta_cov[2] = (real)cov[2];
    out->theta_cov[3] = (real)cov[4];
    out->theta_cov[4] = (real)cov[5];
    out->theta_cov[5] = (real)cov[8];
    out->fit = (hstpf_fit_t)f->fit;
    out->off_what = f->fit == (uint8_t)HSTPF_FIT_NONE ? off_what(f) : 0u;
    out->position_m = f->ever_locked ? f->origin_m + s : (f->have_pend ? f->pend_y : 0.0);
    out->speed_mps = (real)v;
    out->position_sd_m = sqrt(vs > 0.0 ? vs : 0.0);
    out->speed_sd_mps = (real)sqrt(vv > 0.0 ? vv : 0.0);
    out->theta[0] = (real)th[0];
    out->theta[1] = (real)th[1];
    out->theta[2] = (real)th[2];
    {
        const hstpf_theta_t t = {NULL, th[0], th[1], th[2]};
        out->resistance = (real)hstpf_resistance(&t, v);
    }
    out->standstill = f->standstill;
    out->best = best;
    out->declared = f->declared;
    out->status = f->status;
    out->decision_time_s = f->decision_time_s;
    out->outliers = f->outliers;
    out->reacquired = f->reacquired;
    out->acquisitions = f->acquisitions;
    out->nonfinite_resets = f->nonfinite_resets;
    /* a gated last fix: the fixes and the estimate disagree beyond the
     * gate (a reference jump, or a time base that stepped), so the estimate
     * is not to be trusted until they agree again or it re-acquires */
    out->valid = (uint8_t)(f->have_fix && f->outlier_run == 0u && f->lost_run == 0u && in_ranges(out));
    return HSTPF_OK;
}
