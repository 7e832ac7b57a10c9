/* hstpfd: step scheduler. Turns a time-ordered stream of valid position and
 * traction samples (and bare time ticks) into hstpf_step() inputs.
 * Portable C99, no OS, no heap; time only from the samples' timestamps.
 *
 * Rules (docs/daemon.md, "Scheduling"):
 * - A valid position frame triggers a step (step_period_s = 0), or, with
 *   step_period_s = P > 0, only the first one at or after each point of a
 *   grid of period P started at the first fix (2 % of P early counts as
 *   on time: timestamp jitter); the skipped frames are counted. After a
 *   gap the grid restarts at the step that ends it.
 * - dt = time of this position - time of the last step (first step:
 *   first_dt_s). A position not newer than the last step is dropped (late).
 * - Time of a position: its fix time when the frame carries one (the
 *   sender's wrapping millisecond clock, Position.FixTime), mapped onto the
 *   receive timeline, else its receive time. The mapping ("fix clock"):
 *   fix times are unwrapped (between consecutive fixes of one unbroken E2E
 *   sequence: the difference modulo the wrap, taken in (-wrap/2, wrap/2];
 *   otherwise as many whole wraps as the receive times say) and shifted by
 *   the smallest receive latency seen, which may creep up by 100 ppm of
 *   elapsed time (clock drift). A fix is therefore dated at or before its
 *   receive time, and receive jitter does not enter dt.
 * - The other inputs (traction, idle ticks) and the predict steps are dated
 *   by their receive time less the latest fix's latency above the least one:
 *   a stalled path delays every frame alike, so the backlog's traction is
 *   dated as late as its fixes (on one bus, that latency is bus jitter). A
 *   traction sample dated before the last step holds from that step on.
 * - A fix clock whose fixes all come too late to be used, more than 1 s
 *   later than the least latency by an excess that moves less than 0.5 s
 *   for max(3 s, excess / 2) of receive time, is re-dated by that excess
 *   (a receive clock step forward; a sender's backlog grows or drains
 *   instead) and the next position re-acquires.
 * - Traction: zero-order hold of the latest valid sample, converted from
 *   total force (kN) to unit force (N/kN) with the train mass. MEAN: the
 *   time-weighted mean of the held value over the step; LATEST: the value
 *   of the latest sample at or before the step's end. Before any traction
 *   sample: 0. A stale traction input keeps its last value (flagged and
 *   counted).
 * - Position stale: no valid position for more than pos_timeout_s (counted
 *   once per episode). Policy PREDICT: predict-only steps (has_position = 0)
 *   of predict_period_s each while stale; WAIT: no steps until the next
 *   valid position.
 * - A step longer than HSTPF_DT_MAX_S is split into equal predict-only
 *   pieces; a gap between positions longer than max_gap_s (predicted
 *   across or not) restarts the estimator (restart
 *   flag on the step: the caller resets it) with the new position as the
 *   first fix.
 * - Time never goes back: an earlier timestamp counts as time_backwards and
 *   is taken as the latest time seen.
 * - Clock steps (hstpfd_sched_clock_step, from the daemon's clock guard):
 *   no predict steps across the step; the fix clock starts again; the next
 *   position restarts the estimator (restart flag) as a first fix. A
 *   shorter forward step of the receive clock is first predicted across as
 *   an outage of its length; the fix clock rule above then re-dates it.
 * - Every loop here ends within a bounded number of steps or when *stop is
 *   set (hstpfd_sched_set_stop): SIGTERM is honoured between steps. */
#ifndef HSTPFD_SCHED_H
#define HSTPFD_SCHED_H

#include <signal.h>
#include <stdint.h>

#include "hstpf/hstpf.h"

/* Traction changes remembered within one step (more are merged). */
#define HSTPFD_SCHED_SEGMENTS 128

typedef enum { HSTPFD_TRACTION_MEAN = 0, HSTPFD_TRACTION_LATEST = 1 } hstpfd_traction_mode_t;
typedef enum { HSTPFD_STALE_PREDICT = 0, HSTPFD_STALE_WAIT = 1 } hstpfd_stale_policy_t;

typedef struct {
    double step_period_s;    /* 0: a step per valid position frame */
    double pos_timeout_s;    /* > 0 */
    double trac_timeout_s;   /* > 0 */
    double predict_period_s; /* (0, HSTPF_DT_MAX_S] */
    double max_gap_s;        /* > 0 */
    double first_dt_s;       /* (0, HSTPF_DT_MAX_S] */
    double mass_t;           /* > 0 */
    hstpfd_traction_mode_t traction_mode;
    hstpfd_stale_policy_t stale_policy;
} hstpfd_sched_config_t;

/* One step for the estimator. */
typedef struct {
    hstpf_input_t in;
    int64_t t_us;        /* time at the end of the step */
    uint8_t restart;     /* reset the estimator before this step */
    uint8_t pos_stale;   /* position input stale when the step was made */
    uint8_t trac_stale;  /* traction input stale (value held) */
    uint8_t no_traction; /* no valid traction seen yet (u = 0) */
} hstpfd_step_t;

typedef void (*hstpfd_step_fn)(void *ctx, const hstpfd_step_t *step);

