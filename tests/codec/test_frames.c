/* Unit tests of the generated frame table, the saturating physical->raw
 * conversions and a pack -> protect -> check -> unpack round trip. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "hstpf_can.h"
#include "hstpf_e2e.h"
#include "hstpf_frames.h"

static void test_frame_table(void **state)
{
    size_t i, j;
    (void)state;
    assert_int_equal(HSTPF_FRAMES_COUNT, 11);
    for (i = 0; i < HSTPF_FRAMES_COUNT; i++) {
        assert_true(hstpf_frames[i].can_id <= 0x7FFu); /* 11-bit */
        assert_int_equal(hstpf_frames[i].length, 8);
        assert_true(hstpf_frames[i].cycle_ms >= 100u);
        assert_ptr_equal(hstpf_frame_find(hstpf_frames[i].can_id), &hstpf_frames[i]);
        for (j = i + 1; j < HSTPF_FRAMES_COUNT; j++) {
            assert_true(hstpf_frames[i].can_id < hstpf_frames[j].can_id);
            assert_int_not_equal(hstpf_frames[i].data_id, hstpf_frames[j].data_id);
        }
    }
    assert_null(hstpf_frame_find(0x7FFu));
    /* The generated table and cantools' own macros agree. */
    assert_int_equal(HSTPF_FRAME_POSITION_ID, HSTPF_CAN_POSITION_FRAME_ID);
    assert_int_equal(HSTPF_FRAME_EST_THETA_CYCLE_MS, HSTPF_CAN_EST_THETA_CYCLE_TIME_MS);
    assert_string_equal(hstpf_frame_find(HSTPF_FRAME_TRACTION_ID)->name, "Traction");
    assert_string_equal(hstpf_frame_find(HSTPF_FRAME_CONSIST_ID)->name, "Consist");
    assert_int_equal(HSTPF_FRAME_CONSIST_ID, 0x102u);
}

static void test_raw_saturation_and_rounding(void **state)
{
    double nan = 0.0;
    (void)state;
    nan = nan / nan;
    /* Position, signed 35 bit, 1 cm, [-1e8, 1e8] m. */
    assert_true(hstpf_frames_position_position_raw(1234.5649) == 123456);
    assert_true(hstpf_frames_position_position_raw(1234.5651) == 123457);
    assert_true(hstpf_frames_position_position_raw(-3.0051) == -301);
    assert_true(hstpf_frames_position_position_raw(1e12) == INT64_C(10000000000));
    assert_true(hstpf_frames_position_position_raw(-1e12) == -INT64_C(10000000000));
    assert_true(hstpf_frames_position_position_raw(nan) == 0);
    /* Fix time, 13 bit, 1 ms: the sender wraps it; the helper only clamps. */
    assert_int_equal(HSTPF_FIX_TIME_WRAP_MS, 8192);
    assert_int_equal(hstpf_frames_position_fix_time_raw(8191.0), 8191u);
    assert_int_equal(hstpf_frames_position_fix_time_raw(9000.0), 8191u);
    assert_int_equal(hstpf_frames_position_fix_time_raw(-5.0), 0u);
    /* Estimated position, signed 32 bit, 1 cm. */
    assert_int_equal(hstpf_frames_est_state_est_position_raw(350123.456), 35012346);
    assert_int_equal(hstpf_frames_est_state_est_position_raw(-1e9), INT32_MIN);
    /* Traction force, signed 24 bit, 0.01 kN. */
    assert_int_equal(hstpf_frames_traction_tract_force_raw(-123.456), -12346);
    assert_int_equal(hstpf_frames_traction_tract_force_raw(123.454), 12345);
    assert_int_equal(hstpf_frames_traction_tract_force_raw(-1e9), -8388608);
    assert_int_equal(hstpf_frames_traction_tract_force_raw(1e9), 8388607);
    /* Speed, signed 16 bit, 0.01 m/s. */
    assert_int_equal(hstpf_frames_est_state_est_speed_raw(97.2222), 9722);
    assert_int_equal(hstpf_frames_est_state_est_speed_raw(-400.0), -32768);
    /* Weights are clamped to the DBC's [0, 1], not the 16-bit width. */
    assert_int_equal(hstpf_frames_est_type_declared_weight_raw(1.7), 10000u);
    assert_int_equal(hstpf_frames_est_type_leader_weight_raw(0.93214), 9321u);
    /* Theta: CRH3 and a clipped c2. */
    assert_int_equal(hstpf_frames_est_theta_c0_raw(0.79), 790u);
    assert_int_equal(hstpf_frames_est_theta_c1_raw(0.0064), 6400u);
    assert_int_equal(hstpf_frames_est_theta_c2_raw(0.000115), 5750u);
    assert_int_equal(hstpf_frames_est_theta_c2_raw(0.01), 65535u);
    /* 12-bit counters saturate at 4095. */
    assert_int_equal(hstpf_frames_health_rx_bad_crc_raw(100000.0), 4095u);
    assert_int_equal(hstpf_frames_health_sys_degeneracy_raw(17.0), 17u);
}

