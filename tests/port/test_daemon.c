/* End-to-end tests of the hstpfd program: each test writes a candump log of
 * a simulated run (the paper's model, tools/sim; frames packed with the
 * codec and E2E-protected), runs `hstpfd --log` on it as a process and
 * checks its JSON summary. POSIX (system(), wait status). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include <cmocka.h>

#include "candump.h"
#include "hstpf_can.h"
#include "hstpf_e2e.h"
#include "hstpf_frames.h"
#include "hstpf_sim.h"

#define DIR HSTPFD_TEST_DIR
#define MASS_T 500.0
#define T0_US INT64_C(1700000000000000)

typedef struct {
    const char *path;
    int duration_s;
    int faults;      /* inject the fault plan below */
    int time_div;    /* timestamps compressed this many times (a sped-up capture) */
    uint64_t seed;
} gen_t;

static FILE *logf_;
static int time_div_ = 1;

static void put(int64_t t_us, uint32_t id, uint8_t flags, const uint8_t *d, uint8_t len)
{
    hstpfd_frame_t f;
    char line[256];
    memset(&f, 0, sizeof f);
    f.t_us = T0_US + (t_us - T0_US) / time_div_;
    f.id = id;
    f.flags = flags;
    f.len = len;
    memcpy(f.data, d, len);
    assert_true(hstpfd_candump_format(&f, "vcan0", line, sizeof line) > 0);
    fputs(line, logf_);
}

/* The fault plan (gen_t.faults), by whole second k of the run. */
static int in(int k, const int *set, int n)
{
    int i;
    for (i = 0; i < n; ++i) {
        if (set[i] == k) {
            return 1;
        }
    }
    return 0;
}
static const int bad_crc_pos[] = {100, 150, 200, 250, 300};
static const int bad_crc_trac[] = {170, 270};
static const int repeated_pos[] = {120, 220, 320};
static const int short_pos[] = {130, 230};
static const int unknown_at[] = {140, 141, 142, 143};
static const int errframe_at[] = {160, 260};
#define SILENCE_FROM 400 /* position frames lost in [400, 403) */
#define SILENCE_TO 403

/* Case 1 (CRH3, the paper's profile and noise) at 1 s, sent as 100 ms
 * frames: position at the whole second carries the measurement y_k, the
 * nine frames after it a straight line to y_k+1; traction u_k in all ten. */
static void generate(const gen_t *g)
{
    hstpf_sim_config_t sc;
    hstpf_sim_t sim;
    hstpf_sim_sample_t cur, next;
    hstpf_e2e_tx_t tx_pos, tx_trac;
    int k, j;

    logf_ = fopen(g->path, "w");
    assert_non_null(logf_);
    time_div_ = g->time_div;
    hstpf_sim_default(&sc);
    sc.seed = g->seed;
    hstpf_sim_init(&sim, &sc);
    (void)hstpf_e2e_tx_init(&tx_pos, HSTPF_FRAME_POSITION_DATA_ID);
    (void)hstpf_e2e_tx_init(&tx_trac, HSTPF_FRAME_TRACTION_DATA_ID);
    fputs("# hstpfd test log: Case 1, CRH3\n", logf_);
    hstpf_sim_next(&sim, &cur);
    for (k = 0; k < g->duration_s; ++k) {
        hstpf_sim_next(&sim, &next);
        for (j = 0; j < 10; ++j) {
            const int64_t t = T0_US + (int64_t)k * 1000000 + (int64_t)j * 100000;
            struct hstpf_can_position_t p;
            struct hstpf_can_traction_t tr;
            uint8_t d[8];
            const double y = cur.y + (next.y - cur.y) * j / 10.0;
            const int silent = g->faults && k >= SILENCE_FROM && k < SILENCE_TO;

            (void)hstpf_can_position_init(&p);
            p.pos_valid = 1;
            p.pos_quality = 2;
            p.position = hstpf_frames_position_position_raw(y);
            assert_int_equal(hstpf_can_position_pack(d, &p, 8), 8);
            (void)hstpf_e2e_protect(&tx_pos, d, 8);
            if (!silent) {
                if (g->faults && j == 0 && in(k, bad_crc_pos, 5)) {
                    d[0] ^= 0x5A;
                }
                put(t, HSTPF_FRAME_POSITION_ID, 0, d, g->faults && j == 0 && in(k, short_pos, 2) ? 7 : 8);
                if (g->faults && j == 0 && in(k, repeated_pos, 3)) {
                    put(t + 1000, HSTPF_FRAME_POSITION_ID, 0, d, 8);
                }
            }
            (void)hstpf_can_traction_init(&tr);
            tr.tract_valid = 1;
            tr.tract_force = hstpf_frames_traction_tract_force_raw(cur.u * MASS_T * 9.81 / 1000.0);
            assert_int_equal(hstpf_can_traction_pack(d, &tr, 8), 8);
            (void)hstpf_e2e_protect(&tx_trac, d, 8);
            if (g->faults && j == 5 && in(k, bad_crc_trac, 2)) {
                d[0] ^= 0x01;
            }
            put(t, HSTPF_FRAME_TRACTION_ID, 0, d, 8);
            if (g->faults && j == 3 && in(k, unknown_at, 4)) {
                static const uint8_t junk[8] = {1, 2, 3, 4, 5, 6, 7, 8};
                put(t + 500, 0x1F0, 0, junk, 8);
            }
            if (g->faults && j == 7 && in(k, errframe_at, 2)) {
                static const uint8_t zero[8] = {0};
                put(t + 700, HSTPFD_ERR_BUSOFF | HSTPFD_ERR_CRTL, HSTPFD_FRAME_ERR, zero, 8);
            }
        }
        if (g->faults && (k == 50 || k == 51 || k == 52)) {
            fputs(k == 50 ? "this is not a frame\n" : k == 51 ? "(12.3 vcan0 100#00\n" : "(51.0) vcan0 XYZ#00\n",
                  logf_);
        }
        cur = next;
    }
    fclose(logf_);
    logf_ = NULL;
}

