/**
 * @file hstpf.h
 * @brief hstpf: online state, running-resistance and train-type estimation
 * for a high-speed train, by a bank of per-type filters with Bayesian model
 * weights (Xie et al., "An Online State and Parameter Estimation of Dynamic
 * State Space Model of High Speed Train"). Each model's filter is one of the
 * engines of hstpf_engine_t: an extended Kalman filter (exact likelihood for
 * Gaussian noise), a deterministic grid filter (any noise, no Monte Carlo
 * noise; docs/grid.md) or a particle filter (any noise). See docs/model.md.
 *
 * Sources (lib/src): bank.c (life cycle, step, model weights, standstill),
 * lock.c (acquisition and re-acquisition), declare.c (the declaration state
 * machine, "no type fits"), estimate.c (the published blend, its sd and
 * validity), engine.h (the interface every engine implements),
 * engine_kalman.c, engine_grid.c (and grid_*.c), engine_particle.c, refine.c (the
 * continuous-theta hypothesis), config.c (defaults and the one table of
 * ranges), track.c (gradient and curve profile), dist.c (noise tables;
 * dist_blur.c the measurement blur, dist_tables.c constants), rng.c.
 *
 * Model, per step of length T seconds (units: docs/model.md):
 *   s' = s + T v + w_s
 *   v' = v + T xi (u - W(v) - g(s)) + w_v,   W(v) = c0 + c1 V + c2 V^2,
 *   y  = s + e,                               V = 3.6 v (km/h),
 * xi = 9.81 / (1 + gamma) / 1000 (m/s^2 per N/kN), u and W in N/kN,
 * g(s) = i + 600 / R from the optional track profile.
 *
 * Memory: the caller owns one hstpf_t (the bank, about 21 KiB) and, for
 * the particle and grid engines, a workspace sized for the engine and
 * counts in use (hstpf_config_t.workspace, hstpf_workspace_size()); the
 * library never allocates. Time: hstpf_step() has a fixed bound per
 * engine: O(models x particles), O(models), O(models x cells x kernel
 * taps); no loops that depend on data beyond that (the track look-up walks
 * at most the number of segments the state moved).
 * Thread safety: an instance must not be used from two threads at once;
 * different instances are independent. All functions are reentrant.
 */
#ifndef HSTPF_HSTPF_H
#define HSTPF_HSTPF_H

#include "hstpf/common.h"
#include "hstpf/dist.h"
#include "hstpf/rng.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Largest step length accepted, s. */
#define HSTPF_DT_MAX_S 60.0
/** Largest |unit traction or braking force| accepted, N/kN. */
#define HSTPF_U_MAX 1000.0
/** Largest |position| accepted, m (100 000 km). */
#define HSTPF_POS_MAX_M 1.0e8
/** Largest |speed| accepted in a prior, m/s. */
#define HSTPF_SPEED_MAX 200.0
/** A lock taken on fixes behind the furthest point the train has passed
 *  (a reference that restarted: a new run, another line's kilometrage) is
 *  on probation, not valid and the model weights waiting, until the train
 *  has come forward two fix ranges, or for this long, s (time, not steps
 *  with fixes), neither the posterior has fallen half a fix range nor the
 *  fixes' least-squares line a quarter of one. Fixes that fall slowly (a
 *  creep the model, which has no reversal, cannot follow) restart that
 *  count; one slower than the line can tell in 30 s (about 0.12 m/s for
 *  the default noise) ends it once, and a lock taken behind again before
 *  the train has come forward ends only by coming forward (docs/model.md,
 *  "The fixes must run forwards"). */
#define HSTPF_REF_PROBATION_S 30.0

/** Most parts a long step is predicted in: a step longer than 1.5 x
 *  dt_nominal_s is predicted in ceil(dt_s / dt_nominal_s) parts of the
 *  model's own step, at most this many, the fix taken at the last, so
 *  that s' = s + T v holds over an outage or sparse fixes (docs/model.md,
 *  "Long steps"). Such a step costs that many predictions. */
#define HSTPF_SUBSTEPS_MAX 64u

/** The shortest standstill at which hstpf_config_t.consist_change_p
 *  applies, s: coupling or splitting a consist, with its brake test, takes
 *  minutes. A 2-minute station stop or a signal does not change the train,
 *  and no weight is mixed there (each mix costs a near-certain leader some
 *  weight and its declaration up to 30 s: docs/results.md). */
#define HSTPF_CONSIST_STOP_S 180.0

/** How long a traction found implausible (hstpf_estimate_t.traction_fault)
 *  is taken as unknown before it is believed and tested again, s; found
 *  again within this time after such a retry, twice as long the next time,
 *  up to 4 times; hstpf_reset() ends it. Steps whose traction the caller
 *  reports unknown count towards the time and keep the fault. */
#define HSTPF_TRAC_RETRY_S 600.0

/** Largest Davis coefficients a train type may have (and an estimate
 *  published as valid): c0 N/kN, c1 N/kN per km/h, c2 N/kN per (km/h)^2. */
#define HSTPF_C0_MAX 50.0
#define HSTPF_C1_MAX 1.0
#define HSTPF_C2_MAX 0.01

/** Davis resistance coefficients of one train type (units of Table 1). */
typedef struct {
    const char *name; /**< display name, may be NULL */
    double c0;        /**< N/kN, in [0, HSTPF_C0_MAX] */
    double c1;        /**< N/kN per km/h, in [0, HSTPF_C1_MAX] */
    double c2;        /**< N/kN per (km/h)^2, in [0, HSTPF_C2_MAX] */
} hstpf_theta_t;

/** Number of rows in hstpf_train_types. */
#define HSTPF_N_TRAIN_TYPES 17
/** The 17 rows of Table 1 of the paper, in its order (CRH1 first). */
extern const hstpf_theta_t hstpf_train_types[HSTPF_N_TRAIN_TYPES];

/**
 * @brief Index of a Table 1 row by name (exact, case-sensitive, e.g. "CRH3",
 * "SS1/SS3/SS4"), or -1 if there is none or name is NULL. Cost O(17).
 */
int32_t hstpf_train_type_find(const char *name);

/**
 * @brief Running resistance W at speed v, N/kN: c0 + c1 V + c2 V^2,
 * V = 3.6 v km/h. Returns 0 if th is NULL. Cost O(1).
 */
double hstpf_resistance(const hstpf_theta_t *th, double v_mps);

/** One track segment, from start_m to the next segment's start. */
typedef struct {
    double start_m;            /**< segment start, m, increasing */
    double gradient_permille;  /**< i, per mille, + uphill, in [-100, 100] */
    double curve_radius_m;     /**< R, m; 0 = straight, else >= 100 */
} hstpf_track_seg_t;

/** How particle weights update the model weights. */
typedef enum {
    /** log p(y_k | y_1:k-1, theta_l) = logsumexp_i(log W_k-1^i + l_k^i):
     *  the model's marginal likelihood; correct with adaptive resampling. */
    HSTPF_WEIGHT_MARGINAL = 0,
    /** The paper's Eq. 13: likelihood of the model's posterior mean. */
    HSTPF_WEIGHT_PAPER = 1
} hstpf_weight_method_t;

