/* hstpfd: configuration keys, file parser and command-line overrides. */
#include "config.h"
#include "hstpf_frames.h" /* the DBC's E2E receiver parameters of the inputs: the defaults below */

#if HSTPF_FRAME_POSITION_E2E_MAX_DELTA != HSTPF_FRAME_TRACTION_E2E_MAX_DELTA
#error "e2e_max_delta is one key for both inputs: the DBC gives them different HstpfE2EMaxDeltaCounter"
#endif

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef enum {
    K_NAME, /* short string (interface) */
    K_PATH, /* file path; "" or "-" allowed where documented */
    K_U16,
    K_U32,
    K_U64,
    K_DBL,
    K_BOOL,
    K_MODELS,
    K_NOISE,
    K_PRESET,
    K_TRACTION,
    K_STALE,
    K_ENGINE,
    K_FORMAT,
    K_RXFILTER
} ktype_t;

typedef struct {
    const char *name;
    ktype_t type;
    size_t off;
    double lo, hi;
    int lo_open; /* lo excluded */
    const char *help;
} key_t_;

#define OFF(m) offsetof(hstpfd_config_t, m)

static const key_t_ keys[] = {
    {"iface", K_NAME, OFF(iface), 0, 0, 0, "CAN interface to run on, e.g. can0 (live)"},
    {"log", K_PATH, OFF(log), 0, 0, 0, "candump log file to replay instead (offline)"},
    {"models", K_MODELS, 0, 0, 0, 0,
     "model set: Table 1 names and/or name:c0:c1:c2, comma-separated; all = the 17 rows"},
    {"engine", K_ENGINE, 0, 0, 0, 0,
     "per-model estimator: auto (Kalman if all three noises are Gaussian, else particles) | particle | kalman"},
    {"particles", K_U16, OFF(particles), 2, HSTPF_MAX_PARTICLES, 0, "particles per model"},
    {"seed", K_U64, OFF(seed), 0, 0, 0, "random seed of the filter"},
    {"gamma_rot", K_DBL, OFF(gamma_rot), 0, 1, 0, "rotating-mass factor gamma"},
    {"noise", K_PRESET, 0, 0, 0, 0, "noise preset for all three channels: case1 | case2 (the paper's)"},
    {"noise_s", K_NOISE, OFF(noise_s), 0, 0, 0,
     "position process noise w_s, m per step: gaussian:mean:sd | gamma:shape:scale:loc"},
    {"noise_v", K_NOISE, OFF(noise_v), 0, 0, 0, "speed process noise w_v, m/s per step"},
    {"noise_e", K_NOISE, OFF(noise_e), 0, 0, 0, "position measurement noise e, m"},
    {"dt_nominal_s", K_DBL, OFF(dt_nominal_s), 0, HSTPF_DT_MAX_S, 1,
     "step the noise is given for (also the first step's length), s"},
    {"init_speed_mps", K_DBL, OFF(init_speed_mps), -HSTPF_SPEED_MAX, HSTPF_SPEED_MAX, 0,
     "prior speed mean at the first fix, m/s"},
    {"init_speed_sd", K_DBL, OFF(init_speed_sd), 0, HSTPF_SPEED_MAX, 0, "prior speed sd, m/s"},
    {"roughening_k", K_DBL, OFF(roughening_k), 0, 10, 0,
     "particle engine: roughening after resampling, sd = k x spread / sqrt(M)"},
    {"e_blur_sd", K_DBL, OFF(e_blur_sd), 0, 1e3, 0,
     "particle engine: measurement density blurred by N(0, sd), m (0 = exact; for one-sided noise)"},
    {"declare_threshold", K_DBL, OFF(declare_threshold), 0, 1, 1,
     "model weight above which a type may be declared"},
    {"declare_hold_s", K_DBL, OFF(declare_hold_s), 0, 1e6, 0, "how long it must stay above, s"},
    {"gate_m", K_DBL, OFF(gate_m), 0, HSTPF_POS_MAX_M, 0, "outlier gate on the position, m (0 = none)"},
    {"mass_t", K_DBL, OFF(mass_t), 0, 1e5, 1, "train mass, t (traction kN -> N/kN)"},
    {"step_period_s", K_DBL, OFF(sched.step_period_s), 0, HSTPF_DT_MAX_S, 0,
     "0: a step per valid position frame; else step at most this often (decimate)"},
    {"position_timeout_s", K_DBL, OFF(sched.pos_timeout_s), 0, 3600, 1,
     "no valid position for longer: position stale"},
    {"traction_timeout_s", K_DBL, OFF(sched.trac_timeout_s), 0, 3600, 1,
     "no valid traction for longer: traction stale (last value held)"},
    {"stale_policy", K_STALE, 0, 0, 0, 0, "position stale: predict (predict-only steps) | wait"},
    {"predict_period_s", K_DBL, OFF(sched.predict_period_s), 0, HSTPF_DT_MAX_S, 1,
     "length of the predict-only steps while position is stale, s"},
    {"max_gap_s", K_DBL, OFF(sched.max_gap_s), 0, 1e7, 1,
     "a gap between steps longer than this restarts the estimator, s"},
    {"traction_mode", K_TRACTION, 0, 0, 0, 0, "traction of a step: mean (time-weighted over the step) | latest"},
    {"e2e_max_delta", K_U32, OFF(e2e_max_delta), 1, 13, 0,
     "largest accepted alive-counter increment (1 = no frame may be lost)"},
    {"time_scale", K_DBL, OFF(time_scale), 0, 1e4, 1,
     "frame time = first stamp + (stamp - first stamp) x time_scale (a log replayed k x faster: k)"},
    {"tick_s", K_DBL, OFF(tick_s), 0, 60, 1, "idle tick: with no frame for this long, time advances by it, s"},
    {"rx_filter", K_RXFILTER, 0, 0, 0, 0,
     "kernel receive filter: inputs (the two input IDs) | block (0x100-0x1FF) | all"},
    {"send", K_BOOL, OFF(send), 0, 0, 0, "with iface: send the estimate frames (0 = listen only)"},
    {"reopen_s", K_DBL, OFF(reopen_s), 0, 3600, 1, "retry period to reopen a lost interface, s (wall clock)"},
    {"out", K_PATH, OFF(out), 0, 0, 0, "per-step stream file (- = stdout, empty = none)"},
    {"out_format", K_FORMAT, 0, 0, 0, 0, "per-step stream format: jsonl | csv"},
    {"summary", K_PATH, OFF(summary), 0, 0, 0, "also write the final JSON summary line to this file"},
    {"frames_out", K_PATH, OFF(frames_out), 0, 0, 0,
     "write the estimate frames as a candump log (with --log: what would be sent)"},
    {"frames_out_inputs", K_BOOL, OFF(frames_out_inputs), 0, 0, 0,
     "1: frames_out also gets every received frame (a whole-bus recording)"},
};

