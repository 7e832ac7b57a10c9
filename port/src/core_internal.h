/* hstpfd: what the core's files share inside port/src (not an API): the
 * estimate frames, the step stream and the text writers the outputs use. */
#ifndef HSTPFD_CORE_INTERNAL_H
#define HSTPFD_CORE_INTERNAL_H

#include <stdio.h>

#include "core.h"

/* The library fills position_sd_m / speed_sd_mps (with its lock API). */
#define LIB_HAS_SD HSTPFD_LIB_LOCK_API

/* ---- names (core_text.c) ---- */
extern const char *const hstpfd__err_names[11]; /* [-code], code -1..-10; [0] "other" */
extern const char *const hstpfd__class_names[HSTPFD_ERR_N_CLASSES];
const char *hstpfd__status_name(hstpf_status_t s);
/* hstpf_fit_t in the stream and the summary: "unknown", "table", "none". */
const char *hstpfd__fit_name(hstpf_fit_t fit);

/* ---- JSON / CSV values (core_text.c) ---- */
void hstpfd__json_str(FILE *fp, const char *s);
void hstpfd__json_num(FILE *fp, double x);  /* %.9g, null if not finite */
void hstpfd__json_time(FILE *fp, int64_t t_us); /* seconds with 6 decimals */
void hstpfd__csv_str(FILE *fp, const char *s);
/* A number of the step stream: %.*g, or, if it is not finite, JSON null /
 * an empty CSV cell. */
void hstpfd__out_num(FILE *fp, int csv, double x, int prec);

/* ---- estimate frames (core_tx.c) ---- */
/* Every number published as valid is finite and within range, with lock. */
int hstpfd__est_valid(const hstpfd_core_t *c);
/* Encodes output frame i from c->est, logs and sends it. */
void hstpfd__transmit(hstpfd_core_t *c, unsigned i);
/* Sends the periodic outputs that are due at c->t_now. */
void hstpfd__tx_service(hstpfd_core_t *c);
/* The timeline time at which the latest step's EstState falls due (its
 * cycle since the last one has passed), -1 when none is pending. */
int64_t hstpfd__state_due(const hstpfd_core_t *c);
/* The latest step's EstState and EstQuality, when pending and due. */
void hstpfd__state_service(hstpfd_core_t *c);

/* ---- the per-step stream (core_stream.c) ---- */
/* The CSV header line (out_format csv). */
void hstpfd__stream_header(FILE *out, const hstpfd_config_t *cfg);
/* One step's line (JSON or CSV); nothing if c->out is NULL. */
void hstpfd__write_step(hstpfd_core_t *c, const hstpfd_step_t *st, int32_t rc);

#endif