static void test_pack_protect_check_unpack(void **state)
{
    struct hstpf_can_traction_t m, back;
    hstpf_e2e_tx_t tx;
    hstpf_e2e_rx_config_t cfg;
    hstpf_e2e_rx_t rx;
    uint8_t f[8];
    int k;
    (void)state;
    assert_int_equal(hstpf_e2e_tx_init(&tx, HSTPF_FRAME_TRACTION_DATA_ID), 0);
    assert_int_equal(hstpf_e2e_rx_config_default(&cfg, HSTPF_FRAME_TRACTION_DATA_ID, HSTPF_FRAME_TRACTION_LENGTH), 0);
    assert_int_equal(hstpf_e2e_rx_init(&rx, &cfg), 0);
    for (k = 0; k < 20; k++) {
        double force = -250.0 + 31.17 * k;
        assert_int_equal(hstpf_can_traction_init(&m), 0);
        m.tract_valid = 1;
        m.tract_force = hstpf_frames_traction_tract_force_raw(force);
        assert_int_equal(hstpf_can_traction_pack(f, &m, sizeof f), 8);
        assert_int_equal(hstpf_e2e_protect(&tx, f, sizeof f), 0);
        assert_true(hstpf_e2e_accepted(hstpf_e2e_rx_check(&rx, f, sizeof f, (uint32_t)(100 * k))));
        assert_int_equal(hstpf_can_traction_unpack(&back, f, sizeof f), 0);
        assert_int_equal(back.e2e_counter, k % 15);
        assert_int_equal(back.tract_valid, 1);
        assert_float_equal(hstpf_can_traction_tract_force_decode(back.tract_force), force, 0.005 + 1e-9);
    }
    assert_int_equal(hstpf_e2e_rx_counts(&rx)->ok, 20);
}

/* The re-packed position frame: a 35-bit signed field across bytes 2..6,
 * FixTime in the top 13 bits; each field comes back on its own. */
static void test_position_fix_time_round_trip(void **state)
{
    static const double pos[] = {-100000000.0, -2.71, 0.0, 0.01, 1234567.89, 100000000.0};
    static const uint16_t fix[] = {0u, 1u, 4095u, 4096u, 8190u, 8191u};
    struct hstpf_can_position_t m, back;
    uint8_t f[8];
    size_t i;
    (void)state;
    for (i = 0; i < sizeof pos / sizeof pos[0]; i++) {
        assert_int_equal(hstpf_can_position_init(&m), 0);
        m.pos_valid = 1;
        m.pos_quality = 3;
        m.fix_time_valid = 1;
        m.position = hstpf_frames_position_position_raw(pos[i]);
        m.fix_time = fix[i];
        assert_int_equal(hstpf_can_position_pack(f, &m, sizeof f), 8);
        /* by hand: FixTime is bits 51..63, i.e. the top 13 bits of bytes 6..7 */
        assert_int_equal(((unsigned)f[6] >> 3) | ((unsigned)f[7] << 5), fix[i]);
        assert_int_equal((f[1] >> 4) & 1u, 1);         /* PosValid, bit 12 */
        assert_int_equal((f[1] >> 5) & 3u, 3);         /* PosQuality, bits 13..14 */
        assert_int_equal((f[1] >> 7) & 1u, 1);         /* FixTimeValid, bit 15 */
        assert_int_equal(hstpf_can_position_unpack(&back, f, sizeof f), 0);
        assert_int_equal(back.fix_time, fix[i]);
        assert_int_equal(back.fix_time_valid, 1);
        assert_int_equal(back.pos_quality, 3);
        assert_float_equal(hstpf_can_position_position_decode(back.position), pos[i], 0.005 + 1e-9);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_frame_table),
        cmocka_unit_test(test_raw_saturation_and_rounding),
        cmocka_unit_test(test_pack_protect_check_unpack),
        cmocka_unit_test(test_position_fix_time_round_trip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