#define N_KEYS (sizeof keys / sizeof keys[0])

unsigned hstpfd_config_n_keys(void)
{
    return (unsigned)N_KEYS;
}

const char *hstpfd_config_key_name(unsigned i)
{
    return i < N_KEYS ? keys[i].name : NULL;
}

const char *hstpfd_config_key_help(unsigned i)
{
    return i < N_KEYS ? keys[i].help : NULL;
}

/* The format is checked at every caller (and clang's -Wformat-nonliteral is
 * satisfied by the attribute). */
#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static void fail(char *err, size_t size, const char *fmt, ...);

static void fail(char *err, size_t size, const char *fmt, ...)
{
    va_list ap;
    if (err == NULL || size == 0) {
        return;
    }
    va_start(ap, fmt);
    (void)vsnprintf(err, size, fmt, ap);
    va_end(ap);
}

static void gaussian(hstpf_dist_spec_t *d, double mean, double sd)
{
    memset(d, 0, sizeof *d);
    d->kind = HSTPF_DIST_GAUSSIAN;
    d->mean = mean;
    d->sd = sd;
}

static void gamma_(hstpf_dist_spec_t *d, double shape, double scale, double loc)
{
    memset(d, 0, sizeof *d);
    d->kind = HSTPF_DIST_GAMMA;
    d->shape = shape;
    d->scale = scale;
    d->loc = loc;
}

static void preset(hstpfd_config_t *c, int cas)
{
    if (cas == 1) { /* variances 0.02, 0.05, 5 */
        gaussian(&c->noise_s, 0.0, sqrt(0.02));
        gaussian(&c->noise_v, 0.0, sqrt(0.05));
        gaussian(&c->noise_e, 0.0, sqrt(5.0));
    } else {
        gamma_(&c->noise_s, 0.02, 0.1, 0.0);
        gamma_(&c->noise_v, 0.1, 0.05, 0.0);
        gamma_(&c->noise_e, 0.5, 0.2, 0.0);
    }
}

static void all_models(hstpfd_config_t *c)
{
    uint16_t i;
    for (i = 0; i < HSTPF_N_TRAIN_TYPES && i < HSTPF_MAX_MODELS; ++i) {
        (void)snprintf(c->model_name[i], HSTPFD_NAME_MAX, "%s", hstpf_train_types[i].name);
        c->models[i] = hstpf_train_types[i];
        c->models[i].name = c->model_name[i];
    }
    c->n_models = i;
}

