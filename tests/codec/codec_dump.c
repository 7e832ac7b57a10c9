/*
 * Frame dump for tests/python/test_codec_agree.py (not a ctest itself).
 *
 *   hstpf_codec_dump           packs a fixed set of frames from physical
 *                              values with the C codec (saturating raw
 *                              conversion, cantools pack, E2E protect) and
 *                              prints one JSON line per frame: inputs, bytes,
 *                              and the values unpacked back by the C codec.
 *   hstpf_codec_dump e2e       prints the E2E parameters the C codec uses.
 *   hstpf_codec_dump decode    reads a candump -L log on stdin and prints,
 *                              per frame, what the C codec unpacks and the
 *                              E2E check result (one default receiver per
 *                              ID, timestamps as its clock), then the final
 *                              receiver counts per ID.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hstpf_can.h"
#include "hstpf_e2e.h"
#include "hstpf_frames.h"

static void hex(const uint8_t *f, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) {
        printf("%02X", f[i]);
    }
}

/* ---- encode side: one function per frame --------------------------------- */

static hstpf_e2e_tx_t tx[HSTPF_FRAMES_COUNT];

static hstpf_e2e_tx_t *tx_for(uint32_t id)
{
    const hstpf_frame_info_t *fi = hstpf_frame_find(id);
    return &tx[fi - hstpf_frames];
}

static void head(const char *name, uint32_t id, const uint8_t *f)
{
    printf("{\"msg\":\"%s\",\"id\":%u,\"bytes\":\"", name, (unsigned)id);
    hex(f, 8);
    printf("\",");
}

static void position(double valid, double quality, double pos, double fix_valid, double fix_ms)
{
    struct hstpf_can_position_t m;
    uint8_t f[8];
    hstpf_can_position_init(&m);
    m.pos_valid = hstpf_frames_position_pos_valid_raw(valid);
    m.pos_quality = hstpf_frames_position_pos_quality_raw(quality);
    m.fix_time_valid = hstpf_frames_position_fix_time_valid_raw(fix_valid);
    m.position = hstpf_frames_position_position_raw(pos);
    m.fix_time = hstpf_frames_position_fix_time_raw(fix_ms);
    hstpf_can_position_pack(f, &m, 8);
    hstpf_e2e_protect(tx_for(HSTPF_FRAME_POSITION_ID), f, 8);
    hstpf_can_position_unpack(&m, f, 8);
    head("Position", HSTPF_FRAME_POSITION_ID, f);
    printf("\"in\":{\"PosValid\":%.17g,\"PosQuality\":%.17g,\"FixTimeValid\":%.17g,\"Position\":%.17g,"
           "\"FixTime\":%.17g},",
           valid, quality, fix_valid, pos, fix_ms);
    printf("\"out\":{\"E2eCrc\":%u,\"E2eCounter\":%u,\"PosValid\":%.17g,\"PosQuality\":%.17g,"
           "\"FixTimeValid\":%.17g,\"Position\":%.17g,\"FixTime\":%.17g}}\n",
           m.e2e_crc, m.e2e_counter, hstpf_can_position_pos_valid_decode(m.pos_valid),
           hstpf_can_position_pos_quality_decode(m.pos_quality),
           hstpf_can_position_fix_time_valid_decode(m.fix_time_valid), hstpf_can_position_position_decode(m.position),
           hstpf_can_position_fix_time_decode(m.fix_time));
}

static void traction(double valid, double force)
{
    struct hstpf_can_traction_t m;
    uint8_t f[8];
    hstpf_can_traction_init(&m);
    m.tract_valid = hstpf_frames_traction_tract_valid_raw(valid);
    m.tract_force = hstpf_frames_traction_tract_force_raw(force);
    hstpf_can_traction_pack(f, &m, 8);
    hstpf_e2e_protect(tx_for(HSTPF_FRAME_TRACTION_ID), f, 8);
    hstpf_can_traction_unpack(&m, f, 8);
    head("Traction", HSTPF_FRAME_TRACTION_ID, f);
    printf("\"in\":{\"TractValid\":%.17g,\"TractForce\":%.17g},", valid, force);
    printf("\"out\":{\"E2eCrc\":%u,\"E2eCounter\":%u,\"TractValid\":%.17g,\"TractForce\":%.17g}}\n", m.e2e_crc,
           m.e2e_counter, hstpf_can_traction_tract_valid_decode(m.tract_valid),
           hstpf_can_traction_tract_force_decode(m.tract_force));
}