/** When particles are resampled. */
typedef enum {
    HSTPF_RESAMPLE_ALWAYS = 0, /**< every measurement step (the paper) */
    HSTPF_RESAMPLE_ESS = 1     /**< when ESS < ess_threshold x particles */
} hstpf_resample_t;

/** How the filters of the bank relate. */
typedef enum {
    /** Model l draws from its own RNG stream l and resamples on its own
     *  weights: independent filters. Their likelihood estimates carry
     *  independent Monte Carlo noise, which for near-identical models can
     *  decide between them by chance. */
    HSTPF_BANK_INDEPENDENT = 0,
    /** Paired filters: each step's process noise is drawn once, from the
     *  instance's stream, and used by every model; resampling picks one set
     *  of ancestors for all models from a defensive mixture of their
     *  weights, a = sum_l (q_l + 1/n) / 2 * W_l, and each model keeps the
     *  importance correction W_l / a. Particle i of every model is then the
     *  same particle under different dynamics, so the Monte Carlo noise of
     *  the likelihood estimates is shared and cancels in the comparison of
     *  similar models. Results still do not depend on loop order. For
     *  models that differ clearly the shared ancestry leaves each model few
     *  particles of its own and its likelihood is underestimated: use it
     *  for banks of near-identical models only. */
    HSTPF_BANK_PAIRED = 1
} hstpf_bank_t;

/** How each model's state and likelihood are computed. */
typedef enum {
    /** A particle filter per model (the paper's Section 3.1): any noise
     *  densities. Its likelihood estimates carry Monte Carlo noise. */
    HSTPF_ENGINE_PARTICLE = 0,
    /** An extended Kalman filter per model on (s, v): the model is linear
     *  but for c2 V^2 and the no-reversal rule, so with Gaussian noise the
     *  model likelihood is exact up to that linearisation and carries no
     *  Monte Carlo noise (the whole state is marginalised, i.e.
     *  Rao-Blackwellised). n_particles, bank, resampling, roughening and
     *  weight_method are then unused. Needs all three channels Gaussian. Measurements
     *  beyond the likelihood floor (floor_depth of noise_e) count as
     *  floor hits and enter the update clipped to the floor's edge (a
     *  Huber update), so an outlier moves the state by a bounded amount. */
    HSTPF_ENGINE_KALMAN = 1,
    /** KALMAN when noise_s, noise_v and noise_e are all Gaussian, else
     *  GRID: the exact likelihood where it exists, the deterministic grid
     *  where the noise is not Gaussian. */
    HSTPF_ENGINE_AUTO = 2,
    /** A deterministic grid (point-mass) filter per model: the density of
     *  (s, v) on HSTPF_GRID_NS x HSTPF_GRID_NV cells that move and resize
     *  with the posterior every step; the time update transports the cells
     *  by the dynamics and convolves with the process-noise densities, the
     *  measurement update integrates the measurement density over each
     *  cell (one-sided and unbounded densities such as Gamma(0.5) need no
     *  blur). Any noise; no RNG, so the model likelihoods carry no Monte
     *  Carlo noise and runs are bit-for-bit repeatable. n_particles, bank,
     *  resampling, roughening, e_blur_sd and weight_method are unused; the
     *  track profile is evaluated at each model's mean position. Cost per
     *  model-step O(cells x kernel width), see docs/grid.md. */
    HSTPF_ENGINE_GRID = 3
} hstpf_engine_t;

/** Whether the data fit a row of the table (docs/model.md, "Trains that are
 *  not on Table 1"). */
typedef enum {
    HSTPF_FIT_UNKNOWN = 0, /**< not decided (or the hypothesis is off) */
    HSTPF_FIT_TABLE = 1,   /**< a table type is declared: the train is that row */
    /** No table type fits: the continuous hypothesis held above
     *  declare_threshold for declare_hold_s (or the innovations fit no
     *  hypothesis); theta is the refined estimate and off_what says what is
     *  off. */
    HSTPF_FIT_NONE = 2
} hstpf_fit_t;

/** Bits of hstpf_estimate_t.off_what. */
#define HSTPF_OFF_COEF 1u  /**< the Davis coefficients are off every row */
#define HSTPF_OFF_C0 2u    /**< mostly c0: a constant resistance offset (gradient-like) */
#define HSTPF_OFF_GAIN 4u  /**< the reported traction's gain is not 1 */
#define HSTPF_OFF_INNOV 8u /**< the innovations are inconsistent with every hypothesis */

