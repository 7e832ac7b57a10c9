/* hstpfd: the daemon's logic (see core.h). */
#include "core.h"

#include <math.h>
#include <string.h>

#include "candump.h"

static const char *const err_names[11] = {"other",        "E_NULL",  "E_INIT",   "E_SIZE",
                                          "E_NONFINITE",  "E_DT",    "E_RANGE",  "E_ABI",
                                          "E_DIST",       "E_CONFIG", "E_OUTLIER"};

static const char *const class_names[HSTPFD_ERR_N_CLASSES] = {
    "tx_timeout", "lost_arbitration", "controller", "protocol", "transceiver",
    "no_ack",     "bus_off",          "bus_error",  "restarted"};

const char *hstpfd_err_class_name(unsigned i)
{
    return i < HSTPFD_ERR_N_CLASSES ? class_names[i] : "unknown";
}

const char *hstpfd_err_name(int32_t code)
{
    if (code == HSTPF_OK) {
        return "OK";
    }
    if (code < 0 && code >= -10) {
        return err_names[-code];
    }
    return err_names[0];
}

static const char *status_name(hstpf_status_t s)
{
    switch (s) {
    case HSTPF_STATUS_DECLARED:
        return "declared";
    case HSTPF_STATUS_CHANGED:
        return "changed";
    case HSTPF_STATUS_WITHDRAWN:
        return "withdrawn";
    default:
        return "undecided";
    }
}

/* ---- output helpers --------------------------------------------------- */

static void json_str(FILE *fp, const char *s)
{
    fputc('"', fp);
    for (; *s != '\0'; ++s) {
        const unsigned char ch = (unsigned char)*s;
        if (ch == '"' || ch == '\\') {
            fputc('\\', fp);
            fputc(ch, fp);
        } else if (ch < 0x20u) {
            fprintf(fp, "\\u%04x", (unsigned)ch);
        } else {
            fputc(ch, fp);
        }
    }
    fputc('"', fp);
}

static void json_num(FILE *fp, double x)
{
    if (x == x && x < HUGE_VAL && x > -HUGE_VAL) {
        fprintf(fp, "%.9g", x);
    } else {
        fputs("null", fp);
    }
}

static void json_time(FILE *fp, int64_t t_us)
{
    const int64_t s = t_us >= 0 ? t_us / 1000000 : -((-t_us + 999999) / 1000000);
    fprintf(fp, "%lld.%06ld", (long long)s, (long)(t_us - s * 1000000));
}

static void csv_str(FILE *fp, const char *s)
{
    fputc('"', fp);
    for (; *s != '\0'; ++s) {
        if (*s == '"') {
            fputc('"', fp);
        }
        fputc(*s, fp);
    }
    fputc('"', fp);
}

/* ---- init -------------------------------------------------------------- */

static void on_step(void *ctx, const hstpfd_step_t *st);

int hstpfd_core_init(hstpfd_core_t *c, const hstpfd_config_t *cfg, hstpf_t *filt, hstpfd_send_fn send,
                     void *send_ctx, FILE *out, FILE *frames_out, const char *bus)
{
    hstpf_config_t fc;
    int32_t rc;
    uint16_t l;
    memset(c, 0, sizeof *c);
    c->cfg = cfg;
    c->filt = filt;
    c->send = send;
    c->send_ctx = send_ctx;
    c->out = out;
    c->frames_out = frames_out;
    (void)snprintf(c->bus, sizeof c->bus, "%s", bus != NULL ? bus : "can0");
    hstpfd_config_filter(cfg, &fc);
    rc = hstpf_init(filt, sizeof *filt, &fc);
    if (rc != HSTPF_OK) {
        return rc;
    }
    if (hstpfd_sched_init(&c->sched, &cfg->sched, on_step, c) != 0) {
        return HSTPFD_E_SCHED;
    }
    if (hstpfd_rx_init(&c->rx, (uint8_t)cfg->e2e_max_delta, (uint32_t)(cfg->sched.pos_timeout_s * 1000.0 + 0.5),
                       (uint32_t)(cfg->sched.trac_timeout_s * 1000.0 + 0.5)) != 0) {
        return -100;
    }
    hstpfd_tx_init(&c->tx);
    for (l = 0; l < cfg->n_models; ++l) {
        const int32_t r = hstpf_train_type_find(cfg->models[l].name);
        c->row[l] = (r >= 0 && hstpf_train_types[r].c0 == cfg->models[l].c0 &&
                     hstpf_train_types[r].c1 == cfg->models[l].c1 && hstpf_train_types[r].c2 == cfg->models[l].c2)
                        ? (int)r
                        : -2;
    }
    c->tick_us = (int64_t)(cfg->tick_s * 1e6 / cfg->time_scale + 0.5);
    if (c->tick_us < 1000) {
        c->tick_us = 1000; /* 1 ms of source time: the poll timeout's resolution */
    }
    c->declared_prev = -1;
    (void)hstpf_estimate(filt, &c->est);
    if (out != NULL && cfg->out_format == HSTPFD_OUT_CSV) {
        static const char *const pre[2] = {"q_", "ess_"};
        int w;
        fputs("t,k,dt,u,y,err,valid,pos,speed,pos_sd,speed_sd,standstill,acquisitions,c0,c1,c2,best,declared,status,"
              "pos_stale,trac_stale,restart",
              out);
        for (w = 0; w < 2; ++w) {
            for (l = 0; l < cfg->n_models; ++l) {
                char col[HSTPFD_NAME_MAX + 8];
                (void)snprintf(col, sizeof col, "%s%s", pre[w], cfg->models[l].name);
                fputc(',', out);
                csv_str(out, col);
            }
        }
        fputc('\n', out);
    }
    return 0;
}