static void consist(double valid, double counter)
{
    struct hstpf_can_consist_t m;
    uint8_t f[8];
    hstpf_can_consist_init(&m);
    m.topo_valid = hstpf_frames_consist_topo_valid_raw(valid);
    m.topo_counter = hstpf_frames_consist_topo_counter_raw(counter);
    hstpf_can_consist_pack(f, &m, 8);
    hstpf_e2e_protect(tx_for(HSTPF_FRAME_CONSIST_ID), f, 8);
    hstpf_can_consist_unpack(&m, f, 8);
    head("Consist", HSTPF_FRAME_CONSIST_ID, f);
    printf("\"in\":{\"TopoValid\":%.17g,\"TopoCounter\":%.17g},", valid, counter);
    printf("\"out\":{\"E2eCrc\":%u,\"E2eCounter\":%u,\"TopoValid\":%.17g,\"TopoCounter\":%.17g}}\n", m.e2e_crc,
           m.e2e_counter, hstpf_can_consist_topo_valid_decode(m.topo_valid),
           hstpf_can_consist_topo_counter_decode(m.topo_counter));
}

static void est_state(double valid, double fault, double pos, double speed)
{
    struct hstpf_can_est_state_t m;
    uint8_t f[8];
    hstpf_can_est_state_init(&m);
    m.est_valid = hstpf_frames_est_state_est_valid_raw(valid);
    m.est_fault = hstpf_frames_est_state_est_fault_raw(fault);
    m.est_position = hstpf_frames_est_state_est_position_raw(pos);
    m.est_speed = hstpf_frames_est_state_est_speed_raw(speed);
    hstpf_can_est_state_pack(f, &m, 8);
    hstpf_e2e_protect(tx_for(HSTPF_FRAME_EST_STATE_ID), f, 8);
    hstpf_can_est_state_unpack(&m, f, 8);
    head("EstState", HSTPF_FRAME_EST_STATE_ID, f);
    printf("\"in\":{\"EstValid\":%.17g,\"EstFault\":%.17g,\"EstPosition\":%.17g,\"EstSpeed\":%.17g},", valid, fault,
           pos, speed);
    printf("\"out\":{\"E2eCrc\":%u,\"E2eCounter\":%u,\"EstValid\":%.17g,\"EstFault\":%.17g,\"EstPosition\":%.17g,"
           "\"EstSpeed\":%.17g}}\n",
           m.e2e_crc, m.e2e_counter, hstpf_can_est_state_est_valid_decode(m.est_valid),
           hstpf_can_est_state_est_fault_decode(m.est_fault), hstpf_can_est_state_est_position_decode(m.est_position),
           hstpf_can_est_state_est_speed_decode(m.est_speed));
}

static void est_type(double status, double fit, double decl, double dw, double lead, double lw)
{
    struct hstpf_can_est_type_t m;
    uint8_t f[8];
    hstpf_can_est_type_init(&m);
    m.type_status = hstpf_frames_est_type_type_status_raw(status);
    m.fit_status = hstpf_frames_est_type_fit_status_raw(fit);
    m.declared_type = hstpf_frames_est_type_declared_type_raw(decl);
    m.declared_weight = hstpf_frames_est_type_declared_weight_raw(dw);
    m.leader_type = hstpf_frames_est_type_leader_type_raw(lead);
    m.leader_weight = hstpf_frames_est_type_leader_weight_raw(lw);
    hstpf_can_est_type_pack(f, &m, 8);
    hstpf_e2e_protect(tx_for(HSTPF_FRAME_EST_TYPE_ID), f, 8);
    hstpf_can_est_type_unpack(&m, f, 8);
    head("EstType", HSTPF_FRAME_EST_TYPE_ID, f);
    printf("\"in\":{\"TypeStatus\":%.17g,\"FitStatus\":%.17g,\"DeclaredType\":%.17g,\"DeclaredWeight\":%.17g,"
           "\"LeaderType\":%.17g,\"LeaderWeight\":%.17g},",
           status, fit, decl, dw, lead, lw);
    printf("\"out\":{\"E2eCrc\":%u,\"E2eCounter\":%u,\"TypeStatus\":%.17g,\"FitStatus\":%.17g,\"DeclaredType\":%.17g,"
           "\"DeclaredWeight\":%.17g,\"LeaderType\":%.17g,\"LeaderWeight\":%.17g}}\n",
           m.e2e_crc, m.e2e_counter, hstpf_can_est_type_type_status_decode(m.type_status),
           hstpf_can_est_type_fit_status_decode(m.fit_status),
           hstpf_can_est_type_declared_type_decode(m.declared_type),
           hstpf_can_est_type_declared_weight_decode(m.declared_weight),
           hstpf_can_est_type_leader_type_decode(m.leader_type), hstpf_can_est_type_leader_weight_decode(m.leader_weight));
}

