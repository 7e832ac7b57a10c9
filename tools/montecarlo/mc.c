/* hstpf-mc: Monte Carlo study of the estimator over many independent seeds
 * (simulation and filter seeds separate), per scenario and true type.
 * Prints a table and, with --json, machine-readable results; --trace writes
 * one run's time series for the figures. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hstpf/hstpf.h"
#include "hstpf_sim.h"

#define MAXM HSTPF_MAX_MODELS

typedef struct {
    const char *name;
    int paper_case;             /* 1 or 2: noise of the paper's case */
    hstpf_profile_t profile;
    double loss_rate;
    int all17;                  /* models: all 17 types; else the case's 3 */
    double duration_s;
    int hilly;                  /* simulate on the hilly track */
    int filter_knows_track;     /* give the track profile to the filter */
} scenario_t;

/* Filter settings under study: the same for every scenario and truth. */
typedef struct {
    hstpf_config_t base;
    double floor_depth, edge_soft;
    int floor_set, soft_set;
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
    pthread_mutex_t lock;
    const char *trace_path;     /* first run of the first job */
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

static void one_run(const work_t *w, int truth, int seed, run_t *r, FILE *trace)
{
    static const double thr = 0.9;
    hstpf_t *f = malloc(sizeof *f); /* the tool, not the library, allocates */
    hstpf_config_t cfg = w->st->base;
    hstpf_sim_config_t sc;
    hstpf_sim_t sim;
    hstpf_estimate_t est;
    hstpf_sim_sample_t smp;
    double last_below = 0.0, se_p = 0.0, se_v = 0.0, sb_p = 0.0, n_after = 0.0;
    long n_err = 0;
    int k;
    if (f == NULL) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    memset(r, 0, sizeof *r);
    r->truth_index = truth;
    r->t_declare = -1.0;
    r->false_time = -1.0;
    r->false_model = -1;
    hstpf_sim_default(&sc);
    sc.truth = w->models[truth];
    sc.profile = w->sc->profile;
    sc.loss_rate = w->sc->loss_rate;
    if (w->sc->paper_case == 2) {
        hstpf_sim_case2(&sc);
    }
    if (w->sc->hilly) {
        sc.track = hilly_track;
        sc.n_track = (uint16_t)(sizeof hilly_track / sizeof hilly_track[0]);
    }
    /* independent streams: simulation from seed, filter from another */
    sc.seed = 1000003ull * (uint64_t)(truth + 1) + (uint64_t)seed;
    cfg.seed = 0x9E3779B97F4A7C15ull ^ (7919ull * (uint64_t)(truth + 1) + (uint64_t)seed);
    cfg.noise_s = sc.noise_s;
    cfg.noise_v = sc.noise_v;
    cfg.noise_e = sc.noise_e;
    if (w->st->floor_set) {
        cfg.noise_e.floor_depth = w->st->floor_depth;
    }
    if (w->st->soft_set) {
        cfg.noise_e.edge_soft = w->st->edge_soft;
    }
    cfg.models = w->models;
    cfg.n_models = (uint16_t)w->n_models;
    if (w->sc->filter_knows_track) {
        cfg.track = sc.track;
        cfg.n_track = sc.n_track;
    }
    if (hstpf_init(f, sizeof *f, &cfg) != HSTPF_OK) {
        fprintf(stderr, "hstpf_init failed\n");
        exit(1);
    }
    hstpf_sim_init(&sim, &sc);
    if (trace) {
        fprintf(trace, "t,s_true,v_true,u,y,has_y,s_est,v_est,c0,c1,c2,declared");
        for (k = 0; k < w->n_models; ++k) {
            fprintf(trace, ",q%d", k);
        }
        fprintf(trace, "\n");
    }
    while (sim.t <= w->sc->duration_s) {
        hstpf_input_t in;
        double qt;
        hstpf_sim_next_input(&sim, &smp, &in);
        if (hstpf_step(f, &in) != HSTPF_OK) {
            ++n_err;
        }
        (void)hstpf_estimate(f, &est);
        qt = (double)est.model[truth].q;
        if (!(qt > thr)) {
            last_below = smp.t;
        }
        if (est.declared >= 0 && est.declared != truth && !r->false_decl) {
            r->false_decl = 1;
            r->false_time = est.decision_time_s;
            r->false_model = est.declared;
        }
        if (smp.t >= 60.0) {
            se_p += (est.position_m - smp.s) * (est.position_m - smp.s);
            sb_p += est.position_m - smp.s;
            se_v += ((double)est.speed_mps - smp.v) * ((double)est.speed_mps - smp.v);
            n_after += 1.0;
        }
        if (est.declared == truth && r->t_declare >= 0.0) {
            for (k = 0; k < 3; ++k) {
                const double tv = k == 0 ? sc.truth.c0 : (k == 1 ? sc.truth.c1 : sc.truth.c2);
                const double e = fabs((double)est.theta[k] - tv) / tv;
                if (e > r->par_err_max_after[k]) {
                    r->par_err_max_after[k] = e;
                }
            }
        }
        if (est.declared == truth && r->t_declare < 0.0) {
            r->t_declare = est.decision_time_s;
        } else if (est.declared != truth) {
            r->t_declare = -1.0;
        }
        if (trace) {
            fprintf(trace, "%.0f,%.3f,%.4f,%.4f,%.3f,%d,%.3f,%.4f,%.5f,%.6f,%.8f,%d", smp.t, smp.s,
                    smp.v, smp.u, smp.y, smp.has_y, est.position_m, (double)est.speed_mps,
                    (double)est.theta[0], (double)est.theta[1], (double)est.theta[2], est.declared);
            for (k = 0; k < w->n_models; ++k) {
                fprintf(trace, ",%.6g", (double)est.model[k].q);
            }
            fprintf(trace, "\n");
        }
    }
    n_after = n_after > 0.0 ? n_after : 1.0;
    r->pos_rms = sqrt(se_p / n_after);
    r->spd_rms = sqrt(se_v / n_after);
    r->pos_bias = sb_p / n_after;
    r->floor_hits_true = est.model[truth].floor_hits;
    r->q_true_end = (double)est.model[truth].q;
    r->success = r->q_true_end > thr;
    r->t_cross = r->success ? last_below + 1.0 : -1.0;
    r->final_declared = est.declared;
    {
        const double th[3] = {(double)est.theta[0], (double)est.theta[1], (double)est.theta[2]};
        r->par_err[0] = fabs(th[0] - sc.truth.c0) / sc.truth.c0;
        r->par_err[1] = fabs(th[1] - sc.truth.c1) / sc.truth.c1;
        r->par_err[2] = fabs(th[2] - sc.truth.c2) / sc.truth.c2;
        r->w_rms = w_rms_rel(th, &sc.truth);
    }
    if (n_err > 0) {
        fprintf(stderr, "warning: %ld steps rejected (truth %d seed %d)\n", n_err, truth, seed);
    }
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
        if (idx == 0 && w->trace_path) {
            trace = fopen(w->trace_path, "w");
        }
        one_run(w, w->truths[job], seed + 1, &w->runs[idx], trace);
        if (trace) {
            fclose(trace);
        }
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

static const scenario_t scenarios[] = {
    {"paper1", 1, HSTPF_PROFILE_PAPER, 0.0, 0, 1800.0, 0, 0},
    {"paper2", 2, HSTPF_PROFILE_PAPER, 0.0, 0, 1800.0, 0, 0},
    {"all17", 1, HSTPF_PROFILE_PAPER, 0.0, 1, 1800.0, 0, 0},
    {"all17-coast", 1, HSTPF_PROFILE_COAST_BRAKE, 0.0, 1, 1800.0, 0, 0},
    {"all17-coast-loss", 1, HSTPF_PROFILE_COAST_BRAKE, 0.05, 1, 1800.0, 0, 0},
    {"hilly-ignored", 1, HSTPF_PROFILE_PAPER, 0.0, 1, 1800.0, 1, 0},
    {"hilly-known", 1, HSTPF_PROFILE_PAPER, 0.0, 1, 1800.0, 1, 1},
};

static void usage(void)
{
    size_t i;
    fprintf(stderr,
            "usage: hstpf-mc --scenario NAME [--seeds N] [--threads N] [--duration S]\n"
            "  [--truth NAME] [--json FILE] [--trace FILE]\n"
            "  filter settings: [--engine auto|particle|kalman] [--particles M]\n"
            "  [--resample always|ess] [--ess F]\n"
            "  [--bank paired|independent] [--rough K] [--rough-min-s X] [--rough-min-v X] [--weights marginal|paper] [--q-floor X]\n"
            "  [--hold S] [--threshold Q] [--floor-depth X] [--edge-soft X] [--e-blur SD]\n"
            "scenarios:");
    for (i = 0; i < sizeof scenarios / sizeof scenarios[0]; ++i) {
        fprintf(stderr, " %s", scenarios[i].name);
    }
    fprintf(stderr, "\n");
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
    const char *scen = NULL, *json = NULL, *truth_name = NULL;
    int seeds = 100, threads = 2, i, j, n_models;
    double duration = -1.0;
    pthread_t th[16];
    FILE *jf = NULL;
    int tot_s = 0, tot_f = 0, tot_w = 0;
    double worst_w = 0.0;

    memset(&st, 0, sizeof st);
    (void)hstpf_config_default(&st.base);
    memset(&w, 0, sizeof w);
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (v == NULL) {
            usage();
            return 2;
        }
        ++i;
        if (!strcmp(a, "--scenario")) {
            scen = v;
        } else if (!strcmp(a, "--seeds")) {
            seeds = atoi(v);
        } else if (!strcmp(a, "--threads")) {
            threads = atoi(v);
        } else if (!strcmp(a, "--duration")) {
            duration = atof(v);
        } else if (!strcmp(a, "--truth")) {
            truth_name = v;
        } else if (!strcmp(a, "--json")) {
            json = v;
        } else if (!strcmp(a, "--trace")) {
            w.trace_path = v;
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
                usage();
                return 2;
            }
        } else if (!strcmp(a, "--particles")) {
            st.base.n_particles = (uint16_t)atoi(v);
        } else if (!strcmp(a, "--resample")) {
            st.base.resample = !strcmp(v, "always") ? HSTPF_RESAMPLE_ALWAYS : HSTPF_RESAMPLE_ESS;
        } else if (!strcmp(a, "--ess")) {
            st.base.ess_threshold = atof(v);
        } else if (!strcmp(a, "--bank")) {
            st.base.bank = !strcmp(v, "independent") ? HSTPF_BANK_INDEPENDENT : HSTPF_BANK_PAIRED;
        } else if (!strcmp(a, "--rough")) {
            st.base.roughening_k = atof(v);
        } else if (!strcmp(a, "--rough-min-s")) {
            st.base.rough_min_s = atof(v);
        } else if (!strcmp(a, "--rough-min-v")) {
            st.base.rough_min_v = atof(v);
        } else if (!strcmp(a, "--weights")) {
            st.base.weight_method = !strcmp(v, "paper") ? HSTPF_WEIGHT_PAPER : HSTPF_WEIGHT_MARGINAL;
        } else if (!strcmp(a, "--q-floor")) {
            st.base.q_floor = atof(v);
        } else if (!strcmp(a, "--hold")) {
            st.base.declare_hold_s = atof(v);
        } else if (!strcmp(a, "--threshold")) {
            st.base.declare_threshold = atof(v);
        } else if (!strcmp(a, "--floor-depth")) {
            st.floor_depth = atof(v);
            st.floor_set = 1;
        } else if (!strcmp(a, "--e-blur")) {
            st.base.e_blur_sd = atof(v);
        } else if (!strcmp(a, "--edge-soft")) {
            st.edge_soft = atof(v);
            st.soft_set = 1;
        } else {
            usage();
            return 2;
        }
    }
    for (i = 0; scen && i < (int)(sizeof scenarios / sizeof scenarios[0]); ++i) {
        if (!strcmp(scenarios[i].name, scen)) {
            break;
        }
    }
    if (scen == NULL || i == (int)(sizeof scenarios / sizeof scenarios[0]) || seeds < 1 ||
        threads < 1 || threads > 16) {
        usage();
        return 2;
    }
    sc = scenarios[i];
    if (duration > 0.0) {
        sc.duration_s = duration;
    }
    if (sc.all17) {
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
        /* the paper's cases have one truth, CRH3; the 17-type study all */
        if ((!sc.all17 && strcmp(models[j].name, "CRH3") != 0) ||
            (truth_name && strcmp(models[j].name, truth_name) != 0)) {
            continue;
        }
        truths[w.n_jobs++] = j;
    }
    if (w.n_jobs == 0) {
        fprintf(stderr, "no such truth in the model set\n");
        return 2;
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
    pthread_mutex_init(&w.lock, NULL);
    for (i = 0; i < threads; ++i) {
        pthread_create(&th[i], NULL, worker, &w);
    }
    for (i = 0; i < threads; ++i) {
        pthread_join(th[i], NULL);
    }

    if (json) {
        jf = fopen(json, "w");
        if (jf == NULL) {
            perror(json);
            return 1;
        }
        fprintf(jf, "{\"scenario\":\"%s\",\"seeds\":%d,\"duration_s\":%.0f,\"particles\":%u,\"results\":[",
                sc.name, seeds, sc.duration_s, (unsigned)st.base.n_particles);
    }
    printf("scenario %s: %d models, %d seeds, %.0f s, M = %u\n", sc.name, n_models, seeds,
           sc.duration_s, (unsigned)st.base.n_particles);
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
                        "\"spd_rms\":%.4g,\"q_true_end\":%.6g,\"floor_hits_true\":%u}",
                        i ? "," : "", i + 1, r->success, r->t_cross, r->t_declare, r->false_decl, r->false_time,
                        r->false_model >= 0 ? models[r->false_model].name : "",
                        r->final_declared >= 0 ? models[r->final_declared].name : "", r->par_err[0],
                        r->par_err[1], r->par_err[2], r->par_err_max_after[0], r->par_err_max_after[1],
                        r->par_err_max_after[2], r->w_rms, r->pos_rms, r->spd_rms, r->q_true_end,
                        (unsigned)r->floor_hits_true);
            }
            fprintf(jf, "]}");
        }
        free(td);
        free(tx);
    }
    if (w.n_jobs > 1) {
        const int runs = w.n_jobs * seeds;
        printf("total: %d runs, success %.1f%%, false declarations %d (%.1f%%), W(v) error > 5%% in %d "
               "(%.1f%%), worst truth's mean W(v) error %.2f%%\n",
               runs, 100.0 * tot_s / runs, tot_f, 100.0 * tot_f / runs, tot_w, 100.0 * tot_w / runs,
               100.0 * worst_w);
    }
    if (jf) {
        fprintf(jf, "]}\n");
        fclose(jf);
    }
    free(w.runs);
    return 0;
}