/* ---- outputs ----------------------------------------------------------- */


/* The library fills position_sd_m / speed_sd_mps (with its lock API). */
#define LIB_HAS_SD HSTPFD_LIB_LOCK_API

static int lib_valid(const hstpf_estimate_t *e)
{
#if HSTPFD_LIB_LOCK_API
    return e->valid != 0;
#else
    (void)e;
    return 1;
#endif
}

/* Every number published as valid is finite and within the library's
 * documented ranges, and the filter has lock (docs/daemon.md, "Validity"). */
static int est_valid(const hstpfd_core_t *c)
{
    const hstpf_estimate_t *e = &c->est;
    uint16_t l;
    if (!c->have_fix || !lib_valid(e) || !isfinite(e->position_m) || fabs(e->position_m) > HSTPF_POS_MAX_M ||
        !isfinite((double)e->speed_mps) || !isfinite(e->position_sd_m) || !isfinite((double)e->speed_sd_mps)) {
        return 0;
    }
    for (l = 0; l < 3; ++l) {
        if (!isfinite((double)e->theta[l])) {
            return 0;
        }
    }
    for (l = 0; l < e->n_models; ++l) {
        if (!isfinite((double)e->model[l].q)) {
            return 0;
        }
    }
    return 1;
}

static void tx_values(const hstpfd_core_t *c, hstpfd_tx_values_t *v)
{
    const hstpf_estimate_t *e = &c->est;
    const hstpf_e2e_counts_t *p = hstpf_e2e_rx_counts(&c->rx.pos);
    const hstpf_e2e_counts_t *t = hstpf_e2e_rx_counts(&c->rx.trac);
    memset(v, 0, sizeof *v);
    v->have_fix = c->have_fix;
    v->valid = (uint8_t)est_valid(c);
    v->position_m = e->position_m;
    v->speed_mps = (double)e->speed_mps;
    v->position_sd_m = e->position_sd_m;
    v->speed_sd_mps = (double)e->speed_sd_mps;
    v->sd_valid = (uint8_t)LIB_HAS_SD;
    v->standstill = e->standstill;
    v->acquisitions = e->acquisitions;
    if (c->sched.have_fix && c->have_est_t) {
        /* the step's end on the fix clock: the inverse of the fix clock's mapping */
        const int64_t ms = (c->est_t_us - c->sched.fix_off) / 1000;
        const int64_t w = (int64_t)HSTPFD_FIX_WRAP_MS;
        v->est_time_valid = 1;
        v->est_time_ms = (uint16_t)(((ms % w) + w) % w);
    }
    v->status = e->status;
    /* a weight that is not finite names no type */
    if (e->declared >= 0 && e->declared < (int)e->n_models && isfinite((double)e->model[e->declared].q)) {
        v->declared_row = c->row[e->declared];
        v->declared_q = (double)e->model[e->declared].q;
    } else {
        v->declared_row = -1;
    }
    if (c->have_fix && e->best >= 0 && e->best < (int)e->n_models && isfinite((double)e->model[e->best].q)) {
        v->leader_row = c->row[e->best];
        v->leader_q = (double)e->model[e->best].q;
    } else {
        v->leader_row = -1;
    }
    v->theta[0] = (double)e->theta[0];
    v->theta[1] = (double)e->theta[1];
    v->theta[2] = (double)e->theta[2];
    v->pos_stale = c->sched.pos_stale;
    v->trac_stale = c->sched.trac_stale;
    v->bad_crc = p->bad_crc + t->bad_crc;
    v->repeated = p->repeated + t->repeated;
    v->jump = p->jump + t->jump;
    v->wrong_length = p->wrong_length + t->wrong_length;
    v->stale_events = p->stale + t->stale;
    v->unknown_id = c->n.unknown;
    v->error_frames = c->n.error;
    v->degeneracy = c->n.degeneracy;
    v->clock_fwd = c->sched.n.clock_fwd;
    v->clock_back = c->sched.n.clock_back;
    v->late = c->sched.n.late;
    v->reacquire = c->n.reacquire;
}

