/* cmocka tests: the step scheduler, with hand-computed expectations. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "sched.h"

#define S(x) ((int64_t)((x) * 1000000.0 + 0.5)) /* seconds -> us */
#define T0 INT64_C(1700000000000000)

static hstpfd_step_t got[64];
static int n_got;

static void collect(void *ctx, const hstpfd_step_t *st)
{
    (void)ctx;
    assert_true(n_got < 64);
    got[n_got++] = *st;
}

static hstpfd_sched_config_t base(void)
{
    hstpfd_sched_config_t c;
    memset(&c, 0, sizeof c);
    c.step_period_s = 0.0;
    c.pos_timeout_s = 3.0;
    c.trac_timeout_s = 3.0;
    c.predict_period_s = 1.0;
    c.max_gap_s = 600.0;
    c.first_dt_s = 1.0;
    c.mass_t = 500.0;
    c.traction_mode = HSTPFD_TRACTION_MEAN;
    c.stale_policy = HSTPFD_STALE_PREDICT;
    return c;
}

static void start(hstpfd_sched_t *s, const hstpfd_sched_config_t *c)
{
    n_got = 0;
    memset(got, 0, sizeof got);
    assert_int_equal(hstpfd_sched_init(s, c, collect, NULL), 0);
}

static void test_traction_unit(void **state)
{
    (void)state;
    /* 490.5 kN on 500 t: weight 500 x 9.81 = 4905 kN; 490500 N / 4905 kN */
    assert_float_equal(hstpfd_traction_unit(490.5, 500.0), 100.0, 1e-12);
    assert_float_equal(hstpfd_traction_unit(-98.1, 100.0), -100.0, 1e-12);
    assert_float_equal(hstpfd_traction_unit(0.0, 100.0), 0.0, 0.0);
}

static void test_init_checks(void **state)
{
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    (void)state;
    assert_int_equal(hstpfd_sched_init(&s, &c, NULL, NULL), 0);
    c.mass_t = 0.0;
    assert_int_equal(hstpfd_sched_init(&s, &c, NULL, NULL), -1);
    c = base();
    c.predict_period_s = 61.0;
    assert_int_equal(hstpfd_sched_init(&s, &c, NULL, NULL), -1);
    c = base();
    c.step_period_s = -1.0;
    assert_int_equal(hstpfd_sched_init(&s, &c, NULL, NULL), -1);
    c = base();
    c.stale_policy = (hstpfd_stale_policy_t)7;
    assert_int_equal(hstpfd_sched_init(&s, &c, NULL, NULL), -1);
    assert_int_equal(hstpfd_sched_init(NULL, &c, NULL, NULL), -1);
}

/* dt comes from the position timestamps; the first step is first_dt_s. */
static void test_dt_from_timestamps(void **state)
{
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    (void)state;
    start(&s, &c);
    hstpfd_sched_position(&s, T0, 100.0);
    hstpfd_sched_position(&s, T0 + S(1.0), 110.0);
    hstpfd_sched_position(&s, T0 + S(2.5), 125.0);
    hstpfd_sched_position(&s, T0 + S(2.501), 125.1);
    assert_int_equal(n_got, 4);
    assert_float_equal(got[0].in.dt_s, 1.0, 0.0);
    assert_int_equal(got[0].in.has_position, 1);
    assert_float_equal(got[0].in.position_m, 100.0, 0.0);
    assert_int_equal(got[0].no_traction, 1);
    assert_float_equal(got[0].in.traction, 0.0, 0.0);
    assert_float_equal(got[1].in.dt_s, 1.0, 0.0);
    assert_float_equal(got[2].in.dt_s, 1.5, 0.0);
    assert_float_equal(got[3].in.dt_s, 0.001, 1e-15);
    assert_true(got[2].t_us == T0 + S(2.5));
    assert_int_equal(s.n.steps, 4);
    assert_int_equal(s.n.predict_steps, 0);
}