void hstpfd_config_default(hstpfd_config_t *c)
{
    hstpf_config_t fc;
    memset(c, 0, sizeof *c);
    (void)hstpf_config_default(&fc);
    all_models(c);
    c->particles = fc.n_particles;
    c->engine = fc.engine;
    c->seed = 1;
    c->gamma_rot = fc.gamma_rot;
    preset(c, 1);
    c->dt_nominal_s = fc.dt_nominal_s;
    c->init_speed_mps = fc.init_speed_mps;
    c->init_speed_sd = fc.init_speed_sd;
    c->roughening_k = fc.roughening_k;
    c->e_blur_sd = fc.e_blur_sd;
    c->declare_threshold = fc.declare_threshold;
    c->declare_hold_s = fc.declare_hold_s;
    c->gate_m = fc.gate_m;
    c->mass_t = 500.0;
    c->sched.step_period_s = 1.0;
    c->sched.pos_timeout_s = HSTPF_FRAME_POSITION_E2E_TIMEOUT_MS / 1000.0;
    c->sched.trac_timeout_s = HSTPF_FRAME_TRACTION_E2E_TIMEOUT_MS / 1000.0;
    c->sched.predict_period_s = 1.0;
    c->sched.max_gap_s = 600.0;
    c->sched.traction_mode = HSTPFD_TRACTION_MEAN;
    c->sched.stale_policy = HSTPFD_STALE_PREDICT;
    c->e2e_max_delta = HSTPF_FRAME_POSITION_E2E_MAX_DELTA;
    c->rx_filter = HSTPFD_RX_FILTER_BLOCK;
    c->time_scale = 1.0;
    c->tick_s = 0.1;
    c->send = 1;
    c->reopen_s = 1.0;
    c->out_format = HSTPFD_OUT_JSONL;
}

static char *trim(char *s)
{
    char *e;
    while (*s == ' ' || *s == '\t') {
        ++s;
    }
    e = s + strlen(s);
    while (e > s && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\r' || e[-1] == '\n')) {
        *--e = '\0';
    }
    return s;
}

/* Control characters (but tab) cannot be written back as one config line. */
static int printable(const char *s)
{
    for (; *s != '\0'; ++s) {
        const unsigned char ch = (unsigned char)*s;
        if ((ch < 0x20u && ch != '\t') || ch == 0x7fu) {
            return 0;
        }
    }
    return 1;
}

/* A finite number filling all of text. */
static int num(const char *text, double *out)
{
    char *end;
    double x;
    if (*text == '\0') {
        return -1;
    }
    errno = 0;
    x = strtod(text, &end);
    if (end == text || *end != '\0' || errno == ERANGE || !(x == x) || x > 1e300 || x < -1e300) {
        return -1;
    }
    *out = x;
    return 0;
}

static int unum(const char *text, uint64_t *out)
{
    char *end;
    unsigned long long x;
    if (*text < '0' || *text > '9') { /* no sign, no blank */
        return -1;
    }
    errno = 0;
    x = strtoull(text, &end, 0);
    if (*end != '\0' || errno == ERANGE) {
        return -1;
    }
    *out = (uint64_t)x;
    return 0;
}

/* Splits text at ':' into at most max fields (modifies buf). */
static int split(char *buf, char sep, char **field, int max)
{
    int n = 0;
    char *p = buf;
    for (;;) {
        char *q = strchr(p, sep);
        if (n >= max) {
            return -1;
        }
        field[n++] = p;
        if (q == NULL) {
            break;
        }
        *q = '\0';
        p = q + 1;
    }
    return n;
}

int hstpfd_parse_noise(const char *text, hstpf_dist_spec_t *spec, char *err, size_t err_size)
{
    char buf[128];
    char *f[5];
    double a = 0.0, b = 0.0, l = 0.0;
    int n, i;
    const char *kind;
    if (strlen(text) >= sizeof buf) {
        fail(err, err_size, "noise '%s': too long", text);
        return -1;
    }
    (void)snprintf(buf, sizeof buf, "%s", text);
    n = split(buf, ':', f, 5);
    if (n < 0) {
        fail(err, err_size, "noise '%s': too many fields", text);
        return -1;
    }
    for (i = 0; i < n; ++i) {
        f[i] = trim(f[i]);
    }
    kind = f[0];
    if (strcmp(kind, "gaussian") == 0) {
        if (n != 3 || num(f[1], &a) != 0 || num(f[2], &b) != 0) {
            fail(err, err_size, "noise '%s': expected gaussian:mean:sd", text);
            return -1;
        }
        if (!(b > 0.0)) {
            fail(err, err_size, "noise '%s': sd must be > 0", text);
            return -1;
        }
        gaussian(spec, a, b);
        return 0;
    }
    if (strcmp(kind, "gamma") == 0) {
        if ((n != 3 && n != 4) || num(f[1], &a) != 0 || num(f[2], &b) != 0 || (n == 4 && num(f[3], &l) != 0)) {
            fail(err, err_size, "noise '%s': expected gamma:shape:scale:loc", text);
            return -1;
        }
        if (!(a >= 1e-3 && a <= 1e4) || !(b > 0.0)) {
            fail(err, err_size, "noise '%s': shape must be in [0.001, 10000] and scale > 0", text);
            return -1;
        }
        gamma_(spec, a, b, l);
        return 0;
    }
    fail(err, err_size, "noise '%s': kind must be gaussian or gamma", text);
    return -1;
}

