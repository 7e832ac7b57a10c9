/* hstpf-mc: Monte Carlo study of the estimator over many independent seeds
 * (simulation and filter seeds separate), per scenario and true type.
 * Prints a table and, with --json, machine-readable results; --trace writes
 * one run's time series for the figures. Journey scenarios (station stops,
 * a day, a start at speed, clock steps, an outage, a traction-gain bias)
 * print their own table (docs/results.md). */
#define _POSIX_C_SOURCE 200112L

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "hstpf/hstpf.h"
#include "hstpf_sim.h"

#define MAXM HSTPF_MAX_MODELS
#define NAME_MAX_LEN 31 /* a custom row's name, as hstpfd's models key */

/* all17 scenarios put every row of Table 1 in the bank */
typedef char mc_table_fits_bank[HSTPF_N_TRAIN_TYPES <= MAXM ? 1 : -1];

typedef struct {
    const char *name;
    int paper_case;             /* 1 or 2: noise of the paper's case; 3 or 4: Case 1 with the
                                 * Student-t or the multipath-mixture position noise */
    hstpf_profile_t profile;
    double loss_rate;
    int all17;                  /* models: all 17 types; else the case's 3 */
    double duration_s;
    int hilly;                  /* simulate on the hilly track */
    int filter_knows_track;     /* give the track profile to the filter */
    /* journeys (zero for the others) */
    const struct timetable *tt; /* the truth runs this timetable (profile JOURNEY) */
    double clock_step_s;        /* receive-clock step at clock_at_s, s (0 = none) */
    double clock_at_s;
    int outage;                 /* GNSS outage of 20-60 s: 1 during an acceleration, 2 across a stop
                                 * (from 10 m/s braking into it, ~20 s before the train stands) */
    double gain_bias;           /* traction reported = (1 + gain_bias) x applied */
    double sign_flip_at_s;      /* > 0: from then on the traction is reported with the wrong sign */
    /* trains not on Table 1 (issue 10; zero for the others) */
    double perturb;             /* each coefficient of the truth x (1 +- perturb), sign per seed */
    double grade_permille;      /* an unmodelled constant gradient */
    int common;                 /* perturb: one factor (1 +- perturb) for all three, mass-like */
    int absent;                 /* the truth's row is not in the filter's bank */
    /* a reference that restarts (zero for the others) */
    double restart_after_s;     /* at the first stop held after this, the fixes restart at 0 */
    double swap_after_s;        /* at the first stop held after this, the truth becomes row truth + swap_rows */
    int swap_rows;
    double trac_gap_at_s;       /* no traction from here for 20-60 s (0 = none) */
    int gap_no_fix;             /* and no fix either: both inputs silent (a bus that drops out) */
    /* long steps (zero for the others): the inputs of merge_s seconds from
     * merge_at_s fed as one step with the next (an input gap), or one step
     * per step_every seconds (sparse fixes), each with the mean traction */
    double merge_at_s, merge_s;
    int step_every;
    /* a traction signal stuck at its value at stuck_at_s for stuck_s (0 = none) */
    double stuck_at_s, stuck_s;
    /* the fixes (not the train) off by fix_off_m from fix_off_at_s for
     * fix_off_s, again every fix_off_every_s with the sign alternating (0 =
     * once): a GNSS bias that steps, a lone outlier */
    double fix_off_m, fix_off_at_s, fix_off_s, fix_off_every_s;
    /* > 0: the unit is configured for a power-up at rest, a speed prior
     * N(0, init_speed_sd^2) (0 = the default, the speed from two fixes) */
    double init_speed_sd;
    /* > 0: the step and the filter's dt_nominal_s, s (0 = 1 s): a unit stepped at 10 Hz; the
     * process noises are Case 1's per second scaled to the step (a random walk's variance in
     * proportion to T) unless step_noise_per_step, when Case 1's per-step figures are taken
     * per step as given (ten times the variance per second at 10 Hz); a fix every step */
    double step_s;
    int step_noise_per_step;
} scenario_t;

typedef struct timetable {
    const hstpf_sim_leg_t *legs;
    uint16_t n_legs;
    double first_dwell_s;       /* standing at the origin first; < 0: start running */
    double v0_kmh;              /* speed at the first fix */
} timetable_t;

#define MAX_STOPS 24
#define OUTAGE_LEG 1            /* the outage starts OUTAGE_AFTER_S into this leg's run */
#define OUTAGE_AFTER_S 100.0    /* accelerating at HSTPF_SIM_ACCEL, ~40 m/s */

/* Journey metrics of one run (docs/results.md explains each). */
typedef struct {
    int false_at_rest;          /* the first false declaration's hold window saw the truth standing */
    int false_outside_pair;     /* a type outside the truth's near-identical pair was declared */
    int n_stops;
    double tv[MAX_STOPS];       /* total-variation change of q from rest to departure, per stop */
    double v_min_rest;          /* lowest speed estimate while the truth stood */
    double pe10;                /* |position error| 10 s after the event (first fix, clock step) */
    double pe_max_after;        /* max |position error| after that */
    uint32_t outliers, reacquired, acquisitions, fix_steps;
    long cover_p, cover_v, n_cover; /* steps inside the 95 % intervals, steps counted */
    long assert_fail;           /* steps where declared, status and theta disagree */
    double outage_s;            /* outage length drawn for this run, s */
    long out_cover_p, out_cover_v, n_out; /* the same, outage steps only */
    double out_pe_max;          /* max |position error| during the outage */
    double restart_t;           /* when the reference restarted (-1: it did not) */
    double revalid_s;           /* from then to the first valid step (-1: none) */
    long n_restart, n_restart_valid; /* steps after it, and of those valid */
    double restart_pe_max;      /* max |position error| at a valid step after it, new reference */
    double gap_s;               /* the traction gap drawn for this run, s (0: none) */
    long gap_bad;               /* valid steps in the gap and 30 s after it more than 5 sd off */
    long gap_still;             /* steps in that window published at standstill while the train moved */
    double gap_ev_max;          /* max |speed error| at a valid step in that window, m/s */
    double gap_tv;              /* total variation of the weights across the gap */
    long still_moving;          /* steps published at standstill while the train moved (whole run) */
    long moving_still;          /* valid steps published moving (not at standstill, over 0.3 m/s) while the train stood */
    long v_bad;                 /* valid steps whose speed was more than 5 sd and 0.3 m/s off (whole run) */
    long trac_fault;            /* steps with traction_fault raised */
    double trac_cusum_max;      /* the traction check's largest CUSUM while it believed the traction, nats */
    double swap_t;              /* when the truth changed type (-1: it did not) */
    int swap_decl;              /* the type declared then (-1: none) */
    double swap_old_s;          /* how long after the change the old type stayed declared (-1: it was not) */
    double swap_new_s;          /* when after it the new truth was first declared (-1: never) */
    double swap_w_max;          /* max |W(v) error| at 300 km/h while a wrong type was declared and valid */
    double swap_w_end;          /* RMS relative W(v) error against the new truth at the end */
} journey_t;

/* Filter settings under study: the same for every scenario and truth. */
typedef struct {
    hstpf_config_t base;
    double floor_depth, edge_soft;
    int floor_set, soft_set;
    int gauss_e;                /* the filter is told a Gaussian of e's sd, not e's density */
    int oracle;                 /* --oracle: the truth's own theta scored beside its nearest rows */
    int gap_hold;               /* --gap-hold: a traction gap feeds the last traction, as hstpfd did */
} settings_t;

typedef struct {
    int truth_index;            /* into the model set */
    int success;                /* true q > 0.9 from some time to the end */
    double t_cross;             /* start of that final stretch */
    double t_declare;           /* Table 2 rule fired for the truth (-1) */
    int false_decl;             /* a wrong type was declared at some time */
    double false_time;          /* when it first was (-1) */
    int false_model;            /* which (-1) */
    int final_declared;         /* model index or -1 */
    double par_err[3];          /* |theta - true| / true at the end */
    double par_err_max_after[3]; /* max after the decision */
    double w_rms;               /* RMS relative error of W(v), 0..350 km/h, at the end */
    double pos_rms, spd_rms;    /* over the run after the first 60 s */
    double pos_bias;            /* mean signed position error (estimate - truth), same span */
    uint32_t floor_hits_true;
    double q_true_end;
    int nofit_end;              /* "no table type fits" at the end */
    int band_covers;            /* the W(v) band +- 1.96 sd covers the truth at >= 95 % of 0..350 km/h */
    int curve_covers;           /* the curve's band +- HSTPF_BAND_Z_CURVE sd covers it at every speed */
    double theta_nees;          /* (theta - truth)' theta_cov^-1 (theta - truth) at the end; -1: singular */
    double d_table;             /* the truth's W(v) distance from its nearest bank row (w_dist_row) */
    int near_row;               /* that row */
    /* --oracle: a second bank on the same inputs, the truth's own theta
     * beside its ORACLE_ROWS nearest rows, without the hypothesis; its
     * cumulative log-likelihood ratios, the truth's against a row */
    double or_sep;              /* the truth leads its nearest row by log 99 from here to the end (-1: not at the end) */
    double or_lead;             /* on the table: the truth's row leads the bank's rows from here to the end (-1: not) */
    double or_sep_lead;         /* and leads the 8 trains by log 99 counting from there only (-1: not at the end) */
    double or_nb_first;         /* off the table: the nearest row first leads its 8 trains by log 99 (-1: never) */
    int or_nb_decl;             /* ... at a step where the filter had that row declared */
    int or_near_decl;           /* the filter declared the nearest row, not the truth's own, at some step */
    double or_llr_decl;         /* against the wrongly declared row when first declared (NaN: not among them) */
    double or_llr_near_decl;    /* against the nearest row at that time */
    journey_t j;
} run_t;

typedef struct {
    const scenario_t *sc;
    const settings_t *st;
    const hstpf_theta_t *models;
    int n_models;
    const int *truths;          /* truth index per job */
    int n_jobs;
    int seeds;
    run_t *runs;                /* n_jobs * seeds */
    int next;                   /* job counter, under lock */
    int done;                   /* runs finished, under lock */
    pthread_mutex_t lock;
    const char *trace_path;     /* run of trace_seed of the first job */
    int trace_seed;
    int first_seed;             /* seeds first_seed .. first_seed + seeds - 1 */
} work_t;

static const hstpf_track_seg_t hilly_track[] = {
    /* a hilly line: long grades of +-12 per mille and curves, every few km */
    {0.0, 0.0, 0.0},       {3000.0, 12.0, 0.0},    {9000.0, 3.0, 7000.0},
    {14000.0, -12.0, 0.0}, {20000.0, 8.0, 5500.0}, {28000.0, 12.0, 0.0},
    {36000.0, -6.0, 0.0},  {44000.0, 10.0, 8000.0}, {54000.0, -12.0, 0.0},
    {64000.0, 12.0, 0.0},  {76000.0, 0.0, 6000.0}, {88000.0, 9.0, 0.0},
    {100000.0, -9.0, 0.0}, {115000.0, 12.0, 0.0},  {130000.0, -12.0, 0.0},
    {145000.0, 6.0, 0.0},
};

/* d' S^-1 d for the symmetric 3 x 3 S given as (00, 01, 02, 11, 12, 22), by
 * its Cholesky factor scaled to unit diagonal (the coefficients differ by
 * 1e4); -1 when S is not positive definite. */
static double nees3(const hstpf_real_t *c, const double *d)
{
    const double s0 = sqrt((double)c[0]), s1 = sqrt((double)c[3]), s2 = sqrt((double)c[5]);
    double a[3][3], l[3][3] = {{0}}, y[3], e[3], q = 0.0;
    int i, j, k;
    if (!(s0 > 0.0 && s1 > 0.0 && s2 > 0.0)) {
        return -1.0;
    }
    a[0][0] = 1.0, a[1][1] = 1.0, a[2][2] = 1.0;
    a[0][1] = a[1][0] = (double)c[1] / (s0 * s1);
    a[0][2] = a[2][0] = (double)c[2] / (s0 * s2);
    a[1][2] = a[2][1] = (double)c[4] / (s1 * s2);
    e[0] = d[0] / s0, e[1] = d[1] / s1, e[2] = d[2] / s2;
    for (i = 0; i < 3; ++i) {
        for (j = 0; j <= i; ++j) {
            double v = a[i][j];
            for (k = 0; k < j; ++k) {
                v -= l[i][k] * l[j][k];
            }
            if (i == j) {
                if (!(v > 1e-12)) {
                    return -1.0;
                }
                l[i][i] = sqrt(v);
            } else {
                l[i][j] = v / l[j][j];
            }
        }
    }
    for (i = 0; i < 3; ++i) { /* L y = e; the NEES is |y|^2 */
        double v = e[i];
        for (k = 0; k < i; ++k) {
            v -= l[i][k] * y[k];
        }
        y[i] = v / l[i][i];
        q += y[i] * y[i];
    }
    return q;
}

static double w_rms_rel(const double th[3], const hstpf_theta_t *truth)
{
    double acc = 0.0;
    int k;
    for (k = 0; k <= 70; ++k) {
        const double vk = 5.0 * k; /* km/h */
        const double wt = truth->c0 + truth->c1 * vk + truth->c2 * vk * vk;
        const double we = th[0] + th[1] * vk + th[2] * vk * vk;
        acc += ((we - wt) / wt) * ((we - wt) / wt);
    }
    return sqrt(acc / 71.0);
}

/* How far a truth is from a row: RMS over 0..350 km/h of (W_truth - W_row)
 * / W_row, relative to the row as "15 % off a row" is. */
static double w_dist_row(const hstpf_theta_t *truth, const hstpf_theta_t *row)
{
    const double tr[3] = {truth->c0, truth->c1, truth->c2};
    return w_rms_rel(tr, row);
}

/* The near-identical pairs of Table 1: 0, 1, 2, or -1 for the others. */
static int pair_of(const char *name)
{
    static const char *pairs[3][2] = {
        {"CRH2", "CRH3"}, {"Star EMU Central Plains", "China Star"}, {"SS8", "ND5"}};
    int i;
    for (i = 0; name != NULL && i < 3; ++i) {
        if (!strcmp(name, pairs[i][0]) || !strcmp(name, pairs[i][1])) {
            return i;
        }
    }
    return -1;
}

static int in_pair(const hstpf_theta_t *models, int truth, int m)
{
    const int p = pair_of(models[truth].name);
    return m == truth || (p >= 0 && pair_of(models[m].name) == p);
}

/* The header's contract: status DECLARED/CHANGED <=> declared >= 0, and a
 * declared type publishes its own row's theta (relative 1e-6). */
static int decl_consistent(const hstpf_estimate_t *e, const hstpf_theta_t *models, int n)
{
    const int by_status = e->status == HSTPF_STATUS_DECLARED || e->status == HSTPF_STATUS_CHANGED;
    int k;
    if (by_status != (e->declared >= 0) || e->declared >= n) {
        return 0;
    }
    for (k = 0; e->declared >= 0 && k < 3; ++k) {
        const hstpf_theta_t *th = &models[e->declared];
        const double c = k == 0 ? th->c0 : (k == 1 ? th->c1 : th->c2);
        if (!(fabs((double)e->theta[k] - c) <= 1e-6 * fabs(c))) {
            return 0;
        }
    }
    return 1;
}

static double tv_dist(const double *a, const hstpf_estimate_t *e, int n)
{
    double acc = 0.0;
    int k;
    for (k = 0; k < n; ++k) {
        acc += fabs((double)e->model[k].q - a[k]);
    }
    return 0.5 * acc;
}

