/* The simulator's truth physics (tools/sim/hstpf_sim.h), checked against
 * values derived by hand from the rule:
 *   held (v == 0, u - c0 - g <= 0): s' = s, v' = 0, no noise;
 *   else s' = s + T v + w_s, v' = max(0, v + T xi (u - W(v) - g) + w_v);
 * and a journey timetable's stops, dwells and reported holding brake. */
#include "hstpf_sim.h"
#include "testutil.h"

#include <string.h>

static double xi_of(double gamma) { return 9.81 / (1.0 + gamma) / 1000.0; }

static void test_held_rule(void **state)
{
    const hstpf_theta_t th = {"x", 1.0, 0.0, 0.0};
    (void)state;
    assert_true(hstpf_sim_held(&th, 0.0, HSTPF_SIM_HOLD_BRAKE, 0.0));
    assert_true(hstpf_sim_held(&th, 0.0, 0.0, 0.0));  /* u = 0 at a platform */
    assert_true(hstpf_sim_held(&th, 0.0, 1.0, 0.0));  /* exactly c0: cannot start */
    assert_false(hstpf_sim_held(&th, 0.0, 1.5, 0.0)); /* departs */
    assert_true(hstpf_sim_held(&th, 0.0, 1.5, 0.5));  /* uphill: c0 + g = 1.5 */
    assert_false(hstpf_sim_held(&th, 0.0, 0.0, -2.0)); /* downhill pulls it away */
    assert_false(hstpf_sim_held(&th, 1e-9, -50.0, 0.0)); /* moving: not held */
}

/* Noise-free coasting against c0 = 50 N/kN from 1 m/s: 1, 1 - d, 1 - 2d,
 * then 0 (clamped, d = 50 xi = 0.4627 m/s per step), then held. */
static void test_never_reverses_noise_free(void **state)
{
    static const hstpf_track_seg_t none[1] = {{0.0, 0.0, 0.0}};
    hstpf_sim_config_t c;
    hstpf_sim_t sim;
    hstpf_sim_sample_t smp;
    const double d = 50.0 * xi_of(0.06);
    int k;
    (void)state;
    hstpf_sim_default(&c);
    c.truth.c0 = 50.0;
    c.truth.c1 = 0.0;
    c.truth.c2 = 0.0;
    memset(&c.noise_s, 0, sizeof c.noise_s);
    memset(&c.noise_v, 0, sizeof c.noise_v);
    c.noise_s.kind = c.noise_v.kind = HSTPF_DIST_GAUSSIAN;
    c.profile = HSTPF_PROFILE_COAST_BRAKE;
    c.track = none;
    c.n_track = 1;
    hstpf_sim_init(&sim, &c);
    sim.t = 600.0; /* the coasting phase */
    sim.v = 1.0;
    {
        const double want[6] = {1.0, 1.0 - d, 1.0 - 2.0 * d, 0.0, 0.0, 0.0};
        const double s_want[6] = {0.0, 1.0, 2.0 - d, 3.0 - 3.0 * d, 3.0 - 3.0 * d, 3.0 - 3.0 * d};
        for (k = 0; k < 6; ++k) {
            hstpf_sim_next(&sim, &smp);
            TU_CLOSE(smp.v, want[k], 1e-12);
            TU_CLOSE(smp.s, s_want[k], 1e-12);
            TU_CLOSE(smp.u, 0.0, 0.0);
            assert_int_equal(smp.held, k >= 3);
        }
    }
}

/* With Case 1 noise a held train does not move at all, and a braking train
 * never goes below 0. */
static void test_held_train_does_not_random_walk(void **state)
{
    static const hstpf_sim_leg_t legs[1] = {{100.0, 60.0, 600.0}};
    hstpf_sim_config_t c;
    hstpf_sim_t sim;
    hstpf_sim_sample_t smp;
    double s_rest = -1.0, t_rest = -1.0, t_dep = -1.0;
    int k;
    (void)state;
    hstpf_sim_default(&c);
    c.profile = HSTPF_PROFILE_JOURNEY;
    c.legs = legs;
    c.n_legs = 1;
    c.first_dwell_s = 30.0;
    c.seed = 7;
    hstpf_sim_init(&sim, &c);
    for (k = 0; k < 1000; ++k) {
        hstpf_sim_next(&sim, &smp);
        assert_true(smp.v >= 0.0);
        if (smp.t < 30.0) { /* the origin's dwell: at rest from t = 0 */
            assert_true(smp.held);
            TU_CLOSE(smp.s, 0.0, 0.0);
            TU_CLOSE(smp.u, HSTPF_SIM_HOLD_BRAKE, 0.0);
        } else if (smp.t == 30.0) {
            assert_false(smp.held); /* departs after exactly 30 s */
            assert_true(smp.u > c.truth.c0);
        } else if (smp.t > 40.0 && smp.v == 0.0 && t_rest < 0.0) {
            t_rest = smp.t;
            s_rest = smp.s;
        }
        if (t_rest >= 0.0 && smp.t >= t_rest && smp.t < t_rest + 600.0) {
            /* the last leg's stop: held for good (after its dwell too) */
            assert_true(smp.held);
            TU_CLOSE(smp.s, s_rest, 0.0);
            TU_CLOSE(smp.v, 0.0, 0.0);
            TU_CLOSE(smp.u, HSTPF_SIM_HOLD_BRAKE, 0.0);
        }
        if (t_rest >= 0.0 && t_dep < 0.0 && smp.v > 0.0) {
            t_dep = smp.t;
        }
    }
    /* run 60 s from t = 30 (reaching ~24 m/s at 0.4 m/s^2), brake at
     * 0.5 m/s^2 (~48 s): at rest near t = 140 s */
    assert_true(t_rest > 120.0 && t_rest < 160.0);
    assert_true(t_dep < 0.0); /* the last leg: no departure */
}

/* Two legs: the train stands dwell_s from the step it came to rest, then
 * departs with traction above c0. */
static void test_dwell_then_departure(void **state)
{
    static const hstpf_sim_leg_t legs[2] = {{200.0, 120.0, 120.0}, {200.0, 100.0, -1.0}};
    hstpf_sim_config_t c;
    hstpf_sim_t sim;
    hstpf_sim_sample_t smp;
    double t_rest = -1.0, t_dep = -1.0;
    int k;
    (void)state;
    hstpf_sim_default(&c);
    c.profile = HSTPF_PROFILE_JOURNEY;
    c.legs = legs;
    c.n_legs = 2;
    c.first_dwell_s = -1.0;
    c.v0_mps = 200.0 / 3.6; /* starts running at speed */
    c.seed = 3;
    hstpf_sim_init(&sim, &c);
    for (k = 0; k < 800; ++k) {
        hstpf_sim_next(&sim, &smp);
        if (k == 0) {
            TU_CLOSE(smp.v, 200.0 / 3.6, 0.0);
        }
        if (t_rest < 0.0 && smp.v == 0.0) {
            t_rest = smp.t;
        }
        if (t_rest >= 0.0 && t_dep < 0.0 && !smp.held) {
            t_dep = smp.t;
            assert_true(smp.u > c.truth.c0);
        }
    }
    assert_true(t_rest > 0.0);
    TU_CLOSE(t_dep - t_rest, 120.0, 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_held_rule),
        cmocka_unit_test(test_never_reverses_noise_free),
        cmocka_unit_test(test_held_train_does_not_random_walk),
        cmocka_unit_test(test_dwell_then_departure),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
