/* cmocka tests: hstpfd configuration keys, file parser, overrides. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "config.h"

static hstpfd_config_t cfg, cfg2;
static char err[HSTPFD_ERR_MAX];

static void test_defaults(void **state)
{
    (void)state;
    hstpfd_config_default(&cfg);
    assert_int_equal(cfg.n_models, 17);
    assert_string_equal(cfg.models[2].name, "CRH3");
    assert_true(cfg.models[2].name == cfg.model_name[2]);
    assert_int_equal(cfg.particles, 100);
    assert_int_equal(cfg.noise_e.kind, HSTPF_DIST_GAUSSIAN);
    assert_float_equal(cfg.noise_e.sd * cfg.noise_e.sd, 5.0, 1e-12);
    assert_int_equal(cfg.sched.traction_mode, HSTPFD_TRACTION_MEAN);
    assert_int_equal(cfg.sched.stale_policy, HSTPFD_STALE_PREDICT);
    assert_int_equal(cfg.send, 1);
}

static void test_set_numbers(void **state)
{
    (void)state;
    hstpfd_config_default(&cfg);
    assert_int_equal(hstpfd_config_set(&cfg, "particles", " 256 ", err, sizeof err), 0);
    assert_int_equal(cfg.particles, 256);
    assert_int_equal(hstpfd_config_set(&cfg, "particles", "257", err, sizeof err), -1);
    assert_non_null(strstr(err, "particles"));
    assert_int_equal(hstpfd_config_set(&cfg, "particles", "1", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "particles", "-5", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "particles", "12x", err, sizeof err), -1);
    assert_int_equal(cfg.particles, 256); /* unchanged by the failures */
    assert_int_equal(hstpfd_config_set(&cfg, "seed", "0x10", err, sizeof err), 0);
    assert_true(cfg.seed == 16u);
    assert_int_equal(hstpfd_config_set(&cfg, "particles", "0100", err, sizeof err), 0);
    assert_int_equal(cfg.particles, 100); /* decimal, not octal 64 */
    assert_int_equal(hstpfd_config_set(&cfg, "particles", "256", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&cfg, "seed", "18446744073709551615", err, sizeof err), 0);
    assert_true(cfg.seed == UINT64_MAX);
    assert_int_equal(hstpfd_config_set(&cfg, "seed", "18446744073709551616", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "mass_t", "480.5", err, sizeof err), 0);
    assert_float_equal(cfg.mass_t, 480.5, 0.0);
    assert_int_equal(hstpfd_config_set(&cfg, "mass_t", "0", err, sizeof err), -1); /* (0, ...] */
    assert_int_equal(hstpfd_config_set(&cfg, "mass_t", "nan", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "mass_t", "inf", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "mass_t", "", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "gamma_rot", "0", err, sizeof err), 0); /* [0, 1] */
    assert_int_equal(hstpfd_config_set(&cfg, "gamma_rot", "1.01", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "step_period_s", "0", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&cfg, "position_timeout_s", "1.25", err, sizeof err), 0);
    assert_float_equal(cfg.sched.pos_timeout_s, 1.25, 0.0);
    /* 15 cycles of the 100 ms frame: a wrapped counter would read as in sequence */
    assert_int_equal(hstpfd_config_set(&cfg, "position_timeout_s", "1.5", err, sizeof err), -1);
    assert_non_null(strstr(err, "position_timeout_s"));
    assert_int_equal(hstpfd_config_set(&cfg, "traction_timeout_s", "2.5", err, sizeof err), -1);
    /* the E2E checker's timeout is whole ms: 0.1 ms rounded to 0 was refused unnamed */
    assert_int_equal(hstpfd_config_set(&cfg, "position_timeout_s", "0.0001", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "position_timeout_s", "0.001", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&cfg, "e2e_max_delta", "14", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "e2e_max_delta", "1", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&cfg, "send", "no", err, sizeof err), 0);
    assert_int_equal(cfg.send, 0);
    assert_int_equal(hstpfd_config_set(&cfg, "send", "maybe", err, sizeof err), -1);
    { /* a filter setting the daemon passes on: the library's default, then the file's */
        hstpf_config_t lib, fc;
        (void)hstpf_config_default(&lib);
        hstpfd_config_default(&cfg2);
        hstpfd_config_filter(&cfg2, &fc);
        assert_int_equal(fc.grid_speed_lattice, lib.grid_speed_lattice);
        assert_int_equal(hstpfd_config_set(&cfg2, "grid_speed_lattice", lib.grid_speed_lattice ? "0" : "1", err,
                                           sizeof err), 0);
        hstpfd_config_filter(&cfg2, &fc);
        assert_int_equal(fc.grid_speed_lattice, !lib.grid_speed_lattice);
        assert_int_equal(hstpfd_config_set(&cfg2, "grid_speed_lattice", "2", err, sizeof err), -1);
        assert_int_equal(fc.refine, lib.refine);
        assert_int_equal(hstpfd_config_set(&cfg2, "refine", "2", err, sizeof err), 0);
        hstpfd_config_filter(&cfg2, &fc);
        assert_int_equal(fc.refine, 2);
        assert_int_equal(hstpfd_config_set(&cfg2, "refine", "3", err, sizeof err), -1);
        /* the daemon's max_gap_s reaches the library, within its (0, HSTPF_DT_MAX_S]: a
         * step_period_s of 31-60 s was one gap per step to the library's 30 s default */
        assert_true(fc.max_gap_s == HSTPF_DT_MAX_S); /* the daemon's 600 s */
        assert_int_equal(hstpfd_config_set(&cfg2, "max_gap_s", "20", err, sizeof err), 0);
        hstpfd_config_filter(&cfg2, &fc);
        assert_true(fc.max_gap_s == 20.0);
        assert_int_equal(hstpfd_config_set(&cfg2, "step_period_s", "45", err, sizeof err), 0);
        assert_int_equal(hstpfd_config_set(&cfg2, "max_gap_s", "600", err, sizeof err), 0);
        hstpfd_config_filter(&cfg2, &fc);
        assert_true(fc.max_gap_s >= cfg2.sched.step_period_s);
        assert_int_equal(hstpf_config_check(&fc, NULL), HSTPF_OK);
    }
    assert_int_equal(hstpfd_config_set(&cfg, "nosuchkey", "1", err, sizeof err), -1);
    assert_non_null(strstr(err, "unknown key 'nosuchkey'"));
}