static void est_theta(double valid, double sat, double c0, double c1, double c2)
{
    struct hstpf_can_est_theta_t m;
    uint8_t f[8];
    hstpf_can_est_theta_init(&m);
    m.theta_valid = hstpf_frames_est_theta_theta_valid_raw(valid);
    m.theta_saturated = hstpf_frames_est_theta_theta_saturated_raw(sat);
    m.c0 = hstpf_frames_est_theta_c0_raw(c0);
    m.c1 = hstpf_frames_est_theta_c1_raw(c1);
    m.c2 = hstpf_frames_est_theta_c2_raw(c2);
    hstpf_can_est_theta_pack(f, &m, 8);
    hstpf_e2e_protect(tx_for(HSTPF_FRAME_EST_THETA_ID), f, 8);
    hstpf_can_est_theta_unpack(&m, f, 8);
    head("EstTheta", HSTPF_FRAME_EST_THETA_ID, f);
    printf("\"in\":{\"ThetaValid\":%.17g,\"ThetaSaturated\":%.17g,\"C0\":%.17g,\"C1\":%.17g,\"C2\":%.17g},", valid,
           sat, c0, c1, c2);
    printf("\"out\":{\"E2eCrc\":%u,\"E2eCounter\":%u,\"ThetaValid\":%.17g,\"ThetaSaturated\":%.17g,\"C0\":%.17g,"
           "\"C1\":%.17g,\"C2\":%.17g}}\n",
           m.e2e_crc, m.e2e_counter, hstpf_can_est_theta_theta_valid_decode(m.theta_valid),
           hstpf_can_est_theta_theta_saturated_decode(m.theta_saturated), hstpf_can_est_theta_c0_decode(m.c0),
           hstpf_can_est_theta_c1_decode(m.c1), hstpf_can_est_theta_c2_decode(m.c2));
}

static void est_band(double valid, double fault, const double sd[5], double off)
{
    struct hstpf_can_est_band_t m;
    uint8_t f[8];
    hstpf_can_est_band_init(&m);
    m.band_valid = hstpf_frames_est_band_band_valid_raw(valid);
    m.band_fault = hstpf_frames_est_band_band_fault_raw(fault);
    m.w_sd0 = hstpf_frames_est_band_w_sd0_raw(sd[0]);
    m.w_sd1 = hstpf_frames_est_band_w_sd1_raw(sd[1]);
    m.w_sd2 = hstpf_frames_est_band_w_sd2_raw(sd[2]);
    m.w_sd3 = hstpf_frames_est_band_w_sd3_raw(sd[3]);
    m.w_sd4 = hstpf_frames_est_band_w_sd4_raw(sd[4]);
    m.off_what = hstpf_frames_est_band_off_what_raw(off);
    hstpf_can_est_band_pack(f, &m, 8);
    hstpf_e2e_protect(tx_for(HSTPF_FRAME_EST_BAND_ID), f, 8);
    hstpf_can_est_band_unpack(&m, f, 8);
    head("EstBand", HSTPF_FRAME_EST_BAND_ID, f);
    printf("\"in\":{\"BandValid\":%.17g,\"BandFault\":%.17g,\"WSd0\":%.17g,\"WSd1\":%.17g,\"WSd2\":%.17g,"
           "\"WSd3\":%.17g,\"WSd4\":%.17g,\"OffWhat\":%.17g},",
           valid, fault, sd[0], sd[1], sd[2], sd[3], sd[4], off);
    printf("\"out\":{\"E2eCrc\":%u,\"E2eCounter\":%u,\"BandValid\":%.17g,\"BandFault\":%.17g,\"WSd0\":%.17g,"
           "\"WSd1\":%.17g,\"WSd2\":%.17g,\"WSd3\":%.17g,\"WSd4\":%.17g,\"OffWhat\":%.17g}}\n",
           m.e2e_crc, m.e2e_counter, hstpf_can_est_band_band_valid_decode(m.band_valid),
           hstpf_can_est_band_band_fault_decode(m.band_fault), hstpf_can_est_band_w_sd0_decode(m.w_sd0),
           hstpf_can_est_band_w_sd1_decode(m.w_sd1), hstpf_can_est_band_w_sd2_decode(m.w_sd2),
           hstpf_can_est_band_w_sd3_decode(m.w_sd3), hstpf_can_est_band_w_sd4_decode(m.w_sd4),
           hstpf_can_est_band_off_what_decode(m.off_what));
}

