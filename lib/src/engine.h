/* The one internal interface every estimation engine implements. The bank
 * (bank.c) owns the model weights, the declaration and the blend; an engine
 * owns how each model's state and likelihood are computed. The engine of an
 * instance is chosen once, in hstpf__engine_select(). */
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
} hstpf__step_t;

typedef struct {
    /* Every model placed at the first fix yr with prior speed mean v0. */
    void (*place_all)(hstpf_t *f, hstpf_real_t yr, hstpf_real_t v0);
    /* One model placed again at the fix (it lost the train). */
    void (*place_one)(hstpf_t *f, hstpf_model_t *m, hstpf_real_t yr, hstpf_real_t v0);
    /* Predict and (with a measurement) update every model: sets each
     * model's loglik, s_mean, v_mean, ess and floor counters. */
    void (*predict_update)(hstpf_t *f, const hstpf__step_t *st);
    /* After the model weights were updated (the paired bank resamples here);
     * NULL when the engine has nothing to do. */
    void (*after_weights)(hstpf_t *f, const hstpf__step_t *st);
    /* Positions move by -d: the origin moved by +d. */
    void (*shift)(hstpf_t *f, hstpf_real_t d);
} hstpf__engine_t;

extern const hstpf__engine_t hstpf__engine_particle;
extern const hstpf__engine_t hstpf__engine_kalman;

/* The engine of a validated configuration (AUTO resolved). */
hstpf_engine_t hstpf__engine_resolve(const hstpf_config_t *cfg);

/* The interface of an instance's resolved engine. */
const hstpf__engine_t *hstpf__engine_of(const hstpf_t *f);

#endif
