/* The one internal interface every estimation engine implements. The bank
 * (bank.c, weights.c) owns the model weights, the declaration and the
 * blend; an engine owns how each model's state and likelihood are
 * computed. The engine of an instance is chosen once, in
 * hstpf__engine_select(). */
#ifndef HSTPF_ENGINE_H
#define HSTPF_ENGINE_H

#include "hstpf/hstpf.h"

/* One step's inputs, in the engines' units. */
typedef struct {
    double dt;        /* step length, s */
    double xu;        /* xi * traction, m/s^2 */
    double yr;        /* measured position relative to the origin, m */
    double scale;     /* noise scale sqrt(dt / dt_nominal) */
    int has_y;        /* a measurement this step */
    int free_run;     /* the traction is unknown: each model's xu is its own balance (hstpf__step_xu) */
    double acc_var;   /* and the speed's variance this step from the unknown acceleration, (m/s)^2 (0 if known) */
} hstpf__step_t;

/* An acquisition: the fixes a model's state is placed from. With t12 > 0,
 * y1 was measured t12 seconds before y2 and the speed prior is diffuse: the
 * state at y2's time follows from both fixes and the model's dynamics over
 * t12 (traction xu). With t12 == 0, y2 alone with the configured speed
 * prior N(v0, init_speed_sd). */
typedef struct {
    double y1, y2;    /* relative to the origin, m */
    double t12;       /* s, >= 0 */
    double xu;        /* xi * traction over t12, m/s^2 */
    double v0;        /* prior speed mean (t12 == 0), m/s */
} hstpf__acq_t;

/*
 * Standstill physics, which every engine implements (docs/model.md):
 * - the speed is never below 0: braking and resistance bring a train to
 *   rest and no further; a step whose deterministic speed would cross 0
 *   ends at rest, v' = 0 exactly;
 * - a state at rest (v == 0) whose net acceleration xu - k0 - g <= 0 is
 *   held: s' = s, v' = 0, no process noise;
 * - m->held = 1 when the model's whole posterior ends the step at rest
 *   (held, or come to rest within it): then neither s' = s + T v nor
 *   v' = 0 involves W, and the step carries no evidence about it; 2
 *   (HSTPF__HELD_STOPPING) when it may have come to rest: a fix then
 *   scores "has it stopped yet" (the bank's arrival rule, bank.c).
 */
typedef struct {
    /* Every model placed from the acquisition fixes. */
    void (*place_all)(hstpf_t *f, const hstpf__acq_t *a);
    /* One model placed again (it lost the train). */
    void (*place_one)(hstpf_t *f, hstpf_model_t *m, const hstpf__acq_t *a);
    /* Predict and (with a measurement) update every model: sets each
     * model's loglik, s_mean, v_mean, s_var, v_var, held, ess and floor
     * counters. */
    void (*predict_update)(hstpf_t *f, const hstpf__step_t *st);
    /* After the model weights were updated (the paired bank resamples here);
     * NULL when the engine has nothing to do. */
    void (*after_weights)(hstpf_t *f, const hstpf__step_t *st);
    /* Positions move by -d: the origin moved by +d. */
    void (*shift)(hstpf_t *f, hstpf_real_t d);
    /* Positions spread by a zero-mean Gaussian of variance var (m^2): the
     * reference stepped by an offset known to that (fix_step.c). NULL when
     * the engine's states are the Gaussian filters fix_step.c widens. */
    void (*spread)(hstpf_t *f, double var);
    /* Bytes of workspace a validated configuration needs (0: none). */
    size_t (*ws_bytes)(const hstpf_config_t *c);
    /* Points the instance's arrays into ws (ws_bytes long, aligned). */
    void (*attach)(hstpf_t *f, void *ws);
} hstpf__engine_t;

extern const hstpf__engine_t hstpf__engine_particle;
extern const hstpf__engine_t hstpf__engine_kalman;
extern const hstpf__engine_t hstpf__engine_grid;

/* The Kalman engine's filter of one row on (s, v), m->kx and m->kp only,
 * with the noise moments f->noise_mom. The grid engine runs it beside its
 * cells as the continuous hypothesis' yardstick (refine.c). */
