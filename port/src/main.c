/* hstpfd: the hstpf estimator daemon. Reads position and traction frames
 * from a SocketCAN interface (--iface) or a candump log (--log), runs the
 * particle-filter bank, publishes the estimates as frames, writes a
 * per-step stream and a final JSON summary. See docs/daemon.md. */
#define _DEFAULT_SOURCE 1

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "candump.h"
#include "config.h"
#include "core.h"
#include "source.h"

static hstpf_t filt; /* ~100 kB: static, as on a target */
static hstpfd_config_t cfg;
static hstpfd_core_t core;
static volatile sig_atomic_t stop_flag = 0;

static void on_signal(int sig)
{
    (void)sig;
    stop_flag = 1;
}

static void usage(FILE *fp)
{
    unsigned i;
    fprintf(fp,
            "usage: hstpfd (--iface IFACE | --log FILE) [options]\n"
            "\n"
            "  -i, --iface IFACE     run on a SocketCAN interface (key iface)\n"
            "  -l, --log FILE        replay a candump log instead, - = stdin (key log)\n"
            "  -c, --config FILE     read key = value settings (before all options)\n"
            "  -o, --out FILE        per-step stream, - = stdout (key out)\n"
            "  -s, --summary FILE    also write the summary line there (key summary)\n"
            "      --set KEY=VALUE   set any configuration key\n"
            "      --KEY VALUE       the same, '-' in KEY read as '_' (e.g. --mass-t 480)\n"
            "      --print-config    print the effective configuration and exit\n"
            "      --list-types      print the Table 1 train types and exit\n"
            "  -h, --help            this text;  --version  the version\n"
            "\n"
            "The final JSON summary line goes to stdout. Exit status: 0 done (end of\n"
            "log or SIGINT/SIGTERM), 1 run-time failure, 2 bad options or configuration.\n"
            "\nconfiguration keys:\n");
    for (i = 0; i < hstpfd_config_n_keys(); ++i) {
        fprintf(fp, "  %-19s %s\n", hstpfd_config_key_name(i), hstpfd_config_key_help(i));
    }
}

static int bad(const char *msg)
{
    fprintf(stderr, "hstpfd: %s\n(try hstpfd --help)\n", msg);
    return 2;
}

/* "--mass-t" -> "mass_t" in buf; NULL if it is not a long option. */
static const char *key_of(const char *opt, char *buf, size_t size)
{
    size_t i;
    if (strncmp(opt, "--", 2) != 0 || strlen(opt + 2) >= size) {
        return NULL;
    }
    for (i = 0; opt[2 + i] != '\0'; ++i) {
        buf[i] = opt[2 + i] == '-' ? '_' : opt[2 + i];
    }
    buf[i] = '\0';
    return buf;
}

static FILE *open_out(const char *path, const char *what)
{
    FILE *fp;
    if (strcmp(path, "-") == 0) {
        return stdout;
    }
    fp = fopen(path, "w");
    if (fp == NULL) {
        fprintf(stderr, "hstpfd: cannot write %s %s: %s\n", what, path, strerror(errno));
    }
    return fp;
}

/* Closes an output (stdout is flushed); 0, or -1 with a message when a
 * write failed (a full disk, /dev/full): what was written is incomplete. */
static int close_out(FILE *fp, const char *what)
{
    int bad;
    if (fp == NULL) {
        return 0;
    }
    bad = ferror(fp) != 0;
    bad |= (fp == stdout ? fflush(fp) : fclose(fp)) != 0;
    if (bad) {
        fprintf(stderr, "hstpfd: writing %s failed\n", what);
        return -1;
    }
    return 0;
}

/* The same regular file (by path, or by device and inode where it exists);
 * a device such as /dev/null may take any number of outputs */
static int same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    const int ea = stat(a, &sa) == 0, eb = stat(b, &sb) == 0;
    if (a[0] == '\0' || b[0] == '\0' || strcmp(a, "-") == 0 || strcmp(b, "-") == 0) {
        return 0; /* unset, or stdin / stdout */
    }
    if ((ea && !S_ISREG(sa.st_mode)) || (eb && !S_ISREG(sb.st_mode))) {
        return 0;
    }
    if (strcmp(a, b) == 0) {
        return 1;
    }
    return ea && eb && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

