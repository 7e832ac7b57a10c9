/**
 * @file hstpf_e2e.h
 * @brief End-to-end protection of hstpf CAN frames, AUTOSAR E2E Profile 1
 * style (docs/can.md). Portable C99: no OS headers, no heap, no clock.
 *
 * Layout (every hstpf frame, see port/dbc/hstpf.dbc):
 *   byte 0          CRC-8
 *   byte 1 bits 0-3 alive counter, 0..14 then back to 0 (15 is never sent)
 * CRC: SAE J1850 polynomial 0x1D, not reflected, initial value 0x00, no
 * final XOR (Profile 1's effective parameters: AUTOSAR Crc_CalculateCRC8
 * with its 0xFF start/XOR cancelled), computed over the 16-bit data ID
 * (low byte, then high byte: Profile 1 mode "BOTH") and then the frame
 * bytes 1..len-1 (everything but the CRC byte).
 *
 * Receiver rules (hstpf_e2e_rx_check):
 *   1. length != expected                  -> HSTPF_E2E_WRONG_LENGTH
 *   2. CRC mismatch                        -> HSTPF_E2E_BAD_CRC
 *   3. counter value 15                    -> HSTPF_E2E_COUNTER_JUMP
 *   4. first frame, or first after stale   -> HSTPF_E2E_OK_INITIAL (resync)
 *   5. delta = (counter - last) mod 15:
 *        0                                 -> HSTPF_E2E_REPEATED
 *        1                                 -> HSTPF_E2E_OK
 *        2..max_delta                      -> HSTPF_E2E_OK_LOST (delta-1 lost)
 *        above max_delta                   -> HSTPF_E2E_COUNTER_JUMP; the
 *          frame is rejected but its counter becomes the reference, so an
 *          in-sequence successor is accepted again (resync).
 *   A rejected frame leaves the reference counter and the time of the last
 *   accepted frame unchanged (except the resync in 5). The stream is stale
 *   when no frame was accepted for longer than timeout_ms; each transition
 *   to stale counts once.
 * Timestamps are any millisecond clock the caller has (kernel receive
 * time, a log's timestamps): uint32_t, wrapping; only differences below
 * 2^31 ms are used. Keep timeout_ms below 15 cycles so that a counter that
 * wrapped round during a gap is caught as stale, not taken as in sequence.
 *
 * Thread safety: a checker or sender must not be used from two threads at
 * once. Every function is O(length) or O(1), uses no memory beyond its
 * arguments and under 64 bytes of stack.
 */
#ifndef HSTPF_E2E_H
#define HSTPF_E2E_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Byte holding the CRC. */
#define HSTPF_E2E_CRC_BYTE 0u
/** Byte whose low nibble holds the alive counter. */
#define HSTPF_E2E_COUNTER_BYTE 1u
/** Largest counter value sent (Profile 1); the counter cycle is 15. */
#define HSTPF_E2E_COUNTER_MAX 14u
/** Shortest frame that can carry CRC and counter. */
#define HSTPF_E2E_MIN_LENGTH 2u
/** Largest frame the checker accepts as a configured length (CAN FD). */
#define HSTPF_E2E_MAX_LENGTH 64u

/** Argument errors (negative, as the library's HSTPF_E_* codes). */
#define HSTPF_E2E_E_NULL (-1)   /**< a required pointer is NULL */
#define HSTPF_E2E_E_ARG (-2)    /**< a length, delta or timeout out of range */

/** Result of checking one received frame, or of polling a stream. */
typedef enum {
    HSTPF_E2E_OK = 0,           /**< accepted: next in sequence */
    HSTPF_E2E_OK_INITIAL = 1,   /**< accepted: first frame, or first after stale */
    HSTPF_E2E_OK_LOST = 2,      /**< accepted: 2..max_delta ahead, frames lost */
    HSTPF_E2E_WRONG_LENGTH = 3, /**< rejected: length differs from configured */
    HSTPF_E2E_BAD_CRC = 4,      /**< rejected: CRC mismatch */
    HSTPF_E2E_REPEATED = 5,     /**< rejected: same counter as the last accepted */
    HSTPF_E2E_COUNTER_JUMP = 6, /**< rejected: counter beyond max_delta, or 15 */
    HSTPF_E2E_STALE = 7,        /**< poll only: no accepted frame for too long */
    HSTPF_E2E_NO_DATA = 8       /**< poll only: nothing accepted yet, not stale yet */
} hstpf_e2e_result_t;


/** Per-kind counts of one receiver since init (each wraps at 2^32). */
typedef struct {
    uint32_t ok;           /**< frames accepted (all three OK results) */
    uint32_t lost;         /**< frames inferred lost from OK_LOST gaps */
    uint32_t wrong_length; /**< HSTPF_E2E_WRONG_LENGTH */
    uint32_t bad_crc;      /**< HSTPF_E2E_BAD_CRC */
    uint32_t repeated;     /**< HSTPF_E2E_REPEATED */
    uint32_t jump;         /**< HSTPF_E2E_COUNTER_JUMP */
    uint32_t stale;        /**< transitions into stale */
} hstpf_e2e_counts_t;

/** Sender state of one frame. Fill with hstpf_e2e_tx_init(). */
typedef struct {
    uint16_t data_id;
    uint8_t counter; /* value the next protected frame carries */
} hstpf_e2e_tx_t;