static void test_enums(void **state)
{
    (void)state;
    hstpfd_config_default(&cfg);
    assert_int_equal(hstpfd_config_set(&cfg, "traction_mode", "latest", err, sizeof err), 0);
    assert_int_equal(cfg.sched.traction_mode, HSTPFD_TRACTION_LATEST);
    assert_int_equal(hstpfd_config_set(&cfg, "stale_policy", "wait", err, sizeof err), 0);
    assert_int_equal(cfg.sched.stale_policy, HSTPFD_STALE_WAIT);
    assert_int_equal(hstpfd_config_set(&cfg, "stale_policy", "panic", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "out_format", "csv", err, sizeof err), 0);
    assert_int_equal(cfg.out_format, HSTPFD_OUT_CSV);
    assert_int_equal(hstpfd_config_set(&cfg, "out_format", "xml", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "rx_filter", "all", err, sizeof err), 0);
    assert_int_equal(cfg.rx_filter, HSTPFD_RX_FILTER_ALL);
    assert_int_equal(hstpfd_config_set(&cfg, "rx_filter", "inputs", err, sizeof err), 0);
    assert_int_equal(cfg.rx_filter, HSTPFD_RX_FILTER_INPUTS);
    assert_int_equal(hstpfd_config_set(&cfg, "rx_filter", "some", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "noise", "case2", err, sizeof err), 0);
    assert_int_equal(cfg.noise_v.kind, HSTPF_DIST_GAMMA);
    assert_float_equal(cfg.noise_v.shape, 0.1, 0.0);
    assert_float_equal(cfg.noise_v.scale, 0.05, 0.0);
    assert_int_equal(hstpfd_config_set(&cfg, "noise", "case3", err, sizeof err), -1);
}