/** Configuration; fill with hstpf_config_default() then change fields. */
typedef struct {
    const hstpf_theta_t *models; /**< n_models rows, read during init only */
    uint16_t n_models;           /**< 1..HSTPF_MAX_MODELS */
    uint16_t n_particles;        /**< 2..HSTPF_MAX_PARTICLES (default 100) */
    uint64_t seed;               /**< RNG seed; streams: model l uses l, the paired bank HSTPF_MAX_MODELS */
    /** Per-model estimator (HSTPF_ENGINE_AUTO); HSTPF_E_CONFIG if KALMAN
     *  is asked with a non-Gaussian channel. */
    hstpf_engine_t engine;
    /** How the models' particle filters share randomness (see the enum);
     *  (HSTPF_BANK_INDEPENDENT; docs/results.md measures both). */
    hstpf_bank_t bank;
    double gamma_rot;            /**< rotating-mass factor, [0, 1] (0.06) */
    hstpf_dist_spec_t noise_s;   /**< w_s, m per step (N(0, sqrt 0.02)) */
    hstpf_dist_spec_t noise_v;   /**< w_v, m/s per step (N(0, sqrt 0.05)) */
    hstpf_dist_spec_t noise_e;   /**< e, m (N(0, sqrt 5)) */
    /** Noise samples are scaled by sqrt(T / dt_nominal_s): exact for a
     *  Gaussian random walk, a first-order approximation otherwise (1 s). */
    double dt_nominal_s;
    double init_speed_mps;       /**< prior speed mean, m/s, used when init_speed_sd > 0 (0) */
    /** Speed prior at acquisition, m/s. 0 (the default): unknown; the
     *  filter acquires position and speed from its first two fixes (at any
     *  speed, with no other configuration). > 0: the first fix alone
     *  starts the filter with the speed N(init_speed_mps, init_speed_sd),
     *  at the first lock after hstpf_init or hstpf_reset; a lock regained
     *  later (an outage, a clock step, a run of gated fixes,
     *  hstpf_reacquire) takes the speed from two fixes, whatever the
     *  train's speed has become. The prior is a guess until a fix confirms
     *  it: the estimate is not valid before a later fix passes the gate
     *  within some weighted model's floor; two in a row that do not (a
     *  unit that started while the train runs) place the models again
     *  from the latter and the prior's fix (or the first gated one),
     *  counted in hstpf_estimate_t.reacquired. */
    double init_speed_sd;
    hstpf_resample_t resample;   /**< policy (HSTPF_RESAMPLE_ESS) */
    double ess_threshold;        /**< fraction of particles, (0, 1] (0.5) */
    /** Roughening after resampling: jitter sd = k * spread * M^(-1/2) per
     *  state, spread = max - min over the cloud; 0 = off (0.2). */
    double roughening_k;
    double rough_min_s;          /**< minimum roughening sd, m (0) */
    double rough_min_v;          /**< minimum roughening sd, m/s (0) */
    hstpf_weight_method_t weight_method; /**< (HSTPF_WEIGHT_MARGINAL) */
    /** Floor on every model weight q_l after normalisation, so that a model
     *  can recover when conditions change; [0, 1/n_models) (1e-9). A wrong
     *  model at the floor returns to q ~ 0.1 after one step that favours
     *  it by log(0.1 / q_floor) nats: 18.4 at 1e-9, 11.5 at 1e-6, which
     *  single steps of a lost model reached (docs/results.md). */
    double q_floor;
    /** q above which a type may be declared (0.99). The paper's Table 2
     *  uses 0.9 with tau = 0.3 x the run's length, unknown online; with a
     *  short tau, 0.9 lets a wrong type through in 2-4 % of 17-type runs
     *  even with exact likelihoods (docs/results.md). */
    double declare_threshold;
    double declare_hold_s;       /**< tau: how long it must stay above (30 s) */
    /** A declared type whose q falls below this is withdrawn (status
     *  WITHDRAWN, declared -1); [q_floor, declare_threshold] (0.5). */
    double withdraw_threshold;
    /** Probability that the consist (the train type) changed during a
     *  standstill of at least HSTPF_CONSIST_STOP_S (coupled or split at a
     *  station), [0, 0.5] (0.01). At the first weighted step after such a
     *  stop each hypothesis' weight q becomes (1 - p) q + p x its prior
     *  weight, and the continuous hypothesis' theta its moments under the
     *  same mixture with its prior: a new train's row then needs about
     *  log(1 / (p x prior)) nats (7.4 at 17 rows), not the weight floor's
     *  20.7, and no type changes while the train runs. 0: the type never
     *  changes (call hstpf_consist_changed() when the train control knows
     *  it did). docs/model.md, "A consist that changes at a station". */
    double consist_change_p;
    /** Longest step the filter predicts across, s: a longer gap between
     *  accepted inputs (an outage, a clock step) drops the lock and the
     *  filter re-acquires from the next fixes, keeping the model weights;
     *  (0, HSTPF_DT_MAX_S] (30). */
    double max_gap_s;
    /** While the traction is unknown (hstpf_input_t.traction_unknown) the
     *  train's acceleration is taken as 0 with this sd, m/s^2: a zero-mean
     *  Gaussian added to the speed, of variance accel_unknown_sd^2 T tau
     *  over a step of T, tau = max(dt_nominal_s, 1 s) (a random walk, as
     *  the noises scale, whose acceleration lasts at least a second, at
     *  any step rate) while fixes come; across steps without a fix the
     *  acceleration persists: over a span t without one the variance is
     *  accel_unknown_sd^2 t max(t, tau). The traction check's shadow takes
     *  accel_unknown_sd^2 T tau on every step. (0, 10] (0.5: about a high-speed train's service traction
     *  and braking). */
    double accel_unknown_sd;
    /** Measurements farther than this from the predicted position are
     *  not used (the step predicts; HSTPF_E_OUTLIER), m; 0 = no gate (1000).
     *  0 also turns fix_step off. */
    double gate_m;
    /** After this many consecutive gated measurements, or measurements
     *  beyond the likelihood floor of every weighted hypothesis, the next
     *  one is taken as a new first fix (particles redrawn there, model
     *  weights kept): a real jump forward of the position reference is
     *  re-acquired (one back on probation, HSTPF_REF_PROBATION_S, or at
     *  once after hstpf_reacquire(); position_m). The first measurement of such a run moves no model
     *  weight (an outlier of a heavy-tailed noise; docs/model.md). On the
     *  Kalman and grid engines, moving, two measurements beyond every
     *  weighted hypothesis' floor in a row are enough, and the two after
     *  them are the new pair. 0 = never (5). */
    uint16_t reacquire_after;
    /** A model whose every particle was at the likelihood floor for this
     *  many measurements (it lost the train) is redrawn at the fix with the
     *  blended speed, keeping its weight, so it can recover if the train or
     *  its conditions change. Costs identification speed: a redrawn wrong
     *  model challenges the right one for a while (docs/results.md). 0 =
     *  never (0). */
    uint16_t model_reacquire_after;
    const hstpf_track_seg_t *track; /**< optional profile, copied at init */
    uint16_t n_track;            /**< 0..HSTPF_MAX_TRACK_SEGMENTS */
    /** Particle engine: the measurement likelihood is the density of
     *  e + d, d ~ N(0, e_blur_sd), m: e's log-density table is replaced at
     *  init by its exact convolution with that Gaussian (Gaussian or Gamma
     *  e; a TABLE e gives HSTPF_E_CONFIG). A proper, bounded density with
     *  no hard edge, so edge_soft is unused: a Gamma e's unbounded peak
     *  and one-sided support otherwise make the particle weights (and the
     *  model likelihoods) heavy-tailed and lose clouds that run slightly
     *  ahead (docs/results.md, Case 2). The first-fix cloud still draws a
     *  Gamma e itself; a blurred Gaussian e is simply a wider Gaussian. The
     *  Kalman engine ignores it. Init cost with a Gamma e: a few 10^5
     *  exp/pow calls (docs/footprint.md). 0 = none (0). */
    double e_blur_sd;
    /** 1: besides the rows, the bank weighs one continuous hypothesis, a
     *  train near the table but on no row: an augmented EKF on (s, v, c0,
     *  c1, c2, k) with Table 1 as prior (docs/model.md). Used by the
     *  Kalman engine and the grid engine, ignored by the particle engine.
     *  On the grid engine it is scored through a Kalman yardstick of the
     *  rows under Gaussian process noise, and by one more grid model at
     *  its current theta under non-Gaussian process noise (Case 2's Gamma),
     *  which needs one more grid in the workspace (hstpf_workspace_size()
     *  counts it), and its step (docs/model.md,
     *  "Engines"). 2: that grid model under any noise. 0: rows only (with
     *  the hypothesis a train off every row is seldom declared a wrong
     *  type; it costs some identification speed on the table,
     *  docs/results.md). */
    uint8_t refine;
    /** Prior weight of the continuous hypothesis, [0, 0.5] (0.01). */
    double refine_prior_q;
    /** Relative sd of each coefficient around its row (load, wear, wind,
     *  coupled consists), in the continuous hypothesis' prior and in each
     *  row's W(v) band, [0, 1] (0.3; docs/model.md says why). */
    double refine_spread;
    /** Prior sd of the traction gain k around 1, [0, 0.5] (0: k fixed at 1.
     *  At constant speed k u - W(v) = 0 leaves k and theta on a ridge the
     *  data do not resolve, and the EKF drifted along it: k 1 -> 0.84 in
     *  20 min of cruise in a paper Case 1 run, pulling the hypothesis'
     *  weight up with it). */
    double refine_gain_sd;
    /** Grid engine, 1: each model's speed cells are the image of its last
     *  ones under its own dynamics (their width doubled or halved until
     *  the predicted box fits; a box at its quantiles instead, remapped,
     *  where those cells would be over 1.5 times its own or start below
     *  0), so the speed axis is seldom remapped (the default; docs/grid.md,
     *  "The speed lattice": paper Case 2 decides 4.4 s sooner); 0: the
     *  speed box at the predicted marginal's quantiles, remapped at every
     *  step (the default before the thirteenth session). Other engines
     *  ignore it. */
    uint8_t grid_speed_lattice;
    /** 1 (default): test on every fix whether the reported traction
     *  explains the fixes better than no traction would, and take it as
     *  unknown for HSTPF_TRAC_RETRY_S when it does not
     *  (hstpf_estimate_t.traction_fault); 0:
     *  always believe it. A 2 x 2 Kalman filter per step. The Kalman and
     *  grid engines under Gaussian process noise (any fix noise); not the
     *  particle engine (its Monte Carlo likelihoods are too low to test
     *  against), nor non-Gaussian process noise (a Gaussian filter weighed
     *  against exact densities never wins). */
    uint8_t traction_check;
    /** 1 (default): a step in the fixes' reference (a GNSS bias that
     *  changes, a balise or map-matching correction) moves the position,
     *  not the speed: a fix beyond the fix noise's 2^-17 quantiles (a
     *  Gaussian's 4.3 sd, with the prediction's spread) right after one
     *  that fitted is held (HSTPF_E_OUTLIER, not valid), and the next one
     *  beyond its 2^-11 quantiles on the same side at about the same
     *  offset moves the position by their mean
     *  (hstpf_estimate_t.fix_steps). Under a fix noise with heavier
     *  tails (its 2^-17 quantiles beyond 6.5 of its sd on both sides:
     *  Student-t, multipath mixtures) the last 2-6 fixes used, on one side
     *  after one that fitted, are a step when it explains them by 20 nats
     *  of the noise's density. Every engine's positions take the step's
     *  variance. Moving or at rest; not across a long
     *  step, while the traction is in doubt, or with gate_m 0. 0: every
     *  fix within gate_m is used (docs/model.md, "A step in the fixes"). */
    uint8_t fix_step;
    /** Grid engine under Gaussian process noise (the heavy-tailed fixes
     *  of a GNSS receiver): how many rows are stepped on the grid, those
     *  with the largest weights, [0, HSTPF_MAX_MODELS] (3; 0: every row).
     *  The others run the Kalman filter on the noises' moments: their
     *  increment is the leading row's exact one plus the log ratio of
     *  their filter to the leader's (at most 1 nat either way), and they
     *  publish the leader's state. A row whose weight passes a gridded
     *  row's takes that row's grid, started from the leader's density
     *  moved to the row's own Kalman mean.
     *  The workspace then holds min(grid_rows, n_models) row grids (n_models
     *  when grid_rows is 0), and a
     *  17-row step costs that many grid model-steps plus a 2 x 2 filter
     *  per row. Under non-Gaussian process noise (Case 2's Gamma) every
     *  row is gridded whatever this says: the Kalman ratio is not a fair
     *  stand-in there (docs/grid.md, "Rows on the grid"). Other engines
     *  ignore it. */
    uint16_t grid_rows;
    /** Caller-owned memory for the engine in use: the particles or the
     *  grid cells, which hstpf_t does not hold. At least
     *  hstpf_workspace_size() bytes (HSTPF_PARTICLE_WS_BYTES,
     *  HSTPF_GRID_WS_BYTES; none for the Kalman engine, which may leave it
     *  NULL), aligned to HSTPF_WORKSPACE_ALIGN. The instance keeps the
     *  pointer: the memory must live as long as the instance and serve no
     *  other instance (NULL). */
    void *workspace;
    size_t workspace_size;       /**< bytes at workspace (0) */
} hstpf_config_t;