static void transmit(hstpfd_core_t *c, unsigned i)
{
    hstpfd_tx_values_t v;
    hstpfd_frame_t f;
    tx_values(c, &v);
    if (hstpfd_tx_encode(&c->tx, i, &v, &f) != 0) {
        ++c->n.tx_errors;
        return;
    }
    f.t_us = c->src_now; /* the source's clock, as a bus recording has it */
    if (c->frames_out != NULL) {
        char line[256];
        if (hstpfd_candump_format(&f, c->bus, line, sizeof line) > 0) {
            fputs(line, c->frames_out);
        }
    }
    if (c->send != NULL && c->cfg->send) {
        const int r = c->send(c->send_ctx, &f);
        if (r == 0) {
            ++c->n.tx_frames;
        } else if (r == HSTPFD_SEND_OFFLINE) {
            ++c->n.tx_offline;
        } else {
            ++c->n.tx_errors;
        }
    } else {
        ++c->n.tx_skipped;
    }
}

/* The periodic outputs that are due at t_now. */
static void tx_service(hstpfd_core_t *c)
{
    unsigned i;
    for (i = 1; i < HSTPFD_N_OUTPUTS; ++i) {
        const int64_t cyc = hstpfd_tx_cycle_us(i);
        if (i == HSTPFD_OUT_QUALITY) {
            continue; /* goes with the state */
        }
        if (c->t_now >= c->next_tx[i]) {
            transmit(c, i);
            c->next_tx[i] += cyc;
            if (c->next_tx[i] <= c->t_now) {
                c->next_tx[i] = c->t_now + cyc;
            }
        }
    }
}

/* A number of the step stream: %.*g, or, if it is not finite, JSON null /
 * an empty CSV cell (the line's valid field is then 0). */
static void out_num(FILE *fp, int csv, double x, int prec)
{
    if (isfinite(x)) {
        fprintf(fp, "%.*g", prec, x);
    } else if (!csv) {
        fputs("null", fp);
    }
}

/* The separator before a field: "," in CSV, ,"key": in JSON. */
static void out_key(FILE *fp, int csv, const char *key)
{
    if (csv) {
        fputc(',', fp);
    } else {
        fprintf(fp, ",\"%s\":", key);
    }
}

