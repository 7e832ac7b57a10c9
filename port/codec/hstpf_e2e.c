/* E2E Profile 1 style protection; the rules are in hstpf_e2e.h. */
#include "hstpf_e2e.h"

#include "hstpf_frames.h" /* the DBC's E2E defaults (HSTPF_E2E_DEFAULT_*) */

#define CRC8_POLY 0x1Du
#define COUNTER_CYCLE (HSTPF_E2E_COUNTER_MAX + 1u)

uint8_t hstpf_e2e_crc8(uint8_t crc, const uint8_t *data, size_t len)
{
    size_t i;
    unsigned bit;
    uint32_t r = crc;

    if (data == NULL) {
        return crc;
    }
    /* Bitwise: 8 frames of 10 bytes per cycle do not need a table's flash. */
    for (i = 0u; i < len; i++) {
        r ^= data[i];
        for (bit = 0u; bit < 8u; bit++) {
            r = (r & 0x80u) != 0u ? ((r << 1) ^ CRC8_POLY) : (r << 1);
            r &= 0xFFu;
        }
    }
    return (uint8_t)r;
}

uint8_t hstpf_e2e_frame_crc(uint16_t data_id, const uint8_t *frame, size_t len)
{
    uint8_t id[2];
    uint8_t crc;

    if (frame == NULL || len < HSTPF_E2E_MIN_LENGTH) {
        return 0u;
    }
    id[0] = (uint8_t)(data_id & 0xFFu);
    id[1] = (uint8_t)(data_id >> 8);
    crc = hstpf_e2e_crc8(0x00u, id, 2u);
    return hstpf_e2e_crc8(crc, &frame[1], len - 1u);
}

int32_t hstpf_e2e_tx_init(hstpf_e2e_tx_t *tx, uint16_t data_id)
{
    if (tx == NULL) {
        return HSTPF_E2E_E_NULL;
    }
    tx->data_id = data_id;
    tx->counter = 0u;
    return 0;
}

int32_t hstpf_e2e_protect(hstpf_e2e_tx_t *tx, uint8_t *frame, size_t len)
{
    if (tx == NULL || frame == NULL) {
        return HSTPF_E2E_E_NULL;
    }
    if (len < HSTPF_E2E_MIN_LENGTH) {
        return HSTPF_E2E_E_ARG;
    }
    if (tx->counter > HSTPF_E2E_COUNTER_MAX) {
        tx->counter = 0u; /* a corrupted state must not emit 15 */
    }
    frame[HSTPF_E2E_COUNTER_BYTE] = (uint8_t)((frame[HSTPF_E2E_COUNTER_BYTE] & 0xF0u) | tx->counter);
    frame[HSTPF_E2E_CRC_BYTE] = hstpf_e2e_frame_crc(tx->data_id, frame, len);
    tx->counter = (uint8_t)((tx->counter + 1u) % COUNTER_CYCLE);
    return 0;
}

int32_t hstpf_e2e_rx_config_default(hstpf_e2e_rx_config_t *cfg, uint16_t data_id, uint8_t length)
{
    if (cfg == NULL) {
        return HSTPF_E2E_E_NULL;
    }
    cfg->data_id = data_id;
    cfg->length = length;
    cfg->max_delta = (uint8_t)HSTPF_E2E_DEFAULT_MAX_DELTA;
    cfg->timeout_ms = HSTPF_E2E_DEFAULT_TIMEOUT_MS;
    return 0;
}

int32_t hstpf_e2e_rx_init(hstpf_e2e_rx_t *rx, const hstpf_e2e_rx_config_t *cfg)
{
    if (rx == NULL || cfg == NULL) {
        return HSTPF_E2E_E_NULL;
    }
    /* max_delta 14 would make every counter but a repeat "in sequence". */
    if (cfg->length < HSTPF_E2E_MIN_LENGTH || cfg->length > HSTPF_E2E_MAX_LENGTH || cfg->max_delta < 1u ||
        cfg->max_delta > HSTPF_E2E_COUNTER_MAX - 1u || cfg->timeout_ms == 0u || cfg->timeout_ms > 0x7FFFFFFFu) {
        return HSTPF_E2E_E_ARG;
    }
    rx->cfg = *cfg;
    rx->last_ok_ms = 0u;
    rx->last_counter = 0u;
    rx->have_ref = 0u;
    rx->have_time = 0u;
    rx->stale = 0u;
    rx->counts.ok = 0u;
    rx->counts.lost = 0u;
    rx->counts.wrong_length = 0u;
    rx->counts.bad_crc = 0u;
    rx->counts.repeated = 0u;
    rx->counts.jump = 0u;
    rx->counts.stale = 0u;
    return 0;
}

/* Time since `then`; a timestamp from before `then` (reordered) counts as 0. */
static uint32_t elapsed_ms(uint32_t now, uint32_t then)
{
    uint32_t d = now - then;
    return d > 0x7FFFFFFFu ? 0u : d;
}

