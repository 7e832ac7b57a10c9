/* hstpfd: one key set from text (hstpfd_config_set) and the value parsers:
 * numbers, noise specs, model lists. */
#include "config_internal.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
    /* decimal ("0100" is 100, not octal 64), or hex with 0x (a seed) */
    x = strtoull(text, &end, text[0] == '0' && (text[1] == 'x' || text[1] == 'X') ? 16 : 10);
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
        hstpfd__fail(err, err_size, "noise '%s': too long", text);
        return -1;
    }
    (void)snprintf(buf, sizeof buf, "%s", text);
    n = split(buf, ':', f, 5);
    if (n < 0) {
        hstpfd__fail(err, err_size, "noise '%s': too many fields", text);
        return -1;
    }
    for (i = 0; i < n; ++i) {
        f[i] = hstpfd__trim(f[i]);
    }
    kind = f[0];
    if (strcmp(kind, "gaussian") == 0) {
        if (n != 3 || num(f[1], &a) != 0 || num(f[2], &b) != 0) {
            hstpfd__fail(err, err_size, "noise '%s': expected gaussian:mean:sd", text);
            return -1;
        }
        if (!(b > 0.0)) {
            hstpfd__fail(err, err_size, "noise '%s': sd must be > 0", text);
            return -1;
        }
        hstpfd__gaussian(spec, a, b);
        return 0;
    }
    if (strcmp(kind, "gamma") == 0) {
        if ((n != 3 && n != 4) || num(f[1], &a) != 0 || num(f[2], &b) != 0 || (n == 4 && num(f[3], &l) != 0)) {
            hstpfd__fail(err, err_size, "noise '%s': expected gamma:shape:scale:loc", text);
            return -1;
        }
        if (!(a >= 1e-3 && a <= 1e4) || !(b > 0.0)) {
            hstpfd__fail(err, err_size, "noise '%s': shape must be in [0.001, 10000] and scale > 0", text);
            return -1;
        }
        hstpfd__gamma(spec, a, b, l);
        return 0;
    }
    hstpfd__fail(err, err_size, "noise '%s': kind must be gaussian or gamma", text);
    return -1;
}