static int add_model(hstpfd_config_t *c, const char *name, double c0, double c1, double c2, char *err,
                     size_t err_size)
{
    uint16_t i;
    if (c->n_models >= HSTPF_MAX_MODELS) {
        fail(err, err_size, "models: more than %d", HSTPF_MAX_MODELS);
        return -1;
    }
    if (strlen(name) >= HSTPFD_NAME_MAX || name[0] == '\0' || !printable(name)) {
        fail(err, err_size, "models: name '%s' empty, longer than %d or with control characters", name,
             HSTPFD_NAME_MAX - 1);
        return -1;
    }
    for (i = 0; i < c->n_models; ++i) {
        if (strcmp(c->model_name[i], name) == 0) {
            fail(err, err_size, "models: '%s' given twice", name);
            return -1;
        }
    }
    (void)snprintf(c->model_name[i], HSTPFD_NAME_MAX, "%s", name);
    c->models[i].name = c->model_name[i];
    c->models[i].c0 = c0;
    c->models[i].c1 = c1;
    c->models[i].c2 = c2;
    c->n_models = (uint16_t)(i + 1);
    return 0;
}

int hstpfd_parse_models(hstpfd_config_t *c, const char *text, char *err, size_t err_size)
{
    char buf[2048];
    char *item[64];
    int n, i;
    hstpfd_config_t t = *c; /* unchanged on error */
    if (strlen(text) >= sizeof buf) {
        fail(err, err_size, "models: list too long");
        return -1;
    }
    (void)snprintf(buf, sizeof buf, "%s", text);
    n = split(buf, ',', item, 64);
    if (n < 0) {
        fail(err, err_size, "models: too many entries");
        return -1;
    }
    t.n_models = 0;
    for (i = 0; i < n; ++i) {
        char *f[5];
        int nf, k;
        char *name = trim(item[i]);
        if (strcmp(name, "all") == 0) {
            for (k = 0; k < HSTPF_N_TRAIN_TYPES; ++k) {
                const hstpf_theta_t *r = &hstpf_train_types[k];
                if (add_model(&t, r->name, r->c0, r->c1, r->c2, err, err_size) != 0) {
                    return -1;
                }
            }
            continue;
        }
        if (strchr(name, ':') == NULL) {
            const int32_t row = hstpf_train_type_find(name);
            const hstpf_theta_t *r;
            if (row < 0) {
                fail(err, err_size, "models: '%s' is not a Table 1 name (see --list-types) nor name:c0:c1:c2",
                     name);
                return -1;
            }
            r = &hstpf_train_types[row];
            if (add_model(&t, r->name, r->c0, r->c1, r->c2, err, err_size) != 0) {
                return -1;
            }
            continue;
        }
        nf = split(name, ':', f, 5);
        {
            double c0, c1, c2;
            if (nf != 4 || num(trim(f[1]), &c0) != 0 || num(trim(f[2]), &c1) != 0 || num(trim(f[3]), &c2) != 0) {
                fail(err, err_size, "models: custom entry '%s' must be name:c0:c1:c2", item[i]);
                return -1;
            }
            if (!(c0 >= 0.0 && c0 <= 50.0) || !(c1 >= 0.0 && c1 <= 1.0) || !(c2 >= 0.0 && c2 <= 0.01)) {
                fail(err, err_size, "models: '%s': need c0 in [0,50], c1 in [0,1], c2 in [0,0.01]", trim(f[0]));
                return -1;
            }
            if (add_model(&t, trim(f[0]), c0, c1, c2, err, err_size) != 0) {
                return -1;
            }
        }
    }
    if (t.n_models == 0) {
        fail(err, err_size, "models: empty list");
        return -1;
    }
    *c = t;
    for (i = 0; i < c->n_models; ++i) { /* names must point into c, not t */
        c->models[i].name = c->model_name[i];
    }
    return 0;
}

static int choose(const char *v, const char *a, const char *b)
{
    if (strcmp(v, a) == 0) {
        return 0;
    }
    if (strcmp(v, b) == 0) {
        return 1;
    }
    return -1;
}