/* A bank index as an index of w->models: with the truth's row left out
 * (scenario absent) the rows after it moved down by one; -1 stays -1. */
static int table_index(const work_t *w, int truth, int b)
{
    return b < 0 ? -1 : (w->sc->absent && b >= truth ? b + 1 : b);
}

/* The noise sp replaced by a Gaussian of its mean and sd; opt names the
 * option that asked, for the message when sp does not build. */
static void gauss_of(hstpf_dist_spec_t *sp, const char *opt)
{
    hstpf_dist_t *d = malloc(sizeof *d);
    if (d == NULL || hstpf_dist_init(d, sp) != HSTPF_OK) {
        fprintf(stderr, "hstpf-mc: %s: a noise does not build\n", opt);
        exit(1);
    }
    memset(sp, 0, sizeof *sp);
    sp->kind = HSTPF_DIST_GAUSSIAN;
    sp->mean = (double)d->qt.mean;
    sp->sd = (double)d->qt.sd;
    free(d);
}

#define ORACLE_ROWS 4 /* the rows nearest the truth scored in the oracle's bank */
#define ORACLE_NEAR 0.10 /* on the table: trains this far from the truth's row in W(v) */
#define ORACLE_MAX 13 /* the larger of the two banks */
#define LOG99 4.59511985013459 /* log(0.99 / 0.01): the evidence a 0.99 weight stands for */

/* A train on its row: no perturbation, grade, gain bias or missing row. */
static int on_table(const scenario_t *sc)
{
    return sc->perturb == 0.0 && sc->grade_permille == 0.0 && sc->gain_bias == 0.0 && sc->sign_flip_at_s == 0.0 && !sc->absent;
}

/* The eight trains ORACLE_NEAR from row in W(v) (w_dist_row), one per
 * sign pattern of (c0, c1, c2), scaled to that distance; oi[k] = -1. */
static void neighbours(const hstpf_theta_t *row, hstpf_theta_t *ob, int *oi)
{
    int k;
    for (k = 0; k < 8; ++k) {
        const double s0 = (k & 1) ? 1.0 : -1.0, s1 = (k & 2) ? 1.0 : -1.0, s2 = (k & 4) ? 1.0 : -1.0;
        hstpf_theta_t a = {row->name, row->c0 * (1.0 + 0.1 * s0), row->c1 * (1.0 + 0.1 * s1), row->c2 * (1.0 + 0.1 * s2)};
        const double e = 0.1 * ORACLE_NEAR / w_dist_row(&a, row); /* the distance is linear in the perturbation */
        a.c0 = row->c0 * (1.0 + e * s0);
        a.c1 = row->c1 * (1.0 + e * s1);
        a.c2 = row->c2 * (1.0 + e * s2);
        ob[k] = a;
        oi[k] = -1;
    }
}

/* The oracle's bank: ob[0] the truth's own theta (with an unmodelled grade
 * as c0, as the distance counts it), then the filter's rows nearest it in
 * W(v); their indices of w->models in oi[1..]; then the nearest row's
 * eight trains ORACLE_NEAR from it (neighbours()). On the table, instead, the
 * eight trains ORACLE_NEAR from the truth's row in W(v) (w_dist_row), one
 * per sign pattern of (c0, c1, c2), scaled to that distance. Returns the
 * bank size. */
static int oracle_bank(const work_t *w, int truth, const hstpf_theta_t *wt, hstpf_theta_t *ob, int *oi)
{
    int n = 1, k, i;
    double d[ORACLE_ROWS + 1];
    ob[0] = *wt;
    oi[0] = -1;
    if (on_table(w->sc)) {
        neighbours(wt, ob + 1, oi + 1);
        return 9;
    }
    for (k = 0; k < w->n_models; ++k) {
        const double dk = w_dist_row(wt, &w->models[k]);
        if (w->sc->absent && k == truth) {
            continue; /* not in the filter's bank */
        }
        for (i = n; i > 1 && dk < d[i - 1]; --i) { /* insertion into the sorted rows */
            if (i <= ORACLE_ROWS) {
                d[i] = d[i - 1];
                ob[i] = ob[i - 1];
                oi[i] = oi[i - 1];
            }
        }
        if (i <= ORACLE_ROWS) {
            d[i] = dk;
            ob[i] = w->models[k];
            oi[i] = k;
            n += n <= ORACLE_ROWS;
        }
    }
    if (n > 1) { /* and the nearest row's eight */
        neighbours(&ob[1], ob + n, oi + n);
        n += 8;
    }
    return n;
}