/** One step's inputs. Initialise it whole (= {0}, or memset) and set the
 *  fields: a field added in a later version then reads 0, its default. */
typedef struct {
    double dt_s;         /**< step length T, (0, HSTPF_DT_MAX_S] */
    double traction;     /**< u over the step, N/kN (+ traction, - braking) */
    double position_m;   /**< measured position y, m (if has_position); it grows in the
                              direction of travel (the model has no reversal): a unit on a line
                              whose kilometrage falls that way feeds its negative, and calls
                              hstpf_reacquire() when the train reverses. Fixes that run
                              backwards are not tracked: they hold the estimate invalid (the
                              estimate's backward counts them). A reference that restarts
                              behind (a new run from 0) is valid again once its fixes come
                              forward, or do not fall back for HSTPF_REF_PROBATION_S;
                              hstpf_reacquire() skips the wait. Each
                              fix once: one fed twice counts as two independent ones. */
    uint8_t has_position; /**< 0: no measurement this step, predict only */
    /** 1: the traction over the step is not known (its sender is silent or
     *  reports it invalid); traction is then not read, and the step takes
     *  the train's acceleration as 0 with cfg.accel_unknown_sd: no model
     *  holds the train at rest, the model weights and the declaration's
     *  hold wait (a made-up traction is no evidence about W(v)), and the
     *  continuous hypothesis steps without its theta (theta moves only by
     *  what the fix says of s and v). 0 (the default): known. */
    uint8_t traction_unknown;
} hstpf_input_t;

/**
 * Declaration status (Table 2, State A(2)), a state machine:
 *
 *   UNDECIDED --(leader q > declare_threshold held declare_hold_s)--> DECLARED
 *   DECLARED  --(declared q < withdraw_threshold)-----------------> WITHDRAWN
 *   WITHDRAWN --(a leader held as above; same or other type)------> DECLARED
 *   DECLARED  --(another type held as above)----------------------> CHANGED
 *   CHANGED   --(declared q < withdraw_threshold)-----------------> WITHDRAWN
 *   any       --(hstpf_reset)--------------------------------------> UNDECIDED
 *
 * declared >= 0 exactly when the status is DECLARED or CHANGED, and then
 * theta is the declared row's theta. In UNDECIDED and WITHDRAWN, declared
 * is -1 and theta is the weight blend.
 */
typedef enum {
    HSTPF_STATUS_UNDECIDED = 0, /**< no type declared yet */
    HSTPF_STATUS_DECLARED = 1,  /**< a type is declared */
    HSTPF_STATUS_CHANGED = 2,   /**< a different type replaced the declared one */
    HSTPF_STATUS_WITHDRAWN = 3  /**< the declared type lost its weight; none declared */
} hstpf_status_t;

/** Per-model output. */
typedef struct {
    hstpf_real_t q;         /**< model weight q_l */
    double position_m;      /**< posterior mean position, m */
    hstpf_real_t speed_mps; /**< posterior mean speed, m/s */
    hstpf_real_t ess;       /**< effective sample size after the update (n_particles under the Kalman engine) */
    hstpf_real_t loglik;    /**< last log-likelihood increment of the model */
    uint32_t floor_hits;    /**< steps where every particle was at the floor */
    uint32_t reacquired;    /**< times the model lost the train and was redrawn */
} hstpf_model_out_t;