static void write_step(hstpfd_core_t *c, const hstpfd_step_t *st, int32_t rc)
{
    const hstpf_estimate_t *e = &c->est;
    const hstpfd_config_t *cfg = c->cfg;
    FILE *fp = c->out;
    const int csv = cfg->out_format == HSTPFD_OUT_CSV;
    const int valid = est_valid(c);
    uint16_t l;
    const char *best = c->have_fix && e->best >= 0 && e->best < (int)cfg->n_models ? cfg->models[e->best].name : NULL;
    const char *decl = e->declared >= 0 && e->declared < (int)cfg->n_models ? cfg->models[e->declared].name : NULL;
    if (fp == NULL) {
        return;
    }
    if (csv) {
        json_time(fp, st->t_us);
        fprintf(fp, ",%lu", (unsigned long)c->sched.n.steps);
    } else {
        fputs("{\"t\":", fp);
        json_time(fp, st->t_us);
        fprintf(fp, ",\"k\":%lu", (unsigned long)c->sched.n.steps);
    }
    out_key(fp, csv, "dt");
    out_num(fp, csv, st->in.dt_s, 9);
    out_key(fp, csv, "u");
    out_num(fp, csv, st->in.traction, 9);
    out_key(fp, csv, "y");
    out_num(fp, csv, st->in.has_position ? st->in.position_m : HUGE_VAL, 9);
    out_key(fp, csv, "err");
    if (rc != HSTPF_OK) {
        if (csv) {
            fputs(hstpfd_err_name(rc), fp);
        } else {
            json_str(fp, hstpfd_err_name(rc));
        }
    } else if (!csv) {
        fputs("null", fp);
    }
    if (csv) {
        fprintf(fp, ",%d", valid ? 1 : 0);
    } else {
        fprintf(fp, ",\"valid\":%s", valid ? "true" : "false");
    }
    out_key(fp, csv, "pos");
    out_num(fp, csv, e->position_m, 9);
    out_key(fp, csv, "speed");
    out_num(fp, csv, (double)e->speed_mps, 9);
    out_key(fp, csv, "pos_sd"); /* null until the library provides it */
    out_num(fp, csv, LIB_HAS_SD ? e->position_sd_m : HUGE_VAL, 6);
    out_key(fp, csv, "speed_sd");
    out_num(fp, csv, LIB_HAS_SD ? (double)e->speed_sd_mps : HUGE_VAL, 6);
    out_key(fp, csv, "standstill");
    fprintf(fp, "%u", (unsigned)e->standstill);
    out_key(fp, csv, "acquisitions");
    fprintf(fp, "%lu", (unsigned long)e->acquisitions);
    if (csv) {
        for (l = 0; l < 3; ++l) {
            fputc(',', fp);
            out_num(fp, 1, (double)e->theta[l], 9);
        }
        fputc(',', fp);
        csv_str(fp, best != NULL ? best : "");
        fputc(',', fp);
        csv_str(fp, decl != NULL ? decl : "");
        fprintf(fp, ",%s,%u,%u,%u", status_name(e->status), (unsigned)st->pos_stale, (unsigned)st->trac_stale,
                (unsigned)st->restart);
        for (l = 0; l < e->n_models; ++l) {
            fputc(',', fp);
            out_num(fp, 1, (double)e->model[l].q, 9);
        }
        for (l = 0; l < e->n_models; ++l) {
            fputc(',', fp);
            out_num(fp, 1, (double)e->model[l].ess, 6);
        }
        fputc('\n', fp);
        return;
    }
    fputs(",\"theta\":[", fp);
    for (l = 0; l < 3; ++l) {
        fputs(l ? "," : "", fp);
        out_num(fp, 0, (double)e->theta[l], 9);
    }
    fputs("],\"q\":[", fp);
    for (l = 0; l < e->n_models; ++l) {
        fputs(l ? "," : "", fp);
        out_num(fp, 0, (double)e->model[l].q, 9);
    }
    fputs("],\"ess\":[", fp);
    for (l = 0; l < e->n_models; ++l) {
        fputs(l ? "," : "", fp);
        out_num(fp, 0, (double)e->model[l].ess, 6);
    }
    fputs("],\"best\":", fp);
    if (best != NULL) {
        json_str(fp, best);
    } else {
        fputs("null", fp);
    }
    fputs(",\"declared\":", fp);
    if (decl != NULL) {
        json_str(fp, decl);
    } else {
        fputs("null", fp);
    }
    fprintf(fp, ",\"status\":\"%s\",\"pos_stale\":%u,\"trac_stale\":%u,\"restart\":%u}\n", status_name(e->status),
            (unsigned)st->pos_stale, (unsigned)st->trac_stale, (unsigned)st->restart);
}

/* ---- steps --------------------------------------------------------------- */

/* Drops the lock: after a gap beyond max_gap_s or a clock step the filter
 * starts again from the next fix (hstpf_reacquire keeps the model weights;
 * without the library's lock API, hstpf_reset starts from scratch). */
static void reacquire(hstpfd_core_t *c)
{
#if HSTPFD_LIB_LOCK_API
    (void)hstpf_reacquire(c->filt);
#else
    (void)hstpf_reset(c->filt);
    c->declared_prev = -1;
    memset(c->floor_prev, 0, sizeof c->floor_prev);
#endif
    c->have_fix = 0;
    ++c->n.reacquire;
}