static void one_run(const work_t *w, int truth, int seed, run_t *r, FILE *trace)
{
    static const double thr = 0.9;
    hstpf_t *f = malloc(sizeof *f); /* the tool, not the library, allocates */
    hstpf_config_t cfg = w->st->base;
    hstpf_sim_config_t sc;
    hstpf_sim_table_t etab; /* a heavy position noise's table: lives for the run */
    hstpf_sim_t sim;
    hstpf_estimate_t est;
    hstpf_sim_sample_t smp;
    double last_below = 0.0, se_p = 0.0, se_v = 0.0, sb_p = 0.0, n_after = 0.0;
    long n_err = 0;
    int k;
    /* journey bookkeeping */
    const timetable_t *tt = w->sc->tt;
    journey_t *jr = &r->j;
    double q_rest[MAXM], out_start = -1.0, last_rest_t = -1e9;
    const double t_event = w->sc->clock_step_s != 0.0 ? w->sc->clock_at_s : 0.0;
    int at_rest = 0, have_fix = 0; /* at_rest: 1 standing, 2 and held */
    double ref_off = 0.0;          /* the reference's restart: added to the truth and its fixes */
    double acc_dt = 0.0, acc_u = 0.0; /* inputs merged into the next step (long steps) */
    double u_stuck = 0.0;             /* the stuck traction's value */
    double u_known = 0.0, q_gap[MAXM]; /* the traction gap: the last traction before it, the weights */
    int decl_prev = -1, new_truth = -1; /* the type change: the declared row before the step, the new truth */
    hstpf_theta_t bank[MAXM];
    /* --oracle */
    hstpf_t *fo = NULL;
    hstpf_theta_t ob[ORACLE_MAX];
    int oi[ORACLE_MAX], no = 0;
    double ol[ORACLE_MAX] = {0}, sep_below = 0.0;
    /* on the table: ol when the truth's row last took the lead, and the
     * last step its lead over the 8 counted from there was short of log 99 */
    double ol_lead[ORACLE_MAX] = {0}, lead_t = -1.0, lead_below = 0.0;
    int nb_pass = 0, nsep = 0, led = 0;
    const int ontab = on_table(w->sc);
    int decl;                       /* the declared row as an index of w->models, -1 none */
    const int tq = w->sc->absent ? -1 : truth; /* the truth's index in the bank */
    if (f == NULL) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    memset(r, 0, sizeof *r);
    r->truth_index = truth;
    r->t_declare = -1.0;
    r->false_time = -1.0;
    r->false_model = -1;
    jr->v_min_rest = HUGE_VAL;
    jr->pe10 = -1.0;
    jr->restart_t = jr->revalid_s = -1.0;
    jr->swap_t = jr->swap_old_s = jr->swap_new_s = -1.0;
    jr->swap_decl = -1;
    hstpf_sim_default(&sc);
    sc.truth = w->models[truth];
    sc.profile = w->sc->profile;
    sc.loss_rate = w->sc->loss_rate;
    if (w->sc->paper_case == 2) {
        hstpf_sim_case2(&sc);
    } else if (w->sc->paper_case >= 3) {
        /* drawn exactly by the simulator; the filter gets the same density as a table */
        hstpf_sim_heavy(&sc, w->sc->paper_case == 3 ? HSTPF_SIM_HEAVY_T : HSTPF_SIM_HEAVY_MIX, &etab);
    }
    if (w->sc->hilly) {
        sc.track = hilly_track;
        sc.n_track = (uint16_t)(sizeof hilly_track / sizeof hilly_track[0]);
    }
    /* independent streams: simulation from seed, filter from another */
    sc.seed = 1000003ull * (uint64_t)(truth + 1) + (uint64_t)seed;
    if (w->sc->perturb > 0.0) {
        hstpf_rng_t prng; /* its own stream: signs of the perturbation */
        const uint32_t bits = ((void)hstpf_rng_seed(&prng, sc.seed, 0x0FFu), hstpf_rng_next(&prng));
        const uint32_t b1 = w->sc->common ? ((bits & 1u) ? 7u : 0u) : bits;
        sc.truth.c0 *= 1.0 + ((b1 & 1u) ? w->sc->perturb : -w->sc->perturb);
        sc.truth.c1 *= 1.0 + ((b1 & 2u) ? w->sc->perturb : -w->sc->perturb);
        sc.truth.c2 *= 1.0 + ((b1 & 4u) ? w->sc->perturb : -w->sc->perturb);
    }
    if (w->sc->grade_permille != 0.0) {
        static hstpf_track_seg_t grade[1];
        grade[0].start_m = -1e7;
        grade[0].gradient_permille = w->sc->grade_permille;
        grade[0].curve_radius_m = 0.0;
        sc.track = grade; /* the filter is not told */
        sc.n_track = 1;
    }
    if (tt) {
        sc.profile = HSTPF_PROFILE_JOURNEY;
        sc.legs = tt->legs;
        sc.n_legs = tt->n_legs;
        sc.first_dwell_s = tt->first_dwell_s;
        sc.v0_mps = tt->v0_kmh / 3.6;
    }
    if (w->sc->trac_gap_at_s > 0.0) {
        hstpf_rng_t grng; /* its own stream */
        (void)hstpf_rng_seed(&grng, sc.seed, 0x7A6Au);
        jr->gap_s = 20.0 + (double)(hstpf_rng_next(&grng) % 41u); /* 20..60 s */
    }
    if (w->sc->outage) {
        hstpf_rng_t orng; /* its own stream: the trajectory does not change */
        (void)hstpf_rng_seed(&orng, sc.seed, 0x0A7Au);
        jr->outage_s = 20.0 + (double)(hstpf_rng_next(&orng) % 41u); /* 20..60 s */
    }
    cfg.seed = 0x9E3779B97F4A7C15ull ^ (7919ull * (uint64_t)(truth + 1) + (uint64_t)seed);
    if (w->sc->step_s > 0.0) {
        sc.dt_s = w->sc->step_s;
        cfg.dt_nominal_s = w->sc->step_s;
        if (!w->sc->step_noise_per_step) {
            sc.noise_s.sd *= sqrt(w->sc->step_s);
            sc.noise_v.sd *= sqrt(w->sc->step_s);
        }
    }
    cfg.noise_s = sc.noise_s;
    cfg.noise_v = sc.noise_v;
    if (w->sc->init_speed_sd > 0.0) {
        cfg.init_speed_mps = 0.0;
        cfg.init_speed_sd = w->sc->init_speed_sd;
    }
    cfg.noise_e = sc.noise_e;
    if (w->st->gauss_e && cfg.noise_e.kind != HSTPF_DIST_GAUSSIAN) {
        /* a filter that knows only the variance: what knowing the density buys */
        gauss_of(&cfg.noise_e, "--gauss-e");
    }
    if (w->st->floor_set) {
        cfg.noise_e.floor_depth = w->st->floor_depth;
    }
    if (w->st->soft_set) {
        cfg.noise_e.edge_soft = w->st->edge_soft;
    }
    cfg.models = w->models;
    cfg.n_models = (uint16_t)w->n_models;
    if (w->sc->absent) {
        /* the bank without the truth's row; bank index b is models[gidx(b)] */
        for (k = 0; k + 1 < w->n_models; ++k) {
            bank[k] = w->models[k < truth ? k : k + 1];
        }
        cfg.models = bank;
        cfg.n_models = (uint16_t)(w->n_models - 1);
    }
    if (w->sc->filter_knows_track) {
        cfg.track = sc.track;
        cfg.n_track = sc.n_track;
    }
    {
        size_t wsn = 0;
        int32_t rc = hstpf_workspace_size(&cfg, &wsn);
        /* malloc's alignment covers HSTPF_WORKSPACE_ALIGN; sized for this run's engine */
        cfg.workspace = wsn > 0 ? malloc(wsn) : NULL;
        cfg.workspace_size = wsn;
        if (rc == HSTPF_OK) {
            rc = hstpf_init(f, sizeof *f, &cfg);
        }
        if (rc != HSTPF_OK) {
            const char *field = "";
            (void)hstpf_config_check(&cfg, &field);
            /* the scenarios' settings pass: an option's value did not (e.g. --threshold 1.5) */
            fprintf(stderr, "hstpf-mc: the library refuses the settings (%s, %d)%s%s\n", hstpf_strerror(rc), (int)rc,
                    *field ? ": " : "", field);
            exit(2);
        }
    }
    r->or_sep = r->or_lead = r->or_sep_lead = r->or_nb_first = -1.0;
    r->or_llr_decl = r->or_llr_near_decl = NAN;
    if (w->st->oracle) {
        hstpf_config_t co = cfg;
        hstpf_theta_t wt = sc.truth;
        size_t wsn = 0;
        wt.c0 += w->sc->grade_permille;
        no = oracle_bank(w, truth, &wt, ob, oi);
        co.models = ob;
        co.n_models = (uint16_t)no;
        co.refine = 0;
        if (w->st->oracle == 2) { /* the Kalman engine on each noise's mean and sd: what a cheap test sees */
            gauss_of(&co.noise_s, "--oracle-gauss");
            gauss_of(&co.noise_v, "--oracle-gauss");
            gauss_of(&co.noise_e, "--oracle-gauss");
            co.engine = HSTPF_ENGINE_KALMAN;
        }
        fo = malloc(sizeof *fo);
        if (fo == NULL || hstpf_workspace_size(&co, &wsn) != HSTPF_OK) {
            fprintf(stderr, "hstpf-mc: --oracle: no bank\n");
            exit(1);
        }
        co.workspace = wsn > 0 ? malloc(wsn) : NULL;
        co.workspace_size = wsn;
        /* the truth's lead for good: off the table over its nearest row, on it over every one of the 8 */
        nsep = ontab ? no : (no > 1 ? 2 : 1);
        if (hstpf_init(fo, sizeof *fo, &co) != HSTPF_OK) {
            fprintf(stderr, "hstpf-mc: --oracle: hstpf_init failed\n");
            exit(1);
        }
    }
    hstpf_sim_init(&sim, &sc);
    if (trace) {
        fprintf(trace, "t,s_true,v_true,u,y,has_y,s_est,v_est,c0,c1,c2,declared,status,standstill,valid,"
                       "pos_sd,spd_sd");
        for (k = 0; k < w->n_models; ++k) {
            fprintf(trace, ",q%d", k);
        }
        for (k = 0; k < w->n_models; ++k) { /* each model's log-likelihood increment of the step */
            fprintf(trace, ",ll%d", k);
        }
        fprintf(trace, ",q_off,fit\n"); /* the continuous hypothesis' weight, hstpf_fit_t */
    }
    while (sim.t <= w->sc->duration_s) {
        hstpf_input_t in = {0};
        double qt;
        hstpf_sim_next_input(&sim, &smp, &in);
        in.traction *= 1.0 + w->sc->gain_bias;
        if (w->sc->stuck_s > 0.0 && smp.t >= w->sc->stuck_at_s) {
            if (smp.t < w->sc->stuck_at_s + 0.5) {
                u_stuck = in.traction;
            } else if (smp.t < w->sc->stuck_at_s + w->sc->stuck_s) {
                in.traction = u_stuck; /* the sender's value frozen, its frames still valid */
            }
        }
        if (w->sc->sign_flip_at_s > 0.0 && smp.t >= w->sc->sign_flip_at_s) {
            in.traction = -in.traction; /* a wiring or a signal definition swapped */
        }
        if (w->sc->restart_after_s > 0.0 && jr->restart_t < 0.0 && smp.t >= w->sc->restart_after_s && smp.held) {
            /* the positioning unit starts a new run where the train stands */
            jr->restart_t = smp.t;
            ref_off = -smp.s;
        }
        if (jr->gap_s > 0.0) {
            const double a = w->sc->trac_gap_at_s;
            if (smp.t < a) {
                u_known = in.traction;
            } else if (smp.t < a + jr->gap_s) {
                if (w->st->gap_hold) {
                    in.traction = u_known; /* what a receiver that keeps the last value feeds */
                } else {
                    in.traction_unknown = 1;
                    in.traction = NAN; /* not read */
                }
            }
            if (smp.t == a) {
                for (k = 0; k < w->n_models; ++k) {
                    q_gap[k] = (double)est.model[k].q; /* the weights after the step before the gap */
                }
            }
        }
        if (w->sc->swap_after_s > 0.0 && jr->swap_t < 0.0 && smp.t >= w->sc->swap_after_s && smp.held) {
            /* a consist coupled or split at a station: another row's resistance from here */
            jr->swap_t = smp.t;
            jr->swap_decl = decl_prev;
            new_truth = (truth + w->sc->swap_rows) % w->n_models;
            sim.cfg.truth = w->models[new_truth];
        }
        smp.s += ref_off; /* the truth and its fixes on the reference the unit sends */
        smp.y += ref_off;
        in.position_m += ref_off;
        if (w->sc->fix_off_m != 0.0 && smp.t >= w->sc->fix_off_at_s) {
            const double per = w->sc->fix_off_every_s, since = smp.t - w->sc->fix_off_at_s;
            const double n = per > 0.0 ? floor(since / per) : 0.0, in_ep = since - n * per;
            if (in_ep < w->sc->fix_off_s) {
                in.position_m += fmod(n, 2.0) == 0.0 ? w->sc->fix_off_m : -w->sc->fix_off_m;
            }
        }
        if (w->sc->outage == 1 && out_start < 0.0 && sim.leg == OUTAGE_LEG &&
            sim.phase == HSTPF_SIM_RUN && smp.t - sim.phase_t0 >= OUTAGE_AFTER_S) {
            out_start = smp.t;
        }
        if (w->sc->outage == 2 && out_start < 0.0 && sim.leg == OUTAGE_LEG && sim.phase == HSTPF_SIM_BRAKING &&
            smp.v <= 10.0) {
            out_start = smp.t;
        }
        if (out_start >= 0.0 && smp.t < out_start + jr->outage_s) {
            in.has_position = 0;
            ++jr->n_out;
        }
        if (w->sc->gap_no_fix && jr->gap_s > 0.0 && smp.t >= w->sc->trac_gap_at_s &&
            smp.t < w->sc->trac_gap_at_s + jr->gap_s) {
            in.has_position = 0;
        }
        if (w->sc->clock_step_s != 0.0 && smp.t == w->sc->clock_at_s) {
            if (w->sc->clock_step_s > 0.0) {
                /* forward: the daemon dates this step by the stepped clock */
                in.dt_s += w->sc->clock_step_s;
            } else {
                /* backward: the daemon's rule (issue 9) is to detect the
                 * step, call hstpf_reacquire() and go on with the nominal
                 * step length: emulated exactly so */
                (void)hstpf_reacquire(f);
                if (fo) {
                    (void)hstpf_reacquire(fo);
                }
            }
        }
        if ((w->sc->merge_s > 0.0 && smp.t >= w->sc->merge_at_s && smp.t < w->sc->merge_at_s + w->sc->merge_s) ||
            (w->sc->step_every > 1 && sim.k % (unsigned)w->sc->step_every != 0u)) {
            /* no input now: it comes with the next step, which spans this one too */
            acc_u += in.traction * in.dt_s;
            acc_dt += in.dt_s;
            continue;
        }
        if (acc_dt > 0.0) {
            in.traction = (acc_u + in.traction * in.dt_s) / (acc_dt + in.dt_s);
            in.dt_s += acc_dt;
            acc_u = acc_dt = 0.0;
        }
        if (fo) {
            hstpf_estimate_t eo;
            (void)hstpf_step(fo, &in);
            (void)hstpf_estimate(fo, &eo);
            for (k = 0; k < no; ++k) {
                ol[k] += isfinite((double)eo.model[k].loglik) ? (double)eo.model[k].loglik : 0.0;
            }
            if (!ontab && no > 9) { /* the nearest row against its eight */
                int pass = 1, kk;
                for (kk = no - 8; kk < no; ++kk) {
                    pass &= ol[1] - ol[kk] >= LOG99;
                }
                if (pass && r->or_nb_first < 0.0) {
                    r->or_nb_first = smp.t;
                }
                nb_pass = pass;
            }
            for (k = 1; k < nsep; ++k) {
                if (ol[0] - ol[k] < LOG99) {
                    sep_below = smp.t;
                }
            }
        }
        {
            const int32_t rc = hstpf_step(f, &in);
            n_err += rc != HSTPF_OK && rc != HSTPF_E_OUTLIER; /* a gated fix: the step was taken */
        }
        (void)hstpf_estimate(f, &est);
        have_fix |= in.has_position;
        if (jr->restart_t >= 0.0) {
            ++jr->n_restart;
            if (est.valid) {
                const double ep = fabs(est.position_m - smp.s);
                ++jr->n_restart_valid;
                jr->revalid_s = jr->revalid_s < 0.0 ? smp.t - jr->restart_t : jr->revalid_s;
                jr->restart_pe_max = ep > jr->restart_pe_max ? ep : jr->restart_pe_max;
            }
        }
        if (jr->gap_s > 0.0 && smp.t >= w->sc->trac_gap_at_s && smp.t < w->sc->trac_gap_at_s + jr->gap_s + 30.0) {
            const double ep = fabs(est.position_m - smp.s), ev = fabs((double)est.speed_mps - smp.v);
            if (est.valid) {
                jr->gap_bad += (ep > 5.0 * est.position_sd_m && ep > 1.0) ||
                               (ev > 5.0 * (double)est.speed_sd_mps && ev > 0.3);
                jr->gap_ev_max = ev > jr->gap_ev_max ? ev : jr->gap_ev_max;
            }
            jr->gap_still += est.standstill && smp.v > 0.0;
            if (smp.t + 1.0 >= w->sc->trac_gap_at_s + jr->gap_s && smp.t < w->sc->trac_gap_at_s + jr->gap_s) {
                jr->gap_tv = tv_dist(q_gap, &est, w->n_models); /* after the gap's last step */
            }
        }
        if (jr->swap_t >= 0.0) {
            const int d = table_index(w, truth, est.declared);
            if (d == truth && d != new_truth) {
                jr->swap_old_s = smp.t - jr->swap_t;
            }
            if (d == new_truth && jr->swap_new_s < 0.0) {
                jr->swap_new_s = smp.t - jr->swap_t;
            }
            if (d >= 0 && d != new_truth && est.valid) {
                const hstpf_theta_t th = {NULL, (double)est.theta[0], (double)est.theta[1], (double)est.theta[2]};
                const double w300 = hstpf_resistance(&sim.cfg.truth, 300.0 / 3.6);
                const double we = fabs(hstpf_resistance(&th, 300.0 / 3.6) - w300) / w300;
                jr->swap_w_max = we > jr->swap_w_max ? we : jr->swap_w_max;
            }
        }
        jr->assert_fail += !decl_consistent(&est, cfg.models, cfg.n_models);
        decl = table_index(w, truth, est.declared);
        decl_prev = decl;
        if (fo && no > 9 && decl >= 0 && decl == oi[1] && decl != truth) { /* a wrong type: not the truth's own row */
            r->or_near_decl = 1;
            r->or_nb_decl |= nb_pass;
        }
        if (have_fix) {
            const double ep = est.position_m - smp.s, ev = (double)est.speed_mps - smp.v;
            jr->cover_p += fabs(ep) <= 1.96 * est.position_sd_m;
            jr->cover_v += fabs(ev) <= 1.96 * (double)est.speed_sd_mps;
            ++jr->n_cover;
            if (!in.has_position && out_start >= 0.0) {
                jr->out_cover_p += fabs(ep) <= 1.96 * est.position_sd_m;
                jr->out_cover_v += fabs(ev) <= 1.96 * (double)est.speed_sd_mps;
                jr->out_pe_max = fabs(ep) > jr->out_pe_max ? fabs(ep) : jr->out_pe_max;
            }
            if (smp.t == t_event + 10.0) {
                jr->pe10 = fabs(ep);
            } else if (smp.t > t_event + 10.0 && fabs(ep) > jr->pe_max_after) {
                jr->pe_max_after = fabs(ep);
            }
        }
        jr->still_moving += est.standstill && smp.v > 0.0;
        jr->moving_still += est.valid && !est.standstill && smp.v == 0.0 && (double)est.speed_mps > 0.3;
        jr->trac_fault += est.traction_fault;
        if (!est.traction_fault && f->tc.cusum > jr->trac_cusum_max) {
            jr->trac_cusum_max = f->tc.cusum; /* the library's private state: how near a false alarm came */
        }
        if (est.valid) {
            const double ev = fabs((double)est.speed_mps - smp.v);
            jr->v_bad += ev > 5.0 * (double)est.speed_sd_mps && ev > 0.3;
        }
        if (smp.v == 0.0) {
            /* the truth stands: from the step it came to rest to the last
             * step before it departs, every step covers held physics */
            if (!at_rest) {
                at_rest = 1;
                for (k = 0; k < w->n_models; ++k) {
                    q_rest[k] = (double)est.model[k].q;
                }
            }
            last_rest_t = smp.t;
            if ((double)est.speed_mps < jr->v_min_rest) {
                jr->v_min_rest = (double)est.speed_mps;
            }
            if (jr->n_stops < MAX_STOPS) {
                jr->tv[jr->n_stops] = tv_dist(q_rest, &est, w->n_models); /* so far */
            }
            at_rest = smp.held ? 2 : at_rest; /* a stop: held at some step (not a clamp at departure) */
        } else if (at_rest) {
            jr->n_stops += at_rest == 2 && jr->n_stops < MAX_STOPS;
            at_rest = 0;
        }
        qt = tq >= 0 ? (double)est.model[tq].q : 0.0;
        if (fo && ontab) {
            int lead = 0;
            for (k = 1; k < w->n_models; ++k) {
                lead = est.model[k].q > est.model[lead].q ? k : lead;
            }
            if (lead != tq) {
                led = 0;
            } else {
                if (!led) { /* a test of the 8 started now */
                    led = 1;
                    memcpy(ol_lead, ol, sizeof ol);
                    lead_t = smp.t;
                }
                for (k = 1; k < no; ++k) {
                    if ((ol[0] - ol_lead[0]) - (ol[k] - ol_lead[k]) < LOG99) {
                        lead_below = smp.t;
                    }
                }
            }
        }
        if (!(qt > thr)) {
            last_below = smp.t;
        }
        if (decl >= 0 && decl != truth && !r->false_decl) {
            r->false_decl = 1;
            r->false_time = est.decision_time_s;
            r->false_model = decl;
            for (k = 1; fo && k < no; ++k) {
                r->or_llr_decl = oi[k] == decl ? ol[0] - ol[k] : r->or_llr_decl;
            }
            r->or_llr_near_decl = fo && no > 1 ? ol[0] - ol[1] : NAN;
            /* the truth stood during the declaration's hold window */
            jr->false_at_rest = smp.t - last_rest_t <= w->st->base.declare_hold_s;
        }
        if (decl >= 0 && !in_pair(w->models, truth, decl)) {
            jr->false_outside_pair = 1;
        }
        if (smp.t >= 60.0) {
            se_p += (est.position_m - smp.s) * (est.position_m - smp.s);
            sb_p += est.position_m - smp.s;
            se_v += ((double)est.speed_mps - smp.v) * ((double)est.speed_mps - smp.v);
            n_after += 1.0;
        }
        if (decl == truth && r->t_declare >= 0.0) {
            for (k = 0; k < 3; ++k) {
                const double tv = k == 0 ? sc.truth.c0 : (k == 1 ? sc.truth.c1 : sc.truth.c2);
                const double e = fabs((double)est.theta[k] - tv) / tv;
                if (e > r->par_err_max_after[k]) {
                    r->par_err_max_after[k] = e;
                }
            }
        }
        if (decl == truth && r->t_declare < 0.0) {
            r->t_declare = est.decision_time_s;
        } else if (decl != truth) {
            r->t_declare = -1.0;
        }
        if (trace) {
            /* the truth, inputs and fixes to a micrometre: a one-sided noise's
             * density changes within a millimetre (tools/figures/oracle_case2.py) */
            fprintf(trace, "%.0f,%.6f,%.6f,%.6f,%.6f,%d,%.3f,%.4f,%.5f,%.6f,%.8f,%d,%d,%d,%d,%.3f,%.4f", smp.t,
                    smp.s, smp.v, smp.u, smp.y, (int)in.has_position, est.position_m, (double)est.speed_mps,
                    (double)est.theta[0], (double)est.theta[1], (double)est.theta[2], est.declared,
                    (int)est.status, est.standstill, est.valid, est.position_sd_m, (double)est.speed_sd_mps);
            for (k = 0; k < w->n_models; ++k) {
                fprintf(trace, ",%.6g", (double)est.model[k].q);
            }
            for (k = 0; k < w->n_models; ++k) {
                fprintf(trace, ",%.9g", (double)est.model[k].loglik);
            }
            fprintf(trace, ",%.6g,%d\n", (double)est.q_offtable, (int)est.fit);
        }
    }
    if (fo) {
        r->or_sep = no > 1 && sep_below < smp.t ? sep_below + 1.0 : -1.0;
        if (led) { /* the row led at the end: its test of the 8 from when it took the lead for good */
            r->or_lead = lead_t;
            r->or_sep_lead = lead_below < smp.t ? lead_below + 1.0 : -1.0;
        }
        free(fo->cfg.workspace);
        free(fo);
    }
    n_after = n_after > 0.0 ? n_after : 1.0;
    r->pos_rms = sqrt(se_p / n_after);
    r->spd_rms = sqrt(se_v / n_after);
    r->pos_bias = sb_p / n_after;
    jr->n_stops += at_rest == 2 && jr->n_stops < MAX_STOPS; /* ended standing */
    jr->outliers = est.outliers;
    jr->fix_steps = est.fix_steps;
    jr->reacquired = est.reacquired;
    jr->acquisitions = est.acquisitions;
    r->floor_hits_true = tq >= 0 ? est.model[tq].floor_hits : 0u;
    r->q_true_end = tq >= 0 ? (double)est.model[tq].q : 0.0;
    r->success = r->q_true_end > thr;
    r->t_cross = r->success ? last_below + 1.0 : -1.0;
    r->final_declared = table_index(w, truth, est.declared);
    {
        const double th[3] = {(double)est.theta[0], (double)est.theta[1], (double)est.theta[2]};
        r->par_err[0] = fabs(th[0] - sc.truth.c0) / sc.truth.c0;
        r->par_err[1] = fabs(th[1] - sc.truth.c1) / sc.truth.c1;
        r->par_err[2] = fabs(th[2] - sc.truth.c2) / sc.truth.c2;
        hstpf_theta_t wt = sc.truth; /* W(v) of the truth includes an unmodelled grade */
        int kv, in_band = 0, in_curve = 0;
        wt.c0 += w->sc->grade_permille;
        r->w_rms = w_rms_rel(th, &wt);
        jr->swap_w_end = jr->swap_t >= 0.0 ? w_rms_rel(th, &sim.cfg.truth) : -1.0;
        r->d_table = HUGE_VAL;
        r->near_row = -1;
        for (kv = 0; kv < w->n_models; ++kv) {
            const double d = w_dist_row(&wt, &w->models[kv]);
            if (d < r->d_table && !(w->sc->absent && kv == truth)) { /* the filter's bank */
                r->d_table = d;
                r->near_row = kv;
            }
        }
        for (kv = 0; kv <= 70; ++kv) {
            double wv = 0.0, sd = 0.0;
            /* no band (a non-finite estimate) covers nothing */
            if (hstpf_resistance_band(&est, 5.0 * kv / 3.6, &wv, &sd) == HSTPF_OK) {
                const double e = fabs(wv - hstpf_resistance(&wt, 5.0 * kv / 3.6));
                in_band += e <= 1.96 * sd;
                in_curve += e <= HSTPF_BAND_Z_CURVE * sd;
            }
        }
        r->band_covers = in_band >= 68; /* 95 % of the 71 speeds */
        r->curve_covers = in_curve == 71;
        {
            const double d[3] = {th[0] - wt.c0, th[1] - wt.c1, th[2] - wt.c2};
            r->theta_nees = nees3(est.theta_cov, d);
        }
        r->nofit_end = est.fit == HSTPF_FIT_NONE;
    }
    if (n_err > 0) {
        fprintf(stderr, "warning: %ld steps rejected (truth %d seed %d)\n", n_err, truth, seed);
    }
    free(f->cfg.workspace);
    free(f);
}

