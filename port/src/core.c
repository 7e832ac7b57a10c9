/* hstpfd: the daemon's logic (see core.h): set-up, the step handler, the timeline
 * and the received frames. */
#include "core.h"
#include "core_internal.h"

#include <math.h>
#include <string.h>

#include "candump.h"

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
    fc.workspace = c->ws;
    fc.workspace_size = sizeof c->ws;
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
    {
        /* 1 ms of source time at least (the poll timeout's resolution); at
         * most a day: a time_scale near 0 must not overflow the cast */
        const double tk = cfg->tick_s * 1e6 / cfg->time_scale + 0.5;
        c->tick_us = tk < 1000.0 ? 1000 : (tk > 8.64e10 ? INT64_C(86400000000) : (int64_t)tk);
    }
    c->declared_prev = -1;
    c->back_at = -1;
    (void)hstpf_estimate(filt, &c->est);
    if (out != NULL && cfg->out_format == HSTPFD_OUT_CSV) {
        hstpfd__stream_header(out, cfg);
    }
    return 0;
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
    {
        const uint8_t was = c->est.traction_fault;
        (void)hstpf_estimate(c->filt, &c->est);
        c->n.trac_implausible += !was && c->est.traction_fault;
    }
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
    /* mapped now: the least latency may move before a deferred EstState
     * goes out, and its EstTime came out a ms before the last one's, which
     * a receiver unwraps as 8.191 s later */
    c->have_est_fix = c->sched.have_fix;
    c->est_fix_us = st->t_us - c->sched.fix_off;
    hstpfd__write_step(c, st, rc);
    /* the estimated state goes out after a step, at most once per cycle; a
     * step within the cycle goes out when it has passed (hstpfd__tx_service):
     * dropped, the bus kept an estimate up to 200 ms old under 5 ms of jitter */
    c->state_pending = 1;
    hstpfd__state_service(c);
}

/* ---- time and frames --------------------------------------------------- */

/* A scaled source time beyond this many us from the first (30 years) is
 * held there: the cast to int64 must not overflow (a stamp of 1e12 s at
 * time_scale 10); set_time takes such a jump for a clock step anyway. */
#define SCALED_MAX_US 1e15

static int64_t frame_time(const hstpfd_core_t *c, int64_t src)
{
    double d;
    if (c->cfg->time_scale == 1.0) {
        return src;
    }
    d = floor((double)(src - c->src0) * c->cfg->time_scale + 0.5);
    d = d > SCALED_MAX_US ? SCALED_MAX_US : (d < -SCALED_MAX_US ? -SCALED_MAX_US : d);
    return c->src0 + (int64_t)d;
}

/* A source stamp this far behind the latest time is a step of its clock. */
#define CLOCK_BACK_US INT64_C(1000000)
/* Within this much timeline after a backward step, a forward jump of more
 * than CLOCK_BACK_US is the clock stepping back again (two interleaved
 * sources, a flapping clock), not a silence to predict across: 80 kB of
 * such a log made 598 000 predict steps and 300 MB of output. */
#define CLOCK_FLAP_US INT64_C(10000000)

/* Just after a backward step of the source clock. */
static int flapping(const hstpfd_core_t *c)
{
    return c->back_at >= 0 && c->t_now - c->back_at < CLOCK_FLAP_US;
}

/* Timeline time t (frame time + base) is a forward step of the source clock:
 * more than max_gap_s ahead of the latest time, or 1 s just after a
 * backward step. */
static int forward_step(const hstpfd_core_t *c, int64_t t)
{
    return t > c->t_now + (flapping(c) ? CLOCK_BACK_US : c->sched.gap_us);
}

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
        c->back_at = t;
        hstpfd_sched_clock_step(&c->sched, t, -1);
    } else if (t < c->t_now) {
        ++c->sched.n.time_backwards; /* taken as the latest time (the scheduler never sees it) */
    } else if (forward_step(c, t)) {
        const int64_t t2 = c->t_now + CLOCK_BACK_US + (flapping(c) ? 0 : c->sched.gap_us);
        c->base -= t - t2;
        t = c->t_now = t2;
        hstpfd_sched_clock_step(&c->sched, t, 1);
    }
    if (t > c->t_now) {
        c->t_now = t;
    }
}