/* xi u for model m this step: st->xu, or with the traction unknown what
 * balances the model's own resistance and the track's force at its mean
 * (s, v), plus a hair: its acceleration is then 0 in the mean and nothing
 * holds it at rest (hstpf.h's traction_unknown). The largest resistance
 * among the models, the balance before, sped every other model up by the
 * difference: 30 s without inputs at 350 km/h put a CRH3 259 m ahead
 * (5 sd) beside a DFH3 row (a review). */
double hstpf__step_xu(const hstpf_t *f, const hstpf_model_t *m, const hstpf__step_t *st);
void hstpf__kalman_place(hstpf_t *f, hstpf_model_t *m, const hstpf__acq_t *q);
/* One step; returns the log-likelihood increment (0 without a
 * measurement), *held as hstpf_model_t.held, *floored 1 when the
 * measurement was beyond the floor. */
double hstpf__kalman_step(hstpf_t *f, hstpf_model_t *m, const hstpf__step_t *st, uint8_t *held, int *floored);

/* The speed of a Gaussian filter where the train may come to rest within
 * the step (kalman_rest.c): y = v + T a ~ N(vd, pyy) before the process
 * noise w_v (mean mu_w, variance q_w), v' = y + w_v if y >= 0, else 0
 * exactly (docs/model.md, rule 1). */
#define HSTPF__REST_EPS 1e-3 /* at rest once P(y < 0) >= 1 - this */
/* or once P(y < 0) has been at least 1/2 for HSTPF__REST_SETTLE_S, or the
 * speed within sqrt(HSTPF__REST_SD2) sd of 0 for that time divided by
 * HSTPF__REST_SD_RATE (5 s: braking passes through that band in about a
 * second, a train held by a weak force stays in it): kept one Gaussian, the
 * mixture puts the speed noise on the part at rest too at the next step,
 * and where the holding deceleration is not several times the noise's sd a
 * step (a weak holding force, 0.1 s steps) P(y < 0) settled below 1 -
 * HSTPF__REST_EPS: no model was ever at rest and the weights moved through
 * the stop (a review: 15.6 % of `stops` runs at 10 Hz declared a wrong
 * type, 0 % with the rule before the mixture) */
#define HSTPF__REST_SETTLE_S 2.0
#define HSTPF__REST_SD2 2.25
#define HSTPF__REST_SD_RATE 0.4
/* hstpf_model_t.held: the model's posterior at the end of the step */
#define HSTPF__HELD_NO 0u       /* moving */
#define HSTPF__HELD_YES 1u      /* wholly at rest */
#define HSTPF__HELD_STOPPING 2u /* at rest with probability HSTPF__REST_EPS or more, not wholly */
enum { HSTPF__REST_MOVING = 0, HSTPF__REST_MIXED = 1, HSTPF__REST_AT_REST = 2 };
typedef struct {
    double p_rest; /* P(v' = 0) */
    double v, var; /* mean and variance of v' */
    double kappa;  /* cov(x, v') = kappa cov(x, y) for any x jointly Gaussian with y */
} hstpf__rest_t;
/* HSTPF__REST_MOVING: P(y < 0) < 1e-9, the plain Kalman step (out not
 * set); HSTPF__REST_AT_REST: P(y < 0) >= 1 - HSTPF__REST_EPS (out not set);
 * HSTPF__REST_MIXED: out holds the moments of v' (point mass and the rest
 * together). */
int hstpf__kalman_rest(double vd, double pyy, double mu_w, double q_w, hstpf__rest_t *out);
/* The same on a filter's mean x and n x n covariance p (row-major, the
 * speed at index 1) after the step without the speed noise (y's variance
 * in p[n + 1]; v the speed's mean before the step, vd after it): sets the speed's mean, row and column, adds the noise
 * (q_w + acc_var) to a train that moves; returns hstpf_model_t.held. With
 * the traction unknown (free_run) no model holds the train: at rest only
 * if vd < 0. *rest is the model's timer (HSTPF__REST_SETTLE_S; kept by
 * the caller, zeroed at placing), dt the step. The Kalman engine's rows and the
 * continuous hypothesis' EKF both step their speed through it. */