/* Runs hstpfd with args; returns its exit status. */
static int run(const char *args)
{
    char cmd[4096];
    int st;
    (void)snprintf(cmd, sizeof cmd, "'%s' %s", HSTPFD_BIN, args);
    st = system(cmd);
    assert_true(st != -1 && WIFEXITED(st));
    return WEXITSTATUS(st);
}

static char summary[16384];

static void read_file(const char *path, char *buf, size_t size)
{
    FILE *fp = fopen(path, "r");
    size_t n;
    assert_non_null(fp);
    n = fread(buf, 1, size - 1, fp);
    buf[n] = '\0';
    fclose(fp);
}

/* The value after "key": inside the object that starts at "section": (or
 * anywhere with section NULL). */
static const char *field(const char *json, const char *section, const char *key)
{
    char pat[128];
    const char *p = json;
    if (section != NULL) {
        (void)snprintf(pat, sizeof pat, "\"%s\":{", section);
        p = strstr(json, pat);
        if (p == NULL) {
            fail_msg("no section %s in %s", section, json);
        }
    }
    (void)snprintf(pat, sizeof pat, "\"%s\":", key);
    p = strstr(p, pat);
    if (p == NULL) {
        fail_msg("no key %s in %s", key, json);
    }
    return p + strlen(pat);
}

static double num(const char *section, const char *key)
{
    return strtod(field(summary, section, key), NULL);
}

static int is(const char *section, const char *key, const char *text)
{
    return strncmp(field(summary, section, key), text, strlen(text)) == 0;
}

#define MODELS "--models 'SS1/SS3/SS4, CRH3, SS8' --noise case1 --mass-t 500 --particles 100 --seed 2"

