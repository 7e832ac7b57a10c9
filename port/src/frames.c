/* hstpfd: the frame seam filled with port/codec (cantools pack/unpack from
 * port/dbc/hstpf.dbc, hstpf_e2e for CRC and alive counter). */
#include "frames.h"

#include <math.h>
#include <string.h>

#include "hstpf_can.h"
#include "hstpf_frames.h"

#if HSTPF_FIX_TIME_WRAP_MS != HSTPFD_FIX_WRAP_MS
#error "frames.h: HSTPFD_FIX_WRAP_MS differs from the DBC's FixTime width"
#endif

int hstpfd_rx_init(hstpfd_rx_state_t *st, uint8_t max_delta, uint32_t pos_timeout_ms, uint32_t trac_timeout_ms)
{
    hstpf_e2e_rx_config_t c;
    (void)hstpf_frames_e2e_rx_config(&c, HSTPF_FRAME_POSITION_ID);
    c.max_delta = max_delta;
    c.timeout_ms = pos_timeout_ms;
    if (hstpf_e2e_rx_init(&st->pos, &c) != 0) {
        return -1;
    }
    (void)hstpf_frames_e2e_rx_config(&c, HSTPF_FRAME_TRACTION_ID);
    c.max_delta = max_delta;
    c.timeout_ms = trac_timeout_ms;
    if (hstpf_e2e_rx_init(&st->trac, &c) != 0) {
        return -1;
    }
    /* the consist frame as the DBC has it: an event, not a stream the
     * estimate depends on (its staleness is not a fault) */
    (void)hstpf_frames_e2e_rx_config(&c, HSTPF_FRAME_CONSIST_ID);
    c.max_delta = max_delta;
    return hstpf_e2e_rx_init(&st->topo, &c) == 0 ? 0 : -1;
}

uint32_t hstpfd_input_id(unsigned i)
{
    static const uint32_t id[HSTPFD_N_INPUTS] = {HSTPF_FRAME_POSITION_ID, HSTPF_FRAME_TRACTION_ID,
                                                 HSTPF_FRAME_CONSIST_ID};
    return i < HSTPFD_N_INPUTS ? id[i] : 0u;
}

void hstpfd_rx_decode(hstpfd_rx_state_t *st, const hstpfd_frame_t *f, uint32_t now_ms, hstpfd_rx_t *out)
{
    const hstpf_frame_info_t *info;
    memset(out, 0, sizeof *out);
    out->e2e = HSTPF_E2E_NO_DATA;
    if (f->flags & HSTPFD_FRAME_ERR) {
        out->kind = HSTPFD_RX_ERROR;
        return;
    }
    info = (f->flags & HSTPFD_FRAME_EXT) ? NULL : hstpf_frame_find(f->id);
    if (info == NULL) {
        /* an extended ID equal to one of ours is still somebody else's */
        out->kind = HSTPFD_RX_UNKNOWN;
        return;
    }
    if (f->flags & (HSTPFD_FRAME_RTR | HSTPFD_FRAME_FD)) {
        out->kind = HSTPFD_RX_FORMAT;
        return;
    }
    if (f->id == HSTPF_FRAME_POSITION_ID) {
        struct hstpf_can_position_t m;
        out->kind = HSTPFD_RX_POSITION;
        out->e2e = hstpf_e2e_rx_check(&st->pos, f->data, f->len, now_ms);
        out->accepted = (uint8_t)(hstpf_e2e_accepted(out->e2e) != 0);
        if (out->accepted && hstpf_can_position_unpack(&m, f->data, f->len) == 0) {
            out->value = hstpf_can_position_position_decode(m.position);
            out->counter = m.e2e_counter;
            out->valid = (uint8_t)(m.pos_valid == HSTPF_CAN_POSITION_POS_VALID_VALID_CHOICE);
            out->has_fix_time = (uint8_t)(m.fix_time_valid == HSTPF_CAN_POSITION_FIX_TIME_VALID_PRESENT_CHOICE);
            out->fix_time_ms = (uint16_t)(m.fix_time % HSTPF_FIX_TIME_WRAP_MS);
        }
        return;
    }
    if (f->id == HSTPF_FRAME_TRACTION_ID) {
        struct hstpf_can_traction_t m;
        out->kind = HSTPFD_RX_TRACTION;
        out->e2e = hstpf_e2e_rx_check(&st->trac, f->data, f->len, now_ms);
        out->accepted = (uint8_t)(hstpf_e2e_accepted(out->e2e) != 0);
        if (out->accepted && hstpf_can_traction_unpack(&m, f->data, f->len) == 0) {
            out->value = hstpf_can_traction_tract_force_decode(m.tract_force);
            out->valid = (uint8_t)(m.tract_valid == HSTPF_CAN_TRACTION_TRACT_VALID_VALID_CHOICE);
        }
        return;
    }
    if (f->id == HSTPF_FRAME_CONSIST_ID) {
        struct hstpf_can_consist_t m;
        out->kind = HSTPFD_RX_CONSIST;
        out->e2e = hstpf_e2e_rx_check(&st->topo, f->data, f->len, now_ms);
        out->accepted = (uint8_t)(hstpf_e2e_accepted(out->e2e) != 0);
        if (out->accepted && hstpf_can_consist_unpack(&m, f->data, f->len) == 0) {
            out->topo = m.topo_counter;
            out->counter = m.e2e_counter;
            out->valid = (uint8_t)(m.topo_valid == HSTPF_CAN_CONSIST_TOPO_VALID_VALID_CHOICE);
        }
        return;
    }
    out->kind = HSTPFD_RX_OUTPUT;
}