/** Snapshot of the estimate after a step. */
typedef struct {
    uint32_t step;          /**< steps accepted so far */
    double time_s;          /**< sum of accepted step lengths */
    /** Blended position sum_l b_l s_l, m, with b_l = (q_l - q_floor)+
     *  normalised: a model at the floor does not pull the estimates. The
     *  same b_l blend speed and theta. */
    double position_m;
    hstpf_real_t speed_mps; /**< blended speed, m/s */
    /** Standard deviations of the blended posterior (the mixture over the
     *  models, so the spread between models is included), m and m/s. */
    double position_sd_m;
    hstpf_real_t speed_sd_mps;
    /** 1 when every published value is finite and within the ranges this
     *  header documents, the filter has lock on the train (acquired from
     *  fixes and not lost since; from the configured speed prior, once a
     *  later fix has confirmed it) and the latest fix was neither gated nor
     *  beyond the likelihood floor of every weighted model; 0
     *  otherwise: consumers must not use the states, theta or resistance. */
    uint8_t valid;
    /** 1 while the train is held at standstill (docs/model.md): the model
     *  weights are not updated. They also wait, with standstill 0, while
     *  some weighted models hold the train at rest, or may have brought it
     *  to rest, and others still move it (its arrival), for at most 10 s. */
    uint8_t standstill;
    /** 1 while the reported traction is taken for implausible: it
     *  explained the fixes worse than no traction at all (its sign swapped,
     *  a wrong signal; docs/model.md, "A traction that cannot be right").
     *  The steps then take it as unknown, no weight moves and no type is
     *  declared, for HSTPF_TRAC_RETRY_S; then it is believed and tested
     *  again. 2 while the train moves although the traction reported holds
     *  it at rest (a holding brake reported late or stuck at a departure, a
     *  train that rolls): taken as unknown until it can move the train or
     *  the train stands again. 0 with cfg.traction_check off. */
    uint8_t traction_fault;
    hstpf_real_t theta[3];  /**< sum_l b_l theta_l (Table 2, State A(1)); a declared row's theta */
    /** Covariance of theta (c0c0, c0c1, c0c2, c1c1, c1c2, c2c2): the mixture
     *  of the rows and the continuous hypothesis. With cfg.refine each row
     *  carries its spread (refine_spread x its coefficients: load, wear,
     *  wind, coupling; docs/model.md), a declared row too; without it the rows are points
     *  (0 when declared). hstpf_resistance_band() turns it into a band on
     *  W(v). */
    hstpf_real_t theta_cov[6];
    hstpf_real_t q_offtable; /**< weight of the continuous hypothesis (0 when off) */
    hstpf_real_t gain;       /**< its traction-gain estimate k (1 when off) */
    hstpf_real_t gain_sd;    /**< and its sd */
    hstpf_fit_t fit;         /**< does a table row fit */
    uint8_t off_what;        /**< HSTPF_OFF_* bits when fit is NONE */
    hstpf_real_t resistance; /**< W(speed) with theta, N/kN */
    int16_t best;           /**< index of the largest q_l */
    int16_t declared;       /**< declared model index, -1 if none */
    hstpf_status_t status;  /**< declaration status */
    double decision_time_s; /**< time of the latest declaration, -1 if none */
    /** measurements not used: beyond the gate, or held as a possible
     *  step's first fix (cfg.fix_step) */
    uint32_t outliers;
    uint32_t reacquired;    /**< re-acquisitions after consecutive outliers, or fixes that contradict the speed prior */
    /** steps in the fixes' reference taken: the position moved by them,
     *  the speed did not (cfg.fix_step) */
    uint32_t fix_steps;
    uint32_t acquisitions;  /**< lock (re)acquired from fixes: start, outage, gated run, time step */
    uint32_t nonfinite_resets; /**< times the filter went non-finite and was re-initialised */
    uint32_t backward;      /**< fix pairs refused, locks dropped, and locks taken on
                                 probation, because the fixes ran backwards or restarted behind
                                 the furthest point (position_m must grow in the direction of
                                 travel; HSTPF_REF_PROBATION_S) */
    uint16_t n_models;
    hstpf_model_out_t model[HSTPF_MAX_MODELS];
} hstpf_estimate_t;

/*
 * Grid engine capacity: cells per model in position x speed. Override with
 * -D when building the library and its users (they size hstpf_t). More
 * speed than position cells: the types differ in W(v), so the speed axis
 * decides (docs/grid.md, "Cells": Case 2's median decision, 400 seeds,
 * 147 s on 20 x 72 against 152 s on 48 x 48, which has 60 % more cells).
 * cfg.grid_speed_lattice is measured at 20 x 72; at 48 x 48 it declared a
 * wrong type in 3 of 200 paper Case 2 runs: at other capacities, measure
 * it on and off (docs/grid.md, "Cells").
 */
#ifndef HSTPF_GRID_NS
#define HSTPF_GRID_NS 20 /**< grid cells in position */
#endif
#ifndef HSTPF_GRID_NV
#define HSTPF_GRID_NV 72 /**< grid cells in speed */
#endif
#if HSTPF_GRID_NS < 8 || HSTPF_GRID_NV < 8 || HSTPF_GRID_NS > 1024 || HSTPF_GRID_NV > 1024
#error "HSTPF_GRID_NS and HSTPF_GRID_NV must be in [8, 1024]"
#endif
#define HSTPF__GRID_CELLS (HSTPF_GRID_NS * HSTPF_GRID_NV)
#define HSTPF__GRID_K (2 * (HSTPF_GRID_NS > HSTPF_GRID_NV ? HSTPF_GRID_NS : HSTPF_GRID_NV) + 2)

/*
 * The workspace (hstpf_config_t.workspace) each engine needs, in bytes, for
 * n_models models (and n_particles particles): a caller that knows its
 * engine at compile time sizes a static buffer with these; at run time
 * hstpf_workspace_size() gives the same figure for a configuration.
 * Particles: s, v and log weight per particle and model, and three
 * per-particle arrays for one model's step (plus 16-bit counts). Grid:
 * the cells of every model, the transported grid and a model's saved
 * cells for a retried step, and each model's mass at rest. Under
 * Gaussian process noise only cfg.grid_rows rows have a grid:
 * HSTPF_GRID_WS_BYTES(min(grid_rows, n_models)), with grid_rows 0
 * read as n_models. Where the continuous
 * hypothesis runs on a grid (cfg.refine 1 under non-Gaussian process
 * noise, or 2) it is one more grid model: HSTPF_GRID_WS_BYTES(n_models + 1)
 * under non-Gaussian process noise, HSTPF_GRID_WS_BYTES(min(grid_rows,
 * n_models) + 1) with refine 2 under Gaussian process noise.
 */
#define HSTPF_WORKSPACE_ALIGN 8u /**< alignment of the workspace, bytes */
#define HSTPF__WS_ROUND(b) ((((size_t)(b)) + 7u) & ~(size_t)7u)
#define HSTPF_PARTICLE_WS_BYTES(n_models, n_particles)                                                     \
    HSTPF__WS_ROUND(sizeof(hstpf_real_t) * 3u * ((size_t)(n_models) + 1u) * (size_t)(n_particles) +         \
                    sizeof(uint16_t) * (size_t)(n_particles))
#define HSTPF_GRID_WS_BYTES(n_models)                                                                      \
    HSTPF__WS_ROUND(sizeof(hstpf_real_t) * (((size_t)(n_models) + 2u) * (size_t)HSTPF__GRID_CELLS +         \
                                            ((size_t)(n_models) + 1u) * (size_t)HSTPF_GRID_NS + 4u))