static void test_clean_run(void **state)
{
    const gen_t g = {DIR "/clean.log", 600, 0, 1, 1};
    char line[512];
    FILE *fp;
    int n = 0;
    (void)state;
    generate(&g);
    assert_int_equal(run("--log " DIR "/clean.log " MODELS " --out " DIR "/clean.jsonl --summary " DIR
                         "/clean.json --frames-out " DIR "/clean_out.log > " DIR "/clean.stdout"),
                     0);
    read_file(DIR "/clean.json", summary, sizeof summary);
    assert_true(is(NULL, "declared", "\"CRH3\""));
    /* "changed" when another type was declared before (the filter can hold a
     * wrong type above the threshold for the hold time while the speed is low) */
    assert_true(is(NULL, "status", "\"declared\"") || is(NULL, "status", "\"changed\""));
    assert_true(is(NULL, "end", "\"eof\""));
    /* the demo's run of the same case declares after about 250 s */
    assert_true(num(NULL, "decision_time_s") > 60.0 && num(NULL, "decision_time_s") < 500.0);
    assert_float_equal(num(NULL, "weights") /* SS1/SS3/SS4 first */, 0.0, 1e-3);
    assert_float_equal(strtod(field(summary, "weights", "CRH3"), NULL), 1.0, 1e-3);
    assert_float_equal(strtod(field(summary, NULL, "theta") + 1, NULL), 0.79, 0.02);
    /* one step per second from 0 to 599 */
    assert_int_equal((int)num(NULL, "steps"), 600);
    assert_int_equal((int)num(NULL, "predict_steps"), 0);
    assert_int_equal((int)num(NULL, "steps_ok"), 600);
    assert_int_equal((int)num("frames", "position"), 6000);
    assert_int_equal((int)num("frames", "traction"), 6000);
    assert_int_equal((int)num("scheduler", "decimated"), 6000 - 600);
    assert_int_equal((int)num("faults", "bad_crc"), 0);
    assert_int_equal((int)num("faults", "lost"), 0);
    assert_int_equal((int)num("faults", "stale_events"), 0);
    assert_int_equal((int)num("faults", "position_stale"), 0);
    assert_true(is(NULL, "step_errors", "{}"));
    /* the same line on stdout */
    read_file(DIR "/clean.stdout", line, sizeof line);
    assert_true(strncmp(line, "{\"summary\":\"hstpfd\"", 19) == 0);
    /* one JSON line per step */
    fp = fopen(DIR "/clean.jsonl", "r");
    assert_non_null(fp);
    while (fgets(line, sizeof line, fp) != NULL) {
        assert_true(line[0] == '{' && strstr(line, "\"q\":[") != NULL);
        ++n;
    }
    fclose(fp);
    assert_int_equal(n, 600);
}

static void test_faults_counted(void **state)
{
    const gen_t g = {DIR "/faults.log", 600, 1, 1, 1};
    (void)state;
    generate(&g);
    assert_int_equal(run("--log " DIR "/faults.log " MODELS " --summary " DIR "/faults.json > /dev/null"), 0);
    read_file(DIR "/faults.json", summary, sizeof summary);
    assert_true(is(NULL, "declared", "\"CRH3\""));
    assert_int_equal((int)num("faults", "bad_crc"), 7);
    assert_int_equal((int)num("faults", "repeated"), 3);
    assert_int_equal((int)num("faults", "wrong_length"), 2);
    assert_int_equal((int)num("faults", "counter_jump"), 0);
    /* the frame after each rejected bad-CRC or short one shows one lost */
    assert_int_equal((int)num("faults", "lost"), 9);
    assert_int_equal((int)num("faults", "unknown_id"), 4);
    assert_int_equal((int)num("faults", "error_frames"), 2);
    assert_int_equal((int)num("error_classes", "bus_off"), 2);
    assert_int_equal((int)num("error_classes", "controller"), 2);
    assert_int_equal((int)num("error_classes", "no_ack"), 0);
    assert_int_equal((int)num("faults", "bad_lines"), 3);
    /* the 3 s silence: one stale episode; predict-only steps end at 400,
     * 401 and 402; the position returns at 403 */
    assert_int_equal((int)num("faults", "position_stale"), 1);
    assert_int_equal((int)num("e2e", "stale"), 1); /* position's */
    assert_int_equal((int)num("faults", "traction_stale"), 0);
    assert_int_equal((int)num(NULL, "predict_steps"), 3);
    assert_int_equal((int)num(NULL, "steps"), 600);
    assert_true(is(NULL, "step_errors", "{}"));
}

/* The same log gives the same summary byte for byte; a capture made 10
 * times faster, run with --time-scale 10, gives the same decision. */
static void test_deterministic_and_time_scale(void **state)
{
    static char again[16384];
    double t1;
    const gen_t g = {DIR "/fast.log", 600, 0, 10, 1};
    (void)state;
    assert_int_equal(run("--log " DIR "/clean.log " MODELS " --summary " DIR "/again.json > /dev/null"), 0);
    read_file(DIR "/clean.json", summary, sizeof summary);
    read_file(DIR "/again.json", again, sizeof again);
    /* the first run had --out/--frames-out: they do not change the estimate */
    assert_string_equal(strstr(summary, "\"steps\""), strstr(again, "\"steps\""));
    t1 = num(NULL, "decision_time_s");
    generate(&g);
    assert_int_equal(run("--log " DIR "/fast.log " MODELS " --time-scale 10 --summary " DIR "/fast.json > /dev/null"),
                     0);
    read_file(DIR "/fast.json", summary, sizeof summary);
    assert_true(is(NULL, "declared", "\"CRH3\""));
    assert_float_equal(num(NULL, "decision_time_s"), t1, 1.0);
    assert_int_equal((int)num(NULL, "steps"), 600);
}

