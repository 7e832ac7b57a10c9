/* hstpfd: step scheduler (see sched.h for the rules). */
#include "sched.h"

#include <string.h>

#define G_N 9.81 /* 1 t weighs 9.81 kN */

double hstpfd_traction_unit(double force_kn, double mass_t)
{
    return force_kn * 1000.0 / (mass_t * G_N);
}

static int64_t us_of(double s)
{
    return (int64_t)(s * 1e6 + 0.5);
}

static int pos_fin(double x)
{
    return x > 0.0 && x < 1e12; /* also false for NaN */
}

/* No step shorter than 1 us: time is counted in whole microseconds. */
#define MIN_STEP_S 1e-6

int hstpfd_sched_init(hstpfd_sched_t *s, const hstpfd_sched_config_t *cfg, hstpfd_step_fn fn, void *ctx)
{
    const hstpfd_sched_config_t *c = cfg;
    if (s == NULL || c == NULL) {
        return -1;
    }
    if (!((c->step_period_s == 0.0 || c->step_period_s >= MIN_STEP_S) && c->step_period_s <= HSTPF_DT_MAX_S) ||
        !(c->pos_timeout_s >= MIN_STEP_S) || !pos_fin(c->pos_timeout_s) || !(c->trac_timeout_s >= MIN_STEP_S) ||
        !pos_fin(c->trac_timeout_s) || !(c->predict_period_s >= MIN_STEP_S) ||
        c->predict_period_s > HSTPF_DT_MAX_S || !(c->max_gap_s >= MIN_STEP_S) || !pos_fin(c->max_gap_s) ||
        !(c->first_dt_s >= MIN_STEP_S) || c->first_dt_s > HSTPF_DT_MAX_S || !pos_fin(c->mass_t) ||
        (c->traction_mode != HSTPFD_TRACTION_MEAN && c->traction_mode != HSTPFD_TRACTION_LATEST) ||
        (c->stale_policy != HSTPFD_STALE_PREDICT && c->stale_policy != HSTPFD_STALE_WAIT)) {
        return -1;
    }
    memset(s, 0, sizeof *s);
    s->cfg = *c;
    s->fn = fn;
    s->ctx = ctx;
    s->step_us = us_of(c->step_period_s);
    s->pos_to_us = us_of(c->pos_timeout_s);
    s->trac_to_us = us_of(c->trac_timeout_s);
    s->pred_us = us_of(c->predict_period_s);
    s->gap_us = us_of(c->max_gap_s);
    s->first_us = us_of(c->first_dt_s);
    s->dtmax_us = us_of(HSTPF_DT_MAX_S);
    return 0;
}

/* Forgets the held traction before t0: one segment holding s->u from t0. */
static void seg_reset(hstpfd_sched_t *s, int64_t t0)
{
    s->seg_t[0] = t0;
    s->seg_u[0] = s->u;
    s->n_seg = 1;
}

/* u from t on (t >= every segment start). */
static void seg_push(hstpfd_sched_t *s, int64_t t, double u)
{
    if (s->n_seg > 0 && t < s->seg_t[s->n_seg - 1]) {
        t = s->seg_t[s->n_seg - 1]; /* dated before the last step (a backlog): holds from there */
    }
    if (s->n_seg > 0 && s->seg_t[s->n_seg - 1] == t) {
        s->seg_u[s->n_seg - 1] = u;
        return;
    }
    if (s->n_seg == HSTPFD_SCHED_SEGMENTS) { /* merge the two oldest */
        const double d0 = (double)(s->seg_t[1] - s->seg_t[0]);
        const double d1 = (double)(s->seg_t[2] - s->seg_t[1]);
        s->seg_u[0] = (s->seg_u[0] * d0 + s->seg_u[1] * d1) / (d0 + d1);
        memmove(&s->seg_t[1], &s->seg_t[2], (size_t)(s->n_seg - 2) * sizeof s->seg_t[0]);
        memmove(&s->seg_u[1], &s->seg_u[2], (size_t)(s->n_seg - 2) * sizeof s->seg_u[0]);
        --s->n_seg;
    }
    s->seg_t[s->n_seg] = t;
    s->seg_u[s->n_seg] = u;
    ++s->n_seg;
}

/* Mean (MEAN) or end value (LATEST) of the held traction over [a, b], a < b,
 * a = seg_t[0]; then drops what lies before b. */