/** Enough workspace for any engine with n_models models (and n_particles),
 *  the continuous hypothesis' grid included. */
#define HSTPF_WORKSPACE_ANY_BYTES(n_models, n_particles)                                                   \
    (HSTPF_PARTICLE_WS_BYTES(n_models, n_particles) > HSTPF_GRID_WS_BYTES((n_models) + 1u)                \
         ? HSTPF_PARTICLE_WS_BYTES(n_models, n_particles)                                                 \
         : HSTPF_GRID_WS_BYTES((n_models) + 1u))
/** The largest workspace any engine needs at the compile-time capacities. */
#define HSTPF_WORKSPACE_MAX_BYTES HSTPF_WORKSPACE_ANY_BYTES(HSTPF_MAX_MODELS, HSTPF_MAX_PARTICLES)

/** uint64_t words for a static workspace of b bytes (8-aligned by its type):
 *  static uint64_t ws[HSTPF_WORKSPACE_WORDS(HSTPF_WORKSPACE_MAX_BYTES)]; */
#define HSTPF_WORKSPACE_WORDS(b) ((((size_t)(b)) + 7u) / 8u)

/* Private: the grid engine's state. The cells are in the workspace: p[l]
 * and rest[l] are model l's, work and save are scratch. */
typedef struct {
    hstpf_real_t (*p)[HSTPF__GRID_CELLS];                /* cell masses, row j = speed cell */
    hstpf_real_t (*rest)[HSTPF_GRID_NS];                 /* mass at rest (v = 0), per position cell */
    hstpf_real_t *work;                                  /* the transported grid, HSTPF__GRID_CELLS */
    hstpf_real_t *save;                                  /* a model's cells before the step (+ NS + 4) */
    hstpf_real_t geom[HSTPF_MAX_MODELS + 1][4];          /* s0, ds, v0, dv: first edges, widths (+ the hypothesis') */
    hstpf_real_t pred_mass[HSTPF_MAX_MODELS + 1];        /* mass kept by the last prediction */
    hstpf_real_t rnew[HSTPF_GRID_NS], rpend[HSTPF_GRID_NS]; /* rest being built: held, and to be diffused */
    hstpf_real_t tail;                                   /* mass a box leaves out per side */
    hstpf_real_t theta_sd;                               /* this step's speed sd from theta (the hypothesis' grid) */
    hstpf_real_t row[HSTPF_GRID_NS];                     /* one row */
    hstpf_real_t ms[HSTPF_GRID_NS], mv[HSTPF_GRID_NV];   /* marginals */
    hstpf_real_t vimg[HSTPF_GRID_NV + 1];                /* speed-cell edges after the dynamics */
    hstpf_real_t ks[HSTPF__GRID_K], kv[HSTPF__GRID_K];   /* process-noise kernels */
    int16_t first[HSTPF_GRID_NV], last[HSTPF_GRID_NV];   /* occupied cells of each row */
    int16_t box[4];                                      /* occupied rows and columns of work */
    int16_t slot[HSTPF_MAX_MODELS + 1];                  /* model l's grid (p, rest, geom), -1: none */
} hstpf_grid_ws_t;

/* Private: a Gaussian filter's settle timer (kalman_rest.c) and its
 * evidence: "it stood still at s since the timer began" against the filter. */
typedef struct {
    double t;                             /* time it has looked at rest, s */
    hstpf_real_t s, p;                    /* that position's mean (rel.) and variance; p 0: not begun */
    hstpf_real_t llr;                     /* log LR of the fixes since, stood still against the filter */
    hstpf_real_t zv, zp, zc;              /* stopping: the speed unclamped at 0, its variance (0: none) and
                                           * covariance with the position (kalman_rest.c) */
} hstpf_settle_t;

/* Private per-model state. */
typedef struct {
    hstpf_real_t *s;                      /* particles in the workspace: position rel. to origin */
    hstpf_real_t *v;
    hstpf_real_t *lw;                     /* normalised log weights */
    hstpf_rng_t rng;
    hstpf_real_t k0, k1, k2;              /* xi c0, xi c1 3.6, xi c2 3.6^2 */
    double logq;
    hstpf_real_t s_mean, v_mean, ess, loglik;
    hstpf_real_t s_var, v_var;            /* posterior variances */
    uint8_t held;                         /* 1: the whole posterior at rest this step; 2: perhaps (engine.h) */
    uint8_t k_placed;                     /* grid engine: its Kalman filter placed again this step */
    uint32_t floor_hits, reacquired;
    uint16_t floor_run;                   /* consecutive all-floor steps */
    uint16_t track_hint;
    double kx[2];                         /* Kalman engine: mean (s rel., v) */
    double kp[3];                         /* and covariance (ss, sv, vv) */
    double kll;                           /* grid engine: that filter's last increment */
    hstpf_settle_t rest;                  /* Kalman: its settle timer */
} hstpf_model_t;

/* Private: the continuous-theta hypothesis. */
#define HSTPF_REFINE_NZ 6
typedef struct {
    double kz[HSTPF_REFINE_NZ];                   /* s rel., v, c0, c1, c2, k */
    double kp[HSTPF_REFINE_NZ * HSTPF_REFINE_NZ]; /* covariance, row-major */
    double logq, loglik, nis;                     /* nis: running mean of z^2 */
    hstpf_settle_t rest;                          /* as hstpf_model_t's */
    uint16_t track_hint;
    uint8_t held, active, placed;
    uint8_t floored;                              /* this fix beyond its likelihood floor */
} hstpf_refine_t;

/* Private: whether the reported traction can be right (traction_check.c). */
typedef struct {
    hstpf_model_t sh;  /* the shadow filter: kx, kp, k0..k2, track_hint */
    double cusum;      /* of the shadow's log-likelihood against the bank's, nats */
    uint32_t changes;  /* times the fault was raised */
    uint8_t fault;     /* the reported traction explains the fixes worse than none */
    uint8_t placed;    /* the shadow holds a state */
    uint8_t settle;    /* fixes not tested since it was placed */
    double fault_s;    /* time since the fault was raised */
    double retry_s;    /* how long this one stands: HSTPF_TRAC_RETRY_S, doubled when found again soon after */
    double since_retry_s; /* time since the last retry */
    double logq0[HSTPF_MAX_MODELS + 1]; /* the weights when the CUSUM was last 0 (rows, then the hypothesis) */
    uint8_t release;   /* the train moves although the traction holds it: taken as unknown */
    uint8_t doubt;     /* the CUSUM past HSTPF__TRAC_DOUBT: the weights wait */
    uint8_t rel_run;   /* released: consecutive fixes at which the train looked at rest */
    double rel_d;      /* held: CUSUM of the fixes' lead over the held position */
} hstpf_trac_check_t;

/**
 * The instance. Caller-owned; all members are private and may change
 * between versions. sizeof(hstpf_t) is the bank's state, O(HSTPF_MAX_MODELS)
 * plus the four noise tables and the track; the engine's particles or
 * cells are in the caller's workspace (hstpf_config_t.workspace), sized
 * for the engine and the counts in use. Copying an instance copies the
 * workspace pointer, not the workspace. docs/footprint.md lists measured
 * sizes.
 */