uint8_t hstpf__kalman_rest_speed(double *x, double *p, int n, double v, double vd, int free_run, double mu_w,
                                 double q_w, double acc_var, double dt, hstpf_settle_t *rest);
/* The timer's evidence, after a step's fix yr (relative) that the filter
 * predicted N(s, pss): while the timer runs, the fix is scored under
 * "stood still since the timer began" and under the filter's prediction,
 * both on the noise's moments, and the log ratio summed. */
void hstpf__settle_fix(const hstpf_t *f, hstpf_settle_t *c, double s, double pss, double yr);
/* After a fix moved a row's position by ds and its variance from pss to
 * pss_post: the unclamped speed kept while stopping (kalman_rest.c), if
 * any, moves with it by its regression on the position. */
void hstpf__kalman_rest_fix(hstpf_settle_t *c, double pss, double ds, double pss_post);

/* A fix scored by the fix noise's real density against a Gaussian
 * prediction N(s, pss) of the position (kalman_fix.c). */
typedef struct {
    double loglik;    /* log p(y), with the grid's floor */
    double ds;        /* posterior mean of the position minus s */
    double var;       /* posterior variance of the position */
    int floored;      /* every cell of the prediction's +-6 sd beyond the floor: ds = 0, var = pss */
} hstpf__fix_t;
void hstpf__kalman_fix(const hstpf_t *f, double s, double pss, double yr, hstpf__fix_t *out);

/* A fix yr scored on the noise's moments against N(s, pss), with the
 * particle engine's floor: at floor_depth nats below the peak the
 * log-density turns into a slope of 1 nat per sd, and the innovation is
 * clipped there for the update (Huber) (kalman_fix.c). */
typedef struct {
    double loglik;
    double sy, sd;    /* the innovation's variance pss + var(e), and its sd */
    double z;         /* the innovation in sd, clipped */
    int floored;      /* 1 when clipped */
} hstpf__fixm_t;
void hstpf__fix_moments(const hstpf_t *f, double s, double pss, double yr, hstpf__fixm_t *out);

/* The rows' Kalman filters and the continuous hypothesis' EKF score a fix
 * by its real density (hstpf__kalman_fix), not by its moments: on the grid
 * engine, where they stand in for rows without a grid and are the
 * hypothesis' yardstick, and only where the process noise is Gaussian (it
 * is then only the fixes that are not). */
int hstpf__fix_exact(const hstpf_t *f);

/* A Gaussian filter of the train at (s, v) with variances pss, pvv has
 * lost it when it lies HSTPF__LOST_SD sd (of the two together) from model
 * g's posterior in position or speed: the grid engine then places it again
 * at g's (engine_grid.c, refine.c). Its density update scores a fix deep in
 * a heavy tail as an outlier and hardly moves, so a filter placed with a
 * wrong speed at acquisition (an outlier among the first two fixes) ran
 * away and never came back. Against another row's grid too by speed: by
 * position alone heavy-t declared a wrong type in 4 runs of 1 700, not 2
 * (docs/grid.md, "Rows on the grid"). */
#define HSTPF__LOST_SD 5.0
static inline int hstpf__kalman_lost(const hstpf_model_t *g, double s, double v, double pss, double pvv)
{
    const double ds = s - (double)g->s_mean, dv = v - (double)g->v_mean;
    const double k2 = HSTPF__LOST_SD * HSTPF__LOST_SD;
    return ds * ds > k2 * (pss + (double)g->s_var) || dv * dv > k2 * (pvv + (double)g->v_var);
}

/* A row's Kalman filter state published into s_mean, v_mean, s_var,
 * v_var, ess (the Kalman engine's rows). */
void hstpf__kalman_publish(const hstpf_t *f, hstpf_model_t *m);

/* The engine of a validated configuration (AUTO resolved). */
hstpf_engine_t hstpf__engine_resolve(const hstpf_config_t *cfg);

/* The interface of an engine (never AUTO). */
const hstpf__engine_t *hstpf__engine_for(hstpf_engine_t e);

/* The interface of an instance's resolved engine. */
const hstpf__engine_t *hstpf__engine_of(const hstpf_t *f);

#endif