/* Counts the transition to stale once; returns 1 if stale now. */
static int update_stale(hstpf_e2e_rx_t *rx, uint32_t now_ms)
{
    if (rx->have_time != 0u && rx->stale == 0u && elapsed_ms(now_ms, rx->last_ok_ms) > rx->cfg.timeout_ms) {
        rx->stale = 1u;
        rx->counts.stale++;
    }
    return rx->stale != 0u;
}

static hstpf_e2e_result_t accept(hstpf_e2e_rx_t *rx, uint8_t counter, uint32_t now_ms, hstpf_e2e_result_t r)
{
    rx->last_counter = counter;
    rx->have_ref = 1u;
    rx->last_ok_ms = now_ms;
    rx->have_time = 1u;
    rx->stale = 0u;
    rx->counts.ok++;
    return r;
}

hstpf_e2e_result_t hstpf_e2e_rx_check(hstpf_e2e_rx_t *rx, const uint8_t *frame, size_t len, uint32_t now_ms)
{
    uint8_t counter;
    uint8_t delta;

    if (rx == NULL || (frame == NULL && len > 0u)) {
        return HSTPF_E2E_WRONG_LENGTH;
    }
    (void)update_stale(rx, now_ms);
    if (len != rx->cfg.length) {
        rx->counts.wrong_length++;
        return HSTPF_E2E_WRONG_LENGTH;
    }
    if (frame[HSTPF_E2E_CRC_BYTE] != hstpf_e2e_frame_crc(rx->cfg.data_id, frame, len)) {
        rx->counts.bad_crc++;
        return HSTPF_E2E_BAD_CRC;
    }
    counter = (uint8_t)(frame[HSTPF_E2E_COUNTER_BYTE] & 0x0Fu);
    if (counter > HSTPF_E2E_COUNTER_MAX) {
        rx->counts.jump++;
        return HSTPF_E2E_COUNTER_JUMP;
    }
    if (rx->have_ref == 0u || rx->stale != 0u) {
        return accept(rx, counter, now_ms, HSTPF_E2E_OK_INITIAL);
    }
    delta = (uint8_t)((counter + COUNTER_CYCLE - rx->last_counter) % COUNTER_CYCLE);
    if (delta == 0u) {
        rx->counts.repeated++;
        return HSTPF_E2E_REPEATED;
    }
    if (delta > rx->cfg.max_delta) {
        rx->counts.jump++;
        rx->last_counter = counter; /* resync: the next in-sequence frame is good */
        return HSTPF_E2E_COUNTER_JUMP;
    }
    if (delta == 1u) {
        return accept(rx, counter, now_ms, HSTPF_E2E_OK);
    }
    rx->counts.lost += (uint32_t)delta - 1u;
    return accept(rx, counter, now_ms, HSTPF_E2E_OK_LOST);
}

hstpf_e2e_result_t hstpf_e2e_rx_poll(hstpf_e2e_rx_t *rx, uint32_t now_ms)
{
    if (rx == NULL) {
        return HSTPF_E2E_STALE;
    }
    if (rx->have_time == 0u) {
        rx->have_time = 1u;
        rx->last_ok_ms = now_ms;
        return HSTPF_E2E_NO_DATA;
    }
    if (update_stale(rx, now_ms)) {
        return HSTPF_E2E_STALE;
    }
    return rx->have_ref != 0u ? HSTPF_E2E_OK : HSTPF_E2E_NO_DATA;
}

const hstpf_e2e_counts_t *hstpf_e2e_rx_counts(const hstpf_e2e_rx_t *rx)
{
    return rx == NULL ? NULL : &rx->counts;
}

int hstpf_e2e_rx_is_stale(const hstpf_e2e_rx_t *rx)
{
    return rx != NULL && rx->stale != 0u;
}

int hstpf_e2e_accepted(hstpf_e2e_result_t r)
{
    return r == HSTPF_E2E_OK || r == HSTPF_E2E_OK_INITIAL || r == HSTPF_E2E_OK_LOST;
}

const char *hstpf_e2e_result_name(hstpf_e2e_result_t r)
{
    switch (r) {
    case HSTPF_E2E_OK:
        return "ok";
    case HSTPF_E2E_OK_INITIAL:
        return "ok_initial";
    case HSTPF_E2E_OK_LOST:
        return "ok_lost";
    case HSTPF_E2E_WRONG_LENGTH:
        return "wrong_length";
    case HSTPF_E2E_BAD_CRC:
        return "bad_crc";
    case HSTPF_E2E_REPEATED:
        return "repeated";
    case HSTPF_E2E_COUNTER_JUMP:
        return "counter_jump";
    case HSTPF_E2E_STALE:
        return "stale";
    case HSTPF_E2E_NO_DATA:
        return "no_data";
    default:
        return "unknown";
    }
}