void hstpfd_rx_poll(hstpfd_rx_state_t *st, uint32_t now_ms)
{
    (void)hstpf_e2e_rx_poll(&st->pos, now_ms);
    (void)hstpf_e2e_rx_poll(&st->trac, now_ms); /* not the consist's: its silence is no fault */
}

static const uint32_t out_id[HSTPFD_N_OUTPUTS] = {HSTPF_FRAME_EST_STATE_ID,  HSTPF_FRAME_EST_TYPE_ID,
                                                  HSTPF_FRAME_EST_THETA_ID,  HSTPF_FRAME_HEALTH_RX_ID,
                                                  HSTPF_FRAME_HEALTH_SYS_ID, HSTPF_FRAME_HEALTH_TIME_ID,
                                                  HSTPF_FRAME_EST_QUALITY_ID, HSTPF_FRAME_EST_BAND_ID};
static const uint16_t out_data_id[HSTPFD_N_OUTPUTS] = {
    HSTPF_FRAME_EST_STATE_DATA_ID, HSTPF_FRAME_EST_TYPE_DATA_ID,   HSTPF_FRAME_EST_THETA_DATA_ID,
    HSTPF_FRAME_HEALTH_RX_DATA_ID, HSTPF_FRAME_HEALTH_SYS_DATA_ID, HSTPF_FRAME_HEALTH_TIME_DATA_ID,
    HSTPF_FRAME_EST_QUALITY_DATA_ID, HSTPF_FRAME_EST_BAND_DATA_ID};
static const uint32_t out_cycle_ms[HSTPFD_N_OUTPUTS] = {
    HSTPF_FRAME_EST_STATE_CYCLE_MS, HSTPF_FRAME_EST_TYPE_CYCLE_MS,   HSTPF_FRAME_EST_THETA_CYCLE_MS,
    HSTPF_FRAME_HEALTH_RX_CYCLE_MS, HSTPF_FRAME_HEALTH_SYS_CYCLE_MS, HSTPF_FRAME_HEALTH_TIME_CYCLE_MS,
    HSTPF_FRAME_EST_QUALITY_CYCLE_MS, HSTPF_FRAME_EST_BAND_CYCLE_MS};

void hstpfd_tx_init(hstpfd_tx_state_t *st)
{
    unsigned i;
    for (i = 0; i < HSTPFD_N_OUTPUTS; ++i) {
        (void)hstpf_e2e_tx_init(&st->e2e[i], out_data_id[i]);
    }
}

int64_t hstpfd_tx_cycle_us(unsigned i)
{
    return i < HSTPFD_N_OUTPUTS ? (int64_t)out_cycle_ms[i] * 1000 : 0;
}

uint32_t hstpfd_tx_id(unsigned i)
{
    return i < HSTPFD_N_OUTPUTS ? out_id[i] : 0u;
}

static uint8_t row_code(int row)
{
    if (row >= 0 && row < HSTPF_N_TRAIN_TYPES) {
        return (uint8_t)row;
    }
    return row == -2 ? (uint8_t)HSTPF_CAN_EST_TYPE_DECLARED_TYPE_CUSTOM_CHOICE
                     : (uint8_t)HSTPF_CAN_EST_TYPE_DECLARED_TYPE_NONE_CHOICE;
}