static void *worker(void *arg)
{
    work_t *w = arg;
    for (;;) {
        int idx, job, seed;
        FILE *trace = NULL;
        pthread_mutex_lock(&w->lock);
        idx = w->next++;
        pthread_mutex_unlock(&w->lock);
        if (idx >= w->n_jobs * w->seeds) {
            return NULL;
        }
        job = idx / w->seeds;
        seed = idx % w->seeds;
        seed += w->first_seed;
        if (job == 0 && seed == w->trace_seed && w->trace_path) {
            trace = fopen(w->trace_path, "w");
        }
        one_run(w, w->truths[job], seed, &w->runs[idx], trace);
        if (trace) {
            fclose(trace);
        }
        pthread_mutex_lock(&w->lock);
        ++w->done;
        pthread_mutex_unlock(&w->lock);
    }
}

static double now_s(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Waits for the workers, with a progress line on stderr: rewritten in place
 * on a terminal, one line per 10 % otherwise (--progress into a file). */
static void wait_progress(work_t *w, const char *name, int tty)
{
    const int total = w->n_jobs * w->seeds;
    const double t0 = now_s();
    const struct timespec nap = {0, 250000000L};
    int shown = -1, done = 0;
    while (done < total) {
        (void)nanosleep(&nap, NULL);
        pthread_mutex_lock(&w->lock);
        done = w->done;
        pthread_mutex_unlock(&w->lock);
        if (tty || done * 10 / total != shown) {
            const double el = now_s() - t0;
            const double left = done > 0 ? el * (double)(total - done) / (double)done : 0.0;
            shown = done * 10 / total;
            fprintf(stderr, "%shstpf-mc %s: %d/%d runs, %.0f s, ~%.0f s left%s", tty ? "\r" : "", name,
                    done, total, el, left, tty ? "   " : "\n");
            fflush(stderr);
        }
    }
    if (tty) {
        fprintf(stderr, "\n");
    }
}

static int cmp_d(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double pct(double *v, int n, double p)
{
    int i;
    if (n == 0) {
        return -1.0;
    }
    qsort(v, (size_t)n, sizeof *v, cmp_d);
    i = (int)ceil(p * n) - 1;
    return v[i < 0 ? 0 : i];
}

/* Timetables (the same for every truth and seed): {cruise km/h, run s
 * from departure to braking, dwell s from rest; -1 = runs to the end}. */
/* A line of 41 min: 30 s at the origin, 5 stations of 2 min. */
static const hstpf_sim_leg_t line_legs[] = {
    {300.0, 250.0, 120.0}, {250.0, 200.0, 120.0}, {300.0, 250.0, 120.0},
    {200.0, 150.0, 120.0}, {300.0, 200.0, 120.0}};
static const timetable_t line_tt = {line_legs, 5, 30.0, 0.0};
/* Shunting: 15 runs of 60 s at 4 km/h, each followed by 60 s at rest. */
static const hstpf_sim_leg_t shunt_legs[] = {
    {4.0, 60.0, 60.0}, {4.0, 60.0, 60.0}, {4.0, 60.0, 60.0}, {4.0, 60.0, 60.0}, {4.0, 60.0, 60.0},
    {4.0, 60.0, 60.0}, {4.0, 60.0, 60.0}, {4.0, 60.0, 60.0}, {4.0, 60.0, 60.0}, {4.0, 60.0, 60.0},
    {4.0, 60.0, 60.0}, {4.0, 60.0, 60.0}, {4.0, 60.0, 60.0}, {4.0, 60.0, 60.0}, {4.0, 60.0, 60.0}};
static const timetable_t shunt_tt = {shunt_legs, 15, 30.0, 0.0};
/* The line with a consist coupled or split at the second station, where
 * the train stands 5 min (coupling and its brake test take minutes). */
static const hstpf_sim_leg_t couple_legs[] = {
    {300.0, 250.0, 120.0}, {250.0, 200.0, 300.0}, {300.0, 250.0, 120.0},
    {200.0, 150.0, 120.0}, {300.0, 200.0, 120.0}};
static const timetable_t couple_tt = {couple_legs, 5, 30.0, 0.0};
/* A day of 4 h: 60 s at the origin, 12 stations of 2 min, runs of 5 to 20
 * min at 160 to 350 km/h, then a last run to the end of the day. */
static const hstpf_sim_leg_t day_legs[] = {
    {300.0, 900.0, 120.0}, {250.0, 600.0, 120.0}, {350.0, 1200.0, 120.0}, {200.0, 400.0, 120.0},
    {300.0, 800.0, 120.0}, {160.0, 300.0, 120.0}, {300.0, 1000.0, 120.0}, {250.0, 600.0, 120.0},
    {350.0, 1100.0, 120.0}, {200.0, 500.0, 120.0}, {300.0, 900.0, 120.0}, {250.0, 700.0, 120.0},
    {300.0, 0.0, -1.0}};
static const timetable_t day_tt = {day_legs, 13, 60.0, 0.0};
/* Running at 300 km/h when the filter starts; two stations, then on. */
static const hstpf_sim_leg_t start300_legs[] = {
    {300.0, 300.0, 120.0}, {250.0, 400.0, 120.0}, {300.0, 0.0, -1.0}};
static const timetable_t start300_tt = {start300_legs, 3, -1.0, 300.0};

#define CLOCK_AT_S 1250.0 /* on the line: leg 3 cruising at 300 km/h */

static const scenario_t scenarios[] = {
    {.name = "paper1", .paper_case = 1, .profile = HSTPF_PROFILE_PAPER, .all17 = 0, .duration_s = 1800.0},
    {.name = "paper2", .paper_case = 2, .profile = HSTPF_PROFILE_PAPER, .all17 = 0, .duration_s = 1800.0},
    {.name = "all17", .paper_case = 1, .profile = HSTPF_PROFILE_PAPER, .all17 = 1, .duration_s = 1800.0},
    {.name = "all17-coast", .paper_case = 1, .profile = HSTPF_PROFILE_COAST_BRAKE, .all17 = 1, .duration_s = 1800.0},
    {.name = "all17-coast-loss", .paper_case = 1, .profile = HSTPF_PROFILE_COAST_BRAKE, .loss_rate = 0.05, .all17 = 1, .duration_s = 1800.0},
    /* all 17 types with the paper's Case 2 (Gamma) noise (issue 13) */
    {.name = "all17-case2", .paper_case = 2, .profile = HSTPF_PROFILE_PAPER, .all17 = 1, .duration_s = 1800.0},
    {.name = "all17-coast-case2", .paper_case = 2, .profile = HSTPF_PROFILE_COAST_BRAKE, .all17 = 1, .duration_s = 1800.0},
    /* heavy-tailed position noise with Case 1's process noise (issue 13) */
    {.name = "heavy-t", .paper_case = 3, .profile = HSTPF_PROFILE_PAPER, .all17 = 1, .duration_s = 1800.0},
    {.name = "heavy-mix", .paper_case = 4, .profile = HSTPF_PROFILE_PAPER, .all17 = 1, .duration_s = 1800.0},
    {.name = "hilly-ignored", .paper_case = 1, .profile = HSTPF_PROFILE_PAPER, .all17 = 1, .duration_s = 1800.0, .hilly = 1},
    {.name = "hilly-known", .paper_case = 1, .profile = HSTPF_PROFILE_PAPER, .all17 = 1, .duration_s = 1800.0, .hilly = 1, .filter_knows_track = 1},
    /* journeys: 17 types, Case 1 noise, the holding brake reported at rest */
    {.name = "stops", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt},
    {.name = "day", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 14400.0, .tt = &day_tt},
    {.name = "start300", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 1800.0, .tt = &start300_tt},
    /* the line stepped at 10 Hz, a fix every step: Case 1's train (its noises per second scaled to
     * 0.1 s), and Case 1's figures taken per 0.1 s step (a noisier train) */
    {.name = "stops-10hz", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .step_s = 0.1},
    {.name = "all17-10hz", .paper_case = 1, .profile = HSTPF_PROFILE_PAPER, .all17 = 1, .duration_s = 1800.0, .step_s = 0.1},
    {.name = "all17-10hz-raw", .paper_case = 1, .profile = HSTPF_PROFILE_PAPER, .all17 = 1, .duration_s = 1800.0, .step_s = 0.1, .step_noise_per_step = 1},
    /* late60, fixbias20 and stopstep12 at 10 Hz (Case 1's train, noises scaled to 0.1 s) */
    {.name = "late60-10hz", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .stuck_at_s = 1029.0, .stuck_s = 61.0, .step_s = 0.1},
    {.name = "fixbias20-10hz", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .fix_off_m = 20.0, .fix_off_at_s = CLOCK_AT_S, .fix_off_s = 300.0, .step_s = 0.1},
    {.name = "stopstep12-10hz", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .fix_off_m = 12.0, .fix_off_at_s = 1480.0, .fix_off_s = 60.0, .step_s = 0.1},
    {.name = "stops-10hz-raw", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .step_s = 0.1, .step_noise_per_step = 1},
    /* the same with the unit configured for a power-up at rest (speed prior 0 +- 1 m/s): a unit that
     * starts or restarts while the train runs */
    {.name = "start300-prior", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 1800.0, .tt = &start300_tt, .init_speed_sd = 1.0},
    {.name = "clock+30", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .clock_step_s = 30.0, .clock_at_s = CLOCK_AT_S},
    {.name = "clock-30", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .clock_step_s = -30.0, .clock_at_s = CLOCK_AT_S},
    /* a receive clock that steps 1 s or 3 s forward at 300 km/h (hstpfd predicts across it: the step
     * is dated late, the fixes run on), under Case 1's and under Student-t fixes */
    {.name = "clock+1", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .clock_step_s = 1.0, .clock_at_s = CLOCK_AT_S},
    {.name = "clock+3-t", .paper_case = 3, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .clock_step_s = 3.0, .clock_at_s = CLOCK_AT_S},
    {.name = "outage", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .outage = 1},
    /* the outage across the second station's stop: braking into it from 10 m/s under the reported brake */
    {.name = "outage-stop", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .outage = 2},
    {.name = "gain5", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .gain_bias = 0.05},
    /* trains not on Table 1: the line, each coefficient 10 / 15 / 20 % off its row; an
     * unmodelled 8 per-mille climb; all three by one mass-like factor 10 / 20 %; the
     * truth's row left out of the bank; a traction gain 5 % low */
    {.name = "off10", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .perturb = 0.10},
    {.name = "off15", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .perturb = 0.15},
    {.name = "off20", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .perturb = 0.20},
    {.name = "grade8", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .grade_permille = 8.0},
    {.name = "mass10", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .perturb = 0.10, .common = 1},
    {.name = "mass20", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .perturb = 0.20, .common = 1},
    {.name = "absent", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .absent = 1},
    /* the positioning unit starts a new run (0 where the train stands) at a stop on the line */
    {.name = "restart", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .restart_after_s = 1000.0},
    /* a consist coupled or split at the second station: the truth becomes the row 8 further on (far: e.g.
     * CRH3 -> DF11) or the next row (often near), from the first held step after 1000 s */
    {.name = "swap", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .swap_after_s = 1000.0, .swap_rows = 8},
    {.name = "swap-near", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .swap_after_s = 1000.0, .swap_rows = 1},
    {.name = "couple", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2640.0, .tt = &couple_tt, .swap_after_s = 1000.0, .swap_rows = 8},
    {.name = "couple-near", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2640.0, .tt = &couple_tt, .swap_after_s = 1000.0, .swap_rows = 1},
    /* the traction unit silent for 20-60 s from 16 s before the departure from the second station */
    {.name = "tracgap", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .trac_gap_at_s = 1010.0},
    /* both inputs silent for 20-60 s at 300 km/h (a bus that drops out; hstpfd then predicts with the
     * traction unknown), the whole bank: each model's acceleration is 0 in the mean */
    {.name = "silent", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .trac_gap_at_s = CLOCK_AT_S, .gap_no_fix = 1},
    {.name = "gain-5", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .gain_bias = -0.05},
    /* traction present but wrong: a gain 20 % low (a motor cut out, reported for all) and, from 16 s
     * before the departure from the second station, the sign swapped */
    {.name = "gain-20", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .gain_bias = -0.20},
    /* braking into the second station (from about 767 s), no input for 29 s: one step of 30 s */
    {.name = "gap29", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .merge_at_s = 800.0, .merge_s = 29.0},
    /* one step per fix, a fix every 5 s (a caller that steps on each fix of a slow receiver) */
    {.name = "fix5", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .step_every = 5},
    /* the traction stuck at its cruise value from the start of the braking into the second station (769 s), 30 s */
    {.name = "stuck30", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .stuck_at_s = 768.0, .stuck_s = 31.0},
    /* the holding brake still reported for the first 10 s of the departure from the second station (1 030 s) */
    {.name = "late10", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .stuck_at_s = 1029.0, .stuck_s = 11.0},
    /* the same for 60 s: a traction signal stuck at the holding brake */
    {.name = "late60", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .stuck_at_s = 1029.0, .stuck_s = 61.0},
    /* shunting at 4 km/h: the speed's noise and the fixes' leave the train within 2-3 sd of rest */
    {.name = "shunt4", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 1800.0, .tt = &shunt_tt},
    /* the fixes step by +20 m on the line at 300 km/h for 300 s (a GNSS bias); one fix in 150 s
     * 20 m off, the sign alternating (lone outliers) */
    {.name = "fixbias20", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .fix_off_m = 20.0, .fix_off_at_s = CLOCK_AT_S, .fix_off_s = 300.0},
    /* the same with +10 m and +14 m: steps within the hold rule's reach (4.3 sd of the noise with the
     * prediction's) or just beyond it */
    {.name = "fixbias10", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .fix_off_m = 10.0, .fix_off_at_s = CLOCK_AT_S, .fix_off_s = 300.0},
    {.name = "fixbias14", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .fix_off_m = 14.0, .fix_off_at_s = CLOCK_AT_S, .fix_off_s = 300.0},
    /* the same at the third station (at rest from about 1 450 to 1 570 s): +-12 m for 60 s from 1 480 s */
    {.name = "stopstep12", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .fix_off_m = 12.0, .fix_off_at_s = 1480.0, .fix_off_s = 60.0},
    {.name = "stopstep-12", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .fix_off_m = -12.0, .fix_off_at_s = 1480.0, .fix_off_s = 60.0},
    {.name = "spikes20", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .fix_off_m = 20.0, .fix_off_at_s = 150.0, .fix_off_s = 0.5, .fix_off_every_s = 150.0},
    /* two fixes in a row 100 m off every 150 s, the sign alternating (a multipath burst), under
     * Case 1's and under Student-t fixes */
    {.name = "burst100", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .fix_off_m = 100.0, .fix_off_at_s = 150.0, .fix_off_s = 1.5, .fix_off_every_s = 150.0},
    {.name = "burst100-t", .paper_case = 3, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .fix_off_m = 100.0, .fix_off_at_s = 150.0, .fix_off_s = 1.5, .fix_off_every_s = 150.0},
    {.name = "tracsign", .paper_case = 1, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .sign_flip_at_s = 1010.0},
    /* the same on the line with heavy-t's Student-t position noise (the grid
     * engine, the continuous hypothesis through its yardstick) */
    {.name = "stops-t", .paper_case = 3, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt},
    {.name = "restart-t", .paper_case = 3, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .restart_after_s = 1000.0},
    {.name = "tracgap-t", .paper_case = 3, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .trac_gap_at_s = 1010.0},
    /* the stop's step under Student-t fixes and under heavy-mix's multipath mixture, and the step at
     * 300 km/h under Student-t fixes (the grid engine: its cells take the step's variance) */
    {.name = "stopstep12-t", .paper_case = 3, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .fix_off_m = 12.0, .fix_off_at_s = 1480.0, .fix_off_s = 60.0},
    {.name = "stopstep12-mix", .paper_case = 4, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .fix_off_m = 12.0, .fix_off_at_s = 1480.0, .fix_off_s = 60.0},
    /* late60 under Student-t fixes: a departure under a reported brake, which the run rule must not take for a step */
    {.name = "late60-t", .paper_case = 3, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .stuck_at_s = 1029.0, .stuck_s = 61.0},
    {.name = "fixbias20-t", .paper_case = 3, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .fix_off_m = 20.0, .fix_off_at_s = CLOCK_AT_S, .fix_off_s = 300.0},
    {.name = "off15-t", .paper_case = 3, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .perturb = 0.15},
    {.name = "grade8-t", .paper_case = 3, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .grade_permille = 8.0},
    /* the line with Case 2's Gamma noise, 17 types: issue 13's daemon journey;
     * then the start at speed, the clock steps and the outage under it */
    {.name = "stops-case2", .paper_case = 2, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt},
    {.name = "start300-case2", .paper_case = 2, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 1800.0, .tt = &start300_tt},
    {.name = "clock+30-case2", .paper_case = 2, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .clock_step_s = 30.0, .clock_at_s = CLOCK_AT_S},
    {.name = "clock-30-case2", .paper_case = 2, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .clock_step_s = -30.0, .clock_at_s = CLOCK_AT_S},
    {.name = "outage-case2", .paper_case = 2, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .outage = 1},
    /* trains not on Table 1 under Case 2 noise (the hypothesis needs --refine-any-noise) */
    {.name = "off15-case2", .paper_case = 2, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .perturb = 0.15},
    {.name = "grade8-case2", .paper_case = 2, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .grade_permille = 8.0},
    {.name = "mass20-case2", .paper_case = 2, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .perturb = 0.20, .common = 1},
    {.name = "absent-case2", .paper_case = 2, .profile = HSTPF_PROFILE_JOURNEY, .all17 = 1, .duration_s = 2460.0, .tt = &line_tt, .absent = 1},
};

/* Journey table: one row per truth and a total (docs/results.md). */
static void print_journey(const work_t *w, const hstpf_theta_t *models, const int *truths, int seeds,
                          FILE *jf)
{
    const int all = w->n_jobs * seeds;
    double *tv_all = malloc(sizeof(double) * (size_t)all * MAX_STOPS);
    double *pe_all = malloc(sizeof(double) * (size_t)all);
    double *td_all = malloc(sizeof(double) * (size_t)all); /* when the truth was declared */
    int n_tv_all = 0, n_pe_all = 0, n_td_all = 0, n_np = 0, n_td_np = 0, j, i, k;
    long t_false = 0, t_rest = 0, t_out = 0, t_pairbad = 0, t_pairruns = 0, t_assert = 0;
    long t_fs = 0;
    long t_outl = 0, t_reacq = 0, t_cp = 0, t_cv = 0, t_n = 0, o_cp = 0, o_cv = 0, o_n = 0;
    long t_still = 0, t_vbad = 0, t_tf = 0, t_mst = 0;
    int n_still = 0, n_vbad = 0, n_tf = 0, n_mst = 0;
    double t_cmax = 0.0;
    double o_pe = 0.0;
    double t_vmin = HUGE_VAL, t_wmean = 0.0, t_wmax = 0.0, t_pemax = 0.0, t_acq = 0.0;
    if (tv_all == NULL || pe_all == NULL || td_all == NULL) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    printf("%-23s %6s %4s %4s %6s %5s %5s %6s %6s %6s %6s %6s %6s %6s %7s %5s %5s %5s %6s %6s %5s\n", "truth",
           "false", "rest", "!pr", "undec", "pair", "stops", "TVmed", "TVmax", "vmin", "W_mean", "W_max",
           "pe10md", "pe10mx", "pe_max", "outl", "reacq", "acq", "cov_p", "cov_v", "assrt");
    for (j = 0; j < w->n_jobs; ++j) {
        const run_t *rr = &w->runs[j * seeds];
        const int pair = pair_of(models[truths[j]].name) >= 0;
        double *tv = malloc(sizeof(double) * (size_t)seeds * MAX_STOPS), *pe = malloc(sizeof(double) * (size_t)seeds);
        int ntv = 0, npe = 0, nf = 0, nr = 0, no = 0, nu = 0, npair = 0;
        long outl = 0, reacq = 0, cp = 0, cv = 0, n = 0, as = 0;
        double vmin = HUGE_VAL, wsum = 0.0, wmax = 0.0, pemax = 0.0, acq = 0.0, stops = 0.0;
        if (tv == NULL || pe == NULL) {
            fprintf(stderr, "out of memory\n");
            exit(1);
        }
        for (i = 0; i < seeds; ++i) {
            const run_t *r = &rr[i];
            const journey_t *q = &r->j;
            nf += r->false_decl;
            nr += r->false_decl && q->false_at_rest;
            no += q->false_outside_pair;
            nu += r->final_declared < 0;
            npair += r->final_declared < 0 || in_pair(models, truths[j], r->final_declared);
            if (r->t_declare >= 0.0) {
                td_all[n_td_all++] = r->t_declare;
                n_td_np += !pair;
            }
            n_np += !pair;
            for (k = 0; k < q->n_stops; ++k) {
                tv[ntv++] = q->tv[k];
                tv_all[n_tv_all++] = q->tv[k];
            }
            stops += q->n_stops;
            vmin = q->v_min_rest < vmin ? q->v_min_rest : vmin;
            wsum += r->w_rms;
            wmax = r->w_rms > wmax ? r->w_rms : wmax;
            if (q->pe10 >= 0.0) {
                pe[npe++] = q->pe10;
                pe_all[n_pe_all++] = q->pe10;
            }
            pemax = q->pe_max_after > pemax ? q->pe_max_after : pemax;
            outl += q->outliers;
            t_fs += q->fix_steps;
            reacq += q->reacquired;
            acq += q->acquisitions;
            cp += q->cover_p;
            cv += q->cover_v;
            n += q->n_cover;
            as += q->assert_fail;
            o_cp += q->out_cover_p;
            o_cv += q->out_cover_v;
            o_n += q->n_out;
            o_pe = q->out_pe_max > o_pe ? q->out_pe_max : o_pe;
            t_still += q->still_moving;
            n_still += q->still_moving > 0;
            t_mst += q->moving_still;
            n_mst += q->moving_still > 0;
            t_vbad += q->v_bad;
            n_vbad += q->v_bad > 0;
            t_tf += q->trac_fault;
            n_tf += q->trac_fault > 0;
            t_cmax = q->trac_cusum_max > t_cmax ? q->trac_cusum_max : t_cmax;
        }
        {
            const double tvmax = pct(tv, ntv, 1.0), pe10max = pct(pe, npe, 1.0);
            char pair_s[16] = "-";
            if (pair) {
                snprintf(pair_s, sizeof pair_s, "%d", npair);
            }
            printf("%-23.23s %5.1f%% %4d %4d %5.1f%% %5s %5.1f %6.4f %6.4f %+6.2f %5.2f%% %5.2f%% %6.2f %6.2f %7.1f "
                   "%5ld %5ld %5.1f %5.1f%% %5.1f%% %5ld\n",
                   models[truths[j]].name, 100.0 * nf / seeds, nr, no, 100.0 * nu / seeds, pair_s,
                   stops / seeds, pct(tv, ntv, 0.5), tvmax, vmin, 100.0 * wsum / seeds, 100.0 * wmax,
                   pct(pe, npe, 0.5), pe10max, pemax, outl, reacq, acq / seeds, 100.0 * (double)cp / (double)n,
                   100.0 * (double)cv / (double)n, as);
        }
        t_false += nf;
        t_rest += nr;
        t_out += no;
        if (pair) {
            t_pairruns += seeds;
            t_pairbad += seeds - npair;
        } else {
            t_wmean = wsum / seeds > t_wmean ? wsum / seeds : t_wmean;
            t_wmax = wmax > t_wmax ? wmax : t_wmax;
        }
        t_vmin = vmin < t_vmin ? vmin : t_vmin;
        t_pemax = pemax > t_pemax ? pemax : t_pemax;
        t_outl += outl;
        t_reacq += reacq;
        t_acq += acq;
        t_cp += cp;
        t_cv += cv;
        t_n += n;
        t_assert += as;
        if (jf) {
            fprintf(jf, "%s{\"truth\":\"%s\",\"runs\":[", j ? "," : "", models[truths[j]].name);
            for (i = 0; i < seeds; ++i) {
                const run_t *r = &rr[i];
                const journey_t *q = &r->j;
                fprintf(jf,
                        "%s{\"seed\":%d,\"false_decl\":%d,\"false_time\":%.0f,\"false_model\":\"%s\","
                        "\"false_at_rest\":%d,\"false_outside_pair\":%d,\"final_declared\":\"%s\","
                        "\"w_rms\":%.5g,\"band_covers\":%d,\"curve_covers\":%d,\"theta_nees\":%.4g,\"d_table\":%.4g,\"near_row\":\"%s\","
                        "\"nofit_end\":%d,\"q_true_end\":%.4g,\"t_declare\":%.0f,",
                        i ? "," : "", w->first_seed + i, r->false_decl, r->false_time,
                        r->false_model >= 0 ? models[r->false_model].name : "", q->false_at_rest,
                        q->false_outside_pair, r->final_declared >= 0 ? models[r->final_declared].name : "",
                        r->w_rms, r->band_covers, r->curve_covers, r->theta_nees, r->d_table,
                        r->near_row >= 0 ? models[r->near_row].name : "", r->nofit_end, r->q_true_end,
                        r->t_declare);
                if (w->st->oracle) { /* null: no wrong declaration, or its row not in the oracle's bank */
                    char a[32] = "null", b[32] = "null";
                    if (isfinite(r->or_llr_decl)) {
                        snprintf(a, sizeof a, "%.4g", r->or_llr_decl);
                    }
                    if (isfinite(r->or_llr_near_decl)) {
                        snprintf(b, sizeof b, "%.4g", r->or_llr_near_decl);
                    }
                    fprintf(jf, "\"oracle_sep\":%.0f,\"oracle_llr_decl\":%s,\"oracle_llr_near_decl\":%s,", r->or_sep, a, b);
                }
                fprintf(jf, "\"tv\":[");
                for (k = 0; k < q->n_stops; ++k) {
                    fprintf(jf, "%s%.4g", k ? "," : "", q->tv[k]);
                }
                fprintf(jf,
                        "],\"v_min_rest\":%.4g,\"pe10\":%.4g,\"pe_max_after\":%.4g,\"outliers\":%u,"
                        "\"reacquired\":%u,\"acquisitions\":%u,\"cover_p\":%.4f,\"cover_v\":%.4f,"
                        "\"assert_fail\":%ld,\"outage_s\":%.0f,\"out_pe_max\":%.4g,\"pos_rms\":%.4g,\"spd_rms\":%.4g,"
                        "\"still_moving\":%ld,\"moving_still\":%ld,\"v_bad\":%ld,\"trac_fault\":%ld,\"trac_cusum_max\":%.4g,\"fix_steps\":%u",
                        q->v_min_rest < HUGE_VAL ? q->v_min_rest : 0.0, q->pe10, q->pe_max_after,
                        (unsigned)q->outliers, (unsigned)q->reacquired, (unsigned)q->acquisitions,
                        q->n_cover ? (double)q->cover_p / (double)q->n_cover : 0.0,
                        q->n_cover ? (double)q->cover_v / (double)q->n_cover : 0.0, q->assert_fail,
                        q->outage_s, q->out_pe_max, r->pos_rms, r->spd_rms, q->still_moving, q->moving_still, q->v_bad, q->trac_fault, q->trac_cusum_max,
                        (unsigned)q->fix_steps);
                if (w->sc->restart_after_s > 0.0) {
                    fprintf(jf, ",\"restart_t\":%.0f,\"revalid_s\":%.0f,\"restart_valid\":%.4f,\"restart_pe_max\":%.4g",
                            q->restart_t, q->revalid_s,
                            q->n_restart ? (double)q->n_restart_valid / (double)q->n_restart : 0.0,
                            q->restart_pe_max);
                }
                if (w->sc->trac_gap_at_s > 0.0) {
                    fprintf(jf, ",\"gap_s\":%.0f,\"gap_bad\":%ld,\"gap_still\":%ld,\"gap_ev_max\":%.4g,\"gap_tv\":%.4g",
                            q->gap_s, q->gap_bad, q->gap_still, q->gap_ev_max, q->gap_tv);
                }
                if (w->sc->swap_after_s > 0.0) {
                    fprintf(jf, ",\"swap_t\":%.0f,\"swap_declared\":\"%s\",\"swap_old_s\":%.0f,\"swap_new_s\":%.0f,\"swap_w_max\":%.4g,\"swap_w_end\":%.4g",
                            q->swap_t, q->swap_decl >= 0 ? models[q->swap_decl].name : "", q->swap_old_s, q->swap_new_s,
                            q->swap_w_max, q->swap_w_end);
                }
                fputc('}', jf);
            }
            fprintf(jf, "]}");
        }
        free(tv);
        free(pe);
    }
    printf("total: %d runs; false declarations %ld (%.1f%%), %ld from a standstill, %ld outside the pair; "
           "pairs ending outside the pair %ld of %ld; TV across a stop median %.4f max %.4f; "
           "speed at rest min %+.3f m/s; W(v) error outside the pairs: worst truth mean %.2f%%, max %.2f%%; "
           "position error 10 s after the event median %.2f m max %.2f m, later max %.1f m; outliers %ld, "
           "steps in the fixes %ld, "
           "re-acquisitions (gated) %ld, acquisitions %.2f per run; 95%% coverage position %.1f%% speed "
           "%.1f%%; declared/status/theta disagreements %ld\n",
           all, t_false, 100.0 * (double)t_false / all, t_rest, t_out, t_pairbad, t_pairruns,
           pct(tv_all, n_tv_all, 0.5), pct(tv_all, n_tv_all, 1.0), t_vmin, 100.0 * t_wmean, 100.0 * t_wmax,
           pct(pe_all, n_pe_all, 0.5), pct(pe_all, n_pe_all, 1.0), t_pemax, t_outl, t_fs, t_reacq, t_acq / all,
           100.0 * (double)t_cp / (double)t_n, 100.0 * (double)t_cv / (double)t_n, t_assert);
    printf("standstill published while the train moved: %ld steps in %d runs; valid steps with the speed more than "
           "5 sd and 0.3 m/s off: %ld in %d runs; the traction taken for wrong (traction_fault) at %ld steps in %d "
           "runs, its CUSUM while the traction was believed at most %.2f nats\n",
           t_still, n_still, t_vbad, n_vbad, t_tf, n_tf, t_cmax);
    printf("moving published while the train stood (valid, not at standstill, speed over 0.3 m/s): %ld steps in %d "
           "runs\n",
           t_mst, n_mst);
    if (w->sc->trac_gap_at_s > 0.0) { /* the traction unit silent across a departure */
        double *tvg = malloc(sizeof(double) * (size_t)all);
        long bad = 0, still = 0;
        int nbad = 0;
        double evmax = 0.0;
        if (tvg == NULL) {
            fprintf(stderr, "out of memory\n");
            exit(1);
        }
        for (j = 0; j < all; ++j) {
            const journey_t *q = &w->runs[j].j;
            bad += q->gap_bad;
            nbad += q->gap_bad > 0;
            still += q->gap_still;
            evmax = q->gap_ev_max > evmax ? q->gap_ev_max : evmax;
            tvg[j] = q->gap_tv;
        }
        printf("traction gap of 20-60 s from %.0f s (%s): valid steps more than 5 sd off in it and 30 s after: %ld "
               "in %d of %d runs; largest speed error at a valid step %.2f m/s; standstill published while the "
               "train moved: %ld steps; the weights' TV across the gap median %.4f max %.4f\n",
               w->sc->trac_gap_at_s, w->st->gap_hold ? "the last traction fed" : "traction unknown", bad, nbad, all,
               evmax, still, pct(tvg, all, 0.5), pct(tvg, all, 1.0));
        free(tvg);
    }
    if (w->sc->swap_after_s > 0.0) { /* the truth changed type at a stop */
        double *old = malloc(sizeof(double) * (size_t)all), *tnew = malloc(sizeof(double) * (size_t)all),
               *wend = malloc(sizeof(double) * (size_t)all);
        int nold = 0, ndecl = 0, nnew = 0, nw = 0;
        double wmax = 0.0;
        if (old == NULL || tnew == NULL || wend == NULL) {
            fprintf(stderr, "out of memory\n");
            exit(1);
        }
        for (j = 0; j < all; ++j) {
            const journey_t *q = &w->runs[j].j;
            ndecl += q->swap_decl >= 0;
            if (q->swap_new_s >= 0.0) {
                tnew[nnew++] = q->swap_new_s;
            }
            if (q->swap_w_end >= 0.0) {
                wend[nw++] = q->swap_w_end;
            }
            if (q->swap_old_s >= 0.0) {
                old[nold++] = q->swap_old_s;
            }
            wmax = q->swap_w_max > wmax ? q->swap_w_max : wmax;
        }
        printf("type changed at a stop (row + %d): a type declared then in %d of %d runs; the old type kept after the "
               "change in %d, for a median %.0f s, max %.0f s; the new truth declared in %d, a median %.0f s after it; "
               "W(300 km/h) error while a wrong type was declared and valid, max %.1f%%; W(v) error against the new "
               "truth at the end (%d runs) median %.2f%% p90 %.2f%%\n",
               w->sc->swap_rows, ndecl, all, nold, pct(old, nold, 0.5), pct(old, nold, 1.0), nnew,
               pct(tnew, nnew, 0.5), 100.0 * wmax, nw, 100.0 * pct(wend, nw, 0.5), 100.0 * pct(wend, nw, 0.9));
        free(old);
        free(tnew);
        free(wend);
    }
    if (w->sc->restart_after_s > 0.0) { /* the reference restarted at a stop: how soon valid again */
        double *rv = malloc(sizeof(double) * (size_t)all);
        int nrv = 0, nrs = 0;
        long nv = 0, ns = 0;
        double pemax = 0.0;
        if (rv == NULL) {
            fprintf(stderr, "out of memory\n");
            exit(1);
        }
        for (j = 0; j < all; ++j) {
            const journey_t *q = &w->runs[j].j;
            nrs += q->restart_t >= 0.0;
            if (q->revalid_s >= 0.0) {
                rv[nrv++] = q->revalid_s;
            }
            nv += q->n_restart_valid;
            ns += q->n_restart;
            pemax = q->restart_pe_max > pemax ? q->restart_pe_max : pemax;
        }
        printf("reference restarted at a stop in %d of %d runs; valid again after a median %.0f s, p90 %.0f s, "
               "max %.0f s (never in %d); valid at %.1f%% of the steps after it; |position error| at a valid "
               "step after it max %.2f m\n",
               nrs, all, pct(rv, nrv, 0.5), pct(rv, nrv, 0.9), pct(rv, nrv, 1.0), nrs - nrv,
               ns ? 100.0 * (double)nv / (double)ns : 0.0, pemax);
        free(rv);
    }
    if (on_table(w->sc) && n_td_all > 0) { /* the truth's own declaration at the end (Table 2's rule): how many, since when */
        printf("the truth declared: %d of %d runs (%.1f%%), outside the pairs %d of %d (%.1f%%); since a median "
               "%.0f s, p90 %.0f s, max %.0f s\n",
               n_td_all, all, 100.0 * (double)n_td_all / all, n_td_np, n_np,
               n_np ? 100.0 * (double)n_td_np / n_np : 0.0, pct(td_all, n_td_all, 0.5), pct(td_all, n_td_all, 0.9),
               pct(td_all, n_td_all, 1.0));
    }
    if (o_n > 0) {
        printf("outage: %ld steps without a fix; 95%% coverage there position %.1f%% speed %.1f%%; "
               "max |position error| %.1f m\n",
               o_n, 100.0 * (double)o_cp / (double)o_n, 100.0 * (double)o_cv / (double)o_n, o_pe);
    }
    free(tv_all);
    free(pe_all);
    free(td_all);
}

#define OFF_TABLE_D 0.10 /* issue 10: a truth this far from every row is off the table */

#define ORACLE_ENGINE(w) ((w)->st->oracle == 2 ? "the Kalman engine on the noises' mean and sd" : "the same engine")

/* The p-quantile of v[0..n) for print_oracle: "never" for an infinite
 * time, "-" for no value. */
static const char *fmt_pct(char *buf, size_t len, double *v, int n, double p, const char *unit)
{
    const double x = n > 0 ? pct(v, n, p) : 0.0;
    if (n == 0) {
        snprintf(buf, len, "-");
    } else if (x == HUGE_VAL) {
        snprintf(buf, len, "never");
    } else {
        snprintf(buf, len, "%.*f%s", strcmp(unit, " s") == 0 ? 0 : 2, x, unit);
    }
    return buf;
}

/* --oracle on the table: when the truth's row leads every train
 * ORACLE_NEAR from it by log 99 for good, beside when the rule declared it.
 * A rule that refuses a row until the data exclude such trains declares no
 * earlier. */
static void print_oracle_on(const work_t *w, int all)
{
    double *sep = malloc(sizeof(double) * (size_t)all), *td = malloc(sizeof(double) * (size_t)all);
    double *dl = malloc(sizeof(double) * (size_t)all), *sl = malloc(sizeof(double) * (size_t)all);
    double *tl = malloc(sizeof(double) * (size_t)all), *dd = malloc(sizeof(double) * (size_t)all);
    char b[6][24];
    int i, never = 0, nd = 0, before = 0, nl = 0, nlnever = 0, ndd = 0, ndl = 0;
    if (sep == NULL || td == NULL || dl == NULL || sl == NULL || tl == NULL || dd == NULL) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    for (i = 0; i < all; ++i) {
        const run_t *r = &w->runs[i];
        never += r->or_sep < 0.0;
        sep[i] = r->or_sep < 0.0 ? HUGE_VAL : r->or_sep;
        if (r->t_declare >= 0.0) {
            td[nd++] = r->t_declare;
            before += r->or_sep < 0.0 || r->t_declare < r->or_sep;
            if (r->or_sep >= 0.0) {
                dd[ndd++] = r->or_sep - r->t_declare;
            }
            if (r->or_sep_lead >= 0.0) {
                dl[ndl++] = r->or_sep_lead - r->t_declare;
            }
        }
        if (r->or_lead >= 0.0) {
            tl[nl] = r->or_lead;
            sl[nl++] = r->or_sep_lead < 0.0 ? HUGE_VAL : r->or_sep_lead;
            nlnever += r->or_sep_lead < 0.0;
        }
    }
    printf("oracle (8 trains %.0f%% from the truth's row in W(v), one per sign pattern of c0, c1, c2, scored beside it, "
           "%s, no hypothesis): %d runs; the row leads all 8 by log 99 from the end of a median %s (p10 %s, "
           "p90 %s) to the end, never in %d runs; the truth declared (and so at the end) in %d runs, at a median %s "
           "(p90 %s, max %s), before the row led all 8 for good in %d\n",
           100.0 * ORACLE_NEAR, ORACLE_ENGINE(w), all, fmt_pct(b[0], 24, sep, all, 0.5, " s"), fmt_pct(b[1], 24, sep, all, 0.1, " s"),
           fmt_pct(b[2], 24, sep, all, 0.9, " s"), never, nd, fmt_pct(b[3], 24, td, nd, 0.5, " s"),
           fmt_pct(b[4], 24, td, nd, 0.9, " s"), fmt_pct(b[5], 24, td, nd, 1.0, " s"), before);
    printf("oracle, paired with the declaration (runs with both): excluded all 8 minus declared median %s (min %s, "
           "max %s) in %d runs; ",
           fmt_pct(b[0], 24, dd, ndd, 0.5, " s"), fmt_pct(b[1], 24, dd, ndd, 0.0, " s"),
           fmt_pct(b[2], 24, dd, ndd, 1.0, " s"), ndd);
    printf("counting their evidence only from when the row took the lead for good (a median %s): excluded from a "
           "median %s (p90 %s), never in %d of %d runs; minus declared median %s in %d runs\n",
           fmt_pct(b[3], 24, tl, nl, 0.5, " s"), fmt_pct(b[4], 24, sl, nl, 0.5, " s"),
           fmt_pct(b[5], 24, sl, nl, 0.9, " s"), nlnever, nl, fmt_pct(b[0], 24, dl, ndl, 0.5, " s"), ndl);
    free(sep);
    free(td);
    free(dl);
    free(sl);
    free(tl);
    free(dd);
}

/* --oracle, over the runs >= OFF_TABLE_D off: when the truth's own theta
 * leads its nearest row by log 99 for good, and how far it led the row
 * wrongly declared when that was declared. A rule that refuses such a row
 * on the data must wait at least until then. */
static void print_oracle(const work_t *w, int all)
{
    char b[6][24];
    double *sep = malloc(sizeof(double) * (size_t)all), *llr = malloc(sizeof(double) * (size_t)all);
    int i, nfar = 0, never = 0, nd = 0, nout = 0, below = 0, neg = 0, nnb = 0, nnd = 0, nnbd = 0, nother = 0;
    double *tnb = malloc(sizeof(double) * (size_t)all);
    if (sep == NULL || llr == NULL || tnb == NULL) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    for (i = 0; i < all; ++i) {
        const run_t *r = &w->runs[i];
        if (r->d_table < OFF_TABLE_D - 1e-9) {
            continue;
        }
        never += r->or_sep < 0.0;
        sep[nfar++] = r->or_sep < 0.0 ? HUGE_VAL : r->or_sep;
        if (r->or_nb_first >= 0.0) {
            tnb[nnb++] = r->or_nb_first;
        }
        nnd += r->or_near_decl;
        nnbd += r->or_nb_decl;
        nother += r->false_decl && !r->or_near_decl;
        if (r->false_decl) {
            if (!isfinite(r->or_llr_decl)) {
                ++nout;
                continue;
            }
            llr[nd++] = r->or_llr_decl;
            below += r->or_llr_decl < LOG99;
            neg += r->or_llr_decl < 0.0;
        }
    }
    printf("oracle (the truth's own theta scored beside its %d nearest rows, %s, no hypothesis), runs >= "
           "%.0f%% off: %d runs; the truth leads its nearest row by log 99 from the end of a median %s (p10 %s, "
           "p90 %s) to the end, never in %d runs; a wrong row first declared in %d runs (%d not among the %d "
           "nearest): the truth's log-likelihood ratio against it then median %s, p90 %s, max %s; below "
           "log 99 in %d, below 0 in %d\n",
           ORACLE_ROWS, ORACLE_ENGINE(w), 100.0 * OFF_TABLE_D, nfar, fmt_pct(b[0], 24, sep, nfar, 0.5, " s"),
           fmt_pct(b[1], 24, sep, nfar, 0.1, " s"), fmt_pct(b[2], 24, sep, nfar, 0.9, " s"), never, nd + nout,
           nout, ORACLE_ROWS, fmt_pct(b[3], 24, llr, nd, 0.5, " nats"), fmt_pct(b[4], 24, llr, nd, 0.9, " nats"),
           fmt_pct(b[5], 24, llr, nd, 1.0, " nats"), below, neg);
    printf("oracle, the nearest row against 8 trains %.0f%% from it in W(v) (the test of the on-table line): it leads all "
           "8 by log 99 at some step in %d of %d runs (first at a median %s); the filter declared the nearest row in %d "
           "runs (not the truth's own row), and in %d of them at a step where the row led all 8 (a rule that also asks this test would have "
           "declared it); another row (not tested) in %d\n",
           100.0 * ORACLE_NEAR, nnb, nfar, fmt_pct(b[0], 24, tnb, nnb, 0.5, " s"), nnd, nnbd, nother);
    free(tnb);
    free(sep);
    free(llr);
}

/* Trains not on Table 1 (issue 10): W(v) error, the band, "no type fits"
 * and wrong declarations, over every run. */
static void print_offtable(const work_t *w, int seeds)
{
    const int all = w->n_jobs * seeds;
    double *werr = malloc(sizeof(double) * (size_t)all);
    int i, nofit = 0, band = 0, curve = 0, wrong = 0, n_nees = 0, in95 = 0;
    /* issue 10 counts "no type fits" over runs whose truth is >= 10 % from
     * every row: a perturbed row can land near another (or its own) row;
     * [1] those runs, [0] the others */
    int nf[2] = {0, 0}, wr[2] = {0, 0}, we[2] = {0, 0}, n[2] = {0, 0};
    if (werr == NULL) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    for (i = 0; i < all; ++i) {
        const run_t *r = &w->runs[i];
        werr[i] = r->w_rms;
        nofit += r->nofit_end;
        band += r->band_covers;
        curve += r->curve_covers;
        wrong += r->false_decl;
        {
            const int far = r->d_table >= OFF_TABLE_D - 1e-9; /* a mass-like 10 % is 10 % */
            ++n[far];
            nf[far] += r->nofit_end;
            wr[far] += r->false_decl;
            we[far] += r->final_declared >= 0 && r->final_declared != r->truth_index;
        }
        if (r->theta_nees >= 0.0) {
            ++n_nees;
            in95 += r->theta_nees <= 7.815; /* chi-square, 3 degrees of freedom, 95 % */
        }
    }
    printf("trains off the table: W(v) error at the end median %.2f%% p90 %.2f%%; the pointwise 95%% band (+- 1.96 "
           "sd) covers the truth at 68 of 71 speeds in %.1f%% of runs; 'no type fits' at the end in %.1f%%; a type declared in %.1f%% "
           "(refine %s)\n",
           100.0 * pct(werr, all, 0.5), 100.0 * pct(werr, all, 0.9), 100.0 * band / all, 100.0 * nofit / all,
           100.0 * wrong / all, w->st->base.refine == 2u ? "2" : (w->st->base.refine ? "on" : "off"));
    /* the curve's band at all 71 speeds; and theta's own 95 % ellipsoid, which a
     * calibrated covariance holds in 95 % of runs (the curve's band over every
     * speed, not only 0..350 km/h) */
    printf("the curve's 95%% band (+- %.4g sd) covers the truth at every speed in %.1f%% of runs; theta within "
           "its 95%% ellipsoid (theta_cov) at the end in %.1f%% of %d runs with a regular theta_cov\n",
           HSTPF_BAND_Z_CURVE, 100.0 * curve / all, n_nees > 0 ? 100.0 * in95 / n_nees : 0.0, n_nees);
    printf("by the truth's W(v) distance from its nearest bank row (RMS over 0..350 km/h, relative to the row): >= %.0f%%: %d runs, "
           "'no type fits' at the end %.1f%%, a type declared %.1f%% (at the end %.1f%%); < %.0f%%: %d runs, %.1f%%, "
           "%.1f%% (%.1f%%)\n",
           100.0 * OFF_TABLE_D, n[1], n[1] ? 100.0 * nf[1] / n[1] : 0.0, n[1] ? 100.0 * wr[1] / n[1] : 0.0,
           n[1] ? 100.0 * we[1] / n[1] : 0.0, 100.0 * OFF_TABLE_D, n[0], n[0] ? 100.0 * nf[0] / n[0] : 0.0,
           n[0] ? 100.0 * wr[0] / n[0] : 0.0, n[0] ? 100.0 * we[0] / n[0] : 0.0);
    if (w->st->oracle) {
        if (on_table(w->sc)) {
            print_oracle_on(w, all);
        } else {
            print_oracle(w, all);
        }
    }
    free(werr);
}

static const char *engine_name(int e)
{
    return e == HSTPF_ENGINE_PARTICLE ? "particle"
           : e == HSTPF_ENGINE_KALMAN ? "kalman"
           : e == HSTPF_ENGINE_GRID   ? "grid"
                                      : "auto";
}

/* The usage on out: stdout for --help (exit 0), stderr for a bad option (exit 2). */
static void usage_to(FILE *out)
{
    size_t i;
    fprintf(out,
            "usage: hstpf-mc --scenario NAME [--seeds N [--first-seed K]] [--threads N] [--duration S]\n"
            "  [--truth NAME] [--json FILE|-] [--trace FILE [--trace-seed N]] [--progress] [--version]\n"
            "  [--models LIST]  (the bank, each row a truth in turn: Table 1 names and custom rows name:c0:c1:c2,\n"
            "                   comma-separated, as hstpfd's models key)\n"
            "  filter settings: [--engine auto|particle|kalman|grid] [--particles M]\n"
            "  [--resample always|ess] [--ess F]\n"
            "  [--bank paired|independent] [--rough K] [--rough-min-s X] [--rough-min-v X] [--weights marginal|paper] [--q-floor X]\n"
            "  [--hold S] [--threshold Q] [--floor-depth X] [--edge-soft X] [--e-blur SD] [--refine | --no-refine | --refine-any-noise] [--refine-prior Q] [--refine-spread X]\n"
            "  [--consist-p P]  (cfg.consist_change_p: the consist changed at a stop of 3 min or more with probability P)\n"
            "  [--gauss-e]  (the filter told a Gaussian of the position noise's mean and sd, not its density)\n"
            "  [--gap-hold]  (tracgap scenarios: the gap feeds the last traction, as hstpfd did before, not 'unknown')\n"
            "  [--no-traction-check]  (cfg.traction_check = 0: the traction always believed)\n"
            "  [--no-fix-step]  (cfg.fix_step = 0: every fix within the gate used, a step in them too)\n"
            "  [--oracle]  (a second bank on the same inputs: off the table the truth's own theta beside its 4 nearest\n"
            "              rows, on it the truth's row beside 8 trains 10 %% from it; when the data tell them apart.\n"
            "              Not a filter setting)\n"
            "  [--oracle-gauss]  (the same on the Kalman engine with each noise a Gaussian of its mean and sd)\n"
            "  [--speed-lattice | --no-speed-lattice]  (grid: the speed cells carried by each model's map, or remapped)\n"
            "  [--grid-rows K]  (grid, Gaussian process noise: the K rows with the largest weights on the grid, 0 = every row)\n"
            "scenarios:");
    for (i = 0; i < sizeof scenarios / sizeof scenarios[0]; ++i) {
        fprintf(out, " %s", scenarios[i].name);
    }
    fprintf(out, "\n");
}

/* A bad command line: the reason on stderr; returns the exit status 2. */
#if defined(__GNUC__) || defined(__clang__)
__attribute__((format(printf, 1, 2)))
#endif
static int bad(const char *fmt, ...);
static int bad(const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "hstpf-mc: ");
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, " (hstpf-mc --help prints the usage)\n");
    return 2;
}

