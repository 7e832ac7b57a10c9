/* hstpf-bench: time hstpf_step() on the host, one thread.
 *
 * The paper's Case 1 (simulator: CRH3, paper profile, Case 1 noise, seed 1;
 * --case 2: Case 2's Gamma noise, the filter told the same) is simulated first into an array of inputs; then, for each configuration
 * (models x particles), every run initialises the instance (not timed) and
 * times only the loop of hstpf_step() calls over the whole trajectory with
 * clock_gettime(CLOCK_MONOTONIC), repeating the trajectory until the run has
 * lasted --min-time. Reports the median and the best (minimum) of --runs
 * runs, after one warm-up run, as nanoseconds per particle-step
 * (time / (steps x models x particles)) and bank steps per second. The
 * thread's CPU time (CLOCK_THREAD_CPUTIME_ID) is reported beside the wall
 * time: a large gap means the run was preempted (a busy machine).
 *
 * Configurations MxN run the particle engine; MxK runs the Kalman engine
 * (one EKF per model) and MxG the grid engine (HSTPF_GRID_NS x
 * HSTPF_GRID_NV cells per model), both reported per model-step instead.
 * The grid's cost depends on the kernels' width in cells, so on the noise:
 * Case 2's one-sided noises have kernels as wide as the grid (--case 2).
 *
 * Models: 3 = the paper's Case 1 set {SS1/SS3/SS4, CRH3, SS8}; otherwise the
 * first M rows of Table 1 (17 = all of them). Not a test: ctest does not run
 * it. Pin it to one core for stable figures: taskset -c 1 hstpf-bench. */
#define _POSIX_C_SOURCE 200112L

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "hstpf/hstpf.h"
#include "hstpf_sim.h"

#ifndef HSTPF_BENCH_FLAGS
#define HSTPF_BENCH_FLAGS "unknown"
#endif
#ifndef HSTPF_BENCH_BUILD_TYPE
#define HSTPF_BENCH_BUILD_TYPE "unknown"
#endif
#ifndef HSTPF_BENCH_LIB
#define HSTPF_BENCH_LIB "hstpf"
#endif

#if defined(__clang__)
#define COMPILER "clang " __clang_version__
#elif defined(__GNUC__)
#define COMPILER "gcc " __VERSION__
#else
#define COMPILER "unknown compiler"
#endif

#define MAX_CONFIGS 16
#define MAX_RUNS 101
#define TARGET_NS 15.0

typedef struct {
    unsigned models, particles;
    int kalman;               /* Kalman engine: figures are per model-step */
    int grid;                 /* grid engine: the same */
    int skipped;              /* above the library's capacity */
    unsigned runs;
    double ns[MAX_RUNS];      /* ns per particle-step, per run (wall) */
    double cpu[MAX_RUNS];     /* the same in thread CPU time */
    double med, min;          /* of ns[] */
    double cpu_med;           /* of cpu[] */
    unsigned long long particle_steps; /* per run, last run */
    int declared;             /* final declared model of the last pass (use of the result) */
} result_t;