static void health_rx(double ps, double ts, double ti, double crc, double rep, double jump, double len)
{
    struct hstpf_can_health_rx_t m;
    uint8_t f[8];
    hstpf_can_health_rx_init(&m);
    m.pos_stale = hstpf_frames_health_rx_pos_stale_raw(ps);
    m.tract_stale = hstpf_frames_health_rx_tract_stale_raw(ts);
    m.tract_implausible = hstpf_frames_health_rx_tract_implausible_raw(ti);
    m.bad_crc = hstpf_frames_health_rx_bad_crc_raw(crc);
    m.counter_repeat = hstpf_frames_health_rx_counter_repeat_raw(rep);
    m.counter_jump = hstpf_frames_health_rx_counter_jump_raw(jump);
    m.wrong_length = hstpf_frames_health_rx_wrong_length_raw(len);
    hstpf_can_health_rx_pack(f, &m, 8);
    hstpf_e2e_protect(tx_for(HSTPF_FRAME_HEALTH_RX_ID), f, 8);
    hstpf_can_health_rx_unpack(&m, f, 8);
    head("HealthRx", HSTPF_FRAME_HEALTH_RX_ID, f);
    printf("\"in\":{\"PosStale\":%.17g,\"TractStale\":%.17g,\"TractImplausible\":%.17g,\"BadCrc\":%.17g,"
           "\"CounterRepeat\":%.17g,\"CounterJump\":%.17g,\"WrongLength\":%.17g},",
           ps, ts, ti, crc, rep, jump, len);
    printf("\"out\":{\"E2eCrc\":%u,\"E2eCounter\":%u,\"PosStale\":%u,\"TractStale\":%u,\"TractImplausible\":%u,"
           "\"BadCrc\":%u,\"CounterRepeat\":%u,\"CounterJump\":%u,\"WrongLength\":%u}}\n",
           m.e2e_crc, m.e2e_counter, m.pos_stale, m.tract_stale, m.tract_implausible, m.bad_crc, m.counter_repeat,
           m.counter_jump, m.wrong_length);
}

static void health_sys(double stale, double unk, double err, double deg)
{
    struct hstpf_can_health_sys_t m;
    uint8_t f[8];
    hstpf_can_health_sys_init(&m);
    m.stale_events = hstpf_frames_health_sys_stale_events_raw(stale);
    m.unknown_id = hstpf_frames_health_sys_unknown_id_raw(unk);
    m.error_frames = hstpf_frames_health_sys_error_frames_raw(err);
    m.degeneracy = hstpf_frames_health_sys_degeneracy_raw(deg);
    hstpf_can_health_sys_pack(f, &m, 8);
    hstpf_e2e_protect(tx_for(HSTPF_FRAME_HEALTH_SYS_ID), f, 8);
    hstpf_can_health_sys_unpack(&m, f, 8);
    head("HealthSys", HSTPF_FRAME_HEALTH_SYS_ID, f);
    printf("\"in\":{\"StaleEvents\":%.17g,\"UnknownId\":%.17g,\"ErrorFrames\":%.17g,\"Degeneracy\":%.17g},", stale,
           unk, err, deg);
    printf("\"out\":{\"E2eCrc\":%u,\"E2eCounter\":%u,\"StaleEvents\":%u,\"UnknownId\":%u,\"ErrorFrames\":%u,"
           "\"Degeneracy\":%u}}\n",
           m.e2e_crc, m.e2e_counter, m.stale_events, m.unknown_id, m.error_frames, m.degeneracy);
}