/* Option a's value v as a whole integer in [lo, hi] (atoi took "1x",
 * wrapped 65636 particles to 100 and 2^31 seeds to a negative). */
static int int_arg(const char *a, const char *v, long lo, long hi, long *out)
{
    char *end;
    long x;
    errno = 0;
    x = strtol(v, &end, 10);
    if (end == v || *end != '\0' || errno == ERANGE || x < lo || x > hi) {
        (void)bad("%s: '%s' is not a whole number from %ld to %ld", a, v, lo, hi);
        return -1;
    }
    *out = x;
    return 0;
}

/* Option a's value v as a whole finite number in [lo, hi]. */
static int num_arg(const char *a, const char *v, double lo, double hi, double *out)
{
    char *end;
    double x;
    errno = 0;
    x = strtod(v, &end);
    if (end == v || *end != '\0' || errno == ERANGE || !(x >= lo && x <= hi)) {
        if (lo <= -1e300) { /* the library's configuration check holds its range */
            (void)bad("%s: '%s' is not a finite number", a, v);
        } else {
            (void)bad("%s: '%s' is not a number from %g to %g", a, v, lo, hi);
        }
        return -1;
    }
    *out = x;
    return 0;
}

/* Option a's value v, one of the n names: its index, else -1 (a typo fell
 * to the other choice: --bank independnt ran the paired bank). */