static void test_noise(void **state)
{
    hstpf_dist_spec_t d;
    (void)state;
    assert_int_equal(hstpfd_parse_noise("gaussian:0.5:2", &d, err, sizeof err), 0);
    assert_int_equal(d.kind, HSTPF_DIST_GAUSSIAN);
    assert_float_equal(d.mean, 0.5, 0.0);
    assert_float_equal(d.sd, 2.0, 0.0);
    assert_int_equal(hstpfd_parse_noise("gamma : 0.5 : 0.2 : -1", &d, err, sizeof err), 0);
    assert_int_equal(d.kind, HSTPF_DIST_GAMMA);
    assert_float_equal(d.shape, 0.5, 0.0);
    assert_float_equal(d.scale, 0.2, 0.0);
    assert_float_equal(d.loc, -1.0, 0.0);
    assert_int_equal(hstpfd_parse_noise("gamma:0.5:0.2", &d, err, sizeof err), 0); /* loc 0 */
    assert_float_equal(d.loc, 0.0, 0.0);
    assert_int_equal(hstpfd_parse_noise("gaussian:0:0", &d, err, sizeof err), -1);
    assert_int_equal(hstpfd_parse_noise("gaussian:0", &d, err, sizeof err), -1);
    assert_int_equal(hstpfd_parse_noise("gaussian:0:1:2", &d, err, sizeof err), -1);
    assert_int_equal(hstpfd_parse_noise("gamma:0.0001:1:0", &d, err, sizeof err), -1);
    assert_int_equal(hstpfd_parse_noise("gamma:1:-1:0", &d, err, sizeof err), -1);
    assert_int_equal(hstpfd_parse_noise("cauchy:0:1", &d, err, sizeof err), -1);
    assert_int_equal(hstpfd_parse_noise("gaussian:a:1", &d, err, sizeof err), -1);
}

static void test_models(void **state)
{
    (void)state;
    hstpfd_config_default(&cfg);
    assert_int_equal(hstpfd_config_set(&cfg, "models", "SS1/SS3/SS4, CRH3 ,SS8, Mine:1:0.01:0.0002", err, sizeof err),
                     0);
    assert_int_equal(cfg.n_models, 4);
    assert_string_equal(cfg.models[0].name, "SS1/SS3/SS4");
    assert_float_equal(cfg.models[0].c0, 2.25, 0.0);
    assert_string_equal(cfg.models[1].name, "CRH3");
    assert_float_equal(cfg.models[1].c2, 0.000115, 0.0);
    assert_string_equal(cfg.models[3].name, "Mine");
    assert_float_equal(cfg.models[3].c1, 0.01, 0.0);
    assert_true(cfg.models[3].name == cfg.model_name[3]);
    /* errors leave the set unchanged */
    assert_int_equal(hstpfd_config_set(&cfg, "models", "CRH3, CRH9", err, sizeof err), -1);
    assert_non_null(strstr(err, "CRH9"));
    assert_int_equal(hstpfd_config_set(&cfg, "models", "CRH3, CRH3", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "models", "X:1:2", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "models", "X:60:0:0", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "models", "X:1:0:0.02", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "models", " , ", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "models", "all, CRH3", err, sizeof err), -1); /* twice */
    assert_int_equal(cfg.n_models, 4);
    assert_int_equal(hstpfd_config_set(&cfg, "models", "Xian Feng, all", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "models", "Xian Feng", err, sizeof err), 0);
    assert_int_equal(cfg.n_models, 1);
    assert_int_equal(hstpfd_config_set(&cfg, "models", "all", err, sizeof err), 0);
    assert_int_equal(cfg.n_models, 17);
}

