/* hstpf-init-worst: the init time of the noise tables at the corners of
 * their documented ranges (dist.h), for docs/quality.md. Prints each
 * case's CPU time and the worst; with -f the worst whole hstpf_init (three
 * slowest noises, the blur). Not a test: figures depend on the machine. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "dist_impl.h"
#include "hstpf/hstpf.h"

static double cpu_s(void)
{
    struct timespec t;
    (void)clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static hstpf_dist_t d;
static hstpf_t filt;
static uint64_t ws[HSTPF_WORKSPACE_WORDS(HSTPF_WORKSPACE_MAX_BYTES)];
static double tx[HSTPF_DIST_TABLE_MAX], tp[HSTPF_DIST_TABLE_MAX];

int main(void)
{
    static const double shapes[] = {1e-3, 0.5, 1.0, 30.0, 1e4};
    static const double spreads[] = {1e-9, 1.0, 1e9};
    double worst = 0.0, worst_blur = 0.0, t0, t;
    char what[128] = "", what_blur[128] = "";
    hstpf_dist_spec_t s;
    unsigned i, j, k;
    for (i = 0; i < sizeof shapes / sizeof shapes[0]; ++i) {
        for (j = 0; j < sizeof spreads / sizeof spreads[0]; ++j) {
            memset(&s, 0, sizeof s);
            s.kind = HSTPF_DIST_GAMMA;
            s.shape = shapes[i];
            s.scale = spreads[j];
            t0 = cpu_s();
            if (hstpf_dist_init(&d, &s) != HSTPF_OK) {
                return 1;
            }
            t = cpu_s() - t0;
            if (t > worst) {
                worst = t;
                (void)snprintf(what, sizeof what, "Gamma(%g, %g)", shapes[i], spreads[j]);
            }
            for (k = 0; k < sizeof spreads / sizeof spreads[0]; ++k) {
                t0 = cpu_s();
                if (hstpf__dist_blur(&d, &s, spreads[k]) != HSTPF_OK) {
                    return 1;
                }
                t = cpu_s() - t0;
                if (t > worst_blur) {
                    worst_blur = t;
                    (void)snprintf(what_blur, sizeof what_blur, "Gamma(%g, %g) + N(0, %g)", shapes[i], spreads[j],
                                   spreads[k]);
                }
            }
        }
    }
    memset(&s, 0, sizeof s); /* the largest table */
    s.kind = HSTPF_DIST_TABLE;
    for (k = 0; k < HSTPF_DIST_TABLE_MAX; ++k) {
        tx[k] = (double)k;
        tp[k] = 1.0 + (double)(k % 7u);
    }
    s.table_x = tx;
    s.table_p = tp;
    s.table_n = HSTPF_DIST_TABLE_MAX;
    t0 = cpu_s();
    if (hstpf_dist_init(&d, &s) != HSTPF_OK) {
        return 1;
    }
    t = cpu_s() - t0;
    printf("table of %d points: %.1f ms\n", HSTPF_DIST_TABLE_MAX, 1e3 * t);
    if (t > worst) {
        worst = t;
        (void)snprintf(what, sizeof what, "table of %d points", HSTPF_DIST_TABLE_MAX);
    }
    printf("slowest hstpf_dist_init: %s, %.1f ms\n", what, 1e3 * worst);
    printf("slowest blur (hstpf__dist_blur): %s, %.1f ms\n", what_blur, 1e3 * worst_blur);
    { /* a whole init: the slowest noise on all three channels, blur on */
        hstpf_config_t c;
        (void)hstpf_config_default(&c);
        c.models = hstpf_train_types;
        c.n_models = HSTPF_MAX_MODELS;
        c.n_particles = HSTPF_MAX_PARTICLES;
        memset(&s, 0, sizeof s);
        s.kind = HSTPF_DIST_GAMMA;
        s.shape = 1e4;
        s.scale = 1.0;
        c.noise_s = s;
        c.noise_v = s;
        c.noise_e = s;
        c.e_blur_sd = 1.0;
        t0 = cpu_s();
        c.workspace = ws;
        c.workspace_size = sizeof ws;
        if (hstpf_init(&filt, sizeof filt, &c) != HSTPF_OK) {
            return 1;
        }
        printf("hstpf_init, Gamma(1e4, 1) on all three channels, blur 1 m, 17 models x %d particles: %.1f ms\n",
               HSTPF_MAX_PARTICLES, 1e3 * (cpu_s() - t0));
    }
    return 0;
}