typedef struct {
    uint32_t steps;            /* steps emitted */
    uint32_t predict_steps;    /* of which predict-only */
    uint32_t pos_stale;        /* position stale episodes */
    uint32_t trac_stale;       /* traction stale episodes */
    uint32_t decimated;        /* valid positions skipped by the period */
    uint32_t late;             /* positions not newer than the last step */
    uint32_t time_backwards;   /* timestamps earlier than the latest seen */
    uint32_t restarts;         /* gaps beyond max_gap_s */
    uint32_t split;            /* steps split because longer than HSTPF_DT_MAX_S */
    uint32_t fix_dated;        /* positions dated by their fix time */
    uint32_t clock_fwd;        /* receive clock steps forward (the daemon's guard) */
    uint32_t clock_back;       /* receive clock steps back */
    uint32_t fix_clock_steps;  /* forward receive-clock steps found by the fixes' latency */
} hstpfd_sched_counts_t;

typedef struct {
    hstpfd_sched_config_t cfg;
    hstpfd_step_fn fn;
    void *ctx;
    int64_t step_us, pos_to_us, trac_to_us, pred_us, gap_us, first_us, dtmax_us;
    uint8_t started, have_step, have_u, have_pos, have_trac, pos_stale, trac_stale;
    int64_t t_now, t_start, t_step, t_pos, t_trac;
    int64_t t_fix_step;        /* the last step with a position: the gap max_gap_s is measured from */
    int64_t t_due;  /* next point of the decimation grid */
    double u;       /* latest unit traction, N/kN */
    /* The held traction since t_step as segments: seg_u[i] from seg_t[i] to
     * seg_t[i+1] (the last one to now), so that a step ending in the past
     * (a predict step found due late) gets exactly its own interval's mean.
     * When full, the two oldest segments merge (the integral stays exact). */
    int64_t seg_t[HSTPFD_SCHED_SEGMENTS];
    double seg_u[HSTPFD_SCHED_SEGMENTS];
    uint16_t n_seg;
    /* fix clock: the last fix's time unwrapped (us), its receive time, and
     * timeline time - unwrapped fix time */
    uint8_t have_fix;
    int32_t fix_ms_last;
    int64_t fix_u, fix_rx, fix_off;
    int64_t fix_adv_rx; /* receive time the fix clock last moved on (a stuck one: stale) */
    /* fixes all received later than the least latency by more than a
     * second, since lag_rx, by at least lag_min: a receive clock that
     * stepped forward (a stall's backlog drains in a burst and ends it) */
    uint8_t lagging;
    int64_t lag_rx, lag_first, lag_min;
    /* the latest fix's receive latency above the least one (>= 0): the
     * other inputs and the predict steps are dated by receive time less it */
    int64_t fix_lat;
    uint8_t restart_next; /* a clock step: the next position restarts the estimator */
    const volatile sig_atomic_t *stop; /* loops end when *stop (may be NULL) */
    hstpfd_sched_counts_t n;
} hstpfd_sched_t;

/* Unit traction force, N/kN, from total force (kN) and mass (t). */
double hstpfd_traction_unit(double force_kn, double mass_t);

/* Returns 0, or -1 if a config value is out of range (fn may be NULL). */
int hstpfd_sched_init(hstpfd_sched_t *s, const hstpfd_sched_config_t *cfg, hstpfd_step_fn fn, void *ctx);
/* Loops stop early when *stop becomes non-zero (a signal handler's flag). */
void hstpfd_sched_set_stop(hstpfd_sched_t *s, const volatile sig_atomic_t *stop);

/* The receive clock stepped (forward: +1, back: -1) and time is now t_us:
 * nothing is predicted across it; the next position restarts. */
void hstpfd_sched_clock_step(hstpfd_sched_t *s, int64_t t_us, int dir);

/* Time has advanced to t_us without a valid sample (an invalid frame, an
 * unrelated frame, an idle tick). */
void hstpfd_sched_time(hstpfd_sched_t *s, int64_t t_us);
/* A valid traction sample: total force, kN (+ traction, - braking). */
void hstpfd_sched_traction(hstpfd_sched_t *s, int64_t t_us, double force_kn);
/* A valid position sample, m, dated by its receive time t_us. */
void hstpfd_sched_position(hstpfd_sched_t *s, int64_t t_us, double position_m);

/* Fix time wrap, ms (the DBC's Position.FixTime); no fix time: */
#define HSTPFD_SCHED_FIX_WRAP_MS 8192
#define HSTPFD_NO_FIX_TIME (-1)
/* A valid position sample received at t_us with its fix time fix_ms (0 ..
 * wrap-1, or HSTPFD_NO_FIX_TIME: dated by t_us). in_sequence: 1 when the
 * previous fix came in the same unbroken E2E sequence just before this
 * frame (so the fix times' difference is below the wrap), 2 when the
 * counter is in sequence across a stale gap (the same, but a fix older than
 * the last is then dated by the receive times), 0 otherwise. */
void hstpfd_sched_position_at(hstpfd_sched_t *s, int64_t t_us, double position_m, int32_t fix_ms, int in_sequence);

#endif