int hstpfd_config_set(hstpfd_config_t *c, const char *key, const char *value, char *err, size_t err_size)
{
    const key_t_ *k = NULL;
    unsigned i;
    char *base = (char *)c;
    char vbuf[2048];
    const char *v;
    double x;
    uint64_t u;
    int sel;

    for (i = 0; i < N_KEYS; ++i) {
        if (strcmp(keys[i].name, key) == 0) {
            k = &keys[i];
            break;
        }
    }
    if (k == NULL) {
        fail(err, err_size, "unknown key '%s'", key);
        return -1;
    }
    if (strlen(value) >= sizeof vbuf) {
        fail(err, err_size, "%s: value too long", key);
        return -1;
    }
    (void)snprintf(vbuf, sizeof vbuf, "%s", value);
    v = trim(vbuf);
    switch (k->type) {
    case K_NAME:
    case K_PATH: {
        const size_t cap = k->type == K_NAME ? HSTPFD_NAME_MAX : HSTPFD_PATH_MAX;
        if (strlen(v) >= cap) {
            fail(err, err_size, "%s: longer than %u characters", key, (unsigned)(cap - 1));
            return -1;
        }
        if (!printable(v)) {
            fail(err, err_size, "%s: control characters are not allowed", key);
            return -1;
        }
        (void)snprintf(base + k->off, cap, "%s", v);
        return 0;
    }
    case K_U16:
    case K_U32:
    case K_U64:
        if (unum(v, &u) != 0) {
            fail(err, err_size, "%s: '%s' is not a non-negative integer", key, v);
            return -1;
        }
        if (k->type != K_U64 && ((double)u < k->lo || (double)u > k->hi)) {
            fail(err, err_size, "%s: %s is outside [%g, %g]", key, v, k->lo, k->hi);
            return -1;
        }
        if (k->type == K_U16) {
            uint16_t w = (uint16_t)u;
            memcpy(base + k->off, &w, sizeof w);
        } else if (k->type == K_U32) {
            uint32_t w = (uint32_t)u;
            memcpy(base + k->off, &w, sizeof w);
        } else {
            memcpy(base + k->off, &u, sizeof u);
        }
        return 0;
    case K_DBL:
        if (num(v, &x) != 0) {
            fail(err, err_size, "%s: '%s' is not a number", key, v);
            return -1;
        }
        if (x > k->hi || x < k->lo || (k->lo_open && x == k->lo)) {
            fail(err, err_size, "%s: %s is outside %c%g, %g]", key, v, k->lo_open ? '(' : '[', k->lo, k->hi);
            return -1;
        }
        memcpy(base + k->off, &x, sizeof x);
        return 0;
    case K_BOOL:
        if (strcmp(v, "1") == 0 || strcmp(v, "yes") == 0 || strcmp(v, "true") == 0 || strcmp(v, "on") == 0) {
            base[k->off] = 1;
        } else if (strcmp(v, "0") == 0 || strcmp(v, "no") == 0 || strcmp(v, "false") == 0 ||
                   strcmp(v, "off") == 0) {
            base[k->off] = 0;
        } else {
            fail(err, err_size, "%s: '%s' is not a boolean (1/0, yes/no, true/false, on/off)", key, v);
            return -1;
        }
        return 0;
    case K_MODELS:
        return hstpfd_parse_models(c, v, err, err_size);
    case K_NOISE: {
        hstpf_dist_spec_t d;
        if (hstpfd_parse_noise(v, &d, err, err_size) != 0) {
            return -1;
        }
        memcpy(base + k->off, &d, sizeof d);
        return 0;
    }
    case K_PRESET:
        sel = choose(v, "case1", "case2");
        if (sel < 0) {
            fail(err, err_size, "noise: '%s' must be case1 or case2", v);
            return -1;
        }
        preset(c, sel + 1);
        return 0;
    case K_TRACTION:
        sel = choose(v, "mean", "latest");
        if (sel < 0) {
            fail(err, err_size, "traction_mode: '%s' must be mean or latest", v);
            return -1;
        }
        c->sched.traction_mode = sel == 0 ? HSTPFD_TRACTION_MEAN : HSTPFD_TRACTION_LATEST;
        return 0;
    case K_STALE:
        sel = choose(v, "predict", "wait");
        if (sel < 0) {
            fail(err, err_size, "stale_policy: '%s' must be predict or wait", v);
            return -1;
        }
        c->sched.stale_policy = sel == 0 ? HSTPFD_STALE_PREDICT : HSTPFD_STALE_WAIT;
        return 0;
    case K_ENGINE:
        if (strcmp(v, "auto") == 0) {
            c->engine = HSTPF_ENGINE_AUTO;
        } else if (strcmp(v, "particle") == 0) {
            c->engine = HSTPF_ENGINE_PARTICLE;
        } else if (strcmp(v, "kalman") == 0) {
            c->engine = HSTPF_ENGINE_KALMAN;
        } else {
            fail(err, err_size, "engine: '%s' must be auto, particle or kalman", v);
            return -1;
        }
        return 0;
    case K_RXFILTER:
        if (strcmp(v, "inputs") == 0) {
            c->rx_filter = HSTPFD_RX_FILTER_INPUTS;
        } else if (strcmp(v, "block") == 0) {
            c->rx_filter = HSTPFD_RX_FILTER_BLOCK;
        } else if (strcmp(v, "all") == 0) {
            c->rx_filter = HSTPFD_RX_FILTER_ALL;
        } else {
            fail(err, err_size, "rx_filter: '%s' must be inputs, block or all", v);
            return -1;
        }
        return 0;
    case K_FORMAT:
        sel = choose(v, "jsonl", "csv");
        if (sel < 0) {
            fail(err, err_size, "out_format: '%s' must be jsonl or csv", v);
            return -1;
        }
        c->out_format = sel == 0 ? HSTPFD_OUT_JSONL : HSTPFD_OUT_CSV;
        return 0;
    }
    fail(err, err_size, "%s: internal error", key);
    return -1;
}

