/* The daemon's less travelled paths: the command line of hstpfd (every
 * option form, every way it refuses), its outputs that cannot be opened, a
 * log it cannot read, the error names, hstpfd_core_init's refusals and
 * hstpfd_config_write at every buffer size. Each case checks the exit
 * status, the message or the value that docs/daemon.md and the headers
 * promise. POSIX (system(), wait status). */
#define _POSIX_C_SOURCE 200809L
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include <cmocka.h>

#include "config.h"
#include "core.h"
#include "frame.h"
#include "genlog.h"

#define DIR HSTPFD_TEST_DIR
#define LOG DIR "/paths.log"
#define QUICK " --models 'CRH3, SS8' --noise case1 --particles 20"

static char text[65536];

/* Runs hstpfd with args (stdout to DIR/paths.out, stderr to DIR/paths.err);
 * returns its exit status. */
static int run(const char *args)
{
    char cmd[4096];
    int st;
    (void)snprintf(cmd, sizeof cmd, "'%s' %s > " DIR "/paths.out 2> " DIR "/paths.err", HSTPFD_BIN, args);
    st = system(cmd);
    assert_true(st != -1 && WIFEXITED(st));
    return WEXITSTATUS(st);
}

static const char *slurp(const char *path)
{
    FILE *fp = fopen(path, "r");
    size_t n;
    assert_non_null(fp);
    n = fread(text, 1, sizeof text - 1, fp);
    text[n] = '\0';
    fclose(fp);
    return text;
}

static int setup(void **state)
{
    const genlog_t g = {LOG, 60, 0, 1, 3, 500.0, 0, 0, 0, 0, 0, 0, 0};
    (void)state;
    return genlog(&g);
}

static void test_version_and_types(void **state)
{
    char want[64];
    const char *p;
    int r;
    (void)state;
    assert_int_equal(run("--version"), 0);
    (void)snprintf(want, sizeof want, "hstpfd %d.%d.%d\n", HSTPF_VERSION_MAJOR, HSTPF_VERSION_MINOR,
                   HSTPF_VERSION_PATCH);
    assert_string_equal(slurp(DIR "/paths.out"), want);
    /* one line per Table 1 row, in the table's order, index first */
    assert_int_equal(run("--list-types"), 0);
    p = slurp(DIR "/paths.out");
    for (r = 0; r < HSTPF_N_TRAIN_TYPES; ++r) {
        const char *nl = strchr(p, '\n');
        assert_non_null(nl);
        assert_int_equal(atoi(p), r);
        assert_non_null(strstr(p, hstpf_train_types[r].name));
        assert_true(strstr(p, hstpf_train_types[r].name) < nl);
        p = nl + 1;
    }
    assert_string_equal(p, "");
    /* -h lists every configuration key */
    assert_int_equal(run("-h"), 0);
    p = slurp(DIR "/paths.out");
    for (r = 0; r < (int)hstpfd_config_n_keys(); ++r) {
        assert_non_null(strstr(p, hstpfd_config_key_name((unsigned)r)));
    }
}

/* Exit status 2 and the one-line reason on stderr. */
static void refused(const char *args, const char *reason)
{
    assert_int_equal(run(args), 2);
    if (strstr(slurp(DIR "/paths.err"), reason) == NULL) {
        fail_msg("hstpfd %s: '%s' not in: %s", args, reason, text);
    }
    assert_string_equal(slurp(DIR "/paths.out"), ""); /* no summary: nothing ran */
}

static void test_bad_command_lines(void **state)
{
    (void)state;
    refused("--log " LOG " -c", "--config needs a file");
    refused("--log " LOG " --set", "--set needs KEY=VALUE");
    refused("--log " LOG " --set particles", "--set needs KEY=VALUE");
    refused("--log " LOG " --set no_such_key=1", "no_such_key");
    refused("--log " LOG " --set particles=1", "particles");
    refused("--log " LOG " -x 1", "unexpected argument '-x'");
    refused("--log " LOG " plain", "unexpected argument 'plain'");
    /* longer than any key: not taken as one */
    refused("--log " LOG " --aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa 1",
            "unexpected argument");
    refused("--log " LOG " --no-such-key 1", "unknown option '--no-such-key'");
    refused("--log " LOG " --mass-t", "--mass-t needs a value");
    refused("--log " LOG " -o", "-o needs a value");
    refused("-i vcan0 -l " LOG, "");
}

/* --set, the short options and the long ones all reach the configuration
 * that --print-config shows; later settings win. */
static void test_options_reach_config(void **state)
{
    const char *p;
    (void)state;
    assert_int_equal(run("--set particles=77 -l /x/in.log -o /x/o.jsonl -s /x/s.json --particles 78 --print-config"),
                     0);
    p = slurp(DIR "/paths.out");
    assert_non_null(strstr(p, "\nparticles = 78\n"));
    assert_non_null(strstr(p, "\nlog = /x/in.log\n"));
    assert_non_null(strstr(p, "\nout = /x/o.jsonl\n"));
    assert_non_null(strstr(p, "\nsummary = /x/s.json\n"));
    assert_int_equal(run("-i can7 --print-config"), 0);
    assert_non_null(strstr(slurp(DIR "/paths.out"), "iface = can7\n"));
}

