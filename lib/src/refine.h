/* The continuous-theta hypothesis (refine.c). */
#ifndef HSTPF_REFINE_H
#define HSTPF_REFINE_H

#include "engine.h"

/* Places the hypothesis: (s, v) with the given covariance, theta and k
 * from the prior. */
void hstpf__refine_place(hstpf_t *f, double s, double v, double pss, double psv, double pvv);

/* Places (s, v) again, keeping what was learnt of theta and k. */
void hstpf__refine_replace_sv(hstpf_t *f, double s, double v, double pss, double psv, double pvv);

/* One predict/update step; sets rf.loglik, rf.held, rf.nis. */
void hstpf__refine_update(hstpf_t *f, const hstpf__step_t *st);

/* The posterior mean of (c0, c1, c2), each >= 0, and its covariance. */
void hstpf__refine_theta(const hstpf_t *f, double *th, double *cov);

#endif