static void on_step(void *ctx, const hstpfd_step_t *st)
{
    hstpfd_core_t *c = (hstpfd_core_t *)ctx;
    int32_t rc;
    uint16_t l;
    int degenerate = 0;
    if (st->restart) {
        reacquire(c);
    }
    rc = hstpf_step(c->filt, &st->in);
    if (rc == HSTPF_OK) {
        ++c->n.step_ok;
        if (st->in.has_position && !c->have_fix) {
            c->have_fix = 1;
            if (!c->had_fix) {
                c->had_fix = 1;
                c->t_first_fix = st->t_us;
            }
        }
    } else {
        ++c->n.step_err[(rc < 0 && rc >= -10) ? -rc : 0];
    }
    (void)hstpf_estimate(c->filt, &c->est);
    /* degeneracy of the model we believe in: every particle of the leader at
     * the likelihood floor (ruled-out models are there nearly always) */
    for (l = 0; l < c->est.n_models; ++l) {
        if (l == (uint16_t)c->est.best && c->est.model[l].floor_hits > c->floor_prev[l]) {
            degenerate = 1;
        }
        c->floor_prev[l] = c->est.model[l].floor_hits;
    }
    if (degenerate) {
        ++c->n.degeneracy;
    }
    if (c->est.declared != c->declared_prev) {
        c->declared_prev = c->est.declared;
        c->have_decision = c->est.declared >= 0;
        c->decision_t = st->t_us;
    }
    hstpfd_core_publish(c, st, rc);
}

void hstpfd_core_publish(hstpfd_core_t *c, const hstpfd_step_t *st, int32_t rc)
{
    c->est_t_us = st->t_us;
    c->have_est_t = 1;
    write_step(c, st, rc);
    /* the estimated state goes out after a step, at most once per cycle */
    if (!c->state_sent || c->t_now - c->last_state_tx >= hstpfd_tx_cycle_us(0) - hstpfd_tx_cycle_us(0) / 50) {
        c->state_sent = 1;
        c->last_state_tx = c->t_now;
        transmit(c, 0);
        transmit(c, HSTPFD_OUT_QUALITY);
    }
}

void hstpfd_core_send(hstpfd_core_t *c, unsigned i)
{
    transmit(c, i);
}

/* ---- time and frames --------------------------------------------------- */

static int64_t frame_time(const hstpfd_core_t *c, int64_t src)
{
    if (c->cfg->time_scale == 1.0) {
        return src;
    }
    return c->src0 + (int64_t)floor((double)(src - c->src0) * c->cfg->time_scale + 0.5);
}

/* A source stamp this far behind the latest time is a step of its clock. */
#define CLOCK_BACK_US INT64_C(1000000)

/* Source time -> the daemon's timeline, which never goes back and never
 * jumps ahead by more than max_gap_s + 1 s (docs/daemon.md, "Time"): a stamp
 * more than 1 s behind the latest, or more than max_gap_s ahead of it, is a
 * clock step; the timeline carries on from the latest time (back) or
 * advances by max_gap_s + 1 s only (forward), the step is counted and the
 * estimator re-acquires at the next fix. */
static void set_time(hstpfd_core_t *c, int64_t src)
{
    int64_t t = frame_time(c, src) + c->base;
    if (t < c->t_now - CLOCK_BACK_US) {
        c->base += c->t_now - t;
        c->last_src = src;
        c->src_now = src;
        t = c->t_now;
        hstpfd_sched_clock_step(&c->sched, t, -1);
    } else if (t > c->t_now + c->sched.gap_us) {
        const int64_t t2 = c->t_now + c->sched.gap_us + CLOCK_BACK_US;
        c->base -= t - t2;
        t = c->t_now = t2;
        hstpfd_sched_clock_step(&c->sched, t, 1);
    }
    if (t > c->t_now) {
        c->t_now = t;
    }
}

static void tick(hstpfd_core_t *c, int64_t src)
{
    ++c->n.ticks;
    c->src_now = src;
    set_time(c, src);
    hstpfd_sched_time(&c->sched, c->t_now);
    hstpfd_rx_poll(&c->rx, (uint32_t)(c->t_now / 1000));
    tx_service(c);
}

static void start_time(hstpfd_core_t *c, int64_t src)
{
    unsigned i;
    c->have_time = 1;
    c->src0 = src;
    c->last_src = src;
    c->src_now = src;
    c->t_first = c->t_now = frame_time(c, src);
    for (i = 0; i < HSTPFD_N_OUTPUTS; ++i) {
        c->next_tx[i] = c->t_first;
    }
    hstpfd_rx_poll(&c->rx, (uint32_t)(c->t_now / 1000)); /* starts the stale clocks */
}

void hstpfd_core_idle(hstpfd_core_t *c, int64_t t_src_us)
{
    if (!c->have_time) {
        return;
    }
    if (frame_time(c, t_src_us) + c->base - c->t_now > c->sched.gap_us) {
        /* a forward step of the clock: one tick, none across it */
        c->last_src = t_src_us;
        tick(c, t_src_us);
        return;
    }
    while (c->last_src + c->tick_us <= t_src_us) {
        if (c->stop != NULL && *c->stop) {
            return;
        }
        c->last_src += c->tick_us;
        tick(c, c->last_src);
    }
}