static double count(uint32_t n)
{
    return (double)n; /* the _raw helpers saturate at the signal's maximum */
}

/* A standard deviation goes out rounded up to its signal's resolution
 * (the codec rounds to nearest): the grid engine's Case 2 posteriors are
 * millimetres wide, and PositionSd's 0.01 m would have said 0, an interval
 * the truth is never in. The resolution is one count, decoded. */
static double sd_up(double sd, double resolution)
{
    return sd > 0.0 && isfinite(sd) ? ceil(sd / resolution - 1e-6) * resolution : sd;
}

int hstpfd_tx_encode(hstpfd_tx_state_t *st, unsigned i, const hstpfd_tx_values_t *v, hstpfd_frame_t *f)
{
    int n = -1;
    f->flags = 0;
    f->len = 0;
    memset(f->data, 0, sizeof f->data);
    if (i >= HSTPFD_N_OUTPUTS) {
        return -1;
    }
    f->id = out_id[i];
    switch (i) {
    case 0: {
        struct hstpf_can_est_state_t m;
        /* NaN fails the range test too: it is sent as 0, never as valid */
        const int ok = hstpf_can_est_state_est_position_is_in_phys_range(v->position_m) &&
                       hstpf_can_est_state_est_speed_is_in_phys_range(v->speed_mps);
        (void)hstpf_can_est_state_init(&m);
        m.est_valid = (uint8_t)(v->have_fix && v->valid && ok);
        m.est_fault = (uint8_t)(v->have_fix && !ok);
        m.est_position = hstpf_frames_est_state_est_position_raw(v->have_fix ? v->position_m : 0.0);
        m.est_speed = hstpf_frames_est_state_est_speed_raw(v->have_fix ? v->speed_mps : 0.0);
        n = hstpf_can_est_state_pack(f->data, &m, 8u);
        break;
    }
    case 1: {
        struct hstpf_can_est_type_t m;
        (void)hstpf_can_est_type_init(&m);
        m.type_status = hstpf_frames_est_type_type_status_raw((double)v->status);
        m.fit_status = hstpf_frames_est_type_fit_status_raw((double)v->fit);
        m.declared_type = row_code(v->declared_row);
        m.declared_weight = hstpf_frames_est_type_declared_weight_raw(v->declared_row == -1 ? 0.0 : v->declared_q);
        m.leader_type = row_code(v->leader_row);
        m.leader_weight = hstpf_frames_est_type_leader_weight_raw(v->leader_row == -1 ? 0.0 : v->leader_q);
        n = hstpf_can_est_type_pack(f->data, &m, 8u);
        break;
    }
    case 2: {
        struct hstpf_can_est_theta_t m;
        const int ok = hstpf_can_est_theta_c0_is_in_phys_range(v->theta[0]) &&
                       hstpf_can_est_theta_c1_is_in_phys_range(v->theta[1]) &&
                       hstpf_can_est_theta_c2_is_in_phys_range(v->theta[2]);
        (void)hstpf_can_est_theta_init(&m);
        m.theta_valid = (uint8_t)(v->have_fix && v->valid && ok);
        m.theta_saturated = (uint8_t)(v->have_fix && !ok);
        m.c0 = hstpf_frames_est_theta_c0_raw(v->theta[0]);
        m.c1 = hstpf_frames_est_theta_c1_raw(v->theta[1]);
        m.c2 = hstpf_frames_est_theta_c2_raw(v->theta[2]);
        n = hstpf_can_est_theta_pack(f->data, &m, 8u);
        break;
    }
    case 3: {
        struct hstpf_can_health_rx_t m;
        (void)hstpf_can_health_rx_init(&m);
        m.pos_stale = v->pos_stale ? 1u : 0u;
        m.tract_stale = v->trac_stale ? 1u : 0u;
        m.tract_implausible = v->trac_fault ? 1u : 0u;
        m.bad_crc = hstpf_frames_health_rx_bad_crc_raw(count(v->bad_crc));
        m.counter_repeat = hstpf_frames_health_rx_counter_repeat_raw(count(v->repeated));
        m.counter_jump = hstpf_frames_health_rx_counter_jump_raw(count(v->jump));
        m.wrong_length = hstpf_frames_health_rx_wrong_length_raw(count(v->wrong_length));
        n = hstpf_can_health_rx_pack(f->data, &m, 8u);
        break;
    }
    case HSTPFD_OUT_QUALITY: {
        struct hstpf_can_est_quality_t m;
        const int ok = hstpf_can_est_quality_position_sd_is_in_phys_range(v->position_sd_m) &&
                       hstpf_can_est_quality_speed_sd_is_in_phys_range(v->speed_sd_mps);
        (void)hstpf_can_est_quality_init(&m);
        m.qual_valid = (uint8_t)(v->have_fix && v->valid && v->sd_valid && ok);
        m.qual_fault = (uint8_t)(v->have_fix && !ok);
        m.standstill = v->standstill ? 1u : 0u;
        m.position_sd = hstpf_frames_est_quality_position_sd_raw(
            v->have_fix ? sd_up(v->position_sd_m, hstpf_can_est_quality_position_sd_decode(1u)) : 0.0);
        m.speed_sd = hstpf_frames_est_quality_speed_sd_raw(
            v->have_fix ? sd_up(v->speed_sd_mps, hstpf_can_est_quality_speed_sd_decode(1u)) : 0.0);
        m.est_time_valid = v->est_time_valid ? 1u : 0u;
        m.est_time = (uint16_t)(v->est_time_valid ? v->est_time_ms % HSTPF_FIX_TIME_WRAP_MS : 0u);
        n = hstpf_can_est_quality_pack(f->data, &m, 8u);
        break;
    }
    case HSTPFD_OUT_BAND: {
        struct hstpf_can_est_band_t m;
        int ok = 1;
        unsigned k;
        uint16_t raw[HSTPFD_BAND_N];
        for (k = 0; k < HSTPFD_BAND_N; ++k) {
            const double sd = v->w_sd[k];
            ok = ok && hstpf_can_est_band_w_sd0_is_in_phys_range(sd); /* one scale for all five */
            raw[k] = hstpf_frames_est_band_w_sd0_raw(
                v->have_fix && isfinite(sd) ? sd_up(sd, hstpf_can_est_band_w_sd0_decode(1u)) : 0.0);
        }
        (void)hstpf_can_est_band_init(&m);
        m.band_valid = (uint8_t)(v->have_fix && v->valid && v->sd_valid && ok);
        m.band_fault = (uint8_t)(v->have_fix && !ok);
        m.w_sd0 = raw[0];
        m.w_sd1 = raw[1];
        m.w_sd2 = raw[2];
        m.w_sd3 = raw[3];
        m.w_sd4 = raw[4];
        m.off_what = hstpf_frames_est_band_off_what_raw((double)(v->fit == (uint8_t)HSTPF_FIT_NONE ? v->off_what : 0u));
        n = hstpf_can_est_band_pack(f->data, &m, 8u);
        break;
    }
    case 5: {
        struct hstpf_can_health_time_t m;
        (void)hstpf_can_health_time_init(&m);
        m.clock_steps_fwd = hstpf_frames_health_time_clock_steps_fwd_raw(count(v->clock_fwd));
        m.clock_steps_back = hstpf_frames_health_time_clock_steps_back_raw(count(v->clock_back));
        m.late_positions = hstpf_frames_health_time_late_positions_raw(count(v->late));
        m.reacquisitions = hstpf_frames_health_time_reacquisitions_raw(count(v->reacquire));
        m.acquisitions = hstpf_frames_health_time_acquisitions_raw(count(v->acquisitions));
        n = hstpf_can_health_time_pack(f->data, &m, 8u);
        break;
    }
    default: {
        struct hstpf_can_health_sys_t m;
        (void)hstpf_can_health_sys_init(&m);
        m.stale_events = hstpf_frames_health_sys_stale_events_raw(count(v->stale_events));
        m.unknown_id = hstpf_frames_health_sys_unknown_id_raw(count(v->unknown_id));
        m.error_frames = hstpf_frames_health_sys_error_frames_raw(count(v->error_frames));
        m.degeneracy = hstpf_frames_health_sys_degeneracy_raw(count(v->degeneracy));
        n = hstpf_can_health_sys_pack(f->data, &m, 8u);
        break;
    }
    }
    if (n != 8) {
        return -1;
    }
    f->len = 8u;
    return hstpf_e2e_protect(&st->e2e[i], f->data, f->len) == 0 ? 0 : -1;
}
