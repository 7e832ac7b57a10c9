/* hstpfd: the daemon's logic between a frame source and the estimator.
 * Frames in (from a bus or a log, in time order), estimator steps, output
 * frames, the per-step stream and the summary out. Time comes only from the
 * frames' timestamps (and idle ticks on the same clock). Portable C99
 * (stdio for the output streams), no heap. */
#ifndef HSTPFD_CORE_H
#define HSTPFD_CORE_H

#include <signal.h>
#include <stdio.h>

#include "config.h"
#include "frame.h"
#include "frames.h"
#include "sched.h"

/* The library's lock and validity (hstpf_estimate_t.valid, the sd fields)
 * and hstpf_reacquire() are used once the library implements them (the API
 * is in the header and implemented: 1). With 0 (a library without them)
 * the daemon takes "has a fix" for the lock, publishes no sd (null, and
 * QualValid 0) and restarts with hstpf_reset(). */
#ifndef HSTPFD_LIB_LOCK_API
#define HSTPFD_LIB_LOCK_API 1
#endif

/* Sends one frame; returns 0, HSTPFD_SEND_OFFLINE if there is no open
 * interface (counted apart), or another value < 0 if sending failed. */
typedef int (*hstpfd_send_fn)(void *ctx, const hstpfd_frame_t *f);
#define HSTPFD_SEND_OFFLINE (-2)

typedef struct {
    uint32_t frames, ticks;
    uint32_t position, traction, output, unknown, error, format;
    uint32_t pos_invalid, pos_range, trac_invalid, trac_range;
    uint32_t err_class[HSTPFD_ERR_N_CLASSES];
    uint32_t step_ok, step_err[11]; /* step_err[-code], code -1..-10; [0] other */
    uint32_t degeneracy;
    uint32_t trac_implausible; /* times the library found the traction implausible (traction_fault raised) */
    uint32_t consist, consist_changes; /* Consist frames; changes of its topology counter passed on */
    uint32_t reacquire; /* restarts of the filter (gap or clock step) */
    uint32_t tx_frames, tx_errors, tx_offline, tx_skipped;
    /* filled by the I/O layer */
    uint32_t reopens, bad_lines, read_errors;
} hstpfd_counts_t;

typedef struct {
    const hstpfd_config_t *cfg;
    hstpf_t *filt;
    hstpfd_sched_t sched;
    hstpfd_rx_state_t rx;
    hstpfd_tx_state_t tx;
    hstpfd_send_fn send;
    void *send_ctx;
    FILE *out;        /* per-step stream, or NULL */
    FILE *frames_out; /* candump log of the output frames, or NULL */
    char bus[HSTPFD_NAME_MAX];
    int row[HSTPF_MAX_MODELS]; /* Table 1 row of each model, -2 custom */
    /* time, microseconds; frame time = src0 + (source stamp - src0) x time_scale */
    uint8_t have_time;
    int64_t src0, t_first, t_now, last_src, tick_us;
    int64_t base; /* timeline = frame time + base (clock steps taken out) */
    int64_t back_at; /* timeline time of the last backward clock step (-1: none) */
    const volatile sig_atomic_t *stop; /* loops end when set (may be NULL) */
    int64_t src_now; /* latest source time seen (stamps of --frames-out) */
    int64_t next_tx[HSTPFD_N_OUTPUTS];
    uint8_t state_sent;
    uint8_t state_pending; /* a step within the cycle of the last EstState: sent when it has passed */
    int64_t last_state_tx;
    /* estimate */
    hstpf_estimate_t est;
    uint8_t have_fix;      /* the estimator has a fix now */
    uint8_t pos_prev_fix;  /* the last position frame in sequence was a valid fix */
    uint8_t pos_last_counter; /* its alive counter */
    uint8_t had_fix;       /* t_first_fix is set */
    uint8_t have_decision; /* decision_t is set */
    int64_t t_first_fix;
    uint8_t have_est_t;    /* est_t_us is set */
    int64_t est_t_us;      /* timeline time of the published estimate (its step's end) */
    int64_t est_fix_us;    /* the same on the fix clock, as mapped at the step (EstTime) */
    uint8_t have_est_fix;  /* est_fix_us is set: the step had a fix clock */
    uint8_t have_topo;     /* topo is set: a valid Consist frame was received */
    uint32_t topo;         /* its topology counter */
    int16_t declared_prev;
    int64_t decision_t;    /* frame time of the step that declared the current type */
    uint32_t floor_prev[HSTPF_MAX_MODELS];
    hstpfd_counts_t n;
    /* the estimator's workspace: the engine comes from the configuration
     * file, so room for any (uint64_t: HSTPF_WORKSPACE_ALIGN) */
    uint64_t ws[HSTPF_WORKSPACE_WORDS(HSTPF_WORKSPACE_MAX_BYTES)];
} hstpfd_core_t;

/* Initialises the core and the estimator *filt (caller-owned, static).
 * send may be NULL (no bus); out and frames_out may be NULL. bus names the
 * interface in frames_out lines. Returns 0, or an HSTPF_E_* code from
 * hstpf_init, or -100 for a receiver configuration error, or HSTPFD_E_SCHED
 * for a scheduler configuration error (a period or timeout below 1 us). */
#define HSTPFD_E_SCHED (-101)
int hstpfd_core_init(hstpfd_core_t *c, const hstpfd_config_t *cfg, hstpf_t *filt, hstpfd_send_fn send,
                     void *send_ctx, FILE *out, FILE *frames_out, const char *bus);

/* One received frame (t_us: the source's timestamp). */
void hstpfd_core_frame(hstpfd_core_t *c, const hstpfd_frame_t *f);

/* Every loop of the core and the scheduler ends when *stop is set. */
void hstpfd_core_set_stop(hstpfd_core_t *c, const volatile sig_atomic_t *stop);

/* No frame has arrived up to the source time t_us: idle ticks up to it. */
void hstpfd_core_idle(hstpfd_core_t *c, int64_t t_src_us);

/* Microseconds of source time until the next idle tick is due (for a poll
 * timeout), or -1 before the first frame. */
int64_t hstpfd_core_idle_due(const hstpfd_core_t *c, int64_t t_src_us);

/* Publishes the estimate in c->est after a step (rc: the step's result):
 * the step stream line and the state frame. Called by the step handler;
 * public so that tests can publish a crafted estimate. */
void hstpfd_core_publish(hstpfd_core_t *c, const hstpfd_step_t *st, int32_t rc);

/* Sends output frame i (0..HSTPFD_N_OUTPUTS-1) now, from c->est. */
void hstpfd_core_send(hstpfd_core_t *c, unsigned i);

/* Writes the summary as one JSON line (with newline). source_kind is "log"
 * or "iface", source the file or interface, end why the run ended. */
void hstpfd_core_summary(const hstpfd_core_t *c, FILE *fp, const char *source_kind, const char *source,
                         const char *end);

/* Short name of an hstpf error code ("E_OUTLIER"). */
const char *hstpfd_err_name(int32_t code);

#endif