static int choice_arg(const char *a, const char *v, const char *const *names, int n)
{
    int k;
    for (k = 0; k < n; ++k) {
        if (!strcmp(v, names[k])) {
            return k;
        }
    }
    (void)bad("%s: '%s' is not %s or %s", a, v, names[0], names[1]);
    return -1;
}

/* Names compare without case: --truth crh3 is CRH3 (as hstpf-simulate). */
static int same_name(const char *a, const char *b)
{
    if (a == NULL || b == NULL) {
        return 0;
    }
    for (; *a && *b; ++a, ++b) {
        if (tolower((unsigned char)*a) != tolower((unsigned char)*b)) {
            return 0;
        }
    }
    return *a == *b;
}

/* s[0..n) without its leading and trailing blanks, into out (size > n). */
static void trimmed(const char *s, size_t n, char *out)
{
    while (n > 0 && isspace((unsigned char)*s)) {
        ++s;
        --n;
    }
    while (n > 0 && isspace((unsigned char)s[n - 1])) {
        --n;
    }
    memcpy(out, s, n);
    out[n] = '\0';
}

/* A coefficient field of a custom row: a whole number, in (0, hi]. hstpf-mc
 * scores each coefficient's relative error, so none may be 0. */
static int coefficient(const char *item, const char *field, double hi, double *x)
{
    char buf[64], *end;
    const char *colon = strchr(field, ':');
    const size_t n = colon ? (size_t)(colon - field) : strlen(field);
    if (n >= sizeof buf) {
        return -1;
    }
    trimmed(field, n, buf);
    *x = strtod(buf, &end);
    if (end == buf || *end != '\0' || !(*x > 0.0 && *x <= hi)) {
        (void)bad("--models: '%s': c0, c1, c2 must be numbers in (0, %g], (0, %g], (0, %g] (each coefficient's "
                  "relative error is scored)",
                  item, HSTPF_C0_MAX, HSTPF_C1_MAX, HSTPF_C2_MAX);
        return -1;
    }
    return 0;
}