static void test_lines(void **state)
{
    (void)state;
    hstpfd_config_default(&cfg);
    assert_int_equal(hstpfd_config_line(&cfg, "", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_line(&cfg, "  # comment", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_line(&cfg, "; comment", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_line(&cfg, "[filter]", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_line(&cfg, "[filter", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_line(&cfg, "particles = 50   # fewer\r\n", err, sizeof err), 0);
    assert_int_equal(cfg.particles, 50);
    assert_int_equal(hstpfd_config_line(&cfg, "out = a#b.jsonl", err, sizeof err), 0);
    assert_string_equal(cfg.out, "a#b.jsonl"); /* '#' without a blank before it is data */
    assert_int_equal(hstpfd_config_line(&cfg, "particles 50", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_line(&cfg, " = 50", err, sizeof err), -1);
}

/* n bytes (NULs included) into the file at path. */
static void write_bytes(const char *path, const char *bytes, size_t n)
{
    FILE *fp = fopen(path, "wb");
    assert_non_null(fp);
    assert_int_equal(fwrite(bytes, 1, n, fp), n);
    fclose(fp);
}

static void test_file_and_write(void **state)
{
    const char *path = HSTPFD_TEST_DIR "/test_config.ini";
    char buf[8192];
    FILE *fp;
    int n;
    (void)state;
    fp = fopen(path, "w");
    assert_non_null(fp);
    fputs("# test\n[filter]\nmodels = CRH1, CRH3, CRH5\nparticles = 64\nnoise = case2\n"
          "noise_e = gaussian:0:2.5\n[input]\nlog = run.log\nmass_t = 420\n",
          fp);
    fclose(fp);
    hstpfd_config_default(&cfg);
    assert_int_equal(hstpfd_config_load(&cfg, path, err, sizeof err), 0);
    assert_int_equal(cfg.n_models, 3);
    assert_int_equal(cfg.particles, 64);
    assert_int_equal(cfg.noise_s.kind, HSTPF_DIST_GAMMA); /* preset, then noise_e wins */
    assert_int_equal(cfg.noise_e.kind, HSTPF_DIST_GAUSSIAN);
    assert_string_equal(cfg.log, "run.log");
    assert_int_equal(hstpfd_config_finish(&cfg, err, sizeof err), 0);
    assert_float_equal(cfg.sched.mass_t, 420.0, 0.0);
    assert_float_equal(cfg.sched.first_dt_s, cfg.dt_nominal_s, 0.0);

    /* the written configuration loads back to the same values */
    n = hstpfd_config_write(&cfg, buf, sizeof buf);
    assert_true(n > 0);
    fp = fopen(path, "w");
    assert_non_null(fp);
    fputs(buf, fp);
    fclose(fp);
    hstpfd_config_default(&cfg2);
    assert_int_equal(hstpfd_config_load(&cfg2, path, err, sizeof err), 0);
    assert_int_equal(hstpfd_config_finish(&cfg2, err, sizeof err), 0);
    assert_int_equal(cfg2.n_models, cfg.n_models);
    assert_memory_equal(&cfg2.noise_s, &cfg.noise_s, sizeof cfg.noise_s);
    assert_memory_equal(&cfg2.noise_e, &cfg.noise_e, sizeof cfg.noise_e);
    assert_memory_equal(&cfg2.sched, &cfg.sched, sizeof cfg.sched);
    assert_true(cfg2.seed == cfg.seed);
    assert_float_equal(cfg2.models[1].c2, cfg.models[1].c2, 0.0);

    /* an error names the file and the line */
    fp = fopen(path, "w");
    assert_non_null(fp);
    fputs("particles = 10\n\nparticles = ten\n", fp);
    fclose(fp);
    assert_int_equal(hstpfd_config_load(&cfg, path, err, sizeof err), -1);
    assert_non_null(strstr(err, ":3: particles"));
    /* a byte-order mark before the first key is skipped; a NUL is named,
     * also in a last line without its newline */
    write_bytes(path, "\xEF\xBB\xBFparticles = 12\n", sizeof "\xEF\xBB\xBFparticles = 12\n" - 1);
    assert_int_equal(hstpfd_config_load(&cfg, path, err, sizeof err), 0);
    assert_int_equal(cfg.particles, 12);
    write_bytes(path, "particles = 13\nseed = 5\0" "7\n", sizeof "particles = 13\nseed = 5\0" "7\n" - 1);
    assert_int_equal(hstpfd_config_load(&cfg, path, err, sizeof err), -1);
    assert_non_null(strstr(err, ":2: a NUL byte"));
    write_bytes(path, "particles = 13\ngate_m = 50\0junk", sizeof "particles = 13\ngate_m = 50\0junk" - 1);
    assert_int_equal(hstpfd_config_load(&cfg, path, err, sizeof err), -1);
    assert_non_null(strstr(err, ":2: a NUL byte"));
    remove(path);
    assert_int_equal(hstpfd_config_load(&cfg, "/nonexistent/x.ini", err, sizeof err), -1);
    assert_non_null(strstr(err, "/nonexistent/x.ini"));
}

static void test_finish(void **state)
{
    (void)state;
    hstpfd_config_default(&cfg);
    assert_int_equal(hstpfd_config_finish(&cfg, err, sizeof err), -1); /* no source */
    assert_non_null(strstr(err, "exactly one source"));
    assert_int_equal(hstpfd_config_set(&cfg, "iface", "vcan0", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&cfg, "log", "x.log", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_finish(&cfg, err, sizeof err), -1); /* two */
    assert_int_equal(hstpfd_config_set(&cfg, "log", "", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_finish(&cfg, err, sizeof err), 0);
    /* the keys' ranges are the library's and the scheduler's: a value
     * outside is refused where it is set, naming the key and the range (the
     * finish's check said only "scheduling values out of range", or let the
     * library refuse without the file's line) */
    assert_int_equal(hstpfd_config_set(&cfg, "declare_threshold", "1", err, sizeof err), -1);
    assert_non_null(strstr(err, "declare_threshold"));
    assert_non_null(strstr(err, "(0.5, 1)"));
    assert_int_equal(hstpfd_config_set(&cfg, "declare_threshold", "0.99", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&cfg, "predict_period_s", "1e-9", err, sizeof err), -1);
    assert_non_null(strstr(err, "predict_period_s"));
    assert_int_equal(hstpfd_config_set(&cfg, "max_gap_s", "1e-9", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "dt_nominal_s", "1e-9", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "step_period_s", "1e-9", err, sizeof err), 0); /* 0 or >= 1e-6 */
    assert_int_equal(hstpfd_config_finish(&cfg, err, sizeof err), -1);
    assert_non_null(strstr(err, "step_period_s"));
    assert_int_equal(hstpfd_config_set(&cfg, "step_period_s", "0", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_finish(&cfg, err, sizeof err), 0);
    /* a custom model's message shows the entry as given */
    assert_int_equal(hstpfd_config_set(&cfg, "models", "a:b:1:0:0", err, sizeof err), -1);
    assert_non_null(strstr(err, "'a:b:1:0:0'"));
    /* a custom row under a Table 1 name is refused (the summary named it CRH3, the bus 254) */
    assert_int_equal(hstpfd_config_set(&cfg, "models", "CRH3:0:0:0", err, sizeof err), -1);
    assert_non_null(strstr(err, "Table 1 name"));
    assert_int_equal(hstpfd_config_set(&cfg, "models", "CRH3,Mine:0.8:0.006:0.0001", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&cfg, "iface", "averyveryveryveryverylonginterfacename", err, sizeof err),
                     -1);
}

/* The example configurations under port/config load and pass the checks. */
static void test_example_files(void **state)
{
    static const char *const files[] = {"case1.ini", "case2.ini", "train.ini"};
    size_t i;
    char path[1024];
    (void)state;
    for (i = 0; i < sizeof files / sizeof files[0]; ++i) {
        hstpfd_config_default(&cfg);
        (void)snprintf(path, sizeof path, "%s/%s", HSTPFD_CONFIG_DIR, files[i]);
        if (hstpfd_config_load(&cfg, path, err, sizeof err) != 0) {
            fail_msg("%s", err);
        }
        if (cfg.iface[0] == '\0') {
            assert_int_equal(hstpfd_config_set(&cfg, "log", "run.log", err, sizeof err), 0);
        }
        if (hstpfd_config_finish(&cfg, err, sizeof err) != 0) {
            fail_msg("%s: %s", files[i], err);
        }
    }
    assert_int_equal(cfg.n_models, 7);
    assert_string_equal(cfg.models[6].name, "Depot-EMU-7");
    assert_int_equal(cfg.noise_e.kind, HSTPF_DIST_GAMMA);
    assert_int_equal(cfg.out_format, HSTPFD_OUT_CSV);
}

/* --print-config output read back gives the same configuration and the same
 * text again, also for values a config line would otherwise take for a
 * comment ('#', ';' after a blank) or a quote. */
static void roundtrip(const hstpfd_config_t *c)
{
    static char a[16384], b[16384];
    assert_true(hstpfd_config_write(c, a, sizeof a) > 0);
    hstpfd_config_default(&cfg2);
    if (hstpfd_config_text(&cfg2, a, err, sizeof err) != 0) {
        fail_msg("%s in\n%s", err, a);
    }
    assert_true(hstpfd_config_write(&cfg2, b, sizeof b) > 0);
    assert_string_equal(a, b);
}

static void test_write_quoting(void **state)
{
    char name[64];
    int i;
    (void)state;
    hstpfd_config_default(&cfg);
    assert_int_equal(hstpfd_config_set(&cfg, "log", "#run.log", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&cfg, "out", ";x", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&cfg, "summary", "a #b ;c", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&cfg, "frames_out", "\"q\\\" x", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&cfg, "iface", "#0", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&cfg, "models", "#m:1:0.01:0.0001, CRH3", err, sizeof err), 0);
    roundtrip(&cfg);
    assert_string_equal(cfg2.log, "#run.log");
    assert_string_equal(cfg2.out, ";x");
    assert_string_equal(cfg2.summary, "a #b ;c");
    assert_string_equal(cfg2.frames_out, "\"q\\\" x");
    assert_string_equal(cfg2.iface, "#0");
    assert_string_equal(cfg2.models[0].name, "#m");

    /* the quoted form by hand, with a comment after it */
    assert_int_equal(hstpfd_config_line(&cfg, "log = \"#a \\\"b\\\\\"  # note", err, sizeof err), 0);
    assert_string_equal(cfg.log, "#a \"b\\");
    assert_int_equal(hstpfd_config_line(&cfg, "log = \"open", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_line(&cfg, "log = \"a\" b", err, sizeof err), -1);
    /* a newline or other control character cannot be written back: refused */
    assert_int_equal(hstpfd_config_set(&cfg, "log", "a\nb", err, sizeof err), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "models", "a\x01:1:0:0", err, sizeof err), -1);

    /* the longest model list: 17 custom rows with long names and long numbers */
    hstpfd_config_default(&cfg);
    {
        char list[2048];
        size_t pos = 0;
        for (i = 0; i < HSTPF_MAX_MODELS; ++i) {
            (void)snprintf(name, sizeof name, "#%02d%s", i, "_aaaaaaaaaaaaaaaaaaaaaaaaaaa");
            pos += (size_t)snprintf(list + pos, sizeof list - pos, "%s%s:1.2345678901234567:0.12345678901234567:"
                                    "0.0012345678901234567", i ? "," : "", name);
        }
        assert_true(pos < sizeof list);
        if (hstpfd_config_set(&cfg, "models", list, err, sizeof err) != 0) {
            fail_msg("%s", err);
        }
    }
    assert_int_equal(cfg.n_models, HSTPF_MAX_MODELS);
    roundtrip(&cfg);
    assert_int_equal(cfg2.n_models, HSTPF_MAX_MODELS);
    assert_float_equal(cfg2.models[16].c2, cfg.models[16].c2, 0.0);
}

/* Every buffer too short for the printed configuration is refused, never
 * overrun; parse errors of each kind name the key; rarely used values. */
static void test_write_sizes_and_errors(void **state)
{
    static char full[16384], part[16384];
    int n, k;
    char longv[3000];
    (void)state;
    hstpfd_config_default(&cfg);
    assert_int_equal(hstpfd_config_set(&cfg, "models", "CRH3, x:1:0.01:0.0001", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&cfg, "log", "#a", err, sizeof err), 0);
    n = hstpfd_config_write(&cfg, full, sizeof full);
    assert_true(n > 0);
    for (k = 0; k <= n; ++k) {
        memset(part, 'Z', sizeof part);
        assert_int_equal(hstpfd_config_write(&cfg, part, (size_t)k), -1);
        assert_true(part[k] == 'Z'); /* nothing beyond the buffer */
    }
    assert_int_equal(hstpfd_config_write(&cfg, part, (size_t)n + 1u), n);
    assert_null(hstpfd_config_key_name(hstpfd_config_n_keys()));
    assert_null(hstpfd_config_key_help(hstpfd_config_n_keys()));
    /* no room for a message: still refused */
    assert_int_equal(hstpfd_config_set(&cfg, "nosuchkey", "1", NULL, 0), -1);
    assert_int_equal(hstpfd_config_set(&cfg, "nosuchkey", "1", err, 0), -1);

    /* enums and booleans, each spelling */
    assert_int_equal(hstpfd_config_set(&cfg, "engine", "particle", err, sizeof err), 0);
    assert_int_equal(cfg.engine, HSTPF_ENGINE_PARTICLE);
    assert_int_equal(hstpfd_config_set(&cfg, "engine", "kalman", err, sizeof err), 0);
    assert_int_equal(cfg.engine, HSTPF_ENGINE_KALMAN);
    assert_int_equal(hstpfd_config_set(&cfg, "engine", "grid", err, sizeof err), 0);
    assert_int_equal(cfg.engine, HSTPF_ENGINE_GRID);
    assert_int_equal(hstpfd_config_set(&cfg, "engine", "auto", err, sizeof err), 0);
    assert_int_equal(cfg.engine, HSTPF_ENGINE_AUTO);
    assert_int_equal(hstpfd_config_set(&cfg, "engine", "point-mass", err, sizeof err), -1);
    {
        static const char *const yes[] = {"1", "yes", "true", "on"}, *const no[] = {"0", "no", "false", "off"};
        for (k = 0; k < 4; ++k) {
            assert_int_equal(hstpfd_config_set(&cfg, "send", no[k], err, sizeof err), 0);
            assert_int_equal(cfg.send, 0);
            assert_int_equal(hstpfd_config_set(&cfg, "send", yes[k], err, sizeof err), 0);
            assert_int_equal(cfg.send, 1);
        }
    }
    /* noise: each malformed form */
    {
        static const char *const bad[] = {"gaussian:1",   "gaussian:x:1",    "gaussian:0:0",    "gaussian:0:1:2",
                                          "gamma:1",      "gamma:0.5:0.2:x", "gamma:0:1",       "gamma:0.5:-1",
                                          "gamma:2e4:1",  "uniform:1:2",     "gaussian:1:2:3:4:5:6",
                                          "gamma:x:1:0",  "gamma:0.5:y"};
        for (k = 0; k < (int)(sizeof bad / sizeof bad[0]); ++k) {
            if (hstpfd_config_set(&cfg, "noise_e", bad[k], err, sizeof err) != -1) {
                fail_msg("noise '%s' accepted", bad[k]);
            }
            assert_non_null(strstr(err, "noise"));
        }
        assert_int_equal(hstpfd_config_set(&cfg, "noise_v", "gamma:0.1:0.05", err, sizeof err), 0); /* loc 0 */
        assert_int_equal(hstpfd_config_set(&cfg, "noise", "case3", err, sizeof err), -1);
    }
    memset(longv, 'a', sizeof longv);
    longv[200] = '\0';
    assert_int_equal(hstpfd_config_set(&cfg, "noise_e", longv, err, sizeof err), -1); /* too long */
    /* models: each malformed form */
    {
        static const char *const bad[] = {"a:1:2", "a:100:0:0", "a:1:2:0", "a:1:0:1", "", " , ", "a:x:0:0",
                                          "a:1:0:0, a:1:0:0", "NoSuchTrain", ":1:0:0"};
        for (k = 0; k < (int)(sizeof bad / sizeof bad[0]); ++k) {
            if (hstpfd_config_set(&cfg, "models", bad[k], err, sizeof err) != -1) {
                fail_msg("models '%s' accepted", bad[k]);
            }
        }
        longv[200] = 'a';
        longv[2100] = '\0';
        assert_int_equal(hstpfd_config_set(&cfg, "models", longv, err, sizeof err), -1);
        for (k = 0; k < 130; k += 2) { /* 65 entries */
            longv[k] = 'a';
            longv[k + 1] = ',';
        }
        longv[130] = '\0';
        assert_int_equal(hstpfd_config_set(&cfg, "models", longv, err, sizeof err), -1);
        assert_int_equal(hstpfd_config_set(&cfg, "models", "all, CRH3", err, sizeof err), -1); /* 18 */
    }
    /* a value longer than any key takes */
    memset(longv, 'b', sizeof longv);
    longv[sizeof longv - 1] = '\0';
    assert_int_equal(hstpfd_config_set(&cfg, "out", longv, err, sizeof err), -1);
    assert_int_equal(hstpfd_config_line(&cfg, longv, err, sizeof err), 0 - 1);
    /* quoted values with blanks, tabs and comments after them */
    assert_int_equal(hstpfd_config_line(&cfg, "out = \"a b\"\t; c", err, sizeof err), 0);
    assert_string_equal(cfg.out, "a b");
    assert_int_equal(hstpfd_config_line(&cfg, "out = \"a\\\\b\\\\\"\r\n", err, sizeof err), 0);
    assert_string_equal(cfg.out, "a\\b\\");
    assert_int_equal(hstpfd_config_line(&cfg, "out = \"\\q\"", err, sizeof err), 0); /* other escapes: as is */
    assert_string_equal(cfg.out, "\\q");
    /* text: a line too long, and the error names the line */
    assert_int_equal(hstpfd_config_text(&cfg, "particles = 10\nparticles = x\n", err, sizeof err), -1);
    assert_non_null(strstr(err, "line 2"));
    {
        static char big[HSTPFD_LINE_MAX + 10];
        memset(big, 'c', sizeof big - 1);
        big[sizeof big - 1] = '\0';
        assert_int_equal(hstpfd_config_text(&cfg, big, err, sizeof err), -1);
        assert_non_null(strstr(err, "too long"));
    }
    /* the estimator's own ranges, through finish: noise beyond float range */
    hstpfd_config_default(&cfg);
    assert_int_equal(hstpfd_config_set(&cfg, "log", "x.log", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_set(&cfg, "noise_e", "gaussian:1e30:1", err, sizeof err), 0);
    assert_int_equal(hstpfd_config_finish(&cfg, err, sizeof err), -1);
    assert_non_null(strstr(err, "estimator rejects"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults),   cmocka_unit_test(test_set_numbers), cmocka_unit_test(test_enums),
        cmocka_unit_test(test_noise),      cmocka_unit_test(test_models),      cmocka_unit_test(test_lines),
        cmocka_unit_test(test_file_and_write), cmocka_unit_test(test_finish),
        cmocka_unit_test(test_example_files), cmocka_unit_test(test_write_quoting),
        cmocka_unit_test(test_write_sizes_and_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