static void est_quality(double valid, double fault, double still, double tvalid, double psd, double vsd, double t)
{
    struct hstpf_can_est_quality_t m;
    uint8_t f[8];
    hstpf_can_est_quality_init(&m);
    m.qual_valid = hstpf_frames_est_quality_qual_valid_raw(valid);
    m.qual_fault = hstpf_frames_est_quality_qual_fault_raw(fault);
    m.standstill = hstpf_frames_est_quality_standstill_raw(still);
    m.est_time_valid = hstpf_frames_est_quality_est_time_valid_raw(tvalid);
    m.position_sd = hstpf_frames_est_quality_position_sd_raw(psd);
    m.speed_sd = hstpf_frames_est_quality_speed_sd_raw(vsd);
    m.est_time = hstpf_frames_est_quality_est_time_raw(t);
    hstpf_can_est_quality_pack(f, &m, 8);
    hstpf_e2e_protect(tx_for(HSTPF_FRAME_EST_QUALITY_ID), f, 8);
    hstpf_can_est_quality_unpack(&m, f, 8);
    head("EstQuality", HSTPF_FRAME_EST_QUALITY_ID, f);
    printf("\"in\":{\"QualValid\":%.17g,\"QualFault\":%.17g,\"Standstill\":%.17g,\"EstTimeValid\":%.17g,"
           "\"PositionSd\":%.17g,\"SpeedSd\":%.17g,\"EstTime\":%.17g},",
           valid, fault, still, tvalid, psd, vsd, t);
    printf("\"out\":{\"E2eCrc\":%u,\"E2eCounter\":%u,\"QualValid\":%u,\"QualFault\":%u,\"Standstill\":%u,"
           "\"EstTimeValid\":%u,\"PositionSd\":%.17g,\"SpeedSd\":%.17g,\"EstTime\":%u}}\n",
           m.e2e_crc, m.e2e_counter, m.qual_valid, m.qual_fault, m.standstill, m.est_time_valid,
           hstpf_can_est_quality_position_sd_decode(m.position_sd), hstpf_can_est_quality_speed_sd_decode(m.speed_sd),
           m.est_time);
}

static void health_time(double fwd, double back, double late, double reacq, double acq)
{
    struct hstpf_can_health_time_t m;
    uint8_t f[8];
    hstpf_can_health_time_init(&m);
    m.clock_steps_fwd = hstpf_frames_health_time_clock_steps_fwd_raw(fwd);
    m.clock_steps_back = hstpf_frames_health_time_clock_steps_back_raw(back);
    m.late_positions = hstpf_frames_health_time_late_positions_raw(late);
    m.reacquisitions = hstpf_frames_health_time_reacquisitions_raw(reacq);
    m.acquisitions = hstpf_frames_health_time_acquisitions_raw(acq);
    hstpf_can_health_time_pack(f, &m, 8);
    hstpf_e2e_protect(tx_for(HSTPF_FRAME_HEALTH_TIME_ID), f, 8);
    hstpf_can_health_time_unpack(&m, f, 8);
    head("HealthTime", HSTPF_FRAME_HEALTH_TIME_ID, f);
    printf("\"in\":{\"ClockStepsFwd\":%.17g,\"ClockStepsBack\":%.17g,\"LatePositions\":%.17g,\"Reacquisitions\":%.17g,"
           "\"Acquisitions\":%.17g},",
           fwd, back, late, reacq, acq);
    printf("\"out\":{\"E2eCrc\":%u,\"E2eCounter\":%u,\"ClockStepsFwd\":%u,\"ClockStepsBack\":%u,\"LatePositions\":%u,"
           "\"Reacquisitions\":%u,\"Acquisitions\":%u}}\n",
           m.e2e_crc, m.e2e_counter, m.clock_steps_fwd, m.clock_steps_back, m.late_positions, m.reacquisitions,
           m.acquisitions);
}

