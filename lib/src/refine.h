/* The continuous-theta hypothesis (refine.c). */
#ifndef HSTPF_REFINE_H
#define HSTPF_REFINE_H

#include "engine.h"

/* Places the hypothesis' theta and k from the prior, (s, v) at 0 with no
 * spread: hstpf__refine_replace_sv places them. */
void hstpf__refine_place(hstpf_t *f);

/* Places (s, v) again, keeping what was learnt of theta and k. */
void hstpf__refine_replace_sv(hstpf_t *f, double s, double v, double pss, double psv, double pvv);
/* Theta's moments when the consist changed at a stop with probability p
 * (p = 1: Table 1's prior again). */
void hstpf__refine_consist(hstpf_t *f, double p);

/* One predict/update step; sets rf.loglik, rf.held, rf.nis. */
void hstpf__refine_update(hstpf_t *f, const hstpf__step_t *st);

/* Both process noises Gaussian: the rows' Kalman filters on the noise's
 * moments are a fair yardstick for the hypothesis on the grid engine. */
static inline int hstpf__process_gaussian(const hstpf_config_t *c)
{
    return c->noise_s.kind == HSTPF_DIST_GAUSSIAN && c->noise_v.kind == HSTPF_DIST_GAUSSIAN;
}

/* On the grid engine the hypothesis is also one more grid model,
 * f->m[n_models], run at the EKF's theta of the step before, which scores
 * it under the real noise (refine.c): with refine = 2, and with refine = 1
 * under non-Gaussian process noise, where the yardstick fails. */
static inline int hstpf__refine_grid_cfg(const hstpf_config_t *c)
{
    return c->refine_prior_q > 0.0 && (c->refine == 2u || (c->refine == 1u && !hstpf__process_gaussian(c)));
}
static inline int hstpf__refine_on_grid(const hstpf_t *f)
{
    return f->engine == (uint8_t)HSTPF_ENGINE_GRID && hstpf__refine_grid_cfg(&f->cfg);
}

/* Otherwise, on an engine whose likelihoods are not Kalman filters' (the
 * grid's), the rows also run as Kalman filters on the noise's moments: the
 * yardstick the hypothesis is scored with (refine.c). */
static inline int hstpf__refine_yardstick(const hstpf_t *f)
{
    return f->rf.active && f->engine != (uint8_t)HSTPF_ENGINE_KALMAN && !hstpf__refine_on_grid(f);
}

/* The hypothesis' grid model: its resistance from the EKF's
 * theta (each coefficient >= 0). */
void hstpf__refine_grid_theta(hstpf_t *f);

/* The sd of the speed change over the step st that theta's uncertainty
 * adds, for that grid to spread by. */
double hstpf__refine_theta_sd(const hstpf_t *f, const hstpf__step_t *st);

/* With the hypothesis on a grid, after the engine's step and
 * hstpf__refine_update: the hypothesis is scored by its grid (its
 * likelihood, floor and rest), not by the EKF. */
void hstpf__refine_from_grid(hstpf_t *f, const hstpf__step_t *st);

/* The hypothesis' (s, v) mean and variances as published: its grid
 * model's when it has one (hstpf__refine_on_grid), else the EKF's. */
void hstpf__refine_sv(const hstpf_t *f, double *s, double *v, double *pss, double *pvv);

/* After the engine's step (which stepped the rows' yardstick filters) and
 * hstpf__refine_update: the hypothesis' increment becomes the leading
 * row's own plus the log ratio of the hypothesis to that row in the
 * yardstick. */
void hstpf__refine_anchor(hstpf_t *f, const hstpf__step_t *st);

/* The posterior mean of (c0, c1, c2), each >= 0, and its covariance. */
void hstpf__refine_theta(const hstpf_t *f, double *th, double *cov);

#endif