/* Mean: the held value weighted by time over the step; latest: at the end. */
static void test_traction_mean_and_latest(void **state)
{
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    int mode;
    (void)state;
    for (mode = 0; mode < 2; ++mode) {
        c.traction_mode = mode == 0 ? HSTPFD_TRACTION_MEAN : HSTPFD_TRACTION_LATEST;
        start(&s, &c);
        hstpfd_sched_traction(&s, T0 - S(0.5), 98.1);  /* u = 20 */
        hstpfd_sched_position(&s, T0, 0.0);             /* first step: u held now */
        hstpfd_sched_traction(&s, T0 + S(0.25), 490.5); /* u = 100 from 0.25 */
        hstpfd_sched_position(&s, T0 + S(1.0), 10.0);   /* 0.25 x 20 + 0.75 x 100 */
        hstpfd_sched_traction(&s, T0 + S(1.0), -196.2); /* u = -40 from 1.0 */
        hstpfd_sched_traction(&s, T0 + S(1.5), 0.0);    /* u = 0 from 1.5 */
        hstpfd_sched_position(&s, T0 + S(3.0), 30.0);   /* (0.5 x -40 + 1.5 x 0) / 2 */
        assert_int_equal(n_got, 3);
        assert_float_equal(got[0].in.traction, 20.0, 1e-12);
        assert_int_equal(got[0].no_traction, 0);
        if (mode == 0) {
            assert_float_equal(got[1].in.traction, 80.0, 1e-12);
            assert_float_equal(got[2].in.traction, -10.0, 1e-12);
        } else {
            assert_float_equal(got[1].in.traction, 100.0, 1e-12);
            assert_float_equal(got[2].in.traction, 0.0, 1e-12);
        }
    }
}

/* A traction frame at the same time as a position: whichever comes first,
 * the mean over [t_k-1, t_k] is the value held during that interval. */
static void test_traction_same_stamp(void **state)
{
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    (void)state;
    start(&s, &c);
    hstpfd_sched_traction(&s, T0, 49.05); /* u = 10 */
    hstpfd_sched_position(&s, T0, 0.0);
    hstpfd_sched_traction(&s, T0 + S(1.0), 98.1); /* u = 20 from 1.0, before the position */
    hstpfd_sched_position(&s, T0 + S(1.0), 1.0);
    hstpfd_sched_position(&s, T0 + S(2.0), 2.0);
    assert_int_equal(n_got, 3);
    assert_float_equal(got[1].in.traction, 10.0, 1e-12);
    assert_float_equal(got[2].in.traction, 20.0, 1e-12);
}

/* More traction changes in one step than segments: the mean stays exact. */
static void test_many_traction_samples(void **state)
{
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    int i;
    double want = 0.0;
    (void)state;
    start(&s, &c);
    hstpfd_sched_position(&s, T0, 0.0);
    for (i = 0; i < 400; ++i) { /* u = 0, 1, 2, 0, 1, 2, ... each for 2.5 ms */
        hstpfd_sched_traction(&s, T0 + i * 2500, 49.05 * 0.1 * (double)(i % 3));
        want += (double)(i % 3) * 2500.0;
    }
    hstpfd_sched_position(&s, T0 + S(1.0), 10.0);
    assert_int_equal(n_got, 2);
    assert_float_equal(got[1].in.traction, want / 1e6, 1e-9);
    /* 133 cycles of 0 + 1 + 2 then a 0: 399 x 2.5 ms of u = 1 in 1 s */
    assert_float_equal(got[1].in.traction, 0.9975, 1e-9);
}

