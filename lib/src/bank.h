/* What the bank's files (bank.c, lock.c, declare.c, estimate.c) share:
 * the hypotheses' weights and the calls between them. Library-internal. */
#ifndef HSTPF_BANK_H
#define HSTPF_BANK_H

#include <math.h>

#include "engine.h"
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

/* weights.c: Eq. 14 with the floor; the consist changed with
 * probability p; 2 at a standstill, 1 arriving (the weights wait), else 0,
 * its clock run on fixes; every weighted hypothesis beyond its floor. */
void hstpf__update_model_weights(hstpf_t *f);
void hstpf__consist_mix(hstpf_t *f, double p);
int hstpf__weights_hold(hstpf_t *f, double dt, int has_y);
int hstpf__all_lost(const hstpf_t *f);

/* traction_unknown.c: xi u for an acquisition whose traction is unknown
 * (v < 0: each model's own speed); how long an unknown acceleration
 * persists, max(dt_nominal_s, HSTPF__ACC_PERSIST_S); its variance on the
 * speed over a step of dt (the span without a fix kept in f->free_s). */
double hstpf__free_xu(const hstpf_t *f, double v);
double hstpf__acc_tau(const hstpf_t *f);
double hstpf__free_acc_var(hstpf_t *f, double dt, int has_y);

/* lock.c */
int hstpf__acquire(hstpf_t *f, double y, double xu);
void hstpf__drop_lock(hstpf_t *f, int keep_pend);
int hstpf__ran_backwards(hstpf_t *f, double s_m, double y_m);
void hstpf__probation(hstpf_t *f, double s_m, double y_m);
void hstpf__rebase(hstpf_t *f, double rel);
void hstpf__models_reacquire(hstpf_t *f, real yr);
void hstpf__nonfinite_reset(hstpf_t *f);

/* fix_step.c: whether fix y (absolute m) at the end of a step of dt is
 * not used (1): farther than gate_m from the blend's prediction, or held
 * as a possible step in the fixes' reference (cfg.fix_step); 0: used (the
 * origin moved first when it completes a step). */
int hstpf__fix_gate(hstpf_t *f, double y, double dt);
/* The step rule's run of predictions, from an origin moved by +d (rebase). */
void hstpf__fix_step_shift(hstpf_t *f, hstpf_real_t d);

/* declare.c */
void hstpf__update_declaration(hstpf_t *f, double dt, int evidence);
uint8_t hstpf__off_what(const hstpf_t *f);

/* traction_check.c: a CUSUM over per-step log-likelihood ratios, each
 * clipped to +-HSTPF__TRAC_CLIP nats, raises the fault at
 * HSTPF__TRAC_NATS: with a true traction it reached 14.6 nats at most in
 * 340 runs of `day` (4.9 M steps; hstpf-mc) */
#define HSTPF__TRAC_CLIP 3.0
#define HSTPF__TRAC_CLIP_HELD 1.0 /* at a standstill (see bank.c) */
#define HSTPF__TRAC_NATS 25.0
/* past this the traction is in doubt: the weights wait (traction_check.c);
 * with a true traction few runs pass it (day, 850 runs: 12 declarations
 * moved, 7 later, 5 sooner, median and p90 unchanged) */
#define HSTPF__TRAC_DOUBT 10.0
#define HSTPF__TRAC_SETTLE 3 /* fixes a newly placed shadow does not test */
/* A held bank released (traction_check.c): the CUSUM of the fixes' lead
 * over the held position in fix-noise sd, each less HSTPF__RELEASE_K,
 * past HSTPF__RELEASE_H (a departure at 0.5 m/s^2 with Case 1's 2.24 m
 * fixes: about 7 s); released, HSTPF__RELEASE_STILL fixes in a row with
 * the leading row's speed within 1 sd or HSTPF__RELEASE_STOP of 0 end it */
#define HSTPF__RELEASE_K 0.5
#define HSTPF__RELEASE_H 15.0
#define HSTPF__RELEASE_CLIP 5.0 /* each fix adds at most this many sd */
#define HSTPF__RELEASE_STOP 0.1 /* m/s */
#define HSTPF__RELEASE_STILL 10
/* How many parts a step of dt is predicted in (bank.c): 1 up to 1.5
 * dt_nominal_s, else ceil(dt / dt_nominal_s), at most HSTPF_SUBSTEPS_MAX. */
uint32_t hstpf__substeps(const hstpf_t *f, double dt);
/* One of those n parts of st, without its fix. */
hstpf__step_t hstpf__step_part(const hstpf_t *f, const hstpf__step_t *st, uint32_t n);
void hstpf__trac_check_reset(hstpf_t *f);
/* The weights a raised fault goes back to: taken while the traction fits,
 * and wherever the weights are set anew (init, reset, a consist change). */
void hstpf__trac_check_snapshot(hstpf_t *f);
/* Before the bank steps: whether the fault stands this step (it ends
 * HSTPF_TRAC_RETRY_S after it was raised), and the shadow placed if it has
 * none. */
void hstpf__trac_check_begin(hstpf_t *f, int traction_known, double xu, double dt);
/* After the bank stepped, before its weights move: the shadow steps on st
 * (the bank's step) without the traction; with test, and a fix, the CUSUM
 * takes this fix. */
void hstpf__trac_check_end(hstpf_t *f, const hstpf__step_t *st, int test, int standstill);
/* The origin moved by +d. */
void hstpf__trac_check_shift(hstpf_t *f, double d);

/* estimate.c */
void hstpf__blend_weights(const hstpf_t *f, double *wb);
/* The blend's position dt_ahead on (s + T v of each hypothesis, relative
 * to the origin); var, if not NULL, a bound on its variance: each
 * hypothesis' 2 (pss + T^2 pvv), which (sd_s + T sd_v)^2 never exceeds,
 * and the spread between them; speed, if not NULL, the blend's speed. */
double hstpf__blended_position(const hstpf_t *f, double dt_ahead, double *var, double *speed);
/* The bank's predictive log-likelihood of this step's fix: the weighted
 * hypotheses' increments mixed by the weights before the step's update. */
double hstpf__bank_loglik(const hstpf_t *f);

#endif