static void encode_set(void)
{
    size_t i;
    int k;
    for (i = 0; i < HSTPF_FRAMES_COUNT; i++) {
        hstpf_e2e_tx_init(&tx[i], hstpf_frames[i].data_id);
    }
    /* 17 position frames: the counter wraps 14 -> 0 on the way. */
    for (k = 0; k < 17; k++) {
        position(k % 5 != 3, k % 4, 97.2221 * k * k + 0.00037 * k, k % 7 != 2, (double)((k * 997) % 8192));
    }
    position(1, 3, -2.718, 1, 0.0);       /* a noisy fix near the origin */
    position(1, 3, 100000000.0, 1, 8191.0); /* the largest position, the last fix time before the wrap */
    position(1, 3, -100000000.0, 0, 0.0);
    traction(1, 0.0);
    traction(1, 187.33);
    traction(1, -412.07);
    traction(0, -83886.08);
    traction(1, 83886.07);
    consist(1, 0.0);
    consist(1, 4294967295.0);
    consist(0, 17.0);
    est_state(0, 0, 0.0, 0.0);
    est_state(1, 0, 1234.567, 97.22);
    est_state(1, 0, 350123.456, -0.37);
    est_state(1, 0, -42.0, -327.68);
    est_state(0, 1, 21474836.47, 327.67);
    est_type(0, 0, 255, 0.0, 2, 0.4711);
    est_type(1, 1, 2, 0.9532, 2, 0.9532);
    est_type(2, 1, 6, 1.0, 6, 1.0);
    est_type(0, 2, 255, 0.0, 14, 0.7); /* no table type fits */
    est_theta(1, 0, 0.79, 0.0064, 0.000115);
    est_theta(1, 0, 2.25, 0.019, 0.00032);
    est_theta(1, 1, 65.535, 0.065535, 0.0013107);
    health_rx(0, 0, 0, 0, 0, 0, 0);
    health_rx(1, 0, 1, 17, 3, 4095, 1);
    health_sys(2, 0, 41, 4095);
    health_sys(0, 1, 0, 0);
    health_time(1, 2, 37, 1023, 5);
    est_quality(1, 0, 0, 1, 2.24, 0.22, 4660);
    est_quality(1, 0, 1, 1, 0.0, 0.0, 0);
    est_quality(0, 1, 0, 0, 10485.75, 40.95, 8191);
    est_type(3, 0, 255, 0.0, 6, 0.42); /* withdrawn */
    {
        static const double sd0[5] = {0.237, 0.3, 1.175, 2.6, 4.29};
        static const double sd1[5] = {0.0, 0.05, 25.5, 25.55, 0.5};
        est_band(1, 0, sd0, 0);
        est_band(1, 0, sd1, 3);
        est_band(0, 1, sd1, 12);
    }
}

/* ---- decode side ---------------------------------------------------------- */

static hstpf_e2e_rx_t rx[HSTPF_FRAMES_COUNT];