/* --models: a comma-separated bank of Table 1 names (any case), `all`, and
 * custom rows name:c0:c1:c2, as hstpfd's models key (blanks around each
 * entry and field ignored); names kept in names. A custom name is 1-31
 * printable characters without '"' or '\' (they go into the JSON as they
 * are) and is not a Table 1 name (the near-identical pairs are known by
 * name). Returns the number of rows, or -1 with the reason printed. */
static int parse_models(const char *list, hstpf_theta_t *models, char (*names)[NAME_MAX_LEN + 1])
{
    int n = 0, k;
    const char *p = list;
    for (;;) {
        const char *end = strchr(p, ',');
        const size_t len = end ? (size_t)(end - p) : strlen(p);
        char item[160];
        const char *colon, *q;
        if (len >= sizeof item) {
            (void)bad("--models: an entry of %u characters", (unsigned)len);
            return -1;
        }
        trimmed(p, len, item);
        if (item[0] == '\0') {
            (void)bad("--models: an empty entry in '%s'", list);
            return -1;
        }
        colon = strchr(item, ':');
        if (colon == NULL && same_name(item, "all")) {
            if (n + HSTPF_N_TRAIN_TYPES > MAXM) {
                (void)bad("--models: more than %d rows", MAXM);
                return -1;
            }
            for (k = 0; k < HSTPF_N_TRAIN_TYPES; ++k) {
                models[n++] = hstpf_train_types[k];
            }
        } else if (colon == NULL) {
            for (k = 0; k < HSTPF_N_TRAIN_TYPES && !same_name(hstpf_train_types[k].name, item); ++k) {
            }
            if (k == HSTPF_N_TRAIN_TYPES) {
                (void)bad("--models: '%s' is not a Table 1 name; a custom row is name:c0:c1:c2", item);
                return -1;
            }
            if (n == MAXM) {
                (void)bad("--models: more than %d rows", MAXM);
                return -1;
            }
            models[n++] = hstpf_train_types[k];
        } else {
            const char *c1 = strchr(colon + 1, ':'), *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
            char name[NAME_MAX_LEN + 1];
            const size_t nl = (size_t)(colon - item);
            if (c1 == NULL || c2 == NULL || strchr(c2 + 1, ':') != NULL || nl > NAME_MAX_LEN) {
                (void)bad("--models: custom entry '%s' must be name:c0:c1:c2, a name of 1-%d characters", item,
                          NAME_MAX_LEN);
                return -1;
            }
            trimmed(item, nl, name);
            for (q = name; *q && isprint((unsigned char)*q) && *q != '"' && *q != '\\'; ++q) {
            }
            if (name[0] == '\0' || *q != '\0') {
                (void)bad("--models: '%s': a name of printable characters, without '\"' or '\\'", item);
                return -1;
            }
            for (k = 0; k < HSTPF_N_TRAIN_TYPES && !same_name(hstpf_train_types[k].name, name); ++k) {
            }
            if (k < HSTPF_N_TRAIN_TYPES) {
                (void)bad("--models: '%s': a custom row may not take a Table 1 name", item);
                return -1;
            }
            if (n == MAXM) {
                (void)bad("--models: more than %d rows", MAXM);
                return -1;
            }
            if (coefficient(item, colon + 1, HSTPF_C0_MAX, &models[n].c0) != 0 ||
                coefficient(item, c1 + 1, HSTPF_C1_MAX, &models[n].c1) != 0 ||
                coefficient(item, c2 + 1, HSTPF_C2_MAX, &models[n].c2) != 0) {
                return -1;
            }
            memcpy(names[n], name, strlen(name) + 1);
            models[n].name = names[n];
            ++n;
        }
        if (end == NULL) {
            break;
        }
        p = end + 1;
    }
    for (k = 0; k < n - 1; ++k) {
        int j;
        for (j = k + 1; j < n; ++j) {
            if (same_name(models[k].name, models[j].name)) {
                (void)bad("--models: '%s' twice", models[j].name);
                return -1;
            }
        }
    }
    return n;
}