/* -o - puts the step stream on stdout, before the summary; -s writes the
 * same summary line to a file. */
static void test_stream_to_stdout(void **state)
{
    static char summary[sizeof text];
    const char *p, *last;
    int lines = 0;
    (void)state;
    remove(DIR "/paths.sum");
    assert_int_equal(run("-l " LOG QUICK " -o - -s " DIR "/paths.sum"), 0);
    p = slurp(DIR "/paths.sum");
    assert_true(strncmp(p, "{\"summary\":\"hstpfd\"", 19) == 0);
    (void)snprintf(summary, sizeof summary, "%s", p);
    p = slurp(DIR "/paths.out");
    last = p;
    for (; *p != '\0'; ++p) {
        if (*p == '\n') {
            ++lines;
            if (p[1] != '\0') {
                last = p + 1;
            }
        }
    }
    assert_int_equal(lines, 60 + 1); /* a step per second of the log, then the summary */
    assert_string_equal(last, summary);
}

/* An output that cannot be opened: exit 1 with the reason, nothing run. */
static void test_outputs_not_writable(void **state)
{
    (void)state;
    assert_int_equal(run("-l " LOG QUICK " -o " DIR "/no/such/dir/o.jsonl"), 1);
    assert_non_null(strstr(slurp(DIR "/paths.err"), "cannot write the step stream"));
    assert_int_equal(run("-l " LOG QUICK " --frames-out " DIR "/no/such/dir/f.log"), 1);
    assert_non_null(strstr(slurp(DIR "/paths.err"), "cannot write the frame log"));
    assert_int_equal(run("-l " LOG QUICK " -s " DIR "/no/such/dir/s.json"), 1);
    assert_non_null(strstr(slurp(DIR "/paths.err"), "cannot write the summary"));
    /* /dev/full opens but every write fails: the summary's failure is told */
    assert_int_equal(run("-l " LOG QUICK " -s /dev/full"), 1);
    assert_non_null(strstr(slurp(DIR "/paths.err"), "writing the summary failed"));
}

/* A log that opens but cannot be read (a directory; on stdin too): exit 1,
 * "read error", counted in the summary, which still goes out. */
static void test_log_read_error(void **state)
{
    const char *p;
    (void)state;
    assert_int_equal(run("-l " DIR QUICK), 1);
    assert_non_null(strstr(slurp(DIR "/paths.err"), "read error"));
    p = slurp(DIR "/paths.out");
    assert_non_null(strstr(p, "\"read_errors\":1"));
    assert_non_null(strstr(p, "\"end\":\"error\""));
    assert_int_equal(run("-l -" QUICK " < " DIR), 1);
    assert_non_null(strstr(slurp(DIR "/paths.err"), "read error"));
}

/* A line longer than any candump line is skipped to its end and counted;
 * the frames around it are still read. */
static void test_log_long_line(void **state)
{
    FILE *in = fopen(LOG, "r"), *out = fopen(DIR "/long.log", "w");
    char line[512];
    int i, n = 0;
    (void)state;
    assert_non_null(in);
    assert_non_null(out);
    while (fgets(line, sizeof line, in) != NULL) {
        fputs(line, out);
        if (++n == 100) {
            for (i = 0; i < 5000; ++i) {
                fputc('7', out);
            }
            fputc('\n', out);
        }
    }
    fclose(in);
    fclose(out);
    assert_int_equal(run("-l " DIR "/long.log" QUICK), 0);
    assert_non_null(strstr(slurp(DIR "/paths.out"), "\"bad_lines\":1"));
    assert_non_null(strstr(text, "\"end\":\"eof\""));
    assert_int_equal(run("-l " LOG QUICK), 0);
    assert_non_null(strstr(slurp(DIR "/paths.out"), "\"bad_lines\":0"));
}

/* A model name holding a quote, a backslash and a tab reaches the outputs
 * escaped: JSON \" \\ \u0009, CSV a doubled quote inside quotes. */
static void test_names_escaped(void **state)
{
    const char *p;
    (void)state;
    assert_int_equal(run("-l " LOG " --models 'CRH3, q\"t\\x\ty:0.8:0.006:0.0001' --particles 20"), 0);
    p = slurp(DIR "/paths.out");
    if (strstr(p, "\"q\\\"t\\\\x\\u0009y\":") == NULL) {
        fail_msg("escaped name not in the summary: %s", p);
    }
    assert_int_equal(run("-l " LOG " --models 'CRH3, q\"t\\x\ty:0.8:0.006:0.0001' --particles 20 --out-format csv -o "
                         DIR "/esc.csv"),
                     0);
    p = slurp(DIR "/esc.csv");
    assert_non_null(strstr(p, ",\"q_q\"\"t\\x\ty\","));
}