/* A value in double quotes (as hstpfd_config_write puts values holding '#',
 * ';' or '"'): \" and \\ inside; blanks and a comment may follow. The
 * unquoted text replaces the quoted one in place. Returns 0 or -1. */
static int unquote(char *v, char *err, size_t err_size)
{
    char *r = v + 1, *w = v;
    for (;;) {
        if (*r == '\0') {
            fail(err, err_size, "value without its closing '\"'");
            return -1;
        }
        if (*r == '"') {
            break;
        }
        if (*r == '\\' && (r[1] == '"' || r[1] == '\\')) {
            ++r;
        }
        *w++ = *r++;
    }
    ++r;
    while (*r == ' ' || *r == '\t' || *r == '\r' || *r == '\n') {
        ++r;
    }
    if (*r != '\0' && *r != '#' && *r != ';') {
        fail(err, err_size, "text after the closing '\"'");
        return -1;
    }
    *w = '\0';
    return 0;
}

int hstpfd_config_line(hstpfd_config_t *c, const char *line, char *err, size_t err_size)
{
    char buf[HSTPFD_LINE_MAX];
    char *p, *eq;
    const char *key;
    size_t n = strlen(line);
    if (n >= sizeof buf) {
        fail(err, err_size, "line too long");
        return -1;
    }
    memcpy(buf, line, n + 1);
    p = trim(buf);
    if (*p == '\0' || *p == '#' || *p == ';') {
        return 0;
    }
    if (*p == '[') {
        if (p[strlen(p) - 1] != ']') {
            fail(err, err_size, "section line without ']'");
            return -1;
        }
        return 0;
    }
    eq = strchr(p, '=');
    if (eq == NULL) {
        fail(err, err_size, "expected key = value");
        return -1;
    }
    *eq = '\0';
    key = trim(p);
    if (*key == '\0') {
        fail(err, err_size, "missing key before '='");
        return -1;
    }
    /* an inline comment needs a blank before it: "x = 1  # note" */
    {
        char *v = eq + 1, *h;
        while (*v == ' ' || *v == '\t') {
            ++v;
        }
        if (*v == '"') {
            if (unquote(v, err, err_size) != 0) {
                return -1;
            }
            return hstpfd_config_set(c, key, v, err, err_size);
        }
        for (h = v; *h != '\0'; ++h) {
            if ((*h == '#' || *h == ';') && h > v && (h[-1] == ' ' || h[-1] == '\t')) {
                *h = '\0';
                break;
            }
        }
        return hstpfd_config_set(c, key, v, err, err_size);
    }
}

int hstpfd_config_load(hstpfd_config_t *c, const char *path, char *err, size_t err_size)
{
    FILE *fp = fopen(path, "r");
    char line[HSTPFD_LINE_MAX];
    char e[HSTPFD_ERR_MAX];
    unsigned lineno = 0;
    if (fp == NULL) {
        fail(err, err_size, "%s: %s", path, strerror(errno));
        return -1;
    }
    while (fgets(line, sizeof line, fp) != NULL) {
        ++lineno;
        if (strchr(line, '\n') == NULL && !feof(fp)) {
            fail(err, err_size, "%s:%u: line too long", path, lineno);
            (void)fclose(fp);
            return -1;
        }
        if (hstpfd_config_line(c, line, e, sizeof e) != 0) {
            fail(err, err_size, "%s:%u: %s", path, lineno, e);
            (void)fclose(fp);
            return -1;
        }
    }
    if (ferror(fp)) {
        fail(err, err_size, "%s: read error", path);
        (void)fclose(fp);
        return -1;
    }
    (void)fclose(fp);
    return 0;
}