/* The source time at which a pending EstState falls due (its cycle since
 * the last one has passed; hstpfd__state_service), -1 when none is: an
 * idle tick is made then, so a step's state is not held until the next
 * frame. Timeline t = frame_time(src) + base, inverted and rounded up. */
static int64_t state_due_src(const hstpfd_core_t *c)
{
    const int64_t due = hstpfd__state_due(c);
    double d;
    if (due <= 0) {
        return -1;
    }
    d = (double)(due - c->base - c->src0);
    if (c->cfg->time_scale != 1.0) {
        d = ceil(d / c->cfg->time_scale);
    }
    d = d > SCALED_MAX_US ? SCALED_MAX_US : (d < -SCALED_MAX_US ? -SCALED_MAX_US : d);
    return c->src0 + (int64_t)d;
}

static void tick(hstpfd_core_t *c, int64_t src)
{
    ++c->n.ticks;
    c->src_now = src;
    set_time(c, src);
    hstpfd_sched_time(&c->sched, c->t_now);
    hstpfd_rx_poll(&c->rx, (uint32_t)(c->t_now / 1000));
    hstpfd__tx_service(c);
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
    if (forward_step(c, frame_time(c, t_src_us) + c->base)) {
        /* a forward step of the clock: one tick, none across it */
        c->last_src = t_src_us;
        tick(c, t_src_us);
        return;
    }
    for (;;) {
        const int64_t due = state_due_src(c);
        int64_t next = c->last_src + c->tick_us;
        next = due > c->last_src && due < next ? due : next;
        if (next > t_src_us || (c->stop != NULL && *c->stop)) {
            return;
        }
        c->last_src = next;
        tick(c, next);
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
    {
        const int64_t due = state_due_src(c);
        d = c->last_src + c->tick_us;
        d = (due > c->last_src && due < d ? due : d) - t_src_us;
    }
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
         * the alive counter moved on by 1..max_delta since; also across a
         * stale gap (2: a receive clock step or a stalled sender leaves the
         * counter in sequence), where a fix older than the last is not the
         * next one (sched.c, fix_time) */
        const unsigned d_cnt = (r.counter + 15u - c->pos_last_counter) % 15u;
        const int in_seq = c->pos_prev_fix && r.accepted && d_cnt >= 1u && d_cnt <= c->cfg->e2e_max_delta
                               ? (r.e2e == HSTPF_E2E_OK_INITIAL ? 2 : 1)
                               : 0;
        ++c->n.position;
        if (r.accepted || r.e2e == HSTPF_E2E_COUNTER_JUMP) {
            c->pos_prev_fix = r.valid;
            c->pos_last_counter = r.counter;
        }
        if (r.valid && !(fabs(r.value) <= HSTPF_POS_MAX_M)) {
            /* the estimator refuses it (HSTPF_E_RANGE) and its time would
             * move on with the estimate left as it was, still valid: no fix */
            ++c->n.pos_range;
            c->pos_prev_fix = 0;
            hstpfd_sched_time(&c->sched, c->t_now);
        } else if (r.valid) {
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
    case HSTPFD_RX_CONSIST:
        ++c->n.consist;
        if (r.valid && c->have_topo && r.topo != c->topo) {
            /* coupled or split: the type is not what the weights say */
            (void)hstpf_consist_changed(c->filt);
            ++c->n.consist_changes;
        }
        if (r.valid) {
            c->have_topo = 1;
            c->topo = r.topo;
        }
        hstpfd_sched_time(&c->sched, c->t_now);
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
    hstpfd__tx_service(c);
}
