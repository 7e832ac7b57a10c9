/* hstpfd: what the configuration's files share inside port/src (not an
 * API): the key table and the helpers of the parsers. */
#ifndef HSTPFD_CONFIG_INTERNAL_H
#define HSTPFD_CONFIG_INTERNAL_H

#include <stddef.h>

#include "config.h"

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
} hstpfd__ktype_t;

#define HSTPFD_LO_OPEN 1
#define HSTPFD_HI_OPEN 2

typedef struct {
    const char *name;
    hstpfd__ktype_t type;
    size_t off;
    double lo, hi;
    int open; /* HSTPFD_LO_OPEN: lo excluded; HSTPFD_HI_OPEN: hi excluded */
    const char *help;
} hstpfd__key_t;

/* Every key, in the order --help and --print-config list them (config_keys.c). */
extern const hstpfd__key_t hstpfd__keys[];
extern const size_t hstpfd__n_keys;

/* A message in err (if err is not NULL and size > 0), printf-style. The
 * format is checked at every caller (and clang's -Wformat-nonliteral is
 * satisfied by the attribute). */
#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
void hstpfd__fail(char *err, size_t size, const char *fmt, ...);

/* Blanks (and a line end) off both ends of s, in place; returns the start. */
char *hstpfd__trim(char *s);

/* Noise specs: Gaussian, Gamma, and the paper's presets (cas 1 or 2). */
void hstpfd__gaussian(hstpf_dist_spec_t *d, double mean, double sd);
void hstpfd__gamma(hstpf_dist_spec_t *d, double shape, double scale, double loc);
void hstpfd__preset(hstpfd_config_t *c, int cas);

#endif
