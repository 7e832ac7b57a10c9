/* Configuration: the documented defaults and the one table of ranges that
 * hstpf_init(), hstpf_config_check() and the daemon all use. */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "dist_impl.h"
#include "internal.h"

int32_t hstpf_config_default(hstpf_config_t *cfg)
{
    if (cfg == NULL) {
        return HSTPF_E_NULL;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->n_particles = 100;
    cfg->seed = 1;
    cfg->engine = HSTPF_ENGINE_AUTO;
    cfg->bank = HSTPF_BANK_INDEPENDENT;
    cfg->gamma_rot = 0.06;
    cfg->noise_s.kind = HSTPF_DIST_GAUSSIAN;
    cfg->noise_s.sd = sqrt(0.02);
    cfg->noise_v.kind = HSTPF_DIST_GAUSSIAN;
    cfg->noise_v.sd = sqrt(0.05);
    cfg->noise_e.kind = HSTPF_DIST_GAUSSIAN;
    cfg->noise_e.sd = sqrt(5.0);
    cfg->dt_nominal_s = 1.0;
    cfg->init_speed_mps = 0.0;
    cfg->init_speed_sd = 0.0; /* unknown: from the first two fixes */
    cfg->resample = HSTPF_RESAMPLE_ESS;
    cfg->ess_threshold = 0.5;
    cfg->roughening_k = 0.2;
    cfg->weight_method = HSTPF_WEIGHT_MARGINAL;
    cfg->q_floor = 1e-9;
    cfg->declare_threshold = 0.99;
    cfg->declare_hold_s = 30.0;
    cfg->withdraw_threshold = 0.5;
    cfg->consist_change_p = 0.01; /* docs/model.md, "A consist that changes at a station" */
    cfg->max_gap_s = 30.0;
    cfg->gate_m = 1000.0;
    cfg->accel_unknown_sd = 0.5;
    cfg->reacquire_after = 5;
    cfg->refine = 1;
    cfg->refine_prior_q = 0.01;
    cfg->refine_spread = 0.3; /* docs/model.md, "Prior" */
    cfg->refine_gain_sd = 0.0; /* k fixed at 1: see hstpf.h */
    cfg->grid_speed_lattice = 1; /* docs/grid.md, "The speed lattice" */
    cfg->grid_rows = 3; /* docs/grid.md, "Rows on the grid" */
    cfg->traction_check = 1; /* docs/model.md, "A traction that cannot be right" */
    cfg->fix_step = 1;       /* docs/model.md, "A step in the fixes" */
    return HSTPF_OK;
}

int hstpf__all_gaussian(const hstpf_config_t *c)
{
    return c->noise_s.kind == HSTPF_DIST_GAUSSIAN && c->noise_v.kind == HSTPF_DIST_GAUSSIAN &&
           c->noise_e.kind == HSTPF_DIST_GAUSSIAN;
}

/* One row per real-valued field: [lo, hi], each end open or closed, and the
 * code a value outside gives (RANGE for physical quantities, CONFIG for
 * tuning options). Bounds come from physics: no time shorter than 1 us,
 * speeds within HSTPF_SPEED_MAX, distances within HSTPF_POS_MAX_M. */
typedef struct {
    const char *name;
    size_t offset;
    double lo, hi;
    uint8_t lo_open, hi_open;
    int32_t err;
} range_t;

#define ROW(field, lo, lo_open, hi, hi_open, err)                                                   \
    { #field, offsetof(hstpf_config_t, field), lo, hi, lo_open, hi_open, err }

static const range_t ranges[] = {
    ROW(gamma_rot, 0.0, 0, 1.0, 0, HSTPF_E_RANGE),
    ROW(init_speed_mps, -HSTPF_SPEED_MAX, 0, HSTPF_SPEED_MAX, 0, HSTPF_E_RANGE),
    ROW(init_speed_sd, 0.0, 0, HSTPF_SPEED_MAX, 0, HSTPF_E_RANGE),
    ROW(dt_nominal_s, 1e-6, 0, HSTPF_DT_MAX_S, 0, HSTPF_E_CONFIG),
    ROW(ess_threshold, 0.0, 1, 1.0, 0, HSTPF_E_CONFIG),
    ROW(roughening_k, 0.0, 0, 10.0, 0, HSTPF_E_CONFIG),
    ROW(rough_min_s, 0.0, 0, 1000.0, 0, HSTPF_E_CONFIG),
    ROW(rough_min_v, 0.0, 0, HSTPF_SPEED_MAX, 0, HSTPF_E_CONFIG),
    ROW(q_floor, 0.0, 0, 1.0, 1, HSTPF_E_CONFIG),
    ROW(declare_threshold, 0.5, 1, 1.0, 1, HSTPF_E_CONFIG),
    ROW(declare_hold_s, 0.0, 0, 1e6, 0, HSTPF_E_CONFIG),
    ROW(withdraw_threshold, 0.0, 0, 1.0, 1, HSTPF_E_CONFIG),
    ROW(consist_change_p, 0.0, 0, 0.5, 0, HSTPF_E_CONFIG),
    ROW(max_gap_s, 1e-6, 0, HSTPF_DT_MAX_S, 0, HSTPF_E_CONFIG),
    ROW(gate_m, 0.0, 0, HSTPF_POS_MAX_M, 0, HSTPF_E_CONFIG),
    ROW(accel_unknown_sd, 0.0, 1, 10.0, 0, HSTPF_E_CONFIG),
    ROW(e_blur_sd, 0.0, 0, 100.0, 0, HSTPF_E_CONFIG),
    ROW(refine_prior_q, 0.0, 0, 0.5, 0, HSTPF_E_CONFIG),
    ROW(refine_spread, 0.0, 0, 1.0, 0, HSTPF_E_CONFIG),
    ROW(refine_gain_sd, 0.0, 0, 0.5, 0, HSTPF_E_CONFIG),
};

static int in_range(const range_t *r, double x)
{
    const int lo_ok = r->lo_open ? x > r->lo : x >= r->lo;
    const int hi_ok = r->hi_open ? x < r->hi : x <= r->hi;
    return lo_ok && hi_ok;
}

static int32_t fail(const char **field, const char *name, int32_t err)
{
    if (field != NULL) {
        *field = name;
    }
    return err;
}

static int32_t check_theta(const hstpf_theta_t *t, const char **field)
{
    if (!isfinite(t->c0) || !isfinite(t->c1) || !isfinite(t->c2)) {
        return fail(field, "models", HSTPF_E_NONFINITE);
    }
    if (t->c0 < 0.0 || t->c0 > HSTPF_C0_MAX) {
        return fail(field, "models.c0", HSTPF_E_RANGE);
    }
    if (t->c1 < 0.0 || t->c1 > HSTPF_C1_MAX) {
        return fail(field, "models.c1", HSTPF_E_RANGE);
    }
    if (t->c2 < 0.0 || t->c2 > HSTPF_C2_MAX) {
        return fail(field, "models.c2", HSTPF_E_RANGE);
    }
    return HSTPF_OK;
}

static int32_t check_track(const hstpf_config_t *c, const char **field)
{
    uint16_t i;
    for (i = 0; i < c->n_track; ++i) {
        const hstpf_track_seg_t *t = &c->track[i];
        if (!isfinite(t->start_m) || !isfinite(t->gradient_permille) || !isfinite(t->curve_radius_m)) {
            return fail(field, "track", HSTPF_E_NONFINITE);
        }
        if (fabs(t->start_m) > HSTPF_POS_MAX_M || (i > 0u && !(t->start_m > c->track[i - 1u].start_m))) {
            return fail(field, "track.start_m", HSTPF_E_RANGE);
        }
        if (fabs(t->gradient_permille) > 100.0) {
            return fail(field, "track.gradient_permille", HSTPF_E_RANGE);
        }
        if (t->curve_radius_m != 0.0 && (t->curve_radius_m < 100.0 || t->curve_radius_m > 1e7)) {
            return fail(field, "track.curve_radius_m", HSTPF_E_RANGE);
        }
    }
    return HSTPF_OK;
}

static int32_t check_enums(const hstpf_config_t *c, const char **field)
{
    if (c->engine != HSTPF_ENGINE_PARTICLE && c->engine != HSTPF_ENGINE_KALMAN &&
        c->engine != HSTPF_ENGINE_AUTO && c->engine != HSTPF_ENGINE_GRID) {
        return fail(field, "engine", HSTPF_E_CONFIG);
    }
    if (c->engine == HSTPF_ENGINE_KALMAN && !hstpf__all_gaussian(c)) {
        return fail(field, "engine", HSTPF_E_CONFIG);
    }
    if (c->bank != HSTPF_BANK_INDEPENDENT && c->bank != HSTPF_BANK_PAIRED) {
        return fail(field, "bank", HSTPF_E_CONFIG);
    }
    if (c->resample != HSTPF_RESAMPLE_ALWAYS && c->resample != HSTPF_RESAMPLE_ESS) {
        return fail(field, "resample", HSTPF_E_CONFIG);
    }
    if (c->weight_method != HSTPF_WEIGHT_MARGINAL && c->weight_method != HSTPF_WEIGHT_PAPER) {
        return fail(field, "weight_method", HSTPF_E_CONFIG);
    }
    if (c->traction_check > 1u) {
        return fail(field, "traction_check", HSTPF_E_CONFIG);
    }
    if (c->fix_step > 1u) {
        return fail(field, "fix_step", HSTPF_E_CONFIG);
    }
    if (c->grid_speed_lattice > 1u) {
        return fail(field, "grid_speed_lattice", HSTPF_E_CONFIG);
    }
    if (c->grid_rows > HSTPF_MAX_MODELS) {
        return fail(field, "grid_rows", HSTPF_E_CONFIG);
    }
    if (c->refine > 2u) {
        return fail(field, "refine", HSTPF_E_CONFIG);
    }
    return HSTPF_OK;
}

int32_t hstpf__config_check(const hstpf_config_t *c, const char **field)
{
    uint32_t i;
    int32_t err;
    if (field != NULL) {
        *field = "";
    }
    if (c->models == NULL) {
        return fail(field, "models", HSTPF_E_NULL);
    }
    if (c->n_track > 0u && c->track == NULL) {
        return fail(field, "track", HSTPF_E_NULL);
    }
    if (c->n_models < 1u || c->n_models > HSTPF_MAX_MODELS) {
        return fail(field, "n_models", HSTPF_E_SIZE);
    }
    if (c->n_particles < 2u || c->n_particles > HSTPF_MAX_PARTICLES) {
        return fail(field, "n_particles", HSTPF_E_SIZE);
    }
    if (c->n_track > HSTPF_MAX_TRACK_SEGMENTS) {
        return fail(field, "n_track", HSTPF_E_SIZE);
    }
    for (i = 0; i < sizeof ranges / sizeof ranges[0]; ++i) {
        const double x = *(const double *)(const void *)((const char *)c + ranges[i].offset);
        if (!isfinite(x)) {
            return fail(field, ranges[i].name, HSTPF_E_NONFINITE);
        }
    }
    for (i = 0; i < c->n_models; ++i) {
        err = check_theta(&c->models[i], field);
        if (err != HSTPF_OK) {
            return err;
        }
    }
    for (i = 0; i < sizeof ranges / sizeof ranges[0]; ++i) {
        const double x = *(const double *)(const void *)((const char *)c + ranges[i].offset);
        if (!in_range(&ranges[i], x)) {
            return fail(field, ranges[i].name, ranges[i].err);
        }
    }
    err = check_enums(c, field);
    if (err != HSTPF_OK) {
        return err;
    }
    /* ranges that depend on another field */
    if (c->q_floor * (double)c->n_models >= 1.0) {
        return fail(field, "q_floor", HSTPF_E_CONFIG);
    }
    if (c->withdraw_threshold < c->q_floor || c->withdraw_threshold > c->declare_threshold) {
        return fail(field, "withdraw_threshold", HSTPF_E_CONFIG);
    }
    if (c->e_blur_sd > 0.0 && c->noise_e.kind == HSTPF_DIST_TABLE) {
        return fail(field, "e_blur_sd", HSTPF_E_CONFIG);
    }
    err = check_track(c, field);
    if (err != HSTPF_OK) {
        return err;
    }
    if ((err = hstpf__dist_check(&c->noise_s)) != HSTPF_OK) {
        return fail(field, "noise_s", err);
    }
    if ((err = hstpf__dist_check(&c->noise_v)) != HSTPF_OK) {
        return fail(field, "noise_v", err);
    }
    if ((err = hstpf__dist_check(&c->noise_e)) != HSTPF_OK) {
        return fail(field, "noise_e", err);
    }
    return HSTPF_OK;
}

int32_t hstpf_config_check(const hstpf_config_t *cfg, const char **field)
{
    if (cfg == NULL) {
        return fail(field, "cfg", HSTPF_E_NULL);
    }
    return hstpf__config_check(cfg, field);
}
