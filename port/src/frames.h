/* hstpfd: the seam between the daemon and the frame codec. The daemon only
 * sees decoded input samples (or why a frame was refused) and asks for its
 * output frames by index; everything about IDs, layouts, scalings and E2E
 * lives behind these functions (frames.c, on port/codec).
 * Portable C99, no OS, no heap. */
#ifndef HSTPFD_FRAMES_H
#define HSTPFD_FRAMES_H

#include <stdint.h>

#include "frame.h"
#include "hstpf_e2e.h"
#include "hstpf/hstpf.h"

/* What a received frame was. */
typedef enum {
    HSTPFD_RX_POSITION = 0, /* odometry position frame */
    HSTPFD_RX_TRACTION = 1, /* traction/braking effort frame */
    HSTPFD_RX_OUTPUT = 2,   /* one of our own output IDs (another estimator, or an echo) */
    HSTPFD_RX_UNKNOWN = 3,  /* an ID the DBC does not have */
    HSTPFD_RX_ERROR = 4,    /* an error frame */
    HSTPFD_RX_FORMAT = 5,   /* a known ID as extended, remote or CAN FD frame */
    HSTPFD_RX_CONSIST = 6   /* the train control's consist (topology counter) frame */
} hstpfd_rx_kind_t;

typedef struct {
    hstpfd_rx_kind_t kind;
    hstpf_e2e_result_t e2e; /* inputs: the E2E check */
    uint8_t accepted;       /* inputs: E2E accepted */
    uint8_t valid;          /* inputs: accepted and the sender's valid flag set */
    double value;           /* position m, or total traction force kN */
    uint8_t counter;        /* inputs: the E2E alive counter (when accepted) */
    uint8_t has_fix_time;   /* position: the sender dated the fix (FixTimeValid) */
    uint16_t fix_time_ms;   /* position: fix time, ms modulo HSTPFD_FIX_WRAP_MS */
    uint32_t topo;          /* consist: the topology counter (when valid) */
} hstpfd_rx_t;

/* The position frame's fix time wraps at this many ms. */
#define HSTPFD_FIX_WRAP_MS 8192

/* Receiver state: one E2E checker per input stream. */
typedef struct {
    hstpf_e2e_rx_t pos, trac, topo;
} hstpfd_rx_state_t;


/* Returns 0, or -1 if a value is out of the checker's range. */
int hstpfd_rx_init(hstpfd_rx_state_t *st, uint8_t max_delta, uint32_t pos_timeout_ms, uint32_t trac_timeout_ms);
/* Classifies, E2E-checks and decodes one frame received at now_ms. */
void hstpfd_rx_decode(hstpfd_rx_state_t *st, const hstpfd_frame_t *f, uint32_t now_ms, hstpfd_rx_t *out);
/* Stale supervision of the position and traction inputs at now_ms. */
void hstpfd_rx_poll(hstpfd_rx_state_t *st, uint32_t now_ms);

/* The input IDs: position, traction, consist (for kernel filters). */
#define HSTPFD_N_INPUTS 3
uint32_t hstpfd_input_id(unsigned i);

/* EstBand: the sd of W(v) at V = k x 87.5 km/h, k = 0..4 (docs/can.md). */
#define HSTPFD_BAND_N 5
#define HSTPFD_BAND_STEP_KMH 87.5

/* Everything the output frames carry. Validity rule (docs/can.md): a value
 * goes out marked valid only when `valid` is set and the value is finite and
 * within its signal's range; otherwise its frame's valid bit is 0 and, if
 * the estimator has a fix, its fault/saturation bit is 1. */
typedef struct {
    uint8_t have_fix;         /* the estimator has had its first fix */
    uint8_t valid;            /* the estimate is valid (core_tx.c: hstpfd__est_valid) */
    double position_m;
    double speed_mps;
    double position_sd_m, speed_sd_mps; /* blended posterior sd */
    uint8_t sd_valid;                   /* the estimator provides them */
    uint8_t standstill;
    uint32_t acquisitions;
    uint8_t est_time_valid;   /* est_time_ms is known */
    uint16_t est_time_ms;     /* the estimate's time on the fix clock, ms modulo the wrap */
    hstpf_status_t status;
    int declared_row;         /* Table 1 row, -2 custom, -1 none */
    double declared_q;
    int leader_row;           /* Table 1 row, -2 custom, -1 none */
    double leader_q;
    double theta[3];
    uint8_t fit;              /* hstpf_fit_t */
    uint8_t off_what;         /* HSTPF_OFF_* bits */
    double w_sd[HSTPFD_BAND_N]; /* sd of W(v) at HSTPFD_BAND_STEP_KMH x k, N/kN */
    uint8_t pos_stale, trac_stale;
    uint8_t trac_fault;       /* hstpf_estimate_t.traction_fault */
    uint32_t bad_crc, repeated, jump, wrong_length; /* summed over the inputs */
    uint32_t stale_events, unknown_id, error_frames, degeneracy;
    uint32_t clock_fwd, clock_back, late, reacquire;
} hstpfd_tx_values_t;

/* Sender state: one E2E counter per output frame. */
#define HSTPFD_N_OUTPUTS 8
#define HSTPFD_OUT_QUALITY 6 /* EstQuality: sent with the state (output 0), not periodic */
#define HSTPFD_OUT_BAND 7    /* EstBand: W(v)'s band, with EstTheta's cycle */
typedef struct {
    hstpf_e2e_tx_t e2e[HSTPFD_N_OUTPUTS];
} hstpfd_tx_state_t;

void hstpfd_tx_init(hstpfd_tx_state_t *st);
/* Cycle of output i, microseconds; its ID. Outputs 0 (the estimated state)
 * and HSTPFD_OUT_QUALITY (its uncertainty) are sent after a step, at most
 * once per cycle; the others are periodic. */
int64_t hstpfd_tx_cycle_us(unsigned i);
uint32_t hstpfd_tx_id(unsigned i);
/* Packs and E2E-protects output i into f (t_us not set). Returns 0 or -1. */
int hstpfd_tx_encode(hstpfd_tx_state_t *st, unsigned i, const hstpfd_tx_values_t *v, hstpfd_frame_t *f);

#endif
