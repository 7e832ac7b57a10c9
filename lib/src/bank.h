/* What the bank's files (bank.c, lock.c, declare.c, estimate.c) share:
 * the hypotheses' weights and the calls between them. Library-internal. */
#ifndef HSTPF_BANK_H
#define HSTPF_BANK_H

#include <math.h>

#include "internal.h"

typedef hstpf_real_t real;

static inline int hstpf__fin(double x)
{
    return isfinite(x) ? 1 : 0;
}

/* log q of hypothesis i: the rows, then the continuous one. */
static inline double *hstpf__logq_of(hstpf_t *f, uint16_t i)
{
    return i < f->cfg.n_models ? &f->m[i].logq : &f->rf.logq;
}

/* The rows, and the continuous hypothesis when it is on. */
static inline uint16_t hstpf__n_hyp(const hstpf_t *f)
{
    return (uint16_t)(f->cfg.n_models + f->rf.active);
}

/* lock.c */
int hstpf__acquire(hstpf_t *f, double y, double xu);
void hstpf__drop_lock(hstpf_t *f, int keep_pend);
int hstpf__ran_backwards(hstpf_t *f, double s_m, double y_m);
void hstpf__probation(hstpf_t *f, double s_m, double y_m);
void hstpf__rebase(hstpf_t *f, double rel);
void hstpf__models_reacquire(hstpf_t *f, real yr);
void hstpf__nonfinite_reset(hstpf_t *f);

/* declare.c */
void hstpf__update_declaration(hstpf_t *f, double dt, int evidence);
uint8_t hstpf__off_what(const hstpf_t *f);

/* estimate.c */
void hstpf__blend_weights(const hstpf_t *f, double *wb);
double hstpf__blended_position(const hstpf_t *f, double dt_ahead);

#endif
