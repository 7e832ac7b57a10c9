/* hstpfd: the effective configuration written as a config file
 * (--print-config) that reads back to the same configuration. */
#include "config_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
    for (i = 0; i < hstpfd__n_keys; ++i) {
        const hstpfd__key_t *k = &hstpfd__keys[i];
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
                : c->engine == HSTPF_ENGINE_GRID     ? "grid"
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