void hstpfd_core_set_stop(hstpfd_core_t *c, const volatile sig_atomic_t *stop)
{
    c->stop = stop;
    hstpfd_sched_set_stop(&c->sched, stop);
}

int64_t hstpfd_core_idle_due(const hstpfd_core_t *c, int64_t t_src_us)
{
    int64_t d;
    if (!c->have_time) {
        return -1;
    }
    d = c->last_src + c->tick_us - t_src_us;
    return d > 0 ? d : 0;
}

void hstpfd_core_frame(hstpfd_core_t *c, const hstpfd_frame_t *f)
{
    hstpfd_rx_t r;
    uint32_t now_ms;
    if (!c->have_time) {
        start_time(c, f->t_us);
    }
    /* idle ticks for a silence before this frame (strictly before it) */
    if (f->t_us > c->last_src) {
        hstpfd_core_idle(c, f->t_us - 1);
        c->last_src = f->t_us;
    }
    ++c->n.frames;
    if (f->t_us > c->src_now) {
        c->src_now = f->t_us;
    }
    set_time(c, f->t_us);
    if (c->frames_out != NULL && c->cfg->frames_out_inputs) {
        char line[256];
        if (hstpfd_candump_format(f, c->bus, line, sizeof line) > 0) {
            fputs(line, c->frames_out);
        }
    }
    now_ms = (uint32_t)(c->t_now / 1000);
    hstpfd_rx_decode(&c->rx, f, now_ms, &r);
    switch (r.kind) {
    case HSTPFD_RX_POSITION: {
        /* consecutive fixes: the previous accepted position frame was a fix and
         * the alive counter moved on by 1..max_delta since (also across a
         * stale gap: a receive clock step leaves the counter in sequence) */
        const unsigned d_cnt = (r.counter + 15u - c->pos_last_counter) % 15u;
        const int in_seq = c->pos_prev_fix && r.accepted && d_cnt >= 1u && d_cnt <= c->cfg->e2e_max_delta;
        ++c->n.position;
        if (r.accepted || r.e2e == HSTPF_E2E_COUNTER_JUMP) {
            c->pos_prev_fix = r.valid;
            c->pos_last_counter = r.counter;
        }
        if (r.valid) {
            hstpfd_sched_position_at(&c->sched, c->t_now, r.value,
                                     r.has_fix_time ? (int32_t)r.fix_time_ms : HSTPFD_NO_FIX_TIME, in_seq);
        } else {
            if (r.accepted) {
                ++c->n.pos_invalid;
            }
            hstpfd_sched_time(&c->sched, c->t_now);
        }
        break;
    }
    case HSTPFD_RX_TRACTION:
        ++c->n.traction;
        if (r.valid && fabs(hstpfd_traction_unit(r.value, c->cfg->mass_t)) > HSTPF_U_MAX) {
            ++c->n.trac_range;
            hstpfd_sched_time(&c->sched, c->t_now);
        } else if (r.valid) {
            hstpfd_sched_traction(&c->sched, c->t_now, r.value);
        } else {
            if (r.accepted) {
                ++c->n.trac_invalid;
            }
            hstpfd_sched_time(&c->sched, c->t_now);
        }
        break;
    case HSTPFD_RX_ERROR: {
        unsigned i;
        ++c->n.error;
        for (i = 0; i < HSTPFD_ERR_N_CLASSES; ++i) {
            if (f->id & (1u << i)) {
                ++c->n.err_class[i];
            }
        }
        hstpfd_sched_time(&c->sched, c->t_now);
        break;
    }
    case HSTPFD_RX_OUTPUT:
        ++c->n.output;
        hstpfd_sched_time(&c->sched, c->t_now);
        break;
    case HSTPFD_RX_FORMAT:
        ++c->n.format;
        hstpfd_sched_time(&c->sched, c->t_now);
        break;
    default:
        ++c->n.unknown;
        hstpfd_sched_time(&c->sched, c->t_now);
        break;
    }
    hstpfd_rx_poll(&c->rx, now_ms);
    tx_service(c);
}

/* ---- summary ------------------------------------------------------------- */

static void kv(FILE *fp, const char *k, unsigned long v, int first)
{
    fprintf(fp, "%s\"%s\":%lu", first ? "" : ",", k, v);
}

