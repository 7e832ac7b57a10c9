/* Host-side simulator of the paper's train model (Eq. 6-7), for the demo,
 * the Monte Carlo study and the tests. Double precision, exact noise
 * samplers (Box-Muller, Marsaglia-Tsang), its own RNG stream: independent of
 * the filter's tables and streams.
 *
 * Truth physics per step T (tools/hstpf_tools/model.py does the same):
 *   held:   v == 0 and xi (u - c0 - g) <= 0 (nothing can start the train,
 *           e.g. the holding brake or u = 0 at a platform): s' = s, v' = 0,
 *           no process noise (a standing train does not random-walk);
 *   else:   s' = s + T v + w_s,  v' = max(0, v + T xi (u - W(v) - g) + w_v)
 *           (a train never reverses). */
#ifndef HSTPF_SIM_H
#define HSTPF_SIM_H

#include "hstpf/hstpf.h"

typedef enum {
    HSTPF_PROFILE_PAPER = 0,       /* 0 -> 350 km/h at 0.2455 m/s^2, then cruise */
    HSTPF_PROFILE_COAST_BRAKE = 1, /* accelerate, cruise, coast, brake, again */
    HSTPF_PROFILE_STOPS = 2,       /* runs between station stops */
    HSTPF_PROFILE_JOURNEY = 3      /* the legs of a timetable (hstpf_sim_leg_t) */
} hstpf_profile_t;

/* One leg of a journey: depart (or start), run at cruise_kmh (accelerate at
 * HSTPF_SIM_ACCEL, hold the speed), brake at HSTPF_SIM_BRAKE from run_s after
 * the departure until the train stands, then dwell dwell_s from the step it
 * comes to rest, the holding brake applied and reported. dwell_s < 0: the
 * leg runs to the end of the simulation (no stop). After the last leg's
 * dwell the train stays held. */
typedef struct {
    double cruise_kmh;
    double run_s;
    double dwell_s;
} hstpf_sim_leg_t;

#define HSTPF_SIM_ACCEL 0.4          /* m/s^2, journey traction limit */
#define HSTPF_SIM_BRAKE 0.5          /* m/s^2, journey service brake */
#define HSTPF_SIM_HOLD_BRAKE (-50.0) /* N/kN reported while standing */

/* Journey phase of the truth. */
typedef enum {
    HSTPF_SIM_DWELL = 0, /* standing (or coming to rest) with the holding brake */
    HSTPF_SIM_RUN = 1,   /* accelerating or cruising */
    HSTPF_SIM_BRAKING = 2
} hstpf_sim_phase_t;

/* Heavy-tailed position noise a GNSS receiver has (issue 13). The
 * simulator draws e from it exactly; the filter is given the same density
 * as a caller's table (hstpf_sim_heavy_table()), the library's way of
 * taking any known density. HSTPF_SIM_HEAVY_NONE: e is drawn from noise_e. */
typedef enum {
    HSTPF_SIM_HEAVY_NONE = 0,
    HSTPF_SIM_HEAVY_T = 1,  /* Student-t: e = scale x t(nu) */
    HSTPF_SIM_HEAVY_MIX = 2 /* (1 - p_wide) N(0, sd^2) + p_wide N(0, wide_sd^2) */
} hstpf_sim_heavy_kind_t;

typedef struct {
    hstpf_sim_heavy_kind_t kind;
    double nu, scale;           /* Student-t, nu > 0, scale > 0 */
    double sd, wide_sd, p_wide; /* mixture */
    double range;               /* the filter's table spans [-range, range], m */
} hstpf_sim_heavy_t;

/* The heavy scenarios' parameters (docs/results.md says why these):
 * t(3) whose quartiles are Case 1's N(0, 5 m^2) quartiles, +-0.6745 sqrt(5)
 * = +-1.5082 m, and t(3)'s 0.75 quantile is 0.76489: scale 1.9718 m;
 * the mixture's core is Case 1's sd sqrt(5) m, 5 % of the fixes from a
 * component 10 times as wide. Tables to +-200 m: t(3) leaves 2.1e-6 of
 * its mass outside, the mixture 4e-20. */
#define HSTPF_SIM_T_NU 3.0
#define HSTPF_SIM_T_SCALE 1.971787
#define HSTPF_SIM_MIX_P 0.05
#define HSTPF_SIM_MIX_WIDE 10.0
#define HSTPF_SIM_HEAVY_RANGE 200.0