/* A lock on probation (lib/src/lock.c, hstpf__probation): internal. */
typedef struct {
    double base_m;   /* posterior position at its first fix, absolute m */
    double top_m;    /* furthest posterior position in this window, absolute m */
    double t0_s;     /* time_s when this window began */
    double sum[5];   /* the window's fixes: n, sum t, sum y, sum t^2, sum t y (t from t0_s, y from base_m) */
    double end_m;    /* posterior position where the last one ended on its timer */
    uint8_t active;  /* on probation: not valid, the weights wait */
    uint8_t based;   /* base_m is set */
    uint8_t timed;   /* the last one ended on its timer, and the train has not come forward 2 W since */
    uint8_t no_timer; /* this one ends only by coming forward (taken while timed) */
} hstpf_probation_t;

/* A step in the fixes' reference (fix_step.c). */
typedef struct {
    double d;        /* the held fix less the prediction, m */
    /* the last fixes used, newest first (a run of them: a step): each less
     * its prediction, the prediction (from the origin), the speed before
     * it and the time since the fix before */
    hstpf_real_t run[7], run_p[7], run_v[7], run_dt[7];
    uint32_t steps;  /* steps taken */
    uint8_t pend;    /* the last fix was held as a possible step's first */
    int8_t side;     /* where the last fix used lay: -1 / 1 beyond the prediction's reach, 0 within, 2 unknown */
    uint8_t run_n;   /* how many of run[] hold one */
} hstpf_fix_step_t;

typedef struct {
    uint32_t magic;
    hstpf_config_t cfg;              /* models/track pointers cleared */
    hstpf_model_t m[HSTPF_MAX_MODELS + 1]; /* the rows; m[n_models]: the hypothesis' grid, if it has one */
    hstpf_theta_t theta[HSTPF_MAX_MODELS];
    hstpf_dist_quantiles_t ds, dv, unit; /* process noises, N(0,1): never a density */
    hstpf_dist_t de;                      /* the measurement noise, with its density */
    hstpf_track_seg_t track[HSTPF_MAX_TRACK_SEGMENTS];
    hstpf_real_t track_rel[HSTPF_MAX_TRACK_SEGMENTS]; /* starts - origin */
    hstpf_real_t track_acc[HSTPF_MAX_TRACK_SEGMENTS]; /* xi (i + 600/R) */
    hstpf_rng_t rng;                 /* the paired bank's common stream */
    hstpf_real_t *scratch;           /* particle engine, in the workspace */
    hstpf_real_t *nz_s;              /* this step's noise draws */
    hstpf_real_t *nz_v;
    uint16_t *counts;
    double origin_m;                 /* particles are relative to this */
    double time_s;
    double xi;
    double noise_mom[6];             /* mean, sd of w_s, w_v, e: a Gaussian's own, else its table's */
    double held_s;                   /* time the current leader held q > thr */
    double decision_time_s;
    uint32_t steps;
    int16_t leader, declared;
    hstpf_status_t status;
    uint32_t outliers, reacquired;
    uint16_t outlier_run;            /* consecutive gated measurements */
    uint16_t lost_run;               /* consecutive fixes every weighted model put beyond its floor */
    uint8_t have_fix;                /* locked: acquired and tracking */
    uint8_t have_pend;               /* one fix waiting for a second to acquire */
    uint8_t standstill;              /* this step's model weights were held */
    uint8_t weights_wait;            /* held or arriving: this step's weights did not move */
    double arrival_s;                /* time the weighted models disagreed on being at rest */
    double stop_s;                   /* time this standstill has lasted */
    double free_s;                   /* time without a fix used while the traction is unknown */
    double fix_age_s, fix_gap_s;     /* time since the last fix used, and between it and the one before */
    uint8_t mix_pending;             /* a standstill of HSTPF_CONSIST_STOP_S ended: mix at the next weighted step */
    uint8_t ever_locked;
    uint8_t prior_lock;              /* locked from the configured speed prior, no fix fitted since */
    double pend_y;                   /* that fix (after a prior_lock: its fix), absolute m */
    double pend_age_s;               /* time since it */
    uint32_t acquisitions, nonfinite_resets;
    uint32_t backward;               /* fix pairs refused, locks dropped or taken on probation: hstpf_estimate_t */
    double top_m;                    /* furthest posterior position on a fix, absolute m (-inf: none) */
    hstpf_probation_t pr;            /* a lock taken behind top_m */
    hstpf_fix_step_t fs;
    hstpf_refine_t rf;
    hstpf_trac_check_t tc;
    double fit_held_s;               /* time the continuous hypothesis held q > thr */
    uint8_t fit;
    uint8_t engine;                  /* hstpf_engine_t resolved at init (never AUTO) */
    hstpf_grid_ws_t grid;            /* the grid engine's state; its cells are in the workspace */
} hstpf_t;

/**
 * @brief Fills cfg with the defaults listed beside each field: the paper's
 * Case 1 noise, 100 particles, no models (set models and n_models).
 * @return HSTPF_OK or HSTPF_E_NULL. Cost O(1).
 */
int32_t hstpf_config_default(hstpf_config_t *cfg);

/**
 * @brief Checks a configuration against the library's one table of ranges
 * (the same check hstpf_init() makes, but for the workspace, which is
 * memory rather than configuration), without an instance.
 * @param cfg    configuration to check.
 * @param field  if not NULL, set to the name of the first failing field
 *               (e.g. "noise_e", "models.c1", "track.start_m": the
 *               field, not the row or the noise's member), or to "" when
 *               valid. A static string.
 * @return HSTPF_OK or the error hstpf_init() would return. Cost
 *   O(n_models + n_track); no memory.
 */
int32_t hstpf_config_check(const hstpf_config_t *cfg, const char **field);

/**
 * @brief The workspace, in bytes, that hstpf_init() needs for cfg: for the
 * engine cfg resolves to (AUTO included) with its n_models and n_particles.
 * 0 for the Kalman engine. The workspace fields of cfg are not read.
 * @param cfg    configuration (checked as by hstpf_config_check()).
 * @param bytes  set to the size on success.
 * @return HSTPF_OK, HSTPF_E_NULL, or the error hstpf_config_check() gives.
 *   Cost O(n_models + n_track).
 */
int32_t hstpf_workspace_size(const hstpf_config_t *cfg, size_t *bytes);

/**
 * @brief Initialises an instance: validates cfg, copies the models and the
 * track, builds the noise tables and seeds one RNG stream per model.
 * The models are placed when the filter acquires lock from its first fixes
 * (docs/model.md, "Acquisition and lock"): from two fixes with the default
 * diffuse speed prior, from the first with a configured one.
 * @param f       caller-owned instance.
 * @param f_size  sizeof(hstpf_t) as the caller sees it (HSTPF_E_ABI if it
 *                differs from the library's: mismatched capacity macros).
 * @param cfg     configuration (not kept; models and track are copied;
 *                the workspace is kept, see hstpf_config_t.workspace).
 * @return HSTPF_OK; HSTPF_E_NULL (also: no workspace where the engine needs
 *   one); HSTPF_E_ABI; HSTPF_E_SIZE (n_models, n_particles, n_track; a
 *   workspace smaller than hstpf_workspace_size() or not aligned to
 *   HSTPF_WORKSPACE_ALIGN); HSTPF_E_NONFINITE; HSTPF_E_RANGE (coefficients,
 *   gamma_rot, prior, track values out of range, track not increasing);
 *   HSTPF_E_CONFIG (enums, engine KALMAN with non-Gaussian noise,
 *   ess_threshold, q_floor, declare_threshold, declare_hold_s, gate_m,
 *   dt_nominal_s, roughening values); HSTPF_E_DIST
 *   (from hstpf_dist_init()). On error *f is unchanged.
 * Cost: four hstpf_dist_init() calls; no memory besides *f and the workspace.
 */
