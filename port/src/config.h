/* hstpfd: configuration. A file of "key = value" lines (# or ; starts a
 * comment, [section] lines are allowed and ignored; a value may be given in
 * double quotes, with \" and \\ inside, to hold '#' or ';') and command-line
 * overrides "--key value" or "--set key=value"; later settings win.
 * Every key, its default and its range: docs/daemon.md. Portable C99
 * (stdio for the file), no heap. */
#ifndef HSTPFD_CONFIG_H
#define HSTPFD_CONFIG_H

#include <stddef.h>
#include <stdint.h>

#include "hstpf/hstpf.h"
#include "sched.h"

#define HSTPFD_NAME_MAX 32
#define HSTPFD_PATH_MAX 512
#define HSTPFD_ERR_MAX 256
/* Longest config line: the longest model list, quoted (17 x 31-character
 * names with every character escaped and three 24-character numbers). */
#define HSTPFD_LINE_MAX 4096

typedef enum { HSTPFD_OUT_JSONL = 0, HSTPFD_OUT_CSV = 1 } hstpfd_out_format_t;
typedef enum {
    HSTPFD_RX_FILTER_INPUTS = 0, /* kernel passes only the input IDs */
    HSTPFD_RX_FILTER_BLOCK = 1,  /* the input block 0x100-0x1FF (unknown IDs there are counted) */
    HSTPFD_RX_FILTER_ALL = 2     /* everything */
} hstpfd_rx_filter_t;

typedef struct {
    /* source: exactly one of iface / log */
    char iface[HSTPFD_NAME_MAX];
    char log[HSTPFD_PATH_MAX];
    /* models and filter */
    char model_name[HSTPF_MAX_MODELS][HSTPFD_NAME_MAX];
    hstpf_theta_t models[HSTPF_MAX_MODELS]; /* names point into model_name */
    uint16_t n_models;
    uint16_t particles;
    hstpf_engine_t engine;
    uint64_t seed;
    double gamma_rot;
    hstpf_dist_spec_t noise_s, noise_v, noise_e;
    double dt_nominal_s;
    double init_speed_mps, init_speed_sd;
    double roughening_k, e_blur_sd;
    uint8_t grid_speed_lattice;
    uint16_t refine; /* hstpf_config_t.refine */
    uint16_t grid_rows; /* hstpf_config_t.grid_rows */
    double declare_threshold, declare_hold_s;
    double gate_m;
    double accel_unknown_sd; /* hstpf_config_t's: the acceleration's sd while the traction is stale */
    uint8_t traction_check;  /* hstpf_config_t's */
    uint8_t fix_step;        /* hstpf_config_t's */
    double consist_change_p; /* hstpf_config_t's */
    /* train and inputs */
    double mass_t;
    hstpfd_sched_config_t sched; /* mass_t and first_dt_s filled at the end */
    uint32_t e2e_max_delta;
    double time_scale;
    double tick_s;
    /* bus */
    hstpfd_rx_filter_t rx_filter;
    uint8_t send;
    double reopen_s;
    /* outputs */
    char out[HSTPFD_PATH_MAX];
    hstpfd_out_format_t out_format;
    char summary[HSTPFD_PATH_MAX];
    char frames_out[HSTPFD_PATH_MAX];
    uint8_t frames_out_inputs; /* also log every received frame */
} hstpfd_config_t;

/* Defaults (all 17 Table 1 types, paper Case 1 noise, ...). */
void hstpfd_config_default(hstpfd_config_t *c);

/* Sets one key from text. Returns 0, or -1 with a message in err. */
int hstpfd_config_set(hstpfd_config_t *c, const char *key, const char *value, char *err, size_t err_size);

/* Applies a file's lines in order. Returns 0, or -1 with "file:line: ..." in err. */
int hstpfd_config_load(hstpfd_config_t *c, const char *path, char *err, size_t err_size);

/* Applies one line of a config file (no trailing newline needed).
 * Returns 0 (also for blank, comment and section lines) or -1. */
int hstpfd_config_line(hstpfd_config_t *c, const char *line, char *err, size_t err_size);

/* Applies the lines of text (e.g. hstpfd_config_write's output) in order.
 * Returns 0, or -1 with "line N: ..." in err. */
int hstpfd_config_text(hstpfd_config_t *c, const char *text, char *err, size_t err_size);

/* Cross-checks (a source given, ...) and fills the derived fields.
 * Returns 0 or -1 with a message. */
int hstpfd_config_finish(hstpfd_config_t *c, char *err, size_t err_size);

/* The library configuration for c (models point into c). */
void hstpfd_config_filter(const hstpfd_config_t *c, hstpf_config_t *fc);

/* Number of keys and the name / help of key i (for --help). */
unsigned hstpfd_config_n_keys(void);
const char *hstpfd_config_key_name(unsigned i);
const char *hstpfd_config_key_help(unsigned i);

/* Writes the effective configuration as a config file (what --print-config
 * prints): values holding '#', ';' or '"' in double quotes with \" and \\,
 * so that hstpfd_config_text() reads back the same configuration.
 * Returns the length, or -1 if it does not fit in size. */
int hstpfd_config_write(const hstpfd_config_t *c, char *buf, size_t size);

/* "gaussian:mean:sd" / "gamma:shape:scale:loc" into spec; 0 or -1. */
int hstpfd_parse_noise(const char *text, hstpf_dist_spec_t *spec, char *err, size_t err_size);
/* "CRH3, SS8, name:c0:c1:c2, all" into the model table of c; 0 or -1. */
int hstpfd_parse_models(hstpfd_config_t *c, const char *text, char *err, size_t err_size);

#endif
