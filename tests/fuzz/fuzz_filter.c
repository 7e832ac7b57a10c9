/* Fuzz target: hstpf_init / hstpf_step with arbitrary configurations and
 * input sequences. Invariants: init and step return OK or a documented
 * error code; a refused init or step leaves the instance usable; the
 * estimate can always be read; when it says valid, every published field
 * is finite and within the header's ranges, the weights a distribution.
 * After an accepted step with a fix the blended position and speed are
 * finite (issue 11, classes 1-2). */
#include <math.h>

#include "fuzz.h"
#include "hstpf/hstpf.h"

static hstpf_t filt;
static uint64_t ws[HSTPF_WORKSPACE_WORDS(HSTPF_WORKSPACE_MAX_BYTES)];
static hstpf_theta_t models[HSTPF_MAX_MODELS];
static double tx[8], tp[8];

static void noise(fuzz_in_t *in, hstpf_dist_spec_t *d, double typ)
{
    const uint8_t sel = fuzz_u8(in);
    unsigned k;
    memset(d, 0, sizeof *d);
    d->kind = (hstpf_dist_kind_t)(sel % 4u == 3u ? (sel >> 2) % 5u : sel % 3u); /* sometimes not a kind */
    switch (d->kind) {
    case HSTPF_DIST_GAUSSIAN:
        d->mean = fuzz_double(in, -typ, typ);
        d->sd = fuzz_double(in, 1e-3, 3.0 * typ);
        break;
    case HSTPF_DIST_GAMMA:
        d->shape = fuzz_double(in, 1e-3, 10.0);
        d->scale = fuzz_double(in, 1e-3, typ);
        d->loc = fuzz_double(in, -typ, typ);
        break;
    case HSTPF_DIST_TABLE:
        d->table_n = (uint16_t)(fuzz_u8(in) % 9u);
        d->table_x = tx;
        d->table_p = tp;
        for (k = 0; k < 8u; ++k) {
            tx[k] = (k ? tx[k - 1] : -typ) + fuzz_double(in, 0.0, typ);
            tp[k] = fuzz_double(in, 0.0, 1.0);
        }
        break;
    default:
        break;
    }
    if (sel & 0x80u) {
        d->floor_depth = fuzz_double(in, 0.0, 100.0);
        d->edge_soft = fuzz_double(in, 0.0, typ);
    }
}

static int known_error(int32_t rc)
{
    return rc <= HSTPF_OK && rc >= HSTPF_E_OUTLIER;
}