/* The estimate frames written with --frames-out carry valid E2E and decode. */
static void test_output_frames(void **state)
{
    FILE *fp = fopen(DIR "/clean_out.log", "r");
    char line[256];
    hstpf_e2e_rx_t rx[5];
    int n[5] = {0, 0, 0, 0, 0}, i, last_status = -1, last_decl = -1;
    static const uint32_t ids[5] = {HSTPF_FRAME_EST_STATE_ID, HSTPF_FRAME_EST_TYPE_ID, HSTPF_FRAME_EST_THETA_ID,
                                    HSTPF_FRAME_HEALTH_RX_ID, HSTPF_FRAME_HEALTH_SYS_ID};
    (void)state;
    assert_non_null(fp);
    for (i = 0; i < 5; ++i) {
        hstpf_e2e_rx_config_t c;
        (void)hstpf_e2e_rx_config_default(&c, hstpf_frame_find(ids[i])->data_id, 8);
        c.max_delta = 1;
        c.timeout_ms = 5000;
        assert_int_equal(hstpf_e2e_rx_init(&rx[i], &c), 0);
    }
    while (fgets(line, sizeof line, fp) != NULL) {
        hstpfd_frame_t f;
        assert_int_equal(hstpfd_candump_parse(line, &f, NULL, 0), HSTPFD_CANDUMP_OK);
        for (i = 0; i < 5 && ids[i] != f.id; ++i) {
        }
        assert_true(i < 5);
        assert_true(hstpf_e2e_accepted(hstpf_e2e_rx_check(&rx[i], f.data, f.len, (uint32_t)(f.t_us / 1000))));
        ++n[i];
        if (i == 1) {
            struct hstpf_can_est_type_t m;
            assert_int_equal(hstpf_can_est_type_unpack(&m, f.data, f.len), 0);
            last_status = m.type_status;
            last_decl = m.declared_type;
        }
    }
    fclose(fp);
    /* 600 steps at 1 s: one state frame each; 1 Hz frames over 599.9 s */
    assert_int_equal(n[0], 600);
    for (i = 1; i < 5; ++i) {
        assert_int_equal(n[i], 600);
    }
    assert_true(last_status == 1 || last_status == 2);
    assert_int_equal(last_decl, 2); /* CRH3, Table 1 row 2 */
}

static void test_bad_configuration(void **state)
{
    FILE *fp;
    (void)state;
    assert_int_equal(run("--log " DIR "/clean.log --particles 1 2>/dev/null"), 2);
    assert_int_equal(run("--particles 100 2>/dev/null"), 2); /* no source */
    assert_int_equal(run("--log x --iface vcan0 2>/dev/null"), 2);
    assert_int_equal(run("--log " DIR "/clean.log --no-such-option 1 2>/dev/null"), 2);
    assert_int_equal(run("--log " DIR "/clean.log --models CRH9 2>/dev/null"), 2);
    assert_int_equal(run("--log " DIR "/clean.log --noise-e gaussian:0:-1 2>/dev/null"), 2);
    assert_int_equal(run("--config " DIR "/missing.ini --log " DIR "/clean.log 2>/dev/null"), 2);
    fp = fopen(DIR "/bad.ini", "w");
    assert_non_null(fp);
    fputs("particles = 100\nmass_t = heavy\n", fp);
    fclose(fp);
    assert_int_equal(run("--config " DIR "/bad.ini --log " DIR "/clean.log 2> " DIR "/bad.err"), 2);
    read_file(DIR "/bad.err", summary, sizeof summary);
    assert_non_null(strstr(summary, "bad.ini:2: mass_t"));
    /* a run-time failure is 1, with a summary all the same */
    assert_int_equal(run("--log " DIR "/no-such.log > " DIR "/nolog.out 2>/dev/null"), 1);
    read_file(DIR "/nolog.out", summary, sizeof summary);
    assert_true(is(NULL, "end", "\"error\""));
    assert_int_equal(run("--help > /dev/null"), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_clean_run),
        cmocka_unit_test(test_faults_counted),
        cmocka_unit_test(test_deterministic_and_time_scale),
        cmocka_unit_test(test_output_frames),
        cmocka_unit_test(test_bad_configuration),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