/* Stale position, policy predict: predict-only steps of predict_period_s. */
static void test_stale_predict(void **state)
{
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    int i;
    (void)state;
    start(&s, &c);
    hstpfd_sched_position(&s, T0, 0.0);
    hstpfd_sched_position(&s, T0 + S(1.0), 10.0);
    for (i = 2; i <= 6; ++i) { /* traction keeps coming, positions stop */
        hstpfd_sched_traction(&s, T0 + S(i), 49.05);
    }
    /* at 2, 3, 4: 4 - 1 = 3 is not beyond the timeout; stale after 4 s */
    assert_int_equal(s.pos_stale, 1);
    assert_int_equal(s.n.pos_stale, 1);
    /* at 5: stale since 4+; predict steps end at 2, 3, 4 (5 - 4 = 1 is not
     * beyond the period); at 6: one more, ending at 5 */
    assert_int_equal(n_got, 2 + 4);
    for (i = 2; i < 6; ++i) {
        assert_int_equal(got[i].in.has_position, 0);
        assert_float_equal(got[i].in.dt_s, 1.0, 0.0);
        assert_int_equal(got[i].pos_stale, 1);
        assert_true(got[i].t_us == T0 + S(i));
    }
    /* traction u = 10 from 2 s: the step [1, 2] held 0, [2, 3] held 10 */
    assert_float_equal(got[2].in.traction, 0.0, 1e-12);
    assert_float_equal(got[3].in.traction, 10.0, 1e-12);
    /* the position returns at 6.5: a predict step ending at 6 first (6.5 - 5
     * > 1), then the position step of 0.5 s */
    hstpfd_sched_position(&s, T0 + S(6.5), 65.0);
    assert_int_equal(n_got, 8);
    assert_int_equal(got[6].in.has_position, 0);
    assert_true(got[6].t_us == T0 + S(6.0));
    assert_int_equal(got[7].in.has_position, 1);
    assert_float_equal(got[7].in.dt_s, 0.5, 0.0);
    assert_int_equal(got[7].pos_stale, 0);
    assert_int_equal(s.pos_stale, 0);
    assert_int_equal(s.n.predict_steps, 5);
    assert_int_equal(s.n.pos_stale, 1);
    /* and a second episode is counted again */
    hstpfd_sched_time(&s, T0 + S(9.6));
    assert_int_equal(s.n.pos_stale, 2);
}

/* Stale position, policy wait: nothing until the next valid position. */
static void test_stale_wait(void **state)
{
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    int i;
    (void)state;
    c.stale_policy = HSTPFD_STALE_WAIT;
    start(&s, &c);
    hstpfd_sched_position(&s, T0, 0.0);
    hstpfd_sched_position(&s, T0 + S(1.0), 10.0);
    for (i = 2; i <= 6; ++i) {
        hstpfd_sched_time(&s, T0 + S(i));
    }
    assert_int_equal(n_got, 2);
    assert_int_equal(s.n.pos_stale, 1);
    hstpfd_sched_position(&s, T0 + S(6.5), 65.0);
    assert_int_equal(n_got, 3);
    assert_float_equal(got[2].in.dt_s, 5.5, 0.0);
    assert_int_equal(got[2].in.has_position, 1);
}

/* Stale traction: the last value is held and the steps are flagged. */
static void test_stale_traction(void **state)
{
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    int i;
    (void)state;
    start(&s, &c);
    hstpfd_sched_traction(&s, T0, 98.1); /* u = 20 */
    for (i = 0; i <= 5; ++i) {
        hstpfd_sched_position(&s, T0 + S(i), (double)i);
    }
    assert_int_equal(n_got, 6);
    assert_int_equal(got[3].trac_stale, 0); /* 3 - 0 = 3: not beyond */
    assert_int_equal(got[4].trac_stale, 1);
    assert_float_equal(got[5].in.traction, 20.0, 1e-12);
    assert_int_equal(s.n.trac_stale, 1);
    hstpfd_sched_traction(&s, T0 + S(5.5), 0.0);
    assert_int_equal(s.trac_stale, 0);
}

/* step_period_s: one step per grid point; 100 ms frames, period 1 s. */
static void test_decimation(void **state)
{
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    int i;
    (void)state;
    c.step_period_s = 1.0;
    start(&s, &c);
    for (i = 0; i <= 30; ++i) {
        /* jitter: every frame 3 ms early except the first */
        const int64_t t = T0 + S(0.1 * i) - (i ? S(0.003) : 0);
        hstpfd_sched_position(&s, t, 0.1 * i);
    }
    assert_int_equal(n_got, 4); /* at 0, 0.997, 1.997, 2.997 */
    assert_true(got[1].t_us == T0 + S(0.997));
    assert_float_equal(got[1].in.dt_s, 0.997, 1e-12);
    assert_float_equal(got[2].in.dt_s, 1.0, 1e-12);
    assert_int_equal(s.n.decimated, 27);
}

