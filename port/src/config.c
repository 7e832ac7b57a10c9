/* hstpfd: the configuration's defaults, the helpers its parsers share and
 * the library configuration it gives. */
#include "config_internal.h"
#include "hstpf_frames.h" /* the DBC's E2E receiver parameters of the inputs: the defaults below */

#if HSTPF_FRAME_POSITION_E2E_MAX_DELTA != HSTPF_FRAME_TRACTION_E2E_MAX_DELTA
#error "e2e_max_delta is one key for both inputs: the DBC gives them different HstpfE2EMaxDeltaCounter"
#endif

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

void hstpfd__fail(char *err, size_t size, const char *fmt, ...)
{
    va_list ap;
    if (err == NULL || size == 0) {
        return;
    }
    va_start(ap, fmt);
    (void)vsnprintf(err, size, fmt, ap);
    va_end(ap);
}

void hstpfd__gaussian(hstpf_dist_spec_t *d, double mean, double sd)
{
    memset(d, 0, sizeof *d);
    d->kind = HSTPF_DIST_GAUSSIAN;
    d->mean = mean;
    d->sd = sd;
}

void hstpfd__gamma(hstpf_dist_spec_t *d, double shape, double scale, double loc)
{
    memset(d, 0, sizeof *d);
    d->kind = HSTPF_DIST_GAMMA;
    d->shape = shape;
    d->scale = scale;
    d->loc = loc;
}

void hstpfd__preset(hstpfd_config_t *c, int cas)
{
    if (cas == 1) { /* variances 0.02, 0.05, 5 */
        hstpfd__gaussian(&c->noise_s, 0.0, sqrt(0.02));
        hstpfd__gaussian(&c->noise_v, 0.0, sqrt(0.05));
        hstpfd__gaussian(&c->noise_e, 0.0, sqrt(5.0));
    } else {
        hstpfd__gamma(&c->noise_s, 0.02, 0.1, 0.0);
        hstpfd__gamma(&c->noise_v, 0.1, 0.05, 0.0);
        hstpfd__gamma(&c->noise_e, 0.5, 0.2, 0.0);
    }
}

static void all_models(hstpfd_config_t *c)
{
    uint16_t i;
    for (i = 0; i < HSTPF_N_TRAIN_TYPES && i < HSTPF_MAX_MODELS; ++i) {
        (void)snprintf(c->model_name[i], HSTPFD_NAME_MAX, "%s", hstpf_train_types[i].name);
        c->models[i] = hstpf_train_types[i];
        c->models[i].name = c->model_name[i];
    }
    c->n_models = i;
}

void hstpfd_config_default(hstpfd_config_t *c)
{
    hstpf_config_t fc;
    memset(c, 0, sizeof *c);
    (void)hstpf_config_default(&fc);
    all_models(c);
    c->particles = fc.n_particles;
    c->engine = fc.engine;
    c->seed = 1;
    c->gamma_rot = fc.gamma_rot;
    hstpfd__preset(c, 1);
    c->dt_nominal_s = fc.dt_nominal_s;
    c->init_speed_mps = fc.init_speed_mps;
    c->init_speed_sd = fc.init_speed_sd;
    c->roughening_k = fc.roughening_k;
    c->e_blur_sd = fc.e_blur_sd;
    c->grid_speed_lattice = fc.grid_speed_lattice;
    c->refine = fc.refine;
    c->grid_rows = fc.grid_rows;
    c->declare_threshold = fc.declare_threshold;
    c->declare_hold_s = fc.declare_hold_s;
    c->gate_m = fc.gate_m;
    c->accel_unknown_sd = fc.accel_unknown_sd;
    c->traction_check = fc.traction_check;
    c->fix_step = fc.fix_step;
    c->consist_change_p = fc.consist_change_p;
    c->mass_t = 500.0;
    c->sched.step_period_s = 1.0;
    c->sched.pos_timeout_s = HSTPF_FRAME_POSITION_E2E_TIMEOUT_MS / 1000.0;
    c->sched.trac_timeout_s = HSTPF_FRAME_TRACTION_E2E_TIMEOUT_MS / 1000.0;
    c->sched.predict_period_s = 1.0;
    c->sched.max_gap_s = 600.0;
    c->sched.traction_mode = HSTPFD_TRACTION_MEAN;
    c->sched.stale_policy = HSTPFD_STALE_PREDICT;
    c->e2e_max_delta = HSTPF_FRAME_POSITION_E2E_MAX_DELTA;
    c->rx_filter = HSTPFD_RX_FILTER_BLOCK;
    c->time_scale = 1.0;
    c->tick_s = 0.1;
    c->send = 1;
    c->reopen_s = 1.0;
    c->out_format = HSTPFD_OUT_JSONL;
}

char *hstpfd__trim(char *s)
{
    char *e;
    while (*s == ' ' || *s == '\t') {
        ++s;
    }
    e = s + strlen(s);
    while (e > s && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\r' || e[-1] == '\n')) {
        *--e = '\0';
    }
    return s;
}

void hstpfd_config_filter(const hstpfd_config_t *c, hstpf_config_t *fc)
{
    (void)hstpf_config_default(fc);
    fc->models = c->models;
    fc->n_models = c->n_models;
    fc->n_particles = c->particles;
    fc->engine = c->engine;
    fc->seed = c->seed;
    fc->gamma_rot = c->gamma_rot;
    fc->noise_s = c->noise_s;
    fc->noise_v = c->noise_v;
    fc->noise_e = c->noise_e;
    fc->dt_nominal_s = c->dt_nominal_s;
    fc->init_speed_mps = c->init_speed_mps;
    fc->init_speed_sd = c->init_speed_sd;
    fc->roughening_k = c->roughening_k;
    fc->e_blur_sd = c->e_blur_sd;
    fc->grid_speed_lattice = c->grid_speed_lattice;
    fc->refine = (uint8_t)c->refine;
    fc->grid_rows = c->grid_rows;
    fc->declare_threshold = c->declare_threshold;
    fc->declare_hold_s = c->declare_hold_s;
    fc->gate_m = c->gate_m;
    fc->accel_unknown_sd = c->accel_unknown_sd;
    fc->traction_check = c->traction_check;
    fc->fix_step = c->fix_step;
    fc->consist_change_p = c->consist_change_p;
    /* the daemon's gap rule (sched.c: a gap between positions beyond
     * max_gap_s re-acquires) governs; the library's per-step one, left at
     * its 30 s, dropped the lock at every step when step_period_s or
     * predict_period_s was above it (up to HSTPF_DT_MAX_S), silently; a
     * value out of range is sched.c's to refuse */
    fc->max_gap_s = HSTPF_DT_MAX_S;
    if (c->sched.max_gap_s > 0.0 && c->sched.max_gap_s < HSTPF_DT_MAX_S) {
        fc->max_gap_s = c->sched.max_gap_s;
    }
}