int32_t hstpf_init(hstpf_t *f, size_t f_size, const hstpf_config_t *cfg);

/**
 * @brief Restarts the estimation with the same configuration, as after
 * hstpf_init: states, spreads and counters zero, uniform model weights, no
 * declaration, particles drawn again at the next fix. RNG streams continue
 * (not re-seeded); the Kalman and grid engines, which draw none, then
 * repeat a fresh instance's run exactly.
 * @return HSTPF_OK, HSTPF_E_NULL or HSTPF_E_INIT. Cost O(models).
 */
int32_t hstpf_reset(hstpf_t *f);

/**
 * @brief Tells the estimator that the consist changed (coupled or split)
 * while it kept running: the model weights return to their prior, the
 * continuous hypothesis' theta to Table 1's prior, and a declared type is
 * withdrawn (status WITHDRAWN, declared -1; UNDECIDED if none was). The
 * lock, position and speed are kept: the train is where it was.
 * Without this call a changed consist is found from the data
 * (hstpf_config_t.consist_change_p; docs/model.md).
 * @return HSTPF_OK, HSTPF_E_NULL or HSTPF_E_INIT. Cost O(models).
 */
int32_t hstpf_consist_changed(hstpf_t *f);

/**
 * @brief Drops the lock: the filter re-acquires position and speed from the
 * next fixes (as at the start), keeping the model weights and the
 * declaration. For a caller that knows the time base broke (a receive-clock
 * step), or that the position reference turned round (it also forgets how
 * far the fixes had come, so fixes behind that point may lock again;
 * hstpf_input_t.position_m). The estimate reads valid = 0 until re-acquired.
 * @return HSTPF_OK, HSTPF_E_NULL or HSTPF_E_INIT. Cost O(1).
 */
int32_t hstpf_reacquire(hstpf_t *f);

/**
 * @brief Advances every model by one step and, with a position, updates
 * particle weights, model weights and the declaration.
 * Without lock (before the first fixes, after a step longer than
 * max_gap_s, after hstpf_reacquire() or a non-finite state) a step only
 * advances time and its fix serves the acquisition. While every weighted
 * model is held at rest the model weights are not updated (standstill).
 * @return HSTPF_OK; HSTPF_E_NULL; HSTPF_E_INIT; HSTPF_E_NONFINITE (dt,
 *   traction or position NaN/Inf); HSTPF_E_DT; HSTPF_E_RANGE (|traction| >
 *   HSTPF_U_MAX, |position| > HSTPF_POS_MAX_M): on these *f is unchanged.
 *   HSTPF_E_OUTLIER (position farther than gate_m from the blended
 *   prediction, or held as a possible step in the fixes' reference, see
 *   cfg.fix_step): the step WAS taken, as a prediction without the fix; the
 *   outlier counters advance and the fix is kept as a possible first fix
 *   of a re-acquisition (after reacquire_after in a row).
 * Cost: O(n_models x n_particles): per particle two RNG draws and table
 * samples, the model update, one log-density and one exp look-up; per model
 * one log(); bounded. The Kalman engine: O(n_models), about 60 flops and
 * one log() per model. The grid engine: O(grid models x HSTPF_GRID_NS x
 * HSTPF_GRID_NV x kernel taps), a few log() per model, bounded, where the
 * grid models are min(cfg.grid_rows, n_models) under Gaussian process
 * noise (plus a Kalman step per row), every row otherwise, and the
 * continuous hypothesis' grid if it has one (docs/grid.md measures it).
 * The worst step costs a few times the median (a fix far off with a
 * heavy-tailed noise table, a step near max_gap_s; docs/footprint.md).
 * Stack: 1 200 B painted on a Cortex-M4F with libm, the largest engine
 * (budgeted at 1 240 B in the cross test; up to about 1.3 KiB on x86-64);
 * no other memory.
 */
int32_t hstpf_step(hstpf_t *f, const hstpf_input_t *in);

/**
 * @brief Writes the current estimate. Before the first acquisition the states
 * are zero (the position is the pending fix, if any) and the weights
 * uniform; out->valid says whether the estimate may be used.
 * @return HSTPF_OK, HSTPF_E_NULL or HSTPF_E_INIT. Cost O(n_models).
 */
int32_t hstpf_estimate(const hstpf_t *f, hstpf_estimate_t *out);

/** The 95 % band of the whole curve W(v), in sd of W at each speed: the
 *  square root of the chi-square 95 % quantile with 3 degrees of freedom.
 *  W(v) = h'theta is linear in theta, so the curve lies within W +- z sd
 *  at every speed exactly when theta lies within its 95 % ellipsoid
 *  (Scheffe's band; docs/model.md). 1.96 holds one speed only. */
#define HSTPF_BAND_Z_CURVE 2.7955

/**
 * @brief Running resistance W(v) of an estimate's theta and its standard
 * deviation from theta_cov: W = h'theta, sd^2 = h' Cov h, h = (1, V, V^2),
 * V = 3.6 v km/h. W +- 1.96 sd holds W at one speed with 95 %; a band for
 * the whole curve, which holds W at every speed at once with 95 %, is
 * W +- HSTPF_BAND_Z_CURVE sd.
 * @return HSTPF_OK; HSTPF_E_NULL; HSTPF_E_NONFINITE (v, or the estimate's
 *   W or variance at v not finite: *w and *sd are then unchanged). Cost O(1).
 */
int32_t hstpf_resistance_band(const hstpf_estimate_t *e, double v_mps, double *w, double *sd);

/**
 * @brief Copies the particles of model `model` (absolute positions) into
 * caller arrays of at least n_particles elements, and their normalised
 * weights (may be NULL). For plots and tests.
 * @return HSTPF_OK; HSTPF_E_NULL; HSTPF_E_INIT; HSTPF_E_SIZE (model out of
 *   range); HSTPF_E_CONFIG (the Kalman engine has no particles).
 *   Cost O(n_particles).
 */
int32_t hstpf_particles(const hstpf_t *f, uint16_t model, double *s,
                        hstpf_real_t *v, hstpf_real_t *w);

/**
 * @brief Additional track resistance i + 600 / R (N/kN) at absolute position
 * pos_m of the instance's profile; 0 with no profile or before its first
 * segment. @return HSTPF_E_NULL/HSTPF_E_INIT as for the others, else
 * HSTPF_OK and *g_out set. Cost O(n_track).
 */
int32_t hstpf_track_resistance(const hstpf_t *f, double pos_m, double *g_out);

#ifdef __cplusplus
}
#endif

#endif /* HSTPF_HSTPF_H */