void hstpfd_core_summary(const hstpfd_core_t *c, FILE *fp, const char *source_kind, const char *source,
                         const char *end)
{
    const hstpf_estimate_t *e = &c->est;
    const hstpfd_config_t *cfg = c->cfg;
    const hstpf_e2e_counts_t *p = hstpf_e2e_rx_counts(&c->rx.pos);
    const hstpf_e2e_counts_t *t = hstpf_e2e_rx_counts(&c->rx.trac);
    const hstpfd_sched_counts_t *s = &c->sched.n;
    uint16_t l;
    unsigned i;
    int first;

    fprintf(fp, "{\"summary\":\"hstpfd\",\"version\":\"%d.%d.%d\",\"source\":", HSTPF_VERSION_MAJOR,
            HSTPF_VERSION_MINOR, HSTPF_VERSION_PATCH);
    json_str(fp, source_kind);
    fputs(",\"name\":", fp);
    json_str(fp, source);
    fputs(",\"end\":", fp);
    json_str(fp, end);
    fputs(",\"t_first\":", fp);
    if (c->have_time) {
        json_time(fp, c->t_first);
        fputs(",\"t_last\":", fp);
        json_time(fp, c->t_now);
        fputs(",\"duration_s\":", fp);
        json_num(fp, (double)(c->t_now - c->t_first) / 1e6);
    } else {
        fputs("null,\"t_last\":null,\"duration_s\":0", fp);
    }
    fputs(",\"first_fix_t\":", fp);
    if (c->had_fix) {
        json_time(fp, c->t_first_fix);
    } else {
        fputs("null", fp);
    }
    fprintf(fp, ",\"steps\":%lu,\"predict_steps\":%lu,\"steps_ok\":%lu", (unsigned long)s->steps,
            (unsigned long)s->predict_steps, (unsigned long)c->n.step_ok);
    fputs(",\"declared\":", fp);
    if (e->declared >= 0) {
        json_str(fp, cfg->models[e->declared].name);
    } else {
        fputs("null", fp);
    }
    fprintf(fp, ",\"status\":\"%s\",\"decision_time_s\":", status_name(e->status));
    if (e->declared >= 0 && c->have_decision && c->had_fix) {
        json_num(fp, (double)(c->decision_t - c->t_first_fix) / 1e6);
        fputs(",\"decision_t\":", fp);
        json_time(fp, c->decision_t);
    } else {
        fputs("null,\"decision_t\":null", fp);
    }
    fputs(",\"lib_decision_time_s\":", fp);
    if (e->declared >= 0) {
        json_num(fp, e->decision_time_s);
    } else {
        fputs("null", fp);
    }
    fputs(",\"leader\":", fp);
    if (c->have_fix && e->best >= 0 && e->best < (int)cfg->n_models) {
        json_str(fp, cfg->models[e->best].name);
    } else {
        fputs("null", fp);
    }
    fputs(",\"theta\":[", fp);
    for (i = 0; i < 3; ++i) {
        fputs(i ? "," : "", fp);
        out_num(fp, 0, (double)e->theta[i], 9);
    }
    fprintf(fp, "],\"valid\":%s,\"position_m\":", est_valid(c) ? "true" : "false");
    json_num(fp, e->position_m);
    fputs(",\"speed_mps\":", fp);
    json_num(fp, (double)e->speed_mps);
    fputs(",\"position_sd_m\":", fp);
    json_num(fp, LIB_HAS_SD ? e->position_sd_m : HUGE_VAL);
    fputs(",\"speed_sd_mps\":", fp);
    json_num(fp, LIB_HAS_SD ? (double)e->speed_sd_mps : HUGE_VAL);
    fprintf(fp, ",\"standstill\":%u,\"acquisitions\":%lu,\"nonfinite_resets\":%lu", (unsigned)e->standstill,
            (unsigned long)e->acquisitions, (unsigned long)e->nonfinite_resets);
    fputs(",\"weights\":{", fp);
    for (l = 0; l < e->n_models; ++l) {
        if (l) {
            fputc(',', fp);
        }
        json_str(fp, cfg->models[l].name);
        fputc(':', fp);
        out_num(fp, 0, (double)e->model[l].q, 9);
    }
    fputs("},\"faults\":{", fp);
    kv(fp, "bad_crc", (unsigned long)(p->bad_crc + t->bad_crc), 1);
    kv(fp, "wrong_length", (unsigned long)(p->wrong_length + t->wrong_length), 0);
    kv(fp, "repeated", (unsigned long)(p->repeated + t->repeated), 0);
    kv(fp, "counter_jump", (unsigned long)(p->jump + t->jump), 0);
    kv(fp, "lost", (unsigned long)(p->lost + t->lost), 0);
    kv(fp, "stale_events", (unsigned long)(p->stale + t->stale), 0);
    kv(fp, "position_stale", (unsigned long)s->pos_stale, 0);
    kv(fp, "traction_stale", (unsigned long)s->trac_stale, 0);
    kv(fp, "position_invalid", (unsigned long)c->n.pos_invalid, 0);
    kv(fp, "traction_invalid", (unsigned long)c->n.trac_invalid, 0);
    kv(fp, "traction_range", (unsigned long)c->n.trac_range, 0);
    kv(fp, "unknown_id", (unsigned long)c->n.unknown, 0);
    kv(fp, "bad_format", (unsigned long)c->n.format, 0);
    kv(fp, "error_frames", (unsigned long)c->n.error, 0);
    kv(fp, "late_position", (unsigned long)s->late, 0);
    kv(fp, "time_backwards", (unsigned long)s->time_backwards, 0);
    kv(fp, "clock_steps_forward", (unsigned long)s->clock_fwd, 0);
    kv(fp, "clock_steps_back", (unsigned long)s->clock_back, 0);
    kv(fp, "bad_lines", (unsigned long)c->n.bad_lines, 0);
    fputs("},\"e2e\":{\"position\":{", fp);
    kv(fp, "ok", (unsigned long)p->ok, 1);
    kv(fp, "lost", (unsigned long)p->lost, 0);
    kv(fp, "bad_crc", (unsigned long)p->bad_crc, 0);
    kv(fp, "wrong_length", (unsigned long)p->wrong_length, 0);
    kv(fp, "repeated", (unsigned long)p->repeated, 0);
    kv(fp, "counter_jump", (unsigned long)p->jump, 0);
    kv(fp, "stale", (unsigned long)p->stale, 0);
    fputs("},\"traction\":{", fp);
    kv(fp, "ok", (unsigned long)t->ok, 1);
    kv(fp, "lost", (unsigned long)t->lost, 0);
    kv(fp, "bad_crc", (unsigned long)t->bad_crc, 0);
    kv(fp, "wrong_length", (unsigned long)t->wrong_length, 0);
    kv(fp, "repeated", (unsigned long)t->repeated, 0);
    kv(fp, "counter_jump", (unsigned long)t->jump, 0);
    kv(fp, "stale", (unsigned long)t->stale, 0);
    fputs("}},\"error_classes\":{", fp);
    for (i = 0; i < HSTPFD_ERR_N_CLASSES; ++i) {
        kv(fp, class_names[i], (unsigned long)c->n.err_class[i], i == 0);
    }
    fputs("},\"step_errors\":{", fp);
    first = 1;
    for (i = 0; i < 11; ++i) {
        if (c->n.step_err[i] != 0) {
            kv(fp, err_names[i], (unsigned long)c->n.step_err[i], first);
            first = 0;
        }
    }
    fputs("},\"frames\":{", fp);
    kv(fp, "total", (unsigned long)c->n.frames, 1);
    kv(fp, "position", (unsigned long)c->n.position, 0);
    kv(fp, "traction", (unsigned long)c->n.traction, 0);
    kv(fp, "own_outputs", (unsigned long)c->n.output, 0);
    kv(fp, "ticks", (unsigned long)c->n.ticks, 0);
    fputs("},\"scheduler\":{", fp);
    kv(fp, "decimated", (unsigned long)s->decimated, 1);
    kv(fp, "split", (unsigned long)s->split, 0);
    kv(fp, "fix_dated", (unsigned long)s->fix_dated, 0);
    kv(fp, "reacquire", (unsigned long)c->n.reacquire, 0);
    kv(fp, "restarts", (unsigned long)s->restarts, 0);
    kv(fp, "degeneracy", (unsigned long)c->n.degeneracy, 0);
    fputs("},\"io\":{", fp);
    kv(fp, "tx_frames", (unsigned long)c->n.tx_frames, 1);
    kv(fp, "tx_errors", (unsigned long)c->n.tx_errors, 0);
    kv(fp, "tx_offline", (unsigned long)c->n.tx_offline, 0);
    kv(fp, "reopens", (unsigned long)c->n.reopens, 0);
    kv(fp, "read_errors", (unsigned long)c->n.read_errors, 0);
    fputs("}}\n", fp);
}