/* One candump -L line: "(SECONDS) CHANNEL ID#HEX [R|T]". */
static int decode_line(const char *line)
{
    char *end;
    double ts;
    unsigned long id;
    uint8_t f[64];
    size_t n = 0;
    const hstpf_frame_info_t *fi;
    const char *p;
    hstpf_e2e_result_t r;
    uint32_t now_ms;

    p = strchr(line, '(');
    if (p == NULL) {
        return -1;
    }
    ts = strtod(p + 1, &end);
    now_ms = (uint32_t)(uint64_t)(ts * 1000.0 + 0.5); /* wraps: only differences matter */
    p = strchr(end, ' ');
    p = p != NULL ? strchr(p + 1, ' ') : NULL; /* skip the channel */
    if (p == NULL) {
        return -1;
    }
    id = strtoul(p + 1, &end, 16);
    if (*end != '#') {
        return -1;
    }
    p = end + 1;
    while (p[0] != '\0' && p[1] != '\0' && p[0] != ' ' && p[0] != '\n' && n < sizeof f) {
        char b[3];
        b[0] = p[0];
        b[1] = p[1];
        b[2] = 0;
        f[n++] = (uint8_t)strtoul(b, NULL, 16);
        p += 2;
    }
    fi = hstpf_frame_find((uint32_t)id);
    if (fi == NULL) {
        printf("{\"id\":%lu,\"unknown\":true}\n", id);
        return 0;
    }
    r = hstpf_e2e_rx_check(&rx[fi - hstpf_frames], f, n, now_ms);
    printf("{\"msg\":\"%s\",\"id\":%lu,\"e2e\":\"%s\",\"out\":{", fi->name, id, hstpf_e2e_result_name(r));
    if (n != 8) {
        printf("}}\n");
        return 0;
    }
    switch (fi->can_id) {
    case HSTPF_FRAME_POSITION_ID: {
        struct hstpf_can_position_t m;
        hstpf_can_position_unpack(&m, f, n);
        printf("\"E2eCrc\":%u,\"E2eCounter\":%u,\"PosValid\":%u,\"PosQuality\":%u,\"FixTimeValid\":%u,"
               "\"Position\":%.17g,\"FixTime\":%u",
               m.e2e_crc, m.e2e_counter, m.pos_valid, m.pos_quality, m.fix_time_valid,
               hstpf_can_position_position_decode(m.position), m.fix_time);
        break;
    }
    case HSTPF_FRAME_TRACTION_ID: {
        struct hstpf_can_traction_t m;
        hstpf_can_traction_unpack(&m, f, n);
        printf("\"E2eCrc\":%u,\"E2eCounter\":%u,\"TractValid\":%u,\"TractForce\":%.17g", m.e2e_crc, m.e2e_counter,
               m.tract_valid, hstpf_can_traction_tract_force_decode(m.tract_force));
        break;
    }
    case HSTPF_FRAME_CONSIST_ID: {
        struct hstpf_can_consist_t m;
        hstpf_can_consist_unpack(&m, f, n);
        printf("\"E2eCrc\":%u,\"E2eCounter\":%u,\"TopoValid\":%u,\"TopoCounter\":%lu", m.e2e_crc, m.e2e_counter,
               m.topo_valid, (unsigned long)m.topo_counter);
        break;
    }
    case HSTPF_FRAME_EST_STATE_ID: {
        struct hstpf_can_est_state_t m;
        hstpf_can_est_state_unpack(&m, f, n);
        printf("\"E2eCrc\":%u,\"E2eCounter\":%u,\"EstValid\":%u,\"EstFault\":%u,\"EstPosition\":%.17g,"
               "\"EstSpeed\":%.17g",
               m.e2e_crc, m.e2e_counter, m.est_valid, m.est_fault, hstpf_can_est_state_est_position_decode(m.est_position),
               hstpf_can_est_state_est_speed_decode(m.est_speed));
        break;
    }
    case HSTPF_FRAME_EST_TYPE_ID: {
        struct hstpf_can_est_type_t m;
        hstpf_can_est_type_unpack(&m, f, n);
        printf("\"E2eCrc\":%u,\"E2eCounter\":%u,\"TypeStatus\":%u,\"FitStatus\":%u,\"DeclaredType\":%u,"
               "\"DeclaredWeight\":%.17g,\"LeaderType\":%u,\"LeaderWeight\":%.17g",
               m.e2e_crc, m.e2e_counter, m.type_status, m.fit_status, m.declared_type,
               hstpf_can_est_type_declared_weight_decode(m.declared_weight), m.leader_type,
               hstpf_can_est_type_leader_weight_decode(m.leader_weight));
        break;
    }
    case HSTPF_FRAME_EST_BAND_ID: {
        struct hstpf_can_est_band_t m;
        hstpf_can_est_band_unpack(&m, f, n);
        printf("\"E2eCrc\":%u,\"E2eCounter\":%u,\"BandValid\":%u,\"BandFault\":%u,\"WSd0\":%.17g,\"WSd1\":%.17g,"
               "\"WSd2\":%.17g,\"WSd3\":%.17g,\"WSd4\":%.17g,\"OffWhat\":%u",
               m.e2e_crc, m.e2e_counter, m.band_valid, m.band_fault, hstpf_can_est_band_w_sd0_decode(m.w_sd0),
               hstpf_can_est_band_w_sd1_decode(m.w_sd1), hstpf_can_est_band_w_sd2_decode(m.w_sd2),
               hstpf_can_est_band_w_sd3_decode(m.w_sd3), hstpf_can_est_band_w_sd4_decode(m.w_sd4), m.off_what);
        break;
    }
    case HSTPF_FRAME_EST_THETA_ID: {
        struct hstpf_can_est_theta_t m;
        hstpf_can_est_theta_unpack(&m, f, n);
        printf("\"E2eCrc\":%u,\"E2eCounter\":%u,\"ThetaValid\":%u,\"ThetaSaturated\":%u,\"C0\":%.17g,\"C1\":%.17g,"
               "\"C2\":%.17g",
               m.e2e_crc, m.e2e_counter, m.theta_valid, m.theta_saturated, hstpf_can_est_theta_c0_decode(m.c0),
               hstpf_can_est_theta_c1_decode(m.c1), hstpf_can_est_theta_c2_decode(m.c2));
        break;
    }
    case HSTPF_FRAME_HEALTH_RX_ID: {
        struct hstpf_can_health_rx_t m;
        hstpf_can_health_rx_unpack(&m, f, n);
        printf("\"E2eCrc\":%u,\"E2eCounter\":%u,\"PosStale\":%u,\"TractStale\":%u,\"BadCrc\":%u,\"CounterRepeat\":%u,"
               "\"CounterJump\":%u,\"WrongLength\":%u",
               m.e2e_crc, m.e2e_counter, m.pos_stale, m.tract_stale, m.bad_crc, m.counter_repeat, m.counter_jump,
               m.wrong_length);
        break;
    }
    case HSTPF_FRAME_EST_QUALITY_ID: {
        struct hstpf_can_est_quality_t m;
        hstpf_can_est_quality_unpack(&m, f, n);
        printf("\"E2eCrc\":%u,\"E2eCounter\":%u,\"QualValid\":%u,\"QualFault\":%u,\"Standstill\":%u,"
               "\"EstTimeValid\":%u,\"PositionSd\":%.17g,\"SpeedSd\":%.17g,\"EstTime\":%u",
               m.e2e_crc, m.e2e_counter, m.qual_valid, m.qual_fault, m.standstill, m.est_time_valid,
               hstpf_can_est_quality_position_sd_decode(m.position_sd),
               hstpf_can_est_quality_speed_sd_decode(m.speed_sd), m.est_time);
        break;
    }
    case HSTPF_FRAME_HEALTH_TIME_ID: {
        struct hstpf_can_health_time_t m;
        hstpf_can_health_time_unpack(&m, f, n);
        printf("\"E2eCrc\":%u,\"E2eCounter\":%u,\"ClockStepsFwd\":%u,\"ClockStepsBack\":%u,\"LatePositions\":%u,"
               "\"Reacquisitions\":%u,\"Acquisitions\":%u",
               m.e2e_crc, m.e2e_counter, m.clock_steps_fwd, m.clock_steps_back, m.late_positions, m.reacquisitions,
               m.acquisitions);
        break;
    }
    default: {
        struct hstpf_can_health_sys_t m;
        hstpf_can_health_sys_unpack(&m, f, n);
        printf("\"E2eCrc\":%u,\"E2eCounter\":%u,\"StaleEvents\":%u,\"UnknownId\":%u,\"ErrorFrames\":%u,"
               "\"Degeneracy\":%u",
               m.e2e_crc, m.e2e_counter, m.stale_events, m.unknown_id, m.error_frames, m.degeneracy);
        break;
    }
    }
    printf("}}\n");
    return 0;
}