static hstpf_t filt; /* static, as on a target */
static uint64_t ws[HSTPF_WORKSPACE_WORDS(HSTPF_WORKSPACE_MAX_BYTES)]; /* any engine */

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double clock_ns(clockid_t id)
{
    struct timespec ts;
    (void)clock_gettime(id, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

static double median(const double *x, unsigned n)
{
    double s[MAX_RUNS];
    memcpy(s, x, n * sizeof s[0]);
    qsort(s, n, sizeof s[0], cmp_double);
    return (n & 1u) ? s[n / 2u] : 0.5 * (s[n / 2u - 1u] + s[n / 2u]);
}

/* The usage on out: stdout for --help (exit 0), stderr for a bad option (exit 2). */
static void usage_to(FILE *out)
{
    fprintf(out,
            "usage: hstpf-bench [--json] [--case 1|2] [--refine 0|1|2] [--runs N] [--steps N] [--min-time S] [--config MxN]...\n"
            "  [--version]\n"
            "  MxN: M models, N particles; MxK: M models, Kalman engine; MxG: grid engine\n"
            "  default: --runs 9 --steps 1801 --min-time 0.3 --config 3x100 --config 17x1000\n"
            "           --config 3xK --config 17xK --config 3xG --config 17xG\n");
}

static void usage(void)
{
    usage_to(stderr);
}

static int fill_models(hstpf_theta_t *models, unsigned m)
{
    static const char *const case1[3] = {"SS1/SS3/SS4", "CRH3", "SS8"};
    unsigned i;
    for (i = 0; i < m; ++i) {
        if (m == 3u) {
            const int32_t row = hstpf_train_type_find(case1[i]);
            if (row < 0) {
                return -1;
            }
            models[i] = hstpf_train_types[row];
        } else {
            models[i] = hstpf_train_types[i];
        }
    }
    return 0;
}

/* One timed run: passes over the trajectory until min_ns has elapsed inside
 * hstpf_step(). Returns ns per particle-step (wall; *cpu_out: thread CPU
 * time), or a negative value on error. */
static double run_once(const hstpf_config_t *cfg, const hstpf_input_t *in, unsigned steps,
                       double min_ns, result_t *r, double *cpu_out)
{
    double elapsed = 0.0, cpu = 0.0;
    unsigned long long ps = 0;
    do {
        hstpf_estimate_t est;
        double t0, t1, c0, c1;
        unsigned k, ok = 0;
        hstpf_config_t c = *cfg;
        int32_t err;
        c.workspace = ws;
        c.workspace_size = sizeof ws;
        err = hstpf_init(&filt, sizeof filt, &c);
        if (err != HSTPF_OK) {
            fprintf(stderr, "hstpf_init: %s\n", hstpf_strerror(err));
            return -1.0;
        }
        c0 = clock_ns(CLOCK_THREAD_CPUTIME_ID);
        t0 = clock_ns(CLOCK_MONOTONIC);
        for (k = 0; k < steps; ++k) {
            ok += hstpf_step(&filt, &in[k]) == HSTPF_OK ? 1u : 0u;
        }
        t1 = clock_ns(CLOCK_MONOTONIC);
        c1 = clock_ns(CLOCK_THREAD_CPUTIME_ID);
        elapsed += t1 - t0;
        cpu += c1 - c0;
        ps += (unsigned long long)steps * cfg->n_models *
              (cfg->engine == HSTPF_ENGINE_PARTICLE ? cfg->n_particles : 1u);
        (void)hstpf_estimate(&filt, &est);
        r->declared = est.declared;
        if (ok != steps) {
            fprintf(stderr, "warning: %u of %u steps were rejected\n", steps - ok, steps);
        }
    } while (elapsed < min_ns);
    r->particle_steps = ps;
    *cpu_out = cpu / (double)ps;
    return elapsed / (double)ps;
}

int main(int argc, char **argv)
{
    result_t res[MAX_CONFIGS];
    unsigned n_cfg = 0, runs = 9, steps = 1801, i, k;
    double min_time = 0.3;
    int json = 0, noise_case = 1, refine = -1;
    hstpf_input_t *in;
    hstpf_sim_config_t sc;
    hstpf_sim_t sim;
    hstpf_sim_sample_t smp;

    memset(res, 0, sizeof res);
    for (i = 1; i < (unsigned)argc; ++i) {
        const char *a = argv[i];
        if (strcmp(a, "--json") == 0) {
            json = 1;
        } else if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage_to(stdout);
            return 0;
        } else if (strcmp(a, "--version") == 0) {
            printf("hstpf-bench %d.%d.%d\n", HSTPF_VERSION_MAJOR, HSTPF_VERSION_MINOR, HSTPF_VERSION_PATCH);
            return 0;
        } else if (i + 1 < (unsigned)argc && strcmp(a, "--case") == 0) {
            noise_case = atoi(argv[++i]);
            if (noise_case != 1 && noise_case != 2) {
                usage();
                return 2;
            }
        } else if (i + 1 < (unsigned)argc && strcmp(a, "--refine") == 0) {
            refine = atoi(argv[++i]); /* cfg.refine; default: the library's */
        } else if (i + 1 < (unsigned)argc && strcmp(a, "--runs") == 0) {
            runs = (unsigned)strtoul(argv[++i], NULL, 10);
        } else if (i + 1 < (unsigned)argc && strcmp(a, "--steps") == 0) {
            steps = (unsigned)strtoul(argv[++i], NULL, 10);
        } else if (i + 1 < (unsigned)argc && strcmp(a, "--min-time") == 0) {
            min_time = atof(argv[++i]);
        } else if (i + 1 < (unsigned)argc && strcmp(a, "--config") == 0 && n_cfg < MAX_CONFIGS) {
            unsigned m = 0, p = 0;
            const char *arg = argv[++i];
            char kc = 0;
            if (sscanf(arg, "%ux%c", &m, &kc) == 2 && (kc == 'K' || kc == 'G') && m >= 1u &&
                m <= HSTPF_N_TRAIN_TYPES) {
                res[n_cfg].models = m;
                res[n_cfg].particles = 2;
                res[n_cfg].kalman = kc == 'K';
                res[n_cfg].grid = kc == 'G';
                ++n_cfg;
                continue;
            }
            if (sscanf(arg, "%ux%u", &m, &p) != 2 || m < 1u || m > HSTPF_N_TRAIN_TYPES ||
                p < 2u || p > 65535u) {
                usage();
                return 2;
            }
            res[n_cfg].models = m;
            res[n_cfg].particles = p;
            ++n_cfg;
        } else {
            usage();
            return 2;
        }
    }
    if (runs < 1u || runs > MAX_RUNS || steps < 2u || !(min_time >= 0.0)) {
        usage();
        return 2;
    }
    if (n_cfg == 0u) {
        res[0].models = 3;
        res[0].particles = 100;
        res[1].models = 17;
        res[1].particles = 1000;
        res[2].models = 3;
        res[2].particles = 2;
        res[2].kalman = 1;
        res[3].models = 17;
        res[3].particles = 2;
        res[3].kalman = 1;
        res[4].models = 3;
        res[4].particles = 2;
        res[4].grid = 1;
        res[5].models = 17;
        res[5].particles = 2;
        res[5].grid = 1;
        n_cfg = 6;
    }

    /* the inputs, simulated once: only hstpf_step() is timed */
    in = (hstpf_input_t *)calloc(steps, sizeof *in);
    if (in == NULL) {
        fprintf(stderr, "out of memory\n");
        return 1;
    }
    hstpf_sim_default(&sc);
    if (noise_case == 2) {
        hstpf_sim_case2(&sc);
    }
    hstpf_sim_init(&sim, &sc);
    for (k = 0; k < steps; ++k) {
        hstpf_sim_next_input(&sim, &smp, &in[k]);
    }

    for (i = 0; i < n_cfg; ++i) {
        result_t *r = &res[i];
        hstpf_theta_t models[HSTPF_N_TRAIN_TYPES];
        hstpf_config_t cfg;
        if (r->models > HSTPF_MAX_MODELS || r->particles > HSTPF_MAX_PARTICLES) {
            r->skipped = 1;
            continue;
        }
        if (fill_models(models, r->models) != 0) {
            fprintf(stderr, "train type table incomplete\n");
            return 1;
        }
        (void)hstpf_config_default(&cfg);
        cfg.noise_s = sc.noise_s;
        cfg.noise_v = sc.noise_v;
        cfg.noise_e = sc.noise_e;
        cfg.models = models;
        cfg.n_models = (uint16_t)r->models;
        cfg.n_particles = (uint16_t)r->particles;
        cfg.seed = 2;
        if (refine >= 0) {
            cfg.refine = (uint8_t)refine;
        }
        cfg.engine = r->kalman ? HSTPF_ENGINE_KALMAN : (r->grid ? HSTPF_ENGINE_GRID : HSTPF_ENGINE_PARTICLE);
        if (run_once(&cfg, in, steps, 0.0, r, &r->cpu[0]) < 0.0) { /* warm-up */
            return 1;
        }
        for (k = 0; k < runs; ++k) {
            r->ns[k] = run_once(&cfg, in, steps, min_time * 1e9, r, &r->cpu[k]);
            if (r->ns[k] < 0.0) {
                return 1;
            }
        }
        r->runs = runs;
        r->med = median(r->ns, runs);
        r->cpu_med = median(r->cpu, runs);
        r->min = r->ns[0];
        for (k = 1; k < runs; ++k) {
            r->min = r->ns[k] < r->min ? r->ns[k] : r->min;
        }
    }
    free(in);

    if (json) {
        printf("{\n  \"compiler\": \"%s\",\n  \"build_type\": \"%s\",\n  \"flags\": \"%s\",\n",
               COMPILER, HSTPF_BENCH_BUILD_TYPE, HSTPF_BENCH_FLAGS);
        printf("  \"library\": \"%s\",\n  \"capacity\": {\"models\": %d, \"particles\": %d},\n",
               HSTPF_BENCH_LIB, HSTPF_MAX_MODELS, HSTPF_MAX_PARTICLES);
        printf("  \"case\": %d,\n", noise_case);
        printf("  \"real\": \"%s\",\n  \"steps\": %u,\n  \"runs\": %u,\n  \"min_time_s\": %g,\n",
               sizeof(hstpf_real_t) == 4 ? "float" : "double", steps, runs, min_time);
        printf("  \"target_ns_per_particle_step\": %g,\n  \"results\": [", TARGET_NS);
        for (i = 0; i < n_cfg; ++i) {
            const result_t *r = &res[i];
            const int per_model = r->kalman || r->grid;
            const double per = per_model ? 1.0 : (double)r->particles;
            printf("%s\n    {\"models\": %u, \"engine\": \"%s\", \"particles\": %u, ", i ? "," : "",
                   r->models, r->kalman ? "kalman" : (r->grid ? "grid" : "particle"),
                   per_model ? 0u : r->particles);
            if (r->skipped) {
                printf("\"skipped\": \"above the library's capacity\"}");
                continue;
            }
            /* Kalman and grid rows: "particle" reads "model" (one filter per model) */
            printf("\"ns_per_particle_step_median\": %.3f, \"ns_per_particle_step_min\": %.3f, ",
                   r->med, r->min);
            printf("\"steps_per_s_median\": %.1f, \"steps_per_s_max\": %.1f, ",
                   1e9 / (r->med * r->models * per), 1e9 / (r->min * r->models * per));
            printf("\"cpu_ns_per_particle_step_median\": %.3f, ", r->cpu_med);
            printf("\"particle_steps_per_run\": %llu, \"declared\": %d, \"ns_per_particle_step\": [",
                   r->particle_steps, r->declared);
            for (k = 0; k < r->runs; ++k) {
                printf("%s%.3f", k ? ", " : "", r->ns[k]);
            }
            printf("], \"cpu_ns_per_particle_step\": [");
            for (k = 0; k < r->runs; ++k) {
                printf("%s%.3f", k ? ", " : "", r->cpu[k]);
            }
            printf("]}");
        }
        printf("\n  ]\n}\n");
        return 0;
    }

    printf("hstpf-bench: hstpf_step() on the paper's Case %d inputs (%u steps), one thread\n", noise_case, steps);
    printf("compiler: %s; build %s; flags: %s\n", COMPILER, HSTPF_BENCH_BUILD_TYPE,
           HSTPF_BENCH_FLAGS);
    printf("library: %s (HSTPF_MAX_MODELS %d, HSTPF_MAX_PARTICLES %d, %s)\n", HSTPF_BENCH_LIB,
           HSTPF_MAX_MODELS, HSTPF_MAX_PARTICLES, sizeof(hstpf_real_t) == 4 ? "float" : "double");
    printf("%u runs per configuration after a warm-up, each >= %.2f s of hstpf_step()\n\n", runs,
           min_time);
    printf("%6s %9s %14s %14s %14s %15s %13s\n", "models", "particles", "ns/p-step med",
           "ns/p-step min", "steps/s median", "steps/s best", "cpu ns/p med");
    for (i = 0; i < n_cfg; ++i) {
        const result_t *r = &res[i];
        if (r->skipped) {
            printf("%6u %9u   skipped: above this library's capacity\n", r->models, r->particles);
            continue;
        }
        if (r->kalman || r->grid) {
            printf("%6u %9s %14.2f %14.2f %14.0f %15.0f %13.2f  (ns per model-step)\n", r->models,
                   r->kalman ? "Kalman" : "grid", r->med, r->min, 1e9 / (r->med * r->models), 1e9 / (r->min * r->models),
                   r->cpu_med);
            continue;
        }
        printf("%6u %9u %14.2f %14.2f %14.0f %15.0f %13.2f\n", r->models, r->particles, r->med,
               r->min, 1e9 / (r->med * r->models * r->particles),
               1e9 / (r->min * r->models * r->particles), r->cpu_med);
    }
    printf("\ntarget: under %.0f ns per particle-step:", TARGET_NS);
    for (i = 0; i < n_cfg; ++i) {
        if (!res[i].skipped && !res[i].kalman && !res[i].grid) {
            printf(" %ux%u %s", res[i].models, res[i].particles,
                   res[i].med < TARGET_NS ? "met" : "NOT met");
        }
    }
    printf(" (median)\n");
    printf("bank step (median, us):");
    for (i = 0; i < n_cfg; ++i) {
        const result_t *r = &res[i];
        if (!r->skipped) {
            printf(" %ux%s %.1f", r->models, r->kalman ? "K" : (r->grid ? "G" : ""),
                   r->med * r->models * (r->kalman || r->grid ? 1.0 : (double)r->particles) / 1e3);
            if (!r->kalman && !r->grid) {
                printf("(x%u)", r->particles);
            }
        }
    }
    printf("\n");
    return 0;
}