static int add_model(hstpfd_config_t *c, const char *name, double c0, double c1, double c2, char *err,
                     size_t err_size)
{
    uint16_t i;
    if (c->n_models >= HSTPF_MAX_MODELS) {
        hstpfd__fail(err, err_size, "models: more than %d", HSTPF_MAX_MODELS);
        return -1;
    }
    if (strlen(name) >= HSTPFD_NAME_MAX || name[0] == '\0' || !printable(name)) {
        hstpfd__fail(err, err_size, "models: name '%s' empty, longer than %d or with control characters", name,
                     HSTPFD_NAME_MAX - 1);
        return -1;
    }
    for (i = 0; i < c->n_models; ++i) {
        if (strcmp(c->model_name[i], name) == 0) {
            hstpfd__fail(err, err_size, "models: '%s' given twice", name);
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
        hstpfd__fail(err, err_size, "models: list too long");
        return -1;
    }
    (void)snprintf(buf, sizeof buf, "%s", text);
    n = split(buf, ',', item, 64);
    if (n < 0) {
        hstpfd__fail(err, err_size, "models: too many entries");
        return -1;
    }
    t.n_models = 0;
    for (i = 0; i < n; ++i) {
        char *f[5];
        int nf, k;
        char *name = hstpfd__trim(item[i]);
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
                hstpfd__fail(err, err_size, "models: '%s' is not a Table 1 name (see --list-types) nor name:c0:c1:c2",
                             name);
                return -1;
            }
            r = &hstpf_train_types[row];
            if (add_model(&t, r->name, r->c0, r->c1, r->c2, err, err_size) != 0) {
                return -1;
            }
            continue;
        }
        {
            double c0, c1, c2;
            char whole[96]; /* the entry as given, for the message: split() cuts it up */
            (void)snprintf(whole, sizeof whole, "%s", name);
            nf = split(name, ':', f, 5);
            if (nf != 4 || num(hstpfd__trim(f[1]), &c0) != 0 || num(hstpfd__trim(f[2]), &c1) != 0 ||
                num(hstpfd__trim(f[3]), &c2) != 0) {
                hstpfd__fail(err, err_size, "models: custom entry '%s' must be name:c0:c1:c2", whole);
                return -1;
            }
            if (!(c0 >= 0.0 && c0 <= HSTPF_C0_MAX) || !(c1 >= 0.0 && c1 <= HSTPF_C1_MAX) ||
                !(c2 >= 0.0 && c2 <= HSTPF_C2_MAX)) {
                hstpfd__fail(err, err_size, "models: '%s': need c0 in [0,%g], c1 in [0,%g], c2 in [0,%g]",
                             hstpfd__trim(f[0]), HSTPF_C0_MAX, HSTPF_C1_MAX, HSTPF_C2_MAX);
                return -1;
            }
            if (hstpf_train_type_find(hstpfd__trim(f[0])) >= 0) {
                /* a custom row under a Table 1 name: the summary said "declared CRH3" of a row at
                 * (0, 0, 0) while the bus carried 254, custom (a review) */
                hstpfd__fail(err, err_size, "models: custom entry '%s' takes a Table 1 name: give the row by its "
                             "name alone, or the custom one another name", whole);
                return -1;
            }
            if (add_model(&t, hstpfd__trim(f[0]), c0, c1, c2, err, err_size) != 0) {
                return -1;
            }
        }
    }
    if (t.n_models == 0) {
        hstpfd__fail(err, err_size, "models: empty list");
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
    const hstpfd__key_t *k = NULL;
    unsigned i;
    char *base = (char *)c;
    char vbuf[2048];
    const char *v;
    double x;
    uint64_t u;
    int sel;

    for (i = 0; i < hstpfd__n_keys; ++i) {
        if (strcmp(hstpfd__keys[i].name, key) == 0) {
            k = &hstpfd__keys[i];
            break;
        }
    }
    if (k == NULL) {
        hstpfd__fail(err, err_size, "unknown key '%s'", key);
        return -1;
    }
    if (strlen(value) >= sizeof vbuf) {
        hstpfd__fail(err, err_size, "%s: value too long", key);
        return -1;
    }
    (void)snprintf(vbuf, sizeof vbuf, "%s", value);
    v = hstpfd__trim(vbuf);
    switch (k->type) {
    case K_NAME:
    case K_PATH: {
        const size_t cap = k->type == K_NAME ? HSTPFD_NAME_MAX : HSTPFD_PATH_MAX;
        if (strlen(v) >= cap) {
            hstpfd__fail(err, err_size, "%s: longer than %u characters", key, (unsigned)(cap - 1));
            return -1;
        }
        if (!printable(v)) {
            hstpfd__fail(err, err_size, "%s: control characters are not allowed", key);
            return -1;
        }
        (void)snprintf(base + k->off, cap, "%s", v);
        return 0;
    }
    case K_U16:
    case K_U32:
    case K_U64:
        if (unum(v, &u) != 0) {
            hstpfd__fail(err, err_size, "%s: '%s' is not a non-negative integer", key, v);
            return -1;
        }
        if (k->type != K_U64 && ((double)u < k->lo || (double)u > k->hi)) {
            hstpfd__fail(err, err_size, "%s: %s is outside [%g, %g]", key, v, k->lo, k->hi);
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
            hstpfd__fail(err, err_size, "%s: '%s' is not a number", key, v);
            return -1;
        }
        if (x > k->hi || x < k->lo || ((k->open & HSTPFD_LO_OPEN) && x == k->lo) ||
            ((k->open & HSTPFD_HI_OPEN) && x == k->hi)) {
            hstpfd__fail(err, err_size, "%s: %s is outside %c%g, %g%c", key, v, (k->open & HSTPFD_LO_OPEN) ? '(' : '[',
                         k->lo, k->hi, (k->open & HSTPFD_HI_OPEN) ? ')' : ']');
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
            hstpfd__fail(err, err_size, "%s: '%s' is not a boolean (1/0, yes/no, true/false, on/off)", key, v);
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
            hstpfd__fail(err, err_size, "noise: '%s' must be case1 or case2", v);
            return -1;
        }
        hstpfd__preset(c, sel + 1);
        return 0;
    case K_TRACTION:
        sel = choose(v, "mean", "latest");
        if (sel < 0) {
            hstpfd__fail(err, err_size, "traction_mode: '%s' must be mean or latest", v);
            return -1;
        }
        c->sched.traction_mode = sel == 0 ? HSTPFD_TRACTION_MEAN : HSTPFD_TRACTION_LATEST;
        return 0;
    case K_STALE:
        sel = choose(v, "predict", "wait");
        if (sel < 0) {
            hstpfd__fail(err, err_size, "stale_policy: '%s' must be predict or wait", v);
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
        } else if (strcmp(v, "grid") == 0) {
            c->engine = HSTPF_ENGINE_GRID;
        } else {
            hstpfd__fail(err, err_size, "engine: '%s' must be auto, particle, kalman or grid", v);
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
            hstpfd__fail(err, err_size, "rx_filter: '%s' must be inputs, block or all", v);
            return -1;
        }
        return 0;
    case K_FORMAT:
        sel = choose(v, "jsonl", "csv");
        if (sel < 0) {
            hstpfd__fail(err, err_size, "out_format: '%s' must be jsonl or csv", v);
            return -1;
        }
        c->out_format = sel == 0 ? HSTPFD_OUT_JSONL : HSTPFD_OUT_CSV;
        return 0;
    }
    hstpfd__fail(err, err_size, "%s: internal error", key);
    return -1;
}