static void test_error_names(void **state)
{
    (void)state;
    assert_string_equal(hstpfd_err_name(HSTPF_OK), "OK");
    assert_string_equal(hstpfd_err_name(HSTPF_E_NULL), "E_NULL");
    assert_string_equal(hstpfd_err_name(HSTPF_E_DT), "E_DT");
    assert_string_equal(hstpfd_err_name(HSTPF_E_OUTLIER), "E_OUTLIER");
    assert_string_equal(hstpfd_err_name(-11), "other");
    assert_string_equal(hstpfd_err_name(3), "other");
    assert_string_equal(hstpfd_err_class_name(0), "tx_timeout");
    assert_string_equal(hstpfd_err_class_name(HSTPFD_ERR_N_CLASSES - 1), "restarted");
    assert_string_equal(hstpfd_err_class_name(HSTPFD_ERR_N_CLASSES), "unknown");
}

static hstpf_t filt;
static hstpfd_core_t core;

/* hstpfd_core_init refuses what its parts refuse, with core.h's codes. */
static void test_core_init_refusals(void **state)
{
    static hstpfd_config_t c;
    char err[HSTPFD_ERR_MAX];
    (void)state;
    hstpfd_config_default(&c);
    assert_int_equal(hstpfd_config_set(&c, "log", LOG, err, sizeof err), 0);
    assert_int_equal(hstpfd_config_finish(&c, err, sizeof err), 0);
    assert_int_equal(hstpfd_core_init(&core, &c, &filt, NULL, NULL, NULL, NULL, NULL), 0);
    assert_string_equal(core.bus, "can0"); /* the default bus name */
    c.particles = 1;                       /* past the checks of the key */
    assert_int_equal(hstpfd_core_init(&core, &c, &filt, NULL, NULL, NULL, NULL, "x"), HSTPF_E_SIZE);
    c.particles = 100;
    c.sched.max_gap_s = 0.0;
    assert_int_equal(hstpfd_core_init(&core, &c, &filt, NULL, NULL, NULL, NULL, "x"), HSTPFD_E_SCHED);
    c.sched.max_gap_s = 30.0;
    c.e2e_max_delta = 0; /* the E2E receiver needs at least 1 */
    assert_int_equal(hstpfd_core_init(&core, &c, &filt, NULL, NULL, NULL, NULL, "x"), -100);
    c.e2e_max_delta = 2;
    assert_int_equal(hstpfd_core_init(&core, &c, &filt, NULL, NULL, NULL, NULL, "vcan1"), 0);
    assert_string_equal(core.bus, "vcan1");
}

/* At every size too small, hstpfd_config_write returns -1 and writes
 * nothing past the buffer; at the exact size it writes the whole text,
 * which reads back to the same configuration. */
static void write_all_sizes(const hstpfd_config_t *c)
{
    static char full[16384], buf[16384 + 16];
    static hstpfd_config_t back;
    char err[HSTPFD_ERR_MAX];
    const int n = hstpfd_config_write(c, full, sizeof full);
    size_t size;
    assert_true(n > 0 && (size_t)n < sizeof full);
    assert_int_equal((int)strlen(full), n);
    for (size = 0; size <= (size_t)n; ++size) {
        memset(buf, 0x5a, sizeof buf);
        assert_int_equal(hstpfd_config_write(c, buf, size), -1);
        assert_true(buf[size] == 0x5a && buf[size + 1] == 0x5a);
    }
    assert_int_equal(hstpfd_config_write(c, buf, (size_t)n + 1), n);
    assert_string_equal(buf, full);
    hstpfd_config_default(&back);
    assert_int_equal(hstpfd_config_text(&back, full, err, sizeof err), 0);
    assert_int_equal(hstpfd_config_write(&back, buf, sizeof buf), n);
    assert_string_equal(buf, full);
}

static void test_config_write_sizes(void **state)
{
    static hstpfd_config_t c;
    char err[HSTPFD_ERR_MAX];
    static const char *const set[][2] = {
        {"out_format", "csv"},       {"traction_mode", "latest"},  {"stale_policy", "predict"},
        {"engine", "particle"},      {"rx_filter", "block"},       {"models", "CRH3, mine:1:0.01:0.0001"},
        {"summary", "/tmp/a#b;c\"d\\e"}, {"frames_out_inputs", "1"},
    };
    size_t i;
    (void)state;
    hstpfd_config_default(&c);
    write_all_sizes(&c);
    for (i = 0; i < sizeof set / sizeof set[0]; ++i) {
        if (hstpfd_config_set(&c, set[i][0], set[i][1], err, sizeof err) != 0) {
            fail_msg("%s = %s: %s", set[i][0], set[i][1], err);
        }
    }
    write_all_sizes(&c);
    assert_int_equal(hstpfd_config_set(&c, "engine", "kalman", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&c, "rx_filter", "all", err, sizeof err), 0);
    write_all_sizes(&c);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_version_and_types),   cmocka_unit_test(test_bad_command_lines),
        cmocka_unit_test(test_options_reach_config), cmocka_unit_test(test_stream_to_stdout),
        cmocka_unit_test(test_outputs_not_writable), cmocka_unit_test(test_log_read_error),
        cmocka_unit_test(test_log_long_line),        cmocka_unit_test(test_names_escaped),
        cmocka_unit_test(test_error_names),
        cmocka_unit_test(test_core_init_refusals),   cmocka_unit_test(test_config_write_sizes),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