/* A gap beyond HSTPF_DT_MAX_S (60 s) is split; beyond max_gap_s restarts. */
static void test_long_gaps(void **state)
{
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    (void)state;
    c.stale_policy = HSTPFD_STALE_WAIT;
    c.max_gap_s = 200.0;
    start(&s, &c);
    hstpfd_sched_position(&s, T0, 0.0);
    hstpfd_sched_position(&s, T0 + S(130.0), 1300.0); /* 3 pieces */
    assert_int_equal(n_got, 4);
    assert_float_equal(got[1].in.dt_s, 43.333333, 1e-12);
    assert_int_equal(got[1].in.has_position, 0);
    assert_float_equal(got[2].in.dt_s, 43.333333, 1e-12);
    assert_float_equal(got[3].in.dt_s, 43.333334, 1e-12);
    assert_int_equal(got[3].in.has_position, 1);
    assert_int_equal(s.n.split, 1);
    hstpfd_sched_position(&s, T0 + S(331.0), 3310.0); /* 201 s > max_gap_s */
    assert_int_equal(n_got, 5);
    assert_int_equal(got[4].restart, 1);
    assert_float_equal(got[4].in.dt_s, 1.0, 0.0);
    assert_int_equal(got[4].in.has_position, 1);
    assert_int_equal(s.n.restarts, 1);
}

/* The same under PREDICT, traction going on: the predict steps of the
 * outage must not hide its length. A gap of positions beyond max_gap_s
 * restarts the estimator although the last step was a second before. */
static void test_long_gap_predicted(void **state)
{
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    int i;
    (void)state;
    c.max_gap_s = 30.0;
    c.predict_period_s = 10.0;
    start(&s, &c);
    hstpfd_sched_position(&s, T0, 0.0);
    hstpfd_sched_position(&s, T0 + S(1.0), 10.0);
    for (i = 2; i <= 40; ++i) {
        hstpfd_sched_traction(&s, T0 + S(i), 49.05);
    }
    assert_true(s.n.predict_steps >= 3);
    assert_int_equal(got[n_got - 1].in.has_position, 0);
    assert_true(T0 + S(40.5) - got[n_got - 1].t_us <= S(10.0)); /* the last predict step is recent */
    hstpfd_sched_position(&s, T0 + S(40.5), 405.0); /* 39.5 s after the last position */
    assert_int_equal(got[n_got - 1].in.has_position, 1);
    assert_int_equal(got[n_got - 1].restart, 1);
    assert_int_equal(s.n.restarts, 1);
    /* and a gap within max_gap_s after it is stepped across as before */
    hstpfd_sched_position(&s, T0 + S(60.5), 605.0);
    assert_int_equal(got[n_got - 1].restart, 0);
    assert_int_equal(s.n.restarts, 1);
}

/* Time never goes back; a position not newer than the last step is late. */
static void test_time_order(void **state)
{
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    (void)state;
    start(&s, &c);
    hstpfd_sched_position(&s, T0 + S(5.0), 50.0);
    hstpfd_sched_traction(&s, T0 + S(4.0), 10.0);
    assert_int_equal(s.n.time_backwards, 1);
    hstpfd_sched_position(&s, T0 + S(4.5), 45.0);
    hstpfd_sched_position(&s, T0 + S(5.0), 50.0);
    assert_int_equal(s.n.time_backwards, 2);
    assert_int_equal(s.n.late, 2);
    assert_int_equal(n_got, 1);
    hstpfd_sched_position(&s, T0 + S(6.0), 60.0);
    assert_int_equal(n_got, 2);
    assert_float_equal(got[1].in.dt_s, 1.0, 0.0);
}

/* Before the first fix nothing is stepped, even when stale. */
static void test_before_first_fix(void **state)
{
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    (void)state;
    start(&s, &c);
    hstpfd_sched_traction(&s, T0, 49.05);
    hstpfd_sched_time(&s, T0 + S(10.0));
    assert_int_equal(n_got, 0);
    assert_int_equal(s.n.pos_stale, 1);
    hstpfd_sched_position(&s, T0 + S(10.0), 0.0);
    assert_int_equal(n_got, 1);
    assert_float_equal(got[0].in.dt_s, 1.0, 0.0);
    assert_float_equal(got[0].in.traction, 10.0, 1e-12);
    assert_int_equal(s.pos_stale, 0);
}

/* Fix times (Position.FixTime): dt is the difference of the fixes' own
 * times, whatever the receive latency; the 8192 ms wrap is crossed. The
 * mapping keeps the least latency seen (5 ms, the first) and lets it creep
 * up by 100 ppm of receive time: at most 0.1 ms per 0.1 s step here.
 * Frames arrive in order: a frame is not received before its predecessor. */