static int decode_stdin(void)
{
    char line[512];
    size_t i;
    for (i = 0; i < HSTPF_FRAMES_COUNT; i++) {
        hstpf_e2e_rx_config_t c;
        hstpf_frames_e2e_rx_config(&c, hstpf_frames[i].can_id); /* the DBC's parameters of the frame */
        hstpf_e2e_rx_init(&rx[i], &c);
    }
    while (fgets(line, sizeof line, stdin) != NULL) {
        if (decode_line(line) != 0 && line[0] != '\n') {
            fprintf(stderr, "bad line: %s", line);
            return 1;
        }
    }
    /* Final per-frame receiver counts, for comparison with hstpf_tools.e2e. */
    printf("{\"counts\":{");
    for (i = 0; i < HSTPF_FRAMES_COUNT; i++) {
        const hstpf_e2e_counts_t *c = hstpf_e2e_rx_counts(&rx[i]);
        printf("%s\"0x%03X\":{\"ok\":%u,\"lost\":%u,\"wrong_length\":%u,\"bad_crc\":%u,\"repeated\":%u,\"jump\":%u,"
               "\"stale\":%u}",
               i ? "," : "", (unsigned)hstpf_frames[i].can_id, (unsigned)c->ok, (unsigned)c->lost,
               (unsigned)c->wrong_length, (unsigned)c->bad_crc, (unsigned)c->repeated, (unsigned)c->jump,
               (unsigned)c->stale);
    }
    printf("}}\n");
    return 0;
}

/* The E2E parameters the C codec uses: the default receiver configuration
 * and each frame's (for tests/python/test_e2e_params.py). */
static int e2e_params(void)
{
    hstpf_e2e_rx_config_t c;
    size_t i;
    hstpf_e2e_rx_config_default(&c, 0u, 8u);
    printf("{\"profile\":\"%s\",\"default\":{\"max_delta\":%u,\"timeout_ms\":%u},\"frames\":{", HSTPF_E2E_PROFILE,
           (unsigned)c.max_delta, (unsigned)c.timeout_ms);
    for (i = 0; i < HSTPF_FRAMES_COUNT; i++) {
        if (hstpf_frames_e2e_rx_config(&c, hstpf_frames[i].can_id) != 0) {
            return 1;
        }
        printf("%s\"%s\":{\"data_id\":%u,\"max_delta\":%u,\"timeout_ms\":%u}", i ? "," : "", hstpf_frames[i].name,
               (unsigned)c.data_id, (unsigned)c.max_delta, (unsigned)c.timeout_ms);
    }
    printf("}}\n");
    return 0;
}

int main(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "decode") == 0) {
        return decode_stdin();
    }
    if (argc > 1 && strcmp(argv[1], "e2e") == 0) {
        return e2e_params();
    }
    encode_set();
    return 0;
}