/** Receiver configuration of one input stream. */
typedef struct {
    uint16_t data_id;    /**< the frame's E2E data ID (docs/can.md) */
    uint8_t length;      /**< expected length, HSTPF_E2E_MIN_LENGTH..HSTPF_E2E_MAX_LENGTH */
    uint8_t max_delta;   /**< largest accepted counter step, 1..13 (default 3) */
    uint32_t timeout_ms; /**< stale after this long without an accepted frame, > 0 */
} hstpf_e2e_rx_config_t;

/** Receiver state of one input stream; members are private. */
typedef struct {
    hstpf_e2e_rx_config_t cfg;
    uint32_t last_ok_ms;  /* time of the last accepted frame (or of the first poll) */
    uint8_t last_counter; /* reference counter */
    uint8_t have_ref;     /* a reference counter exists */
    uint8_t have_time;    /* last_ok_ms is set */
    uint8_t stale;        /* currently stale */
    hstpf_e2e_counts_t counts;
} hstpf_e2e_rx_t;

/**
 * @brief CRC-8 SAE J1850 (poly 0x1D, MSB first) update: feeds len bytes
 * into crc and returns the new register. No initial or final XOR is
 * applied: pass 0x00 to start a Profile 1 CRC, or 0xFF and XOR the result
 * with 0xFF for the plain SAE J1850 CRC (check value 0x4B for "123456789").
 * @param data may be NULL only when len is 0. Cost O(8 len) shifts, no table.
 */
uint8_t hstpf_e2e_crc8(uint8_t crc, const uint8_t *data, size_t len);

/**
 * @brief The Profile 1 CRC of a frame: over data ID low, data ID high and
 * frame[1..len-1]. frame[0] (the CRC byte) is not read.
 * @return the CRC; 0 if frame is NULL or len < HSTPF_E2E_MIN_LENGTH.
 */
uint8_t hstpf_e2e_frame_crc(uint16_t data_id, const uint8_t *frame, size_t len);

/**
 * @brief Starts a sender: the first protected frame carries counter 0.
 * @return 0, or HSTPF_E2E_E_NULL.
 */
int32_t hstpf_e2e_tx_init(hstpf_e2e_tx_t *tx, uint16_t data_id);

/**
 * @brief Protects a packed frame in place: writes the counter into the low
 * nibble of byte 1 (keeping its high nibble), then the CRC into byte 0,
 * then advances the counter (14 -> 0).
 * @return 0; HSTPF_E2E_E_NULL; HSTPF_E2E_E_ARG (len < 2). On error nothing
 * changes.
 */
int32_t hstpf_e2e_protect(hstpf_e2e_tx_t *tx, uint8_t *frame, size_t len);

/**
 * @brief Fills cfg with defaults: the given data ID and length, and the
 * DBC's default receiver parameters (BA_DEF_DEF_ of HstpfE2EMaxDeltaCounter
 * and HstpfE2ETimeoutMs, generated into hstpf_frames.h: max_delta 3,
 * timeout_ms 500, 5 cycles of a 100 ms frame). hstpf_frames_e2e_rx_config()
 * gives a frame's own values.
 * @return 0 or HSTPF_E2E_E_NULL.
 */
int32_t hstpf_e2e_rx_config_default(hstpf_e2e_rx_config_t *cfg, uint16_t data_id, uint8_t length);

/**
 * @brief Starts a receiver with zero counts, no reference counter, not stale.
 * @return 0; HSTPF_E2E_E_NULL; HSTPF_E2E_E_ARG (length, max_delta or
 * timeout_ms out of range). On error *rx is unchanged.
 */
int32_t hstpf_e2e_rx_init(hstpf_e2e_rx_t *rx, const hstpf_e2e_rx_config_t *cfg);

/**
 * @brief Checks one received frame by the rules at the top of this file
 * and counts the result. If the stream had become stale (the gap since the
 * last accepted frame exceeds timeout_ms) and no poll noticed it yet, the
 * stale transition is counted first.
 * @param frame the received bytes (may be NULL only when len is 0).
 * @param len   the received length (DLC).
 * @param now_ms receive time.
 * @return the check result (never STALE or NO_DATA); HSTPF_E2E_WRONG_LENGTH
 * also when rx is NULL or frame is NULL with len > 0 (nothing counted).
 */
hstpf_e2e_result_t hstpf_e2e_rx_check(hstpf_e2e_rx_t *rx, const uint8_t *frame, size_t len, uint32_t now_ms);

/**
 * @brief Stale supervision, to call periodically. The first call on a
 * stream that never had a frame starts its clock, so an input that never
 * appears goes stale timeout_ms after that.
 * @return HSTPF_E2E_STALE (counted once per transition), HSTPF_E2E_NO_DATA
 * (nothing accepted yet, within the timeout), or HSTPF_E2E_OK; STALE when
 * rx is NULL.
 */
hstpf_e2e_result_t hstpf_e2e_rx_poll(hstpf_e2e_rx_t *rx, uint32_t now_ms);

/** @brief Counts of a receiver; NULL if rx is NULL. */
const hstpf_e2e_counts_t *hstpf_e2e_rx_counts(const hstpf_e2e_rx_t *rx);

/** @brief 1 while the stream is stale, else 0 (also for NULL). */
int hstpf_e2e_rx_is_stale(const hstpf_e2e_rx_t *rx);

/** @brief 1 when a check result means the frame's data may be used (OK,
 * OK_INITIAL, OK_LOST), else 0. A function, so r is evaluated once. */
int hstpf_e2e_accepted(hstpf_e2e_result_t r);

/** @brief Short English name of a result ("ok", "bad_crc", ...). */
const char *hstpf_e2e_result_name(hstpf_e2e_result_t r);

#ifdef __cplusplus
}
#endif

#endif /* HSTPF_E2E_H */
