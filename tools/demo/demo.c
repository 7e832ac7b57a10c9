/* hstpf-demo: simulates the paper's Case 1 (or 2) with its own RNG stream
 * and runs the estimator on it, printing the model weights as they evolve. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hstpf/hstpf.h"
#include "hstpf_sim.h"

static hstpf_t filt; /* static, as on a target */
static uint64_t ws[HSTPF_WORKSPACE_WORDS(HSTPF_WORKSPACE_MAX_BYTES)]; /* any engine */

static void usage(void)
{
    fprintf(stderr, "usage: hstpf-demo [--case 1|2] [--seed N] [--filter-seed N] "
                    "[--duration S] [--every S] [--version]\n");
}

int main(int argc, char **argv)
{
    int cas = 1, i;
    unsigned long long seed = 1, fseed = 2;
    double duration = 1800.0, every = 30.0;
    const char *names1[3] = {"SS1/SS3/SS4", "CRH3", "SS8"};
    const char *names2[3] = {"CRH1", "CRH3", "CRH5"};
    hstpf_theta_t models[3];
    hstpf_config_t cfg;
    hstpf_sim_config_t sc;
    hstpf_sim_t sim;
    hstpf_estimate_t est;
    double next_print = 0.0;
    int32_t err;

    for (i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--version") == 0) {
            printf("hstpf-demo %d.%d.%d\n", HSTPF_VERSION_MAJOR, HSTPF_VERSION_MINOR, HSTPF_VERSION_PATCH);
            return 0;
        }
        if (i + 1 < argc && strcmp(argv[i], "--case") == 0) {
            cas = atoi(argv[++i]);
        } else if (i + 1 < argc && strcmp(argv[i], "--seed") == 0) {
            seed = strtoull(argv[++i], NULL, 0);
        } else if (i + 1 < argc && strcmp(argv[i], "--filter-seed") == 0) {
            fseed = strtoull(argv[++i], NULL, 0);
        } else if (i + 1 < argc && strcmp(argv[i], "--duration") == 0) {
            duration = atof(argv[++i]);
        } else if (i + 1 < argc && strcmp(argv[i], "--every") == 0) {
            every = atof(argv[++i]);
        } else {
            usage();
            return 2;
        }
    }
    if ((cas != 1 && cas != 2) || !(duration > 0.0) || !(every > 0.0)) {
        usage();
        return 2;
    }
    for (i = 0; i < 3; ++i) {
        models[i] = hstpf_train_types[hstpf_train_type_find(cas == 1 ? names1[i] : names2[i])];
    }
    hstpf_sim_default(&sc);
    sc.seed = seed;
    (void)hstpf_config_default(&cfg);
    if (cas == 2) {
        hstpf_sim_case2(&sc);
    }
    /* the filter knows the noise model of the case, as in the paper */
    cfg.noise_s = sc.noise_s;
    cfg.noise_v = sc.noise_v;
    cfg.noise_e = sc.noise_e;
    cfg.models = models;
    cfg.n_models = 3;
    cfg.seed = fseed;
    cfg.workspace = ws;
    cfg.workspace_size = sizeof ws;
    err = hstpf_init(&filt, sizeof filt, &cfg);
    if (err != HSTPF_OK) {
        fprintf(stderr, "hstpf_init: %s\n", hstpf_strerror(err));
        return 1;
    }
    hstpf_sim_init(&sim, &sc);
    printf("hstpf demo: paper Case %d, truth %s, models {%s, %s, %s}, %u particles, "
           "sim seed %llu, filter seed %llu\n",
           cas, sc.truth.name, models[0].name, models[1].name, models[2].name,
           (unsigned)cfg.n_particles, seed, fseed);
    printf("%8s %10s %8s %8s %8s %8s  %s\n", "t [s]", "s [m]", "v [km/h]", "q1", "q2", "q3", "declared");
    {
        hstpf_sim_sample_t smp;
        while (sim.t <= duration) {
            hstpf_input_t in = {0};
            hstpf_sim_next_input(&sim, &smp, &in);
            err = hstpf_step(&filt, &in);
            if (err != HSTPF_OK) {
                fprintf(stderr, "t=%.0f: hstpf_step: %s\n", smp.t, hstpf_strerror(err));
            }
            (void)hstpf_estimate(&filt, &est);
            if (smp.t >= next_print) {
                printf("%8.0f %10.1f %8.1f %8.4f %8.4f %8.4f  %s\n", smp.t, est.position_m,
                       3.6 * (double)est.speed_mps, (double)est.model[0].q, (double)est.model[1].q,
                       (double)est.model[2].q, est.declared >= 0 ? models[est.declared].name : "-");
                next_print += every;
            }
        }
        printf("\nresult: %s", est.declared >= 0 ? models[est.declared].name : "undecided");
        if (est.declared >= 0) {
            printf(" declared at t = %.0f s (weight above %.2f for %.0f s)", est.decision_time_s,
                   cfg.declare_threshold, cfg.declare_hold_s);
        }
        printf("\ntruth : %s\n", sc.truth.name);
        printf("theta : c0 = %.4f  c1 = %.6f  c2 = %.7f   (true %.4f %.6f %.7f)\n",
               (double)est.theta[0], (double)est.theta[1], (double)est.theta[2], sc.truth.c0,
               sc.truth.c1, sc.truth.c2);
        printf("state : s = %.1f m (true %.1f), v = %.2f km/h (true %.2f)\n", est.position_m, smp.s,
               3.6 * (double)est.speed_mps, 3.6 * smp.v);
        return (est.declared >= 0 && strcmp(models[est.declared].name, sc.truth.name) == 0) ? 0 : 3;
    }
}