static void check_estimate(const hstpf_estimate_t *e, uint16_t n_models)
{
    unsigned l;
    double sum = 0.0;
    FUZZ_CHECK(e->n_models == n_models, "n_models %u", (unsigned)e->n_models);
    FUZZ_CHECK(e->status <= HSTPF_STATUS_WITHDRAWN, "status %d", (int)e->status);
    FUZZ_CHECK(e->declared >= -1 && e->declared < (int)n_models, "declared %d", (int)e->declared);
    FUZZ_CHECK((e->declared >= 0) == (e->status == HSTPF_STATUS_DECLARED || e->status == HSTPF_STATUS_CHANGED),
               "declared %d with status %d", (int)e->declared, (int)e->status);
    if (!e->valid) {
        return;
    }
    FUZZ_CHECK(isfinite(e->position_m) && fabs(e->position_m) <= HSTPF_POS_MAX_M, "valid, position %g",
               e->position_m);
    FUZZ_CHECK(isfinite((double)e->speed_mps) && fabs((double)e->speed_mps) <= HSTPF_SPEED_MAX, "valid, speed %g",
               (double)e->speed_mps);
    FUZZ_CHECK(isfinite(e->position_sd_m) && e->position_sd_m >= 0.0, "valid, position sd %g", e->position_sd_m);
    FUZZ_CHECK(isfinite((double)e->speed_sd_mps) && e->speed_sd_mps >= 0, "valid, speed sd %g",
               (double)e->speed_sd_mps);
    FUZZ_CHECK(isfinite((double)e->theta[0]) && isfinite((double)e->theta[1]) && isfinite((double)e->theta[2]) &&
                   isfinite((double)e->resistance),
               "valid, theta or resistance not finite");
    FUZZ_CHECK(isfinite(e->time_s), "valid, time %g", e->time_s);
    FUZZ_CHECK(e->theta[0] >= 0 && (double)e->theta[0] <= HSTPF_C0_MAX && e->theta[1] >= 0 &&
                   (double)e->theta[1] <= HSTPF_C1_MAX && e->theta[2] >= 0 && (double)e->theta[2] <= HSTPF_C2_MAX,
               "valid, theta (%g, %g, %g) outside its range", (double)e->theta[0], (double)e->theta[1],
               (double)e->theta[2]);
    for (l = 0; l < 6u; ++l) {
        FUZZ_CHECK(isfinite((double)e->theta_cov[l]), "valid, theta_cov[%u] = %g", l, (double)e->theta_cov[l]);
    }
    FUZZ_CHECK(isfinite((double)e->gain) && isfinite((double)e->gain_sd), "valid, gain %g sd %g", (double)e->gain,
               (double)e->gain_sd);
    for (l = 0; l < n_models; ++l) {
        const hstpf_model_out_t *m = &e->model[l];
        FUZZ_CHECK(isfinite((double)m->q) && m->q >= 0 && m->q <= 1, "valid, q[%u] = %g", l, (double)m->q);
        FUZZ_CHECK(isfinite(m->position_m) && fabs(m->position_m) <= HSTPF_POS_MAX_M, "valid, model %u at %g", l,
                   m->position_m);
        FUZZ_CHECK(m->speed_mps >= 0 && (double)m->speed_mps <= HSTPF_SPEED_MAX, "valid, model %u at %g m/s", l,
                   (double)m->speed_mps);
        sum += (double)m->q;
    }
    /* the rows and the continuous hypothesis (cfg.refine) share the weight */
    sum += (double)e->q_offtable;
    FUZZ_CHECK(fabs(sum - 1.0) < 1e-3, "valid, weights sum to %g", sum);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_in_t in;
    hstpf_config_t cfg;
    hstpf_estimate_t est;
    int32_t rc;
    unsigned i, steps;
    double truth_s = 0.0;

    fuzz_in(&in, data, size);
    (void)hstpf_config_default(&cfg);
    cfg.n_models = (uint16_t)(1u + fuzz_u8(&in) % 4u);
    for (i = 0; i < cfg.n_models; ++i) {
        const uint8_t sel = fuzz_u8(&in);
        if (sel < 200u) {
            models[i] = hstpf_train_types[sel % HSTPF_N_TRAIN_TYPES];
        } else {
            models[i].name = "fuzz";
            models[i].c0 = fuzz_double(&in, 0.0, 50.0);
            models[i].c1 = fuzz_double(&in, 0.0, 1.0);
            models[i].c2 = fuzz_double(&in, 0.0, 0.01);
        }
    }
    cfg.models = models;
    cfg.n_particles = (uint16_t)(fuzz_u8(&in) % 40u); /* 0, 1 refused; small keeps runs fast */
    cfg.seed = fuzz_u64(&in);
    /* from the seed's bits, so the corpus reads as before: off, on, refused */
    cfg.grid_speed_lattice = (uint8_t)((cfg.seed >> 7) % 3u);
    cfg.refine = (uint8_t)((cfg.seed >> 9) % 4u); /* off, on, under any noise, refused */
    {
        const uint8_t e = fuzz_u8(&in);
        cfg.engine = (hstpf_engine_t)(e % 4u);
        cfg.bank = (hstpf_bank_t)((e >> 2) % 3u);
        cfg.resample = (hstpf_resample_t)((e >> 4) % 3u);
        cfg.weight_method = (hstpf_weight_method_t)((e >> 6) % 3u);
    }
    if (fuzz_u8(&in) & 1u) { /* the rest of the options from the input, else defaults */
        cfg.gamma_rot = fuzz_double(&in, 0.0, 1.0);
        noise(&in, &cfg.noise_s, 1.0);
        noise(&in, &cfg.noise_v, 1.0);
        noise(&in, &cfg.noise_e, 10.0);
        cfg.dt_nominal_s = fuzz_double(&in, 0.1, 10.0);
        cfg.init_speed_mps = fuzz_double(&in, -10.0, 100.0);
        cfg.init_speed_sd = fuzz_double(&in, 0.0, 10.0);
        cfg.ess_threshold = fuzz_double(&in, 0.0, 1.0);
        cfg.roughening_k = fuzz_double(&in, 0.0, 2.0);
        cfg.rough_min_s = fuzz_double(&in, 0.0, 10.0);
        cfg.rough_min_v = fuzz_double(&in, 0.0, 1.0);
        cfg.q_floor = fuzz_double(&in, 0.0, 0.1);
        cfg.declare_threshold = fuzz_double(&in, 0.5, 1.0);
        cfg.declare_hold_s = fuzz_double(&in, 0.0, 100.0);
        cfg.withdraw_threshold = fuzz_double(&in, 0.0, 1.0);
        cfg.max_gap_s = fuzz_double(&in, 0.0, 60.0);
        cfg.gate_m = fuzz_double(&in, 0.0, 2000.0);
        cfg.reacquire_after = fuzz_u8(&in);
        cfg.model_reacquire_after = fuzz_u8(&in);
        cfg.e_blur_sd = fuzz_double(&in, 0.0, 1.0);
    }
    cfg.workspace = ws; /* the fuzzed counts and engine need at most this */
    cfg.workspace_size = sizeof ws;
    rc = hstpf_init(&filt, sizeof filt, &cfg);
    FUZZ_CHECK(known_error(rc), "hstpf_init returned %d", (int)rc);
    {
        const char *field = NULL;
        const int32_t chk = hstpf_config_check(&cfg, &field);
        FUZZ_CHECK(chk == rc, "hstpf_config_check %d but hstpf_init %d", (int)chk, (int)rc);
        FUZZ_CHECK(field != NULL && (chk == HSTPF_OK) == (field[0] == '\0'), "field '%s' for %d",
                   field ? field : "(null)", (int)chk);
    }
    if (rc != HSTPF_OK) {
        return 0;
    }
    FUZZ_CHECK(hstpf_estimate(&filt, &est) == HSTPF_OK, "estimate after init");
    check_estimate(&est, cfg.n_models);

    for (steps = 0; steps < 4000u && in.i < in.n; ++steps) {
        hstpf_input_t u = {0};
        const uint8_t op = fuzz_u8(&in);
        if (op == 0xFFu) {
            FUZZ_CHECK(hstpf_reset(&filt) == HSTPF_OK, "reset");
            continue;
        }
        u.dt_s = op & 0x40u ? fuzz_double(&in, 0.0, 70.0) : 1.0;
        u.traction = op & 0x20u ? fuzz_double(&in, -1100.0, 1100.0) : 5.0;
        truth_s += 50.0 * (isfinite(u.dt_s) && u.dt_s > 0.0 && u.dt_s <= 60.0 ? u.dt_s : 0.0);
        u.has_position = (uint8_t)(op & 1u);
        u.traction_unknown = (uint8_t)((op & 0x0Eu) == 0x0Eu); /* one op in eight: traction then not read */
        if (u.traction_unknown && (op & 0x80u)) {
            u.traction = NAN; /* an unknown traction is not read, whatever it holds */
        }
        u.position_m = op & 0x10u ? fuzz_double(&in, -1e8, 1e8) : truth_s + fuzz_range(&in, -5.0, 5.0);
        rc = hstpf_step(&filt, &u);
        FUZZ_CHECK(known_error(rc), "hstpf_step returned %d", (int)rc);
        FUZZ_CHECK(hstpf_estimate(&filt, &est) == HSTPF_OK, "estimate after step");
        check_estimate(&est, cfg.n_models);
        if (rc == HSTPF_OK && u.has_position) { /* issue 11, class 2 (fixed) */
            FUZZ_CHECK(isfinite(est.position_m) && isfinite((double)est.speed_mps),
                       "step %u accepted a fix, estimate position %g speed %g", steps, est.position_m,
                       (double)est.speed_mps);
        }
    }
    return 0;
}