/* The log and the outputs are distinct files: an output opened for writing
 * truncates the log it names, and two outputs in one file tear each other. */
static int distinct_files(const hstpfd_config_t *c)
{
    const char *const path[4] = {c->log, c->out, c->frames_out, c->summary};
    static const char *const role[4] = {"--log", "--out", "--frames-out", "--summary"};
    int i, j;
    for (i = 0; i < 4; ++i) {
        for (j = i + 1; j < 4; ++j) {
            if (same_file(path[i], path[j])) {
                fprintf(stderr, "hstpfd: %s and %s name the same file %s\n", role[i], role[j], path[j]);
                return 0;
            }
        }
    }
    return 1;
}

/* Only a regular file is read twice: the format check would take the
 * start of a pipe or FIFO (and block on a FIFO with no writer). */
static int regular_file(const char *path)
{
    struct stat st;
    return strcmp(path, "-") != 0 && stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

int main(int argc, char **argv)
{
    char err[HSTPFD_ERR_MAX], key[64];
    int i, print_config = 0, rc;
    FILE *out = NULL, *frames_out = NULL, *summary = NULL;
    const char *end = HSTPFD_END_ERROR;
    int cli_source = 0; /* the source named on the command line: 1 iface, 2 log */
    struct sigaction sa;

    hstpfd_config_default(&cfg);
    /* the configuration file first, whatever its place on the line */
    for (i = 1; i < argc; ++i) {
        if ((strcmp(argv[i], "-c") == 0 || strcmp(argv[i], "--config") == 0)) {
            if (i + 1 >= argc) {
                return bad("--config needs a file");
            }
            if (hstpfd_config_load(&cfg, argv[i + 1], err, sizeof err) != 0) {
                return bad(err);
            }
            ++i;
        }
    }
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *k = NULL;
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            usage(stdout);
            return 0;
        }
        if (strcmp(a, "--version") == 0) {
            printf("hstpfd %d.%d.%d\n", HSTPF_VERSION_MAJOR, HSTPF_VERSION_MINOR, HSTPF_VERSION_PATCH);
            return 0;
        }
        if (strcmp(a, "--list-types") == 0) {
            int r;
            for (r = 0; r < HSTPF_N_TRAIN_TYPES; ++r) {
                printf("%2d  %-24s c0 %-5g c1 %-8g c2 %g\n", r, hstpf_train_types[r].name, hstpf_train_types[r].c0,
                       hstpf_train_types[r].c1, hstpf_train_types[r].c2);
            }
            return 0;
        }
        if (strcmp(a, "--print-config") == 0) {
            print_config = 1;
            continue;
        }
        if (strcmp(a, "-c") == 0 || strcmp(a, "--config") == 0) {
            ++i; /* done above */
            continue;
        }
        if (strcmp(a, "--set") == 0) {
            char kv[2304];
            char *eq;
            if (i + 1 >= argc) {
                return bad("--set needs KEY=VALUE");
            }
            (void)snprintf(kv, sizeof kv, "%s", argv[++i]);
            eq = strchr(kv, '=');
            if (eq == NULL) {
                return bad("--set needs KEY=VALUE");
            }
            *eq = '\0';
            if (hstpfd_config_set(&cfg, kv, eq + 1, err, sizeof err) != 0) {
                return bad(err);
            }
            continue;
        }
        if (strcmp(a, "-i") == 0) {
            k = "iface";
        } else if (strcmp(a, "-l") == 0) {
            k = "log";
        } else if (strcmp(a, "-o") == 0) {
            k = "out";
        } else if (strcmp(a, "-s") == 0) {
            k = "summary";
        } else {
            k = key_of(a, key, sizeof key);
        }
        if (k == NULL) {
            char m[HSTPFD_ERR_MAX];
            (void)snprintf(m, sizeof m, "unexpected argument '%s'", a);
            return bad(m);
        }
        if (i + 1 >= argc) {
            char m[HSTPFD_ERR_MAX];
            (void)snprintf(m, sizeof m, "%s needs a value", a);
            return bad(m);
        }
        if (strcmp(k, "iface") == 0 || strcmp(k, "log") == 0) {
            /* the command line's source replaces the config file's (a live
             * unit's file, run offline with --log); two on it are an error */
            const int src = strcmp(k, "iface") == 0 ? 1 : 2;
            if (cli_source != 0 && cli_source != src) {
                return bad("give exactly one source: --iface IFACE or --log FILE");
            }
            cli_source = src;
            (src == 1 ? cfg.log : cfg.iface)[0] = '\0';
        }
        if (hstpfd_config_set(&cfg, k, argv[++i], err, sizeof err) != 0) {
            char m[2 * HSTPFD_ERR_MAX];
            if (strncmp(err, "unknown key", 11) == 0) {
                (void)snprintf(m, sizeof m, "unknown option '%s'", a);
            } else {
                (void)snprintf(m, sizeof m, "%s", err);
            }
            return bad(m);
        }
    }
    if (print_config) {
        static char buf[16384];
        if (hstpfd_config_write(&cfg, buf, sizeof buf) < 0) {
            return 1;
        }
        fputs(buf, stdout);
        return 0;
    }
    if (hstpfd_config_finish(&cfg, err, sizeof err) != 0) {
        return bad(err);
    }

    if (!distinct_files(&cfg)) {
        return 2;
    }
    if (cfg.log[0] != '\0' && regular_file(cfg.log) && hstpfd_candump_check_file(cfg.log, err, sizeof err) != 0) {
        fprintf(stderr, "hstpfd: %s\n", err);
        return 1;
    }
    if (cfg.out[0] != '\0' && (out = open_out(cfg.out, "the step stream")) == NULL) {
        return 1;
    }
    if (cfg.frames_out[0] != '\0' && (frames_out = open_out(cfg.frames_out, "the frame log")) == NULL) {
        return 1;
    }
    if (cfg.summary[0] != '\0' && (summary = open_out(cfg.summary, "the summary")) == NULL) {
        return 1;
    }
    if (cfg.iface[0] != '\0') { /* live: lines out as they happen */
        if (out != NULL) {
            (void)setvbuf(out, NULL, _IOLBF, 0);
        }
        if (frames_out != NULL) {
            (void)setvbuf(frames_out, NULL, _IOLBF, 0);
        }
    }
    rc = hstpfd_core_init(&core, &cfg, &filt, cfg.iface[0] != '\0' ? hstpfd_iface_send : NULL, NULL, out,
                          frames_out, cfg.iface[0] != '\0' ? cfg.iface : "can0");
    if (rc != 0) {
        fprintf(stderr, "hstpfd: cannot start the estimator: %s (%d)\n",
                rc == -100            ? "receiver configuration"
                : rc == HSTPFD_E_SCHED ? "step_period_s, predict_period_s, the timeouts, max_gap_s and the "
                                         "first step must be at least 1e-6 s"
                                       : hstpf_strerror(rc),
                rc);
        return 2;
    }

    hstpfd_core_set_stop(&core, &stop_flag);
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal; /* no SA_RESTART: poll() returns EINTR */
    (void)sigemptyset(&sa.sa_mask);
    (void)sigaction(SIGINT, &sa, NULL);
    (void)sigaction(SIGTERM, &sa, NULL);
    sa.sa_handler = SIG_IGN;
    (void)sigaction(SIGPIPE, &sa, NULL);

    if (cfg.iface[0] != '\0') {
        rc = hstpfd_run_iface(&core, cfg.iface, &stop_flag, &end);
    } else {
        rc = hstpfd_run_log(&core, cfg.log, &stop_flag, &end);
    }

    if (close_out(out, "the step stream") != 0) {
        rc = -1;
    }
    if (frames_out != out && close_out(frames_out, "the frame log") != 0) {
        rc = -1;
    }
    hstpfd_core_summary(&core, stdout, cfg.iface[0] != '\0' ? "iface" : "log",
                        cfg.iface[0] != '\0' ? cfg.iface : cfg.log, end);
    if (close_out(stdout, "the summary to stdout") != 0) {
        rc = -1;
    }
    if (summary != NULL && summary != stdout) {
        hstpfd_core_summary(&core, summary, cfg.iface[0] != '\0' ? "iface" : "log",
                            cfg.iface[0] != '\0' ? cfg.iface : cfg.log, end);
        if (fclose(summary) != 0) {
            fprintf(stderr, "hstpfd: writing the summary failed\n");
            return 1;
        }
    }
    return rc == 0 ? 0 : 1;
}
