/* Host-side simulator of the paper's train model (Eq. 6-7), for the demo,
 * the Monte Carlo study and the tests. Double precision, exact noise
 * samplers (Box-Muller, Marsaglia-Tsang), its own RNG stream: independent of
 * the filter's tables and streams. */
#ifndef HSTPF_SIM_H
#define HSTPF_SIM_H

#include "hstpf/hstpf.h"

typedef enum {
    HSTPF_PROFILE_PAPER = 0,       /* 0 -> 350 km/h at 0.2455 m/s^2, then cruise */
    HSTPF_PROFILE_COAST_BRAKE = 1, /* accelerate, cruise, coast, brake, again */
    HSTPF_PROFILE_STOPS = 2        /* runs between station stops */
} hstpf_profile_t;

typedef struct {
    hstpf_theta_t truth;
    double gamma_rot;            /* 0.06 */
    hstpf_dist_spec_t noise_s, noise_v, noise_e; /* GAUSSIAN or GAMMA */
    hstpf_profile_t profile;
    double dt_s;                 /* 1 */
    double loss_rate;            /* probability a position is missing */
    uint64_t seed;
    const hstpf_track_seg_t *track;
    uint16_t n_track;
} hstpf_sim_config_t;

typedef struct {
    double t, s, v;   /* true time, position, speed at this sample */
    double u;         /* traction applied from this sample to the next, N/kN */
    double y;         /* measured position (valid if has_y) */
    int has_y;
} hstpf_sim_sample_t;

typedef struct {
    hstpf_sim_config_t cfg;
    hstpf_rng_t rng;
    double xi, t, s, v;
    double u_prev;    /* traction of the step just ended */
    uint32_t k;
} hstpf_sim_t;

/* The sample at the current time as the filter's input, then advances one
 * step: the traction is the one applied over the step just ended, the
 * first step's length is 1 s (no step precedes it). */
void hstpf_sim_next_input(hstpf_sim_t *sim, hstpf_sim_sample_t *smp, hstpf_input_t *in);
/* Paper Case 1 / Case 2 noise into a config (truth and profile untouched). */
void hstpf_sim_case1(hstpf_sim_config_t *c);
void hstpf_sim_case2(hstpf_sim_config_t *c);
/* Defaults: CRH3, paper profile, Case 1 noise, dt 1 s, seed 1. */
void hstpf_sim_default(hstpf_sim_config_t *c);
void hstpf_sim_init(hstpf_sim_t *sim, const hstpf_sim_config_t *c);
/* The sample at the current time, then advances one step. */
void hstpf_sim_next(hstpf_sim_t *sim, hstpf_sim_sample_t *out);
/* Profile's commanded acceleration at time t and true speed v, m/s^2; *coast
 * set when traction is off (u = 0). */
double hstpf_sim_accel_cmd(hstpf_profile_t p, double t, double v, int *coast);
/* i + 600/R at position s. */
double hstpf_sim_track(const hstpf_sim_config_t *c, double s);
/* Exact samplers, exposed for tests. */
double hstpf_sim_gauss(hstpf_rng_t *r);
double hstpf_sim_gamma(hstpf_rng_t *r, double shape);
double hstpf_sim_noise(hstpf_rng_t *r, const hstpf_dist_spec_t *d);

#endif
