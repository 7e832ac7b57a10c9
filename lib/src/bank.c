/* The bank: life cycle, the step, the model weights (paper Eq. 14), the
 * declaration (Table 2) and the blended estimate. How each model's state and
 * likelihood are computed is the engine's (engine.h). */
#include <math.h>
#include <string.h>

#include "dist_impl.h"
#include "engine.h"
#include "internal.h"
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
        return hstpf__all_gaussian(cfg) ? HSTPF_ENGINE_KALMAN : HSTPF_ENGINE_PARTICLE;
    }
    return cfg->engine;
}

/* The one place an engine is chosen. */
const hstpf__engine_t *hstpf__engine_of(const hstpf_t *f)
{
    switch ((hstpf_engine_t)f->engine) {
    case HSTPF_ENGINE_KALMAN: return &hstpf__engine_kalman;
    default: return &hstpf__engine_particle;
    }
}

static void reset_state(hstpf_t *f)
{
    uint16_t l;
    const double lq = -log((double)f->cfg.n_models);
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
    f->outlier_run = 0;
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

/* Every model placed at the first fix, with the speed prior. */
static void first_fix(hstpf_t *f, double y)
{
    f->origin_m = floor(y);
    hstpf__track_rebase(f);
    hstpf__engine_of(f)->place_all(f, (real)(y - f->origin_m), (real)f->cfg.init_speed_mps);
    f->have_fix = 1;
}

static void update_model_weights(hstpf_t *f)
{
    const uint16_t nm = f->cfg.n_models;
    const double lfloor = f->cfg.q_floor > 0.0 ? log(f->cfg.q_floor) : -HUGE_VAL;
    double mx = -HUGE_VAL, sum = 0.0, lsum;
    uint16_t l;
    int pass;
    for (l = 0; l < nm; ++l) {
        f->m[l].logq += (double)f->m[l].loglik;
    }
    /* Eq. 14 by log-sum-exp; then the floor, and normalise again */
    for (pass = 0; pass < 2; ++pass) {
        mx = -HUGE_VAL;
        sum = 0.0;
        for (l = 0; l < nm; ++l) {
            mx = f->m[l].logq > mx ? f->m[l].logq : mx;
        }
        for (l = 0; l < nm; ++l) {
            sum += exp(f->m[l].logq - mx);
        }
        lsum = mx + log(sum);
        for (l = 0; l < nm; ++l) {
            f->m[l].logq -= lsum;
            if (pass == 0 && f->m[l].logq < lfloor) {
                f->m[l].logq = lfloor;
            }
        }
    }
}

static void update_declaration(hstpf_t *f, double dt)
{
    int16_t best = 0;
    uint16_t l;
    for (l = 1; l < f->cfg.n_models; ++l) {
        if (f->m[l].logq > f->m[best].logq) {
            best = (int16_t)l;
        }
    }
    if (exp(f->m[best].logq) > f->cfg.declare_threshold) {
        if (best == f->leader) {
            f->held_s += dt;
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
}

/* Weights for blended estimates: q_l less the floor, normalised. The floor
 * keeps a model able to recover; it must not let a model that lost the
 * train pull the estimates. */
static void blend_weights(const hstpf_t *f, double *wb)
{
    double sum = 0.0;
    uint16_t l;
    for (l = 0; l < f->cfg.n_models; ++l) {
        const double q = exp(f->m[l].logq) - f->cfg.q_floor;
        wb[l] = q > 0.0 ? q : 0.0;
        sum += wb[l];
    }
    for (l = 0; l < f->cfg.n_models; ++l) {
        wb[l] = sum > 0.0 ? wb[l] / sum : 1.0 / (double)f->cfg.n_models;
    }
}

static double blended_position(const hstpf_t *f, double dt_ahead)
{
    double s = 0.0, wb[HSTPF_MAX_MODELS];
    uint16_t l;
    blend_weights(f, wb);
    for (l = 0; l < f->cfg.n_models; ++l) {
        const hstpf_model_t *m = &f->m[l];
        s += wb[l] * ((double)m->s_mean + dt_ahead * (double)m->v_mean);
    }
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
    double wb[HSTPF_MAX_MODELS], vb = 0.0;
    uint16_t l;
    blend_weights(f, wb);
    for (l = 0; l < f->cfg.n_models; ++l) {
        vb += wb[l] * (double)f->m[l].v_mean;
    }
    for (l = 0; l < f->cfg.n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        if (m->floor_run >= f->cfg.model_reacquire_after) {
            e->place_one(f, m, yr, (real)vb);
            m->floor_run = 0;
            ++m->reacquired;
        }
    }
}

int32_t hstpf_step(hstpf_t *f, const hstpf_input_t *in)
{
    const int has_y = (in != NULL && in->has_position) ? 1 : 0;
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
    if (!f->have_fix) {
        if (has_y) {
            first_fix(f, in->position_m);
            update_declaration(f, in->dt_s);
        }
        f->time_s += in->dt_s;
        ++f->steps;
        return HSTPF_OK;
    }
    if (has_y && f->cfg.gate_m > 0.0 &&
        fabs(in->position_m - f->origin_m - blended_position(f, in->dt_s)) > f->cfg.gate_m) {
        if (f->cfg.reacquire_after == 0u || f->outlier_run < f->cfg.reacquire_after) {
            ++f->outliers;
            ++f->outlier_run;
            return HSTPF_E_OUTLIER;
        }
        /* the reference really moved: start the particles again there */
        f->outlier_run = 0;
        ++f->reacquired;
        first_fix(f, in->position_m);
        f->time_s += in->dt_s;
        ++f->steps;
        return HSTPF_OK;
    }
    if (has_y) {
        f->outlier_run = 0;
    }
    /* all checks passed: from here on the step cannot fail */
    e = hstpf__engine_of(f);
    st.dt = in->dt_s;
    st.xu = f->xi * in->traction;
    st.yr = has_y ? in->position_m - f->origin_m : 0.0;
    st.scale = (double)(real)sqrt(in->dt_s / f->cfg.dt_nominal_s);
    st.has_y = has_y;
    e->predict_update(f, &st);
    if (has_y) {
        update_model_weights(f);
    }
    if (has_y && f->cfg.model_reacquire_after > 0u) {
        models_reacquire(f, (real)st.yr);
    }
    if (e->after_weights != NULL) {
        e->after_weights(f, &st);
    }
    f->time_s += in->dt_s;
    ++f->steps;
    update_declaration(f, in->dt_s);
    rebase(f);
    return HSTPF_OK;
}

int32_t hstpf_estimate(const hstpf_t *f, hstpf_estimate_t *out)
{
    uint16_t l;
    double v = 0.0, th[3] = {0.0, 0.0, 0.0};
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
    double wb[HSTPF_MAX_MODELS];
    blend_weights(f, wb);
    for (l = 0; l < f->cfg.n_models; ++l) {
        const hstpf_model_t *m = &f->m[l];
        const double q = wb[l];
        hstpf_model_out_t *o = &out->model[l];
        o->q = (real)exp(m->logq);
        o->position_m = f->origin_m + (double)m->s_mean;
        o->speed_mps = m->v_mean;
        o->ess = m->ess;
        o->loglik = m->loglik;
        o->floor_hits = m->floor_hits;
        o->reacquired = m->reacquired;
        v += q * (double)m->v_mean;
        th[0] += q * f->theta[l].c0;
        th[1] += q * f->theta[l].c1;
        th[2] += q * f->theta[l].c2;
        if (m->logq > f->m[best].logq) {
            best = (int16_t)l;
        }
    }
    out->position_m = f->have_fix ? f->origin_m + blended_position(f, 0.0) : 0.0;
    out->speed_mps = (real)v;
    out->theta[0] = (real)th[0];
    out->theta[1] = (real)th[1];
    out->theta[2] = (real)th[2];
    {
        const hstpf_theta_t t = {NULL, th[0], th[1], th[2]};
        out->resistance = (real)hstpf_resistance(&t, v);
    }
    out->best = best;
    out->declared = f->declared;
    out->status = f->status;
    out->decision_time_s = f->decision_time_s;
    out->outliers = f->outliers;
    out->reacquired = f->reacquired;
    return HSTPF_OK;
}