static double seg_take(hstpfd_sched_t *s, int64_t a, int64_t b)
{
    double acc = 0.0, last = s->seg_u[0];
    uint16_t i, keep;
    for (i = 0; i < s->n_seg && s->seg_t[i] <= b; ++i) {
        const int64_t lo = s->seg_t[i] > a ? s->seg_t[i] : a;
        const int64_t hi = (i + 1 < s->n_seg && s->seg_t[i + 1] < b) ? s->seg_t[i + 1] : b;
        if (hi > lo) {
            acc += s->seg_u[i] * (double)(hi - lo);
        }
        last = s->seg_u[i];
    }
    /* i - 1 is the segment that holds at b: it becomes the first */
    keep = (uint16_t)(i - 1);
    if (keep > 0) {
        memmove(&s->seg_t[0], &s->seg_t[keep], (size_t)(s->n_seg - keep) * sizeof s->seg_t[0]);
        memmove(&s->seg_u[0], &s->seg_u[keep], (size_t)(s->n_seg - keep) * sizeof s->seg_u[0]);
        s->n_seg = (uint16_t)(s->n_seg - keep);
    }
    s->seg_t[0] = b;
    if (s->cfg.traction_mode == HSTPFD_TRACTION_LATEST) {
        return last;
    }
    return acc / (double)(b - a);
}

/* Emits the step [t_step, t_end] (t_end > t_step). */
static void emit(hstpfd_sched_t *s, int64_t t_end, int has_pos, double y, int restart, int stale)
{
    hstpfd_step_t st;
    memset(&st, 0, sizeof st);
    if (restart) {
        st.in.dt_s = (double)s->first_us / 1e6;
        st.in.traction = s->u;
        seg_reset(s, t_end);
    } else {
        st.in.dt_s = (double)(t_end - s->t_step) / 1e6;
        st.in.traction = seg_take(s, s->t_step, t_end);
    }
    st.in.position_m = has_pos ? y : 0.0;
    st.in.has_position = (uint8_t)(has_pos != 0);
    st.t_us = t_end;
    st.restart = (uint8_t)(restart != 0);
    st.pos_stale = (uint8_t)(stale != 0);
    st.trac_stale = s->trac_stale;
    st.no_traction = (uint8_t)!s->have_u;
    /* a held or assumed traction is no measurement: the library takes the
     * acceleration as unknown (hstpf_input_t.traction_unknown) */
    st.in.traction_unknown = (uint8_t)(st.trac_stale || st.no_traction);
    s->t_step = t_end;
    if (has_pos) {
        s->t_fix_step = t_end;
    }
    s->have_step = 1;
    ++s->n.steps;
    if (!has_pos) {
        ++s->n.predict_steps;
    }
    if (s->fn != NULL) {
        s->fn(s->ctx, &st);
    }
}

/* Receive time -> the inputs' timeline: less the latest fix's latency above
 * the least one (0 without a fix clock). A stalled path (a replayer, a
 * gateway) delays every frame alike, so a frame received in a fix's
 * backlog is dated as late as that fix was; on one bus with independent
 * senders that latency is the bus jitter, a few ms. */
static int64_t in_time(const hstpfd_sched_t *s, int64_t t_rx)
{
    return s->have_fix ? t_rx - s->fix_lat : t_rx;
}

static void advance(hstpfd_sched_t *s, int64_t t)
{
    int64_t ti;
    if (!s->started) {
        s->started = 1;
        s->t_now = s->t_start = s->t_step = t;
        seg_reset(s, t);
    }
    if (t < s->t_now) {
        ++s->n.time_backwards;
        t = s->t_now;
    }
    s->t_now = t;
    if (!s->trac_stale && t - (s->have_trac ? s->t_trac : s->t_start) > s->trac_to_us) {
        s->trac_stale = 1;
        ++s->n.trac_stale;
    }
    if (!s->pos_stale && t - (s->have_pos ? s->t_pos : s->t_start) > s->pos_to_us) {
        s->pos_stale = 1;
        ++s->n.pos_stale;
    }
    ti = in_time(s, t);
    if (s->pos_stale && s->have_step && s->cfg.stale_policy == HSTPFD_STALE_PREDICT) {
        while (ti - s->t_step > s->pred_us) {
            if (s->stop != NULL && *s->stop) {
                s->t_step = ti - s->pred_us; /* the rest is not predicted */
                seg_reset(s, s->t_step);
                break;
            }
            emit(s, s->t_step + s->pred_us, 0, 0.0, 0, 1);
        }
    }
    if (!s->have_step) {
        /* before the first fix nothing is estimated: only the latest u counts */
        s->t_step = t;
        seg_reset(s, t);
    }
}

void hstpfd_sched_set_stop(hstpfd_sched_t *s, const volatile sig_atomic_t *stop)
{
    s->stop = stop;
}

