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

/* On an engine whose likelihoods are not Kalman filters' (the grid's), the
 * rows also run as Kalman filters on the noise's moments: the yardstick
 * the hypothesis is scored with (refine.c). */
static inline int hstpf__refine_yardstick(const hstpf_t *f)
{
    return f->rf.active && f->engine != (uint8_t)HSTPF_ENGINE_KALMAN;
}

/* The yardstick's step, after the engine's and hstpf__refine_update: the
 * hypothesis' increment becomes the leading row's own plus the log ratio
 * of the hypothesis to that row in the yardstick. */
void hstpf__refine_anchor(hstpf_t *f, const hstpf__step_t *st);

/* The posterior mean of (c0, c1, c2), each >= 0, and its covariance. */
void hstpf__refine_theta(const hstpf_t *f, double *th, double *cov);

#endif