int hstpfd_config_text(hstpfd_config_t *c, const char *text, char *err, size_t err_size)
{
    char line[HSTPFD_LINE_MAX];
    char e[HSTPFD_ERR_MAX];
    unsigned lineno = 0;
    while (*text != '\0') {
        const char *nl = strchr(text, '\n');
        const size_t n = nl != NULL ? (size_t)(nl - text) : strlen(text);
        ++lineno;
        if (n >= sizeof line) {
            fail(err, err_size, "line %u: line too long", lineno);
            return -1;
        }
        memcpy(line, text, n);
        line[n] = '\0';
        if (hstpfd_config_line(c, line, e, sizeof e) != 0) {
            fail(err, err_size, "line %u: %s", lineno, e);
            return -1;
        }
        text += n + (nl != NULL ? 1u : 0u);
    }
    return 0;
}

int hstpfd_config_finish(hstpfd_config_t *c, char *err, size_t err_size)
{
    hstpf_config_t fc;
    hstpfd_sched_t s;
    int32_t rc;
    static hstpf_t probe; /* about 100 kB: not on the stack */
    if ((c->iface[0] != '\0') == (c->log[0] != '\0')) {
        fail(err, err_size, "give exactly one source: --iface IFACE or --log FILE");
        return -1;
    }
    c->sched.mass_t = c->mass_t;
    c->sched.first_dt_s = c->dt_nominal_s;
    if (hstpfd_sched_init(&s, &c->sched, NULL, NULL) != 0) {
        fail(err, err_size, "scheduling values out of range");
        return -1;
    }
    hstpfd_config_filter(c, &fc);
    rc = hstpf_init(&probe, sizeof probe, &fc);
    if (rc != HSTPF_OK) {
        fail(err, err_size, "the estimator rejects the configuration: %s (%ld)", hstpf_strerror(rc), (long)rc);
        return -1;
    }
    return 0;
}

void hstpfd_config_filter(const hstpfd_config_t *c, hstpf_config_t *fc)
{
    (void)hstpf_config_default(fc);
    fc->models = c->models;
    fc->n_models = c->n_models;
    fc->n_particles = c->particles;
    fc->engine = c->engine;
    fc->seed = c->seed;
    fc->gamma_rot = c->gamma_rot;
    fc->noise_s = c->noise_s;
    fc->noise_v = c->noise_v;
    fc->noise_e = c->noise_e;
    fc->dt_nominal_s = c->dt_nominal_s;
    fc->init_speed_mps = c->init_speed_mps;
    fc->init_speed_sd = c->init_speed_sd;
    fc->roughening_k = c->roughening_k;
    fc->e_blur_sd = c->e_blur_sd;
    fc->declare_threshold = c->declare_threshold;
    fc->declare_hold_s = c->declare_hold_s;
    fc->gate_m = c->gate_m;
}

/* The shortest of %.15g, %.16g, %.17g that reads back as x. */
static const char *g17(double x, char *buf, size_t size)
{
    int p;
    for (p = 15; p <= 17; ++p) {
        (void)snprintf(buf, size, "%.*g", p, x);
        if (strtod(buf, NULL) == x) {
            break;
        }
    }
    return buf;
}

static int noise_text(const hstpf_dist_spec_t *d, char *buf, size_t size)
{
    char a[32], b[32], c[32];
    if (d->kind == HSTPF_DIST_GAMMA) {
        return snprintf(buf, size, "gamma:%s:%s:%s", g17(d->shape, a, sizeof a), g17(d->scale, b, sizeof b),
                        g17(d->loc, c, sizeof c));
    }
    return snprintf(buf, size, "gaussian:%s:%s", g17(d->mean, a, sizeof a), g17(d->sd, b, sizeof b));
}

/* v as it must stand after "key = " to read back as v: in double quotes,
 * with \" and \\, when it holds '#', ';' or '"' (a comment or a quote to
 * hstpfd_config_line). Returns 0, or -1 if it does not fit. */
static int quoted(const char *v, char *out, size_t size)
{
    size_t w = 0;
    if (strpbrk(v, "#;\"") == NULL) {
        if (strlen(v) >= size) {
            return -1;
        }
        memcpy(out, v, strlen(v) + 1);
        return 0;
    }
    if (size < 3) {
        return -1;
    }
    out[w++] = '"';
    for (; *v != '\0'; ++v) {
        if (w + 4 > size) {
            return -1;
        }
        if (*v == '"' || *v == '\\') {
            out[w++] = '\\';
        }
        out[w++] = *v;
    }
    out[w++] = '"';
    out[w] = '\0';
    return 0;
}