void hstpfd_sched_clock_step(hstpfd_sched_t *s, int64_t t_us, int dir)
{
    if (dir > 0) {
        ++s->n.clock_fwd;
    } else {
        ++s->n.clock_back;
    }
    if (!s->started) {
        return;
    }
    if (t_us > s->t_now) {
        s->t_now = t_us;
    }
    if (s->have_step) {
        /* nothing is predicted across the step; the next fix starts again */
        s->t_step = s->t_now;
        seg_reset(s, s->t_step);
        s->restart_next = 1;
    }
    s->have_fix = 0; /* the fix clock starts again from the next fix */
    s->fix_lat = 0;
    s->lagging = 0;
}

void hstpfd_sched_time(hstpfd_sched_t *s, int64_t t_us)
{
    advance(s, t_us);
}

void hstpfd_sched_traction(hstpfd_sched_t *s, int64_t t_us, double force_kn)
{
    advance(s, t_us);
    s->u = hstpfd_traction_unit(force_kn, s->cfg.mass_t);
    seg_push(s, in_time(s, s->t_now), s->u);
    s->have_u = 1;
    s->have_trac = 1;
    s->t_trac = s->t_now;
    s->trac_stale = 0;
}

#define FIX_WRAP_US ((int64_t)HSTPFD_SCHED_FIX_WRAP_MS * 1000)
/* Consecutive fixes (a few 100 ms cycles) are at most this far apart. */
#define FIX_SEQ_MAX_US INT64_C(2000000)