static void test_fix_time_dates_fixes(void **state)
{
    static const int lat_ms[10] = {5, 80, 20, 150, 5, 60, 300, 10, 5, 40};
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    int64_t rx[10];
    int k;
    (void)state;
    c.stale_policy = HSTPFD_STALE_WAIT;
    start(&s, &c);
    for (k = 0; k < 10; ++k) {
        const int32_t f = 8000 + 100 * k; /* crosses the wrap at k = 2 */
        rx[k] = T0 + S(f / 1000.0) + S(lat_ms[k] / 1000.0);
        if (k > 0 && rx[k] < rx[k - 1]) {
            rx[k] = rx[k - 1];
        }
        hstpfd_sched_position_at(&s, rx[k], (double)k, f % 8192, k > 0);
    }
    assert_int_equal(n_got, 10);
    assert_int_equal(s.n.fix_dated, 10);
    assert_int_equal(s.n.time_backwards, 0);
    for (k = 1; k < 10; ++k) {
        /* by receive time dt would be 0.1 + (lat_k - lat_k-1): up to 0.39 s */
        assert_true(got[k].in.dt_s >= 0.1 && got[k].in.dt_s <= 0.1 + 1e-4);
        assert_true(got[k].t_us <= rx[k]); /* never dated after its receipt */
    }
    /* a fix older than the last one (same sequence): late, and the next one
     * is dated from it (150 ms later, so 100 ms after the last step) */
    hstpfd_sched_position_at(&s, T0 + S(9.0), 9.5, (8900 - 50) % 8192, 1);
    assert_int_equal(s.n.late, 1);
    hstpfd_sched_position_at(&s, T0 + S(9.1), 10.0, 9000 % 8192, 1);
    assert_int_equal(n_got, 11);
    assert_true(got[10].in.dt_s >= 0.1 && got[10].in.dt_s <= 0.1 + 1e-4);
    /* after an outage (not in sequence) the receive times count the wraps:
     * 20 s later is 2 x 8192 + 3616 ms (3.616 s apart is too far for
     * consecutive fixes, so even a fix flagged in sequence is unwrapped so) */
    hstpfd_sched_position_at(&s, T0 + S(29.0 + 0.03), 20.0, (29000) % 8192, 0);
    assert_int_equal(n_got, 12);
    assert_true(got[11].in.dt_s >= 20.0 && got[11].in.dt_s <= 20.0 + 20.1 * 1e-4);
    hstpfd_sched_position_at(&s, T0 + S(49.0 + 0.03), 40.0, (49000) % 8192, 1);
    assert_int_equal(n_got, 13);
    assert_true(got[12].in.dt_s >= 20.0 && got[12].in.dt_s <= 20.0 + 20.1 * 1e-4);
}

/* A fix without a fix time is dated by its receive time (the fallback). */
static void test_fix_time_absent(void **state)
{
    hstpfd_sched_t s;
    hstpfd_sched_config_t c = base();
    (void)state;
    start(&s, &c);
    hstpfd_sched_position_at(&s, T0, 0.0, HSTPFD_NO_FIX_TIME, 0);
    hstpfd_sched_position_at(&s, T0 + S(0.25), 1.0, HSTPFD_NO_FIX_TIME, 1);
    hstpfd_sched_position_at(&s, T0 + S(0.3), 2.0, 8192, 1); /* out of range: ignored */
    assert_int_equal(n_got, 3);
    assert_float_equal(got[1].in.dt_s, 0.25, 1e-12);
    assert_float_equal(got[2].in.dt_s, 0.05, 1e-12);
    assert_int_equal(s.n.fix_dated, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_traction_unit),
        cmocka_unit_test(test_init_checks),
        cmocka_unit_test(test_dt_from_timestamps),
        cmocka_unit_test(test_traction_mean_and_latest),
        cmocka_unit_test(test_traction_same_stamp),
        cmocka_unit_test(test_many_traction_samples),
        cmocka_unit_test(test_stale_predict),
        cmocka_unit_test(test_stale_wait),
        cmocka_unit_test(test_stale_traction),
        cmocka_unit_test(test_decimation),
        cmocka_unit_test(test_long_gaps),
        cmocka_unit_test(test_long_gap_predicted),
        cmocka_unit_test(test_time_order),
        cmocka_unit_test(test_before_first_fix),
        cmocka_unit_test(test_fix_time_dates_fixes),
        cmocka_unit_test(test_fix_time_absent),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