int hstpfd_config_write(const hstpfd_config_t *c, char *buf, size_t size)
{
    size_t pos = 0;
    unsigned i;
    int n;
    char tmp[HSTPFD_LINE_MAX];
    char raw[HSTPFD_LINE_MAX / 2];
#define PUT(...)                                                                                             \
    do {                                                                                                     \
        n = snprintf(buf + pos, size - pos, __VA_ARGS__);                                                    \
        if (n < 0 || (size_t)n >= size - pos) {                                                              \
            return -1;                                                                                       \
        }                                                                                                    \
        pos += (size_t)n;                                                                                    \
    } while (0)
    for (i = 0; i < N_KEYS; ++i) {
        const key_t_ *k = &keys[i];
        const char *base = (const char *)c;
        switch (k->type) {
        case K_NAME:
        case K_PATH:
            if (quoted(base + k->off, tmp, sizeof tmp) != 0) {
                return -1;
            }
            PUT("%s = %s\n", k->name, tmp);
            break;
        case K_U16: {
            uint16_t w;
            memcpy(&w, base + k->off, sizeof w);
            PUT("%s = %u\n", k->name, (unsigned)w);
            break;
        }
        case K_U32: {
            uint32_t w;
            memcpy(&w, base + k->off, sizeof w);
            PUT("%s = %lu\n", k->name, (unsigned long)w);
            break;
        }
        case K_U64: {
            uint64_t w;
            memcpy(&w, base + k->off, sizeof w);
            PUT("%s = %llu\n", k->name, (unsigned long long)w);
            break;
        }
        case K_DBL: {
            double x;
            memcpy(&x, base + k->off, sizeof x);
            PUT("%s = %s\n", k->name, g17(x, tmp, sizeof tmp));
            break;
        }
        case K_BOOL:
            PUT("%s = %d\n", k->name, base[k->off] ? 1 : 0);
            break;
        case K_MODELS: {
            uint16_t m;
            size_t r = 0;
            raw[0] = '\0';
            for (m = 0; m < c->n_models; ++m) {
                const hstpf_theta_t *t = &c->models[m];
                const int32_t row = hstpf_train_type_find(c->model_name[m]);
                int q;
                if (row >= 0 && hstpf_train_types[row].c0 == t->c0 && hstpf_train_types[row].c1 == t->c1 &&
                    hstpf_train_types[row].c2 == t->c2) {
                    q = snprintf(raw + r, sizeof raw - r, "%s%s", m ? ", " : "", c->model_name[m]);
                } else {
                    char a[32], b[32], d[32];
                    q = snprintf(raw + r, sizeof raw - r, "%s%s:%s:%s:%s", m ? ", " : "", c->model_name[m],
                                 g17(t->c0, a, sizeof a), g17(t->c1, b, sizeof b), g17(t->c2, d, sizeof d));
                }
                if (q < 0 || (size_t)q >= sizeof raw - r) {
                    return -1;
                }
                r += (size_t)q;
            }
            if (quoted(raw, tmp, sizeof tmp) != 0) {
                return -1;
            }
            PUT("%s = %s\n", k->name, tmp);
            break;
        }
        case K_NOISE:
            (void)noise_text((const hstpf_dist_spec_t *)(const void *)(base + k->off), tmp, sizeof tmp);
            PUT("%s = %s\n", k->name, tmp);
            break;
        case K_PRESET:
            break; /* written as noise_s / noise_v / noise_e */
        case K_TRACTION:
            PUT("%s = %s\n", k->name, c->sched.traction_mode == HSTPFD_TRACTION_MEAN ? "mean" : "latest");
            break;
        case K_STALE:
            PUT("%s = %s\n", k->name, c->sched.stale_policy == HSTPFD_STALE_PREDICT ? "predict" : "wait");
            break;
        case K_ENGINE:
            PUT("%s = %s\n", k->name,
                c->engine == HSTPF_ENGINE_AUTO       ? "auto"
                : c->engine == HSTPF_ENGINE_PARTICLE ? "particle"
                                                     : "kalman");
            break;
        case K_FORMAT:
            PUT("%s = %s\n", k->name, c->out_format == HSTPFD_OUT_JSONL ? "jsonl" : "csv");
            break;
        case K_RXFILTER:
            PUT("%s = %s\n", k->name,
                c->rx_filter == HSTPFD_RX_FILTER_INPUTS ? "inputs"
                : c->rx_filter == HSTPFD_RX_FILTER_BLOCK ? "block"
                                                          : "all");
            break;
        }
    }
#undef PUT
    return (int)pos;
}