/* floor(a / b), b > 0 */
static int64_t floor_div(int64_t a, int64_t b)
{
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/* A receive clock that steps forward by X (1 s < X < max_gap_s) and a
 * stalled or slow sender both make fixes arrive more than LAG_STEP_US later
 * than the least latency, and both are first predicted across as a
 * silence. The other inputs and the predict steps are dated by receive time
 * less the latest fix's latency (in_time), so either way fixes and traction
 * share one time, and once the fixes' own times pass the predicted steps
 * they are used again: nothing needs re-dating. Only a fix clock whose fixes
 * keep coming too late to be used for long is re-dated: a slow sender's
 * excess grows, its backlog drains when it catches up (the excess falls),
 * while a stepped clock's excess jumps once and stays. When the excess
 * has moved by no more than LAG_DRIFT_US for max(LAG_HOLD_US, excess / 2)
 * of receive time while every fix came too late to be used, the fix clock
 * takes the new offset (the smallest excess of the window), counted in
 * fix_clock_steps, and the estimator re-acquires from the next fix (as
 * after a receive clock step). Any other fix ends the window. Measured in
 * the HIL stage under a CPU hog: a replayer 10 s behind kept pace without
 * draining for 3 s, then drained over 20 s (docs/vm.md). */
#define LAG_STEP_US INT64_C(1000000)
#define LAG_HOLD_US INT64_C(3000000)
#define LAG_DRIFT_US INT64_C(500000)
static void lag_check(hstpfd_sched_t *s, int64_t t_rx)
{
    const int64_t excess = (t_rx - s->fix_u) - s->fix_off;
    const int late = s->have_step && s->fix_u + s->fix_off <= s->t_step;
    int64_t hold;
    if (excess <= LAG_STEP_US || !late ||
        (s->lagging && (excess < s->lag_first - LAG_DRIFT_US || excess > s->lag_first + LAG_DRIFT_US))) {
        s->lagging = 0; /* used, or a sender falling behind or draining: not a clock step */
        if (excess <= LAG_STEP_US || !late) {
            return;
        }
    }
    if (!s->lagging) {
        s->lagging = 1;
        s->lag_rx = t_rx;
        s->lag_first = s->lag_min = excess;
    } else if (excess < s->lag_min) {
        s->lag_min = excess;
    }
    hold = s->lag_first / 2 > LAG_HOLD_US ? s->lag_first / 2 : LAG_HOLD_US;
    if (t_rx - s->lag_rx >= hold) {
        s->fix_off += s->lag_min;
        s->lagging = 0;
        s->restart_next = 1;
        ++s->n.fix_clock_steps;
    }
}

/* Timeline time of a fix received at t_rx (see the rules in sched.h). */
static int64_t fix_time(hstpfd_sched_t *s, int64_t t_rx, int32_t fix_ms, int in_sequence)
{
    if (!s->have_fix) {
        s->have_fix = 1;
        s->fix_u = (int64_t)fix_ms * 1000;
        s->fix_off = t_rx - s->fix_u;
    } else {
        int64_t d = (int64_t)((fix_ms - s->fix_ms_last + HSTPFD_SCHED_FIX_WRAP_MS) % HSTPFD_SCHED_FIX_WRAP_MS) * 1000;
        int64_t off;
        if (in_sequence && d > FIX_WRAP_US / 2) {
            /* older than the last fix: a sender that reordered, within one
             * unbroken sequence; across a stale gap, lost frames whose
             * counter landed in sequence again (76 frames: every fix dated a
             * wrap early and dropped as late), so the receive times count */
            if (in_sequence == 2) {
                in_sequence = 0;
            } else {
                d -= FIX_WRAP_US;
            }
        }
        if (in_sequence && (d > FIX_SEQ_MAX_US || d < -FIX_SEQ_MAX_US)) {
            in_sequence = 0; /* more than a few cycles apart: not the next fix after all */
        }
        if (!in_sequence) {
            d = (int64_t)((fix_ms - s->fix_ms_last + HSTPFD_SCHED_FIX_WRAP_MS) % HSTPFD_SCHED_FIX_WRAP_MS) * 1000;
            d += floor_div(t_rx - s->fix_rx - d + FIX_WRAP_US / 2, FIX_WRAP_US) * FIX_WRAP_US;
        }
        s->fix_u += d;
        lag_check(s, t_rx);
        /* least latency seen; creeps up by 100 ppm so a drifting clock is followed */
        off = s->fix_off + (t_rx - s->fix_rx) / 10000;
        if (t_rx - s->fix_u < off) {
            off = t_rx - s->fix_u;
        }
        s->fix_off = off;
    }
    s->fix_lat = t_rx - (s->fix_u + s->fix_off);
    s->fix_ms_last = fix_ms;
    s->fix_rx = t_rx;
    ++s->n.fix_dated;
    return s->fix_u + s->fix_off;
}

void hstpfd_sched_position(hstpfd_sched_t *s, int64_t t_us, double position_m)
{
    hstpfd_sched_position_at(s, t_us, position_m, HSTPFD_NO_FIX_TIME, 0);
}

/* Fixes whose time has not moved on for this long of receive time are not
 * new positions (a sender's fix clock stuck: each frame dated a little later
 * by the least latency's creep, every one decimated, no step ever made and
 * the estimate left valid): the position goes stale. */
#define FIX_STUCK_US INT64_C(2000000)

void hstpfd_sched_position_at(hstpfd_sched_t *s, int64_t t_us, double position_m, int32_t fix_ms, int in_sequence)
{
    int64_t gap;
    const int had_step = s->have_step;
    advance(s, t_us);
    t_us = s->t_now;
    if (fix_ms >= 0 && fix_ms < HSTPFD_SCHED_FIX_WRAP_MS) {
        if (!s->have_fix || fix_ms != s->fix_ms_last) {
            s->fix_adv_rx = s->t_now;
        } else if (s->t_now - s->fix_adv_rx > FIX_STUCK_US) {
            /* not dated either: its latency would grow with the receive
             * clock and hold the predict steps back */
            return;
        }
        t_us = fix_time(s, s->t_now, fix_ms, in_sequence);
    }
    s->have_pos = 1;
    s->t_pos = s->t_now; /* staleness runs on the receive clock */
    if (!had_step) {
        /* the first step has length first_dt_s and the traction held now */
        s->pos_stale = 0;
        s->t_step = t_us - s->first_us;
        seg_reset(s, s->t_step);
        s->t_due = t_us + s->step_us;
        emit(s, t_us, 1, position_m, 0, 0);
        return;
    }
    gap = t_us - s->t_step;
    if (gap <= 0) {
        ++s->n.late;
        s->pos_stale = 0;
        return;
    }
    if (s->step_us > 0 && !s->pos_stale) {
        if (t_us < s->t_due - s->step_us / 50) {
            ++s->n.decimated;
            return;
        }
        s->t_due += s->step_us;
    }
    if (s->t_due <= t_us) {
        s->t_due = t_us + s->step_us; /* fell behind the grid: start it again */
    }
    s->pos_stale = 0;
    /* the gap is the positions' own: the predict steps of an outage move
     * t_step on, and a 700 s outage was predicted across to a 2 km sd, its
     * first fixes then gated as outliers (a review's reproducer) */
    if (s->restart_next || t_us - s->t_fix_step > s->gap_us) {
        if (!s->restart_next) {
            ++s->n.restarts;
        }
        s->restart_next = 0;
        emit(s, t_us, 1, position_m, 1, 0);
        return;
    }
    if (gap > s->dtmax_us) {
        const int64_t pieces = (gap + s->dtmax_us - 1) / s->dtmax_us;
        const int64_t t0 = s->t_step;
        int64_t k;
        ++s->n.split;
        for (k = 1; k < pieces; ++k) {
            emit(s, t0 + gap * k / pieces, 0, 0.0, 0, 0);
        }
    }
    emit(s, t_us, 1, position_m, 0, 0);
}