/* Points of the table given to the filter (odd: one at e = 0). */
#define HSTPF_SIM_TABLE_N 255
typedef struct {
    double x[HSTPF_SIM_TABLE_N], p[HSTPF_SIM_TABLE_N];
} hstpf_sim_table_t;

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
    /* HSTPF_PROFILE_JOURNEY: the timetable, read during the run */
    const hstpf_sim_leg_t *legs;
    uint16_t n_legs;
    double first_dwell_s;        /* standing at the origin before leg 0; < 0: start running */
    double v0_mps;               /* speed at t = 0 (0) */
    double hold_brake;           /* traction reported while standing (HSTPF_SIM_HOLD_BRAKE) */
    hstpf_sim_heavy_t heavy_e;   /* kind != NONE: e drawn from it, not from noise_e */
} hstpf_sim_config_t;

typedef struct {
    double t, s, v;   /* true time, position, speed at this sample */
    double u;         /* traction applied from this sample to the next, N/kN */
    double y;         /* measured position (valid if has_y) */
    int has_y;
    int held;         /* the truth is held at rest over the step from this sample */
} hstpf_sim_sample_t;

typedef struct {
    hstpf_sim_config_t cfg;
    hstpf_rng_t rng;
    double xi, t, s, v;
    double u_prev;    /* traction of the step just ended */
    uint32_t k;
    /* journey state */
    int leg;                     /* current leg; -1 = the first dwell */
    hstpf_sim_phase_t phase;
    double phase_t0;             /* when the phase (dwell: the rest) began; -1 = not yet at rest */
} hstpf_sim_t;

/* The sample at the current time as the filter's input, then advances one
 * step: the traction is the one applied over the step just ended, the
 * first step's length is 1 s (no step precedes it). */
void hstpf_sim_next_input(hstpf_sim_t *sim, hstpf_sim_sample_t *smp, hstpf_input_t *in);
/* Paper Case 1 / Case 2 noise into a config (truth and profile untouched). */
void hstpf_sim_case1(hstpf_sim_config_t *c);
void hstpf_sim_case2(hstpf_sim_config_t *c);
/* Case 1's process noise with a heavy-tailed position noise of kind k
 * (T or MIX, the parameters above): heavy_e set for the simulator, and
 * noise_e the same density as a table in *tab (which must outlive every
 * use of noise_e) for the filter. */
void hstpf_sim_heavy(hstpf_sim_config_t *c, hstpf_sim_heavy_kind_t k, hstpf_sim_table_t *tab);
/* The exact density of h at x, and an exact draw from it. */
double hstpf_sim_heavy_pdf(const hstpf_sim_heavy_t *h, double x);
double hstpf_sim_heavy_draw(hstpf_rng_t *r, const hstpf_sim_heavy_t *h);
/* h's density at HSTPF_SIM_TABLE_N points on [-range, range], dense near 0
 * (x = c sinh(a u), u uniform, c the core's scale), into *tab, and the
 * spec of a table distribution over it (floor and edge at the defaults). */
void hstpf_sim_heavy_table(const hstpf_sim_heavy_t *h, hstpf_sim_table_t *tab, hstpf_dist_spec_t *spec);
/* Defaults: CRH3, paper profile, Case 1 noise, dt 1 s, seed 1, holding
 * brake HSTPF_SIM_HOLD_BRAKE. */
void hstpf_sim_default(hstpf_sim_config_t *c);
void hstpf_sim_init(hstpf_sim_t *sim, const hstpf_sim_config_t *c);
/* The sample at the current time, then advances one step. */
void hstpf_sim_next(hstpf_sim_t *sim, hstpf_sim_sample_t *out);
/* Profile's commanded acceleration at time t and true speed v, m/s^2; *coast
 * set when traction is off (u = 0). */
double hstpf_sim_accel_cmd(hstpf_profile_t p, double t, double v, int *coast);
/* 1 when the rule above holds the train at rest over a step with traction u
 * at speed v and track resistance g. */
int hstpf_sim_held(const hstpf_theta_t *truth, double v, double u, double g);
/* i + 600/R at position s. */
double hstpf_sim_track(const hstpf_sim_config_t *c, double s);
/* Exact samplers, exposed for tests. */
double hstpf_sim_gauss(hstpf_rng_t *r);
double hstpf_sim_gamma(hstpf_rng_t *r, double shape);
double hstpf_sim_noise(hstpf_rng_t *r, const hstpf_dist_spec_t *d);

#endif