int main(int argc, char **argv)
{
    static const char *case1[3] = {"SS1/SS3/SS4", "CRH3", "SS8"};
    static const char *case2[3] = {"CRH1", "CRH3", "CRH5"};
    scenario_t sc;
    settings_t st;
    work_t w;
    hstpf_theta_t models[MAXM];
    int truths[MAXM];
    static char custom[MAXM][NAME_MAX_LEN + 1];
    const char *scen = NULL, *json = NULL, *truth_name = NULL, *models_list = NULL;
    int seeds = 100, threads = 2, i, j, n_models;
    double duration = -1.0;
    long lv = 0;
    int trace_seed_set = 0;
    pthread_t th[16];
    FILE *jf = NULL;
    int tot_s = 0, tot_f = 0, tot_w = 0, progress = isatty(2);
    double worst_w = 0.0;

    memset(&st, 0, sizeof st);
    (void)hstpf_config_default(&st.base);
    memset(&w, 0, sizeof w);
    w.trace_seed = 1;
    w.first_seed = 1;
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage_to(stdout);
            return 0;
        }
        if (!strcmp(a, "--version")) {
            printf("hstpf-mc %d.%d.%d\n", HSTPF_VERSION_MAJOR, HSTPF_VERSION_MINOR, HSTPF_VERSION_PATCH);
            return 0;
        }
        if (!strcmp(a, "--progress")) {
            progress = progress ? progress : 2; /* 2: asked for, not a terminal */
            continue;
        }
        if (!strcmp(a, "--gauss-e")) {
            st.gauss_e = 1;
            continue;
        }
        if (!strcmp(a, "--no-fix-step")) {
            st.base.fix_step = 0;
            continue;
        }
        if (!strcmp(a, "--no-traction-check")) {
            st.base.traction_check = 0;
            continue;
        }
        if (!strcmp(a, "--gap-hold")) {
            st.gap_hold = 1;
            continue;
        }
        if (!strcmp(a, "--oracle") || !strcmp(a, "--oracle-gauss")) {
            st.oracle = a[8] == '-' ? 2 : 1;
            continue;
        }
        if (!strcmp(a, "--speed-lattice") || !strcmp(a, "--no-speed-lattice")) {
            /* the grid's speed cells carried by each model's map (docs/grid.md) */
            st.base.grid_speed_lattice = (uint8_t)(a[2] == 's');
            continue;
        }
        if (!strcmp(a, "--refine") || !strcmp(a, "--no-refine")) {
            /* the continuous-theta hypothesis (docs/model.md; on by default) */
            st.base.refine = (uint8_t)(a[2] == 'r');
            continue;
        }
        if (!strcmp(a, "--refine-any-noise")) {
            /* the hypothesis also under non-Gaussian process noise (cfg.refine = 2) */
            st.base.refine = 2;
            continue;
        }
        if (v == NULL) {
            return bad("'%s': an unknown option, or one without its value", a);
        }
        ++i;
        {
            /* the options that take any finite number: the library's
             * configuration check holds their ranges (flag: set when given) */
            const struct {
                const char *name;
                double *x;
                int *flag;
            } reals[] = {{"--refine-prior", &st.base.refine_prior_q, NULL},
                         {"--refine-spread", &st.base.refine_spread, NULL},
                         {"--ess", &st.base.ess_threshold, NULL},
                         {"--rough", &st.base.roughening_k, NULL},
                         {"--rough-min-s", &st.base.rough_min_s, NULL},
                         {"--rough-min-v", &st.base.rough_min_v, NULL},
                         {"--q-floor", &st.base.q_floor, NULL},
                         {"--consist-p", &st.base.consist_change_p, NULL},
                         {"--hold", &st.base.declare_hold_s, NULL},
                         {"--threshold", &st.base.declare_threshold, NULL},
                         {"--e-blur", &st.base.e_blur_sd, NULL},
                         {"--floor-depth", &st.floor_depth, &st.floor_set},
                         {"--edge-soft", &st.edge_soft, &st.soft_set}};
            size_t r = 0;
            while (r < sizeof reals / sizeof reals[0] && strcmp(a, reals[r].name) != 0) {
                ++r;
            }
            if (r < sizeof reals / sizeof reals[0]) {
                if (num_arg(a, v, -1e300, 1e300, reals[r].x) != 0) {
                    return 2;
                }
                if (reals[r].flag != NULL) {
                    *reals[r].flag = 1;
                }
                continue;
            }
        }
        if (!strcmp(a, "--scenario")) {
            scen = v;
        } else if (!strcmp(a, "--models")) {
            models_list = v;
        } else if (!strcmp(a, "--seeds")) {
            if (int_arg(a, v, 1, 10000000, &lv) != 0) {
                return 2;
            }
            seeds = (int)lv;
        } else if (!strcmp(a, "--grid-rows")) {
            if (int_arg(a, v, 0, HSTPF_MAX_MODELS, &lv) != 0) {
                return 2;
            }
            st.base.grid_rows = (uint16_t)lv;
        } else if (!strcmp(a, "--threads")) {
            if (int_arg(a, v, 1, 16, &lv) != 0) {
                return 2;
            }
            threads = (int)lv;
        } else if (!strcmp(a, "--duration")) {
            /* at most 1e6 s: beyond it the simulated train runs past the library's position range */
            if (num_arg(a, v, 1.0, 1e6, &duration) != 0) {
                return 2;
            }
        } else if (!strcmp(a, "--truth")) {
            truth_name = v;
        } else if (!strcmp(a, "--json")) {
            json = v;
        } else if (!strcmp(a, "--trace")) {
            w.trace_path = v;
        } else if (!strcmp(a, "--first-seed")) {
            if (int_arg(a, v, 1, INT_MAX, &lv) != 0) {
                return 2;
            }
            w.first_seed = (int)lv;
        } else if (!strcmp(a, "--trace-seed")) {
            if (int_arg(a, v, 1, INT_MAX, &lv) != 0) {
                return 2;
            }
            w.trace_seed = (int)lv;
            trace_seed_set = 1;
        } else if (!strcmp(a, "--engine")) {
            if (!strcmp(v, "auto")) {
                st.base.engine = HSTPF_ENGINE_AUTO;
            } else if (!strcmp(v, "particle")) {
                st.base.engine = HSTPF_ENGINE_PARTICLE;
            } else if (!strcmp(v, "kalman")) {
                st.base.engine = HSTPF_ENGINE_KALMAN;
            } else if (!strcmp(v, "grid")) {
                st.base.engine = HSTPF_ENGINE_GRID;
            } else {
                return bad("--engine: '%s' is not auto, particle, kalman or grid", v);
            }
        } else if (!strcmp(a, "--particles")) {
            if (int_arg(a, v, 2, HSTPF_MAX_PARTICLES, &lv) != 0) {
                return 2;
            }
            st.base.n_particles = (uint16_t)lv;
        } else if (!strcmp(a, "--resample")) {
            static const char *const names[2] = {"always", "ess"};
            const int k = choice_arg(a, v, names, 2);
            if (k < 0) {
                return 2;
            }
            st.base.resample = k == 0 ? HSTPF_RESAMPLE_ALWAYS : HSTPF_RESAMPLE_ESS;
        } else if (!strcmp(a, "--bank")) {
            static const char *const names[2] = {"paired", "independent"};
            const int k = choice_arg(a, v, names, 2);
            if (k < 0) {
                return 2;
            }
            st.base.bank = k == 1 ? HSTPF_BANK_INDEPENDENT : HSTPF_BANK_PAIRED;
        } else if (!strcmp(a, "--weights")) {
            static const char *const names[2] = {"marginal", "paper"};
            const int k = choice_arg(a, v, names, 2);
            if (k < 0) {
                return 2;
            }
            st.base.weight_method = k == 1 ? HSTPF_WEIGHT_PAPER : HSTPF_WEIGHT_MARGINAL;
        } else {
            return bad("unknown option '%s'", a);
        }
    }
    for (i = 0; scen && i < (int)(sizeof scenarios / sizeof scenarios[0]); ++i) {
        if (!strcmp(scenarios[i].name, scen)) {
            break;
        }
    }
    if (scen == NULL) {
        return bad("no --scenario");
    }
    if (i == (int)(sizeof scenarios / sizeof scenarios[0])) {
        return bad("no scenario '%s'%s", scen,
                   strstr(scen, "-particle") ? " (a scenario on the particle engine: --engine particle)" : "");
    }
    if (seeds > INT_MAX - w.first_seed + 1) {
        return bad("--first-seed %d with --seeds %d runs past seed %d", w.first_seed, seeds, INT_MAX);
    }
    if (w.trace_path != NULL) { /* said now, not after the study */
        FILE *t;
        if (!trace_seed_set) {
            w.trace_seed = w.first_seed;
        }
        if (w.trace_seed < w.first_seed || w.trace_seed - w.first_seed >= seeds) {
            return bad("--trace-seed %d is not among the seeds %d to %d", w.trace_seed, w.first_seed,
                       w.first_seed + seeds - 1);
        }
        t = fopen(w.trace_path, "w");
        if (t == NULL) {
            return bad("--trace %s: %s", w.trace_path, strerror(errno));
        }
        fclose(t);
    }
    sc = scenarios[i];
    if (duration > 0.0) {
        sc.duration_s = duration;
    }
    if (models_list) {
        n_models = parse_models(models_list, models, custom);
        if (n_models < 0) {
            return 2;
        }
        if (sc.absent && n_models < 2) {
            return bad("--scenario %s leaves the truth's row out of the bank: --models needs 2 rows or more", sc.name);
        }
    } else if (sc.all17) {
        n_models = HSTPF_N_TRAIN_TYPES;
        for (j = 0; j < n_models; ++j) {
            models[j] = hstpf_train_types[j];
        }
    } else {
        n_models = 3;
        for (j = 0; j < 3; ++j) {
            models[j] = hstpf_train_types[hstpf_train_type_find(sc.paper_case == 1 ? case1[j] : case2[j])];
        }
    }
    w.n_jobs = 0;
    for (j = 0; j < n_models; ++j) {
        /* the paper's cases have one truth, CRH3; the 17-type study and a
         * bank of --models every row */
        if ((!sc.all17 && !models_list && strcmp(models[j].name, "CRH3") != 0) ||
            (truth_name && !same_name(models[j].name, truth_name))) {
            continue;
        }
        truths[w.n_jobs++] = j;
    }
    if (w.n_jobs == 0) {
        return bad(!sc.all17 && !models_list ? "--truth %s: the paper's scenarios have one truth, CRH3 (with --models "
                                               "every row of the bank is a truth)"
                                             : "--truth %s: no such row in the bank",
                   truth_name ? truth_name : "");
    }
    w.sc = &sc;
    w.st = &st;
    w.models = models;
    w.n_models = n_models;
    w.truths = truths;
    w.seeds = seeds;
    w.runs = calloc((size_t)(w.n_jobs * seeds), sizeof(run_t));
    if (w.runs == NULL) {
        return 1;
    }
    if (json && strcmp(json, "-") != 0) { /* opened before the study: a bad path loses no runs */
        jf = fopen(json, "w");
        if (jf == NULL) {
            return bad("--json %s: %s", json, strerror(errno));
        }
    }
    pthread_mutex_init(&w.lock, NULL);
    for (i = 0; i < threads; ++i) {
        pthread_create(&th[i], NULL, worker, &w);
    }
    if (progress) {
        wait_progress(&w, sc.name, progress == 1);
    }
    for (i = 0; i < threads; ++i) {
        pthread_join(th[i], NULL);
    }

    if (json && !strcmp(json, "-")) { /* JSON on stdout, the table on stderr (python's "-" convention) */
        const int fd = dup(STDOUT_FILENO);
        fflush(stdout);
        jf = fd >= 0 ? fdopen(fd, "w") : NULL;
        if (jf == NULL || dup2(STDERR_FILENO, STDOUT_FILENO) < 0) {
            perror("--json -");
            return 1;
        }
    }
    if (jf) {
        fprintf(jf,
                "{\"scenario\":\"%s\",\"engine\":\"%s\",\"seeds\":%d,\"duration_s\":%.0f,\"particles\":%u,"
                "\"results\":[",
                sc.name, engine_name(st.base.engine), seeds, sc.duration_s, (unsigned)st.base.n_particles);
    }
    printf("scenario %s: %d models, %d seeds, %.0f s, engine %s, M = %u\n", sc.name, n_models, seeds,
           sc.duration_s, engine_name(st.base.engine), (unsigned)st.base.n_particles);
    if (sc.tt) {
        print_journey(&w, models, truths, seeds, jf);
        print_offtable(&w, seeds);
        if (jf) {
            fprintf(jf, "]}\n");
            fclose(jf);
        }
        free(w.runs);
        return 0;
    }
    printf("%-24s %7s %7s %7s %7s %7s %6s %6s %7s %7s %5s %7s %7s %8s\n", "truth", "success", "x_med",
           "x_p90", "x_max", "t_med", "false", "undec", "c_err", "W_rms", "W>5%", "pos_rms", "spd_rms", "pos_bias");
    for (j = 0; j < w.n_jobs; ++j) {
        const run_t *rr = &w.runs[j * seeds];
        double *td = malloc(sizeof(double) * (size_t)seeds), *tx = malloc(sizeof(double) * (size_t)seeds);
        int ns = 0, nd = 0, nx = 0, nf = 0, nu = 0, nw = 0;
        double cerr = 0.0, wsum = 0.0, prms = 0.0, vrms = 0.0, pbias = 0.0;
        for (i = 0; i < seeds; ++i) {
            ns += rr[i].success;
            nf += rr[i].false_decl;
            nu += rr[i].final_declared < 0;
            if (rr[i].t_declare >= 0.0) {
                td[nd++] = rr[i].t_declare;
            }
            if (rr[i].success) {
                tx[nx++] = rr[i].t_cross;
            }
            cerr += (rr[i].par_err[0] + rr[i].par_err[1] + rr[i].par_err[2]) / 3.0;
            wsum += rr[i].w_rms;
            nw += rr[i].w_rms > 0.05;
            prms += rr[i].pos_rms * rr[i].pos_rms;
            vrms += rr[i].spd_rms * rr[i].spd_rms;
            pbias += rr[i].pos_bias;
        }
        printf("%-24s %6.1f%% %7.0f %7.0f %7.0f %7.0f %5.1f%% %5.1f%% %6.2f%% %6.2f%% %5d %7.2f %7.3f %+8.3f\n",
               models[truths[j]].name, 100.0 * ns / seeds, pct(tx, nx, 0.5), pct(tx, nx, 0.9),
               pct(tx, nx, 1.0), pct(td, nd, 0.5), 100.0 * nf / seeds, 100.0 * nu / seeds,
               100.0 * cerr / seeds, 100.0 * wsum / seeds, nw, sqrt(prms / seeds), sqrt(vrms / seeds),
               pbias / seeds);
        tot_s += ns;
        tot_f += nf;
        tot_w += nw;
        worst_w = wsum / seeds > worst_w ? wsum / seeds : worst_w;
        if (jf) {
            fprintf(jf, "%s{\"truth\":\"%s\",\"runs\":[", j ? "," : "", models[truths[j]].name);
            for (i = 0; i < seeds; ++i) {
                const run_t *r = &rr[i];
                fprintf(jf,
                        "%s{\"seed\":%d,\"success\":%d,\"t_cross\":%.0f,\"t_declare\":%.0f,"
                        "\"false_decl\":%d,\"false_time\":%.0f,\"false_model\":\"%s\",\"final_declared\":\"%s\",\"par_err\":[%.5g,%.5g,%.5g],"
                        "\"par_err_max_after\":[%.5g,%.5g,%.5g],\"w_rms\":%.5g,\"pos_rms\":%.4g,"
                        "\"spd_rms\":%.4g,\"q_true_end\":%.6g,\"floor_hits_true\":%u",
                        i ? "," : "", w.first_seed + i, r->success, r->t_cross, r->t_declare, r->false_decl, r->false_time,
                        r->false_model >= 0 ? models[r->false_model].name : "",
                        r->final_declared >= 0 ? models[r->final_declared].name : "", r->par_err[0],
                        r->par_err[1], r->par_err[2], r->par_err_max_after[0], r->par_err_max_after[1],
                        r->par_err_max_after[2], r->w_rms, r->pos_rms, r->spd_rms, r->q_true_end,
                        (unsigned)r->floor_hits_true);
                if (st.oracle && on_table(&sc)) {
                    fprintf(jf, ",\"oracle_sep\":%.0f", r->or_sep);
                }
                fputc('}', jf);
            }
            fprintf(jf, "]}");
        }
        free(td);
        free(tx);
    }
    if (w.n_jobs > 1) {
        const int runs = w.n_jobs * seeds;
        double sp = 0.0, sv = 0.0;
        for (i = 0; i < runs; ++i) {
            sp += w.runs[i].pos_rms * w.runs[i].pos_rms;
            sv += w.runs[i].spd_rms * w.runs[i].spd_rms;
        }
        printf("total: %d runs, success %.1f%%, false declarations %d (%.1f%%), W(v) error > 5%% in %d "
               "(%.1f%%), worst truth's mean W(v) error %.2f%%, position RMS %.3f m, speed RMS %.4f m/s\n",
               runs, 100.0 * tot_s / runs, tot_f, 100.0 * tot_f / runs, tot_w, 100.0 * tot_w / runs,
               100.0 * worst_w, sqrt(sp / runs), sqrt(sv / runs));
    }
    {
        const int runs = w.n_jobs * seeds;
        long tf = 0;
        int ntf = 0;
        double cmax = 0.0;
        for (i = 0; i < runs; ++i) {
            tf += w.runs[i].j.trac_fault;
            ntf += w.runs[i].j.trac_fault > 0;
            cmax = w.runs[i].j.trac_cusum_max > cmax ? w.runs[i].j.trac_cusum_max : cmax;
        }
        printf("the traction taken for wrong (traction_fault) at %ld steps in %d of %d runs; its CUSUM while the "
               "traction was believed at most %.2f nats\n", tf, ntf, runs, cmax);
    }
    if (st.oracle && on_table(&sc)) {
        print_oracle_on(&w, w.n_jobs * seeds);
    }
    if (jf) {
        fprintf(jf, "]}\n");
        fclose(jf);
    }
    free(w.runs);
    return 0;
}
