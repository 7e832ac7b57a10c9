/* Link test and on-target run for the Cortex-M4F: the paper's Case 1 as in
 * tools/demo (simulator seed 1, filter seed 2, models {SS1/SS3/SS4, CRH3,
 * SS8}, 100 particles, 1801 steps of 1 s), with the estimator in static
 * memory. Prints, through semihosting, the step count, the declared type,
 * its decision time, the estimated coefficients and state in the demo's
 * formats, and the stack that hstpf_init and hstpf_step used (measured by
 * painting the stack). A second pass over the same inputs is timed with the
 * SysTick on the processor clock: under QEMU -icount shift=0 (one virtual ns
 * per instruction, 25 MHz processor clock) one count is 40 instructions.
 * Exit status 0 when the true type (CRH3) is declared. */
#include <stdint.h>
#include <string.h>

#include "fw.h"
#include "hstpf/hstpf.h"
#include "hstpf_sim.h"

#define N_STEPS 1801u        /* t = 0 .. 1800 s, as hstpf-demo */
#define PAINT_WORDS 2048u    /* 8 KiB below the caller's stack pointer */
#define PAINT 0xC5A5C5A5u

static hstpf_t filt;
/* the workspace for what this program runs: 3 models, 100 particles or
 * the grid */
static uint64_t ws[HSTPF_WORKSPACE_WORDS(HSTPF_WORKSPACE_ANY_BYTES(3, 100))];
static hstpf_input_t inputs[N_STEPS];

static inline __attribute__((always_inline)) uint32_t *stack_pointer(void)
{
    uint32_t *sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    return sp;
}

/* Inlined into the caller: writes only below its stack pointer. */
static inline __attribute__((always_inline)) void paint(uint32_t *sp)
{
    uint32_t i;
    for (i = 1u; i <= PAINT_WORDS; ++i) {
        ((volatile uint32_t *)sp)[-(int32_t)i] = PAINT;
    }
}

/* Bytes below sp written since paint(sp); PAINT_WORDS * 4 means "at least". */
static uint32_t used(uint32_t *sp)
{
    uint32_t i;
    for (i = PAINT_WORDS; i >= 1u; --i) {
        if (((volatile uint32_t *)sp)[-(int32_t)i] != PAINT) {
            return 4u * i;
        }
    }
    return 0u;
}

/* ---- text output without stdio ---- */
static char *put_u(char *p, uint64_t v)
{
    char tmp[24];
    int n = 0;
    do {
        tmp[n++] = (char)('0' + (int)(v % 10u));
        v /= 10u;
    } while (v != 0u);
    while (n > 0) {
        *p++ = tmp[--n];
    }
    return p;
}

/* x with `dec` decimals, rounded half away from zero (as printf in all but
 * exact-tie cases). */
static char *put_f(char *p, double x, int dec)
{
    double scale = 1.0;
    uint64_t v, ip;
    int i;
    for (i = 0; i < dec; ++i) {
        scale *= 10.0;
    }
    if (x < 0.0) {
        x = -x;
        *p++ = '-';
    }
    v = (uint64_t)(x * scale + 0.5);
    ip = v / (uint64_t)scale;
    p = put_u(p, ip);
    if (dec > 0) {
        char frac[24];
        uint64_t f = v - ip * (uint64_t)scale;
        *p++ = '.';
        for (i = dec - 1; i >= 0; --i) {
            frac[i] = (char)('0' + (int)(f % 10u));
            f /= 10u;
        }
        memcpy(p, frac, (size_t)dec);
        p += dec;
    }
    return p;
}

static char *put_s(char *p, const char *s)
{
    size_t n = strlen(s);
    memcpy(p, s, n);
    return p + n;
}

static void emit(char *line, char *end)
{
    *end++ = '\n';
    *end = '\0';
    fw_puts(line);
}

/* One run over the inputs with SysTick on: accepted steps and ticks. */
static int timed_pass(const hstpf_config_t *cfg, uint32_t *ok, uint64_t *ticks)
{
    uint64_t t0;
    uint32_t k;
    *ok = 0u;
    if (hstpf_init(&filt, sizeof filt, cfg) != HSTPF_OK) {
        return -1;
    }
    fw_ticks_start();
    t0 = fw_ticks();
    for (k = 0u; k < N_STEPS; ++k) {
        *ok += hstpf_step(&filt, &inputs[k]) == HSTPF_OK ? 1u : 0u;
    }
    *ticks = fw_ticks() - t0;
    fw_ticks_stop();
    return 0;
}

int main(void)
{
    static const char *const names[3] = {"SS1/SS3/SS4", "CRH3", "SS8"};
    hstpf_theta_t models[3];
    hstpf_config_t cfg;
    hstpf_sim_config_t sc;
    hstpf_sim_t sim;
    hstpf_sim_sample_t smp;
    hstpf_estimate_t est;
    char line[160], *p;
    uint32_t k, ok = 0u, stack_init, stack_step;
    uint32_t *sp;
    int32_t err = HSTPF_OK, i;

    for (i = 0; i < 3; ++i) {
        const int32_t row = hstpf_train_type_find(names[i]);
        if (row < 0) {
            fw_puts("HSTPF-M4F-FAIL: train type missing\n");
            return 1;
        }
        models[i] = hstpf_train_types[row];
    }
    hstpf_sim_default(&sc);
    sc.seed = 1u;
    (void)hstpf_config_default(&cfg);
    cfg.noise_s = sc.noise_s;
    cfg.noise_v = sc.noise_v;
    cfg.noise_e = sc.noise_e;
    cfg.models = models;
    cfg.n_models = 3u;
    cfg.seed = 2u;
    cfg.workspace = ws;
    cfg.workspace_size = sizeof ws;

    /* the simulated inputs first, so that only the estimator runs below */
    hstpf_sim_init(&sim, &sc);
    for (k = 0u; k < N_STEPS; ++k) {
        hstpf_sim_next_input(&sim, &smp, &inputs[k]);
    }

    sp = stack_pointer();
    paint(sp);
    err = hstpf_init(&filt, sizeof filt, &cfg);
    stack_init = used(sp);
    if (err != HSTPF_OK) {
        p = put_s(line, "HSTPF-M4F-FAIL: hstpf_init: ");
        emit(line, put_s(p, hstpf_strerror(err)));
        return 1;
    }
    sp = stack_pointer();
    paint(sp);
    for (k = 0u; k < N_STEPS; ++k) {
        ok += hstpf_step(&filt, &inputs[k]) == HSTPF_OK ? 1u : 0u;
    }
    stack_step = used(sp);
    (void)hstpf_estimate(&filt, &est);
    /* the particle engine's stack too (the default picks Kalman here) */
    {
        hstpf_config_t pc = cfg;
        uint32_t ok_p = 0u, stack_p;
        pc.engine = HSTPF_ENGINE_PARTICLE;
        if (hstpf_init(&filt, sizeof filt, &pc) != HSTPF_OK) {
            return 1;
        }
        sp = stack_pointer();
        paint(sp);
        for (k = 0u; k < N_STEPS; ++k) {
            ok_p += hstpf_step(&filt, &inputs[k]) == HSTPF_OK ? 1u : 0u;
        }
        stack_p = used(sp);
        p = put_s(line, "m4f: particle engine: steps ");
        p = put_u(p, ok_p);
        p = put_s(p, ", stack used by hstpf_step ");
        p = put_u(p, stack_p);
        emit(line, put_s(p, " B"));
        stack_step = stack_p > stack_step ? stack_p : stack_step;
    }

    /* timed passes: the SysTick interrupt pushes frames, so it stays off
     * while the stack is measured above */
    {
        uint32_t ok2;
        uint64_t ticks;
        hstpf_config_t pc = cfg;
        pc.engine = HSTPF_ENGINE_PARTICLE;
        if (timed_pass(&pc, &ok2, &ticks) != 0) {
            return 1;
        }
        p = put_s(line, "m4f: timed pass: ");
        p = put_u(p, ok2);
        p = put_s(p, " steps of 3 models x ");
        p = put_u(p, cfg.n_particles);
        p = put_s(p, " particles in ");
        p = put_u(p, ticks);
        emit(line, put_s(p, " SysTick counts"));
        /* the per-model engines: one line each, read by footprint.cmake */
        for (i = 0; i < 2; ++i) {
            static const hstpf_engine_t engines[2] = {HSTPF_ENGINE_KALMAN, HSTPF_ENGINE_GRID};
            static const char *const labels[2] = {"m4f: timed Kalman pass: ", "m4f: timed grid pass: "};
            pc.engine = engines[i];
            if (timed_pass(&pc, &ok2, &ticks) != 0) {
                return 1;
            }
            p = put_s(line, labels[i]);
            p = put_u(p, ok2);
            p = put_s(p, " steps of 3 models in ");
            p = put_u(p, ticks);
            emit(line, put_s(p, " SysTick counts"));
        }
        /* all 17 rows with the library's defaults and Student-t(3) fixes
         * (issue 13's heavy-t, where engine auto picks the grid): under
         * this Gaussian process noise the grid_rows rows with the largest
         * weights are on the grid, the others on their Kalman filters,
         * which score each fix by its density (kalman_fix.c) */
        {
            static hstpf_theta_t all[HSTPF_N_TRAIN_TYPES];
            static hstpf_sim_table_t tab;
            hstpf_sim_config_t st = sc;
            hstpf_config_t c17 = cfg;
            hstpf_sim_heavy(&st, HSTPF_SIM_HEAVY_T, &tab);
            hstpf_sim_init(&sim, &st);
            for (k = 0u; k < N_STEPS; ++k) {
                hstpf_sim_next_input(&sim, &smp, &inputs[k]);
            }
            memcpy(all, hstpf_train_types, sizeof all);
            c17.models = all;
            c17.n_models = HSTPF_N_TRAIN_TYPES;
            c17.noise_e = st.noise_e;
            if (timed_pass(&c17, &ok2, &ticks) != 0) {
                return 1;
            }
            p = put_s(line, "m4f: timed 17-row grid pass: ");
            p = put_u(p, ok2);
            p = put_s(p, " bank steps in ");
            p = put_u(p, ticks);
            p = put_s(p, " SysTick counts (");
            p = put_u(p, c17.grid_rows);
            emit(line, put_s(p, " rows on the grid)"));
        }
        p = put_s(line, "m4f: grid cells ");
        p = put_u(p, HSTPF_GRID_NS);
        p = put_s(p, " x ");
        emit(line, put_u(p, HSTPF_GRID_NV));
        /* paper Case 2's Gamma noise, the grid engine's purpose: the
         * library's defaults (engine auto picks the grid) also run the
         * continuous hypothesis on a grid of its own, a fourth grid model */
        {
            hstpf_sim_config_t s2 = sc;
            hstpf_config_t c2 = cfg;
            hstpf_sim_case2(&s2);
            c2.noise_s = s2.noise_s;
            c2.noise_v = s2.noise_v;
            c2.noise_e = s2.noise_e;
            hstpf_sim_init(&sim, &s2);
            for (k = 0u; k < N_STEPS; ++k) {
                hstpf_sim_next_input(&sim, &smp, &inputs[k]);
            }
            if (timed_pass(&c2, &ok2, &ticks) != 0) {
                return 1;
            }
            p = put_s(line, "m4f: timed Case 2 grid pass: ");
            p = put_u(p, ok2);
            p = put_s(p, " steps of 4 grid models in ");
            p = put_u(p, ticks);
            emit(line, put_s(p, " SysTick counts (3 rows and the hypothesis' grid)"));
        }
    }

    p = put_s(line, "m4f: steps ");
    p = put_u(p, ok);
    p = put_s(p, " of ");
    p = put_u(p, N_STEPS);
    p = put_s(p, ", sizeof(hstpf_t) ");
    p = put_u(p, sizeof filt);
    emit(line, p);
    p = put_s(line, "m4f: stack used: hstpf_init ");
    p = put_u(p, stack_init);
    p = put_s(p, " B, hstpf_step ");
    p = put_u(p, stack_step);
    emit(line, put_s(p, " B (painted, includes libm and run-time helpers)"));
    p = put_s(line, "m4f: q =");
    for (i = 0; i < 3; ++i) {
        p = put_s(p, " ");
        p = put_f(p, (double)est.model[i].q, 4);
    }
    emit(line, p);
    /* the same lines as hstpf-demo prints at the end */
    p = put_s(line, "result: ");
    p = put_s(p, est.declared >= 0 ? models[est.declared].name : "undecided");
    if (est.declared >= 0) {
        p = put_s(p, " declared at t = ");
        p = put_f(p, est.decision_time_s, 0);
        p = put_s(p, " s (weight above ");
        p = put_f(p, cfg.declare_threshold, 2);
        p = put_s(p, " for ");
        p = put_f(p, cfg.declare_hold_s, 0);
        p = put_s(p, " s)");
    }
    emit(line, p);
    p = put_s(line, "theta : c0 = ");
    p = put_f(p, (double)est.theta[0], 4);
    p = put_s(p, "  c1 = ");
    p = put_f(p, (double)est.theta[1], 6);
    p = put_s(p, "  c2 = ");
    p = put_f(p, (double)est.theta[2], 7);
    emit(line, p);
    p = put_s(line, "state : s = ");
    p = put_f(p, est.position_m, 1);
    p = put_s(p, " m, v = ");
    p = put_f(p, 3.6 * (double)est.speed_mps, 2);
    emit(line, put_s(p, " km/h"));

    if (ok != N_STEPS || est.declared < 0 || strcmp(models[est.declared].name, "CRH3") != 0) {
        fw_puts("HSTPF-M4F-FAIL: the true type (CRH3) was not declared\n");
        return 1;
    }
    fw_puts("HSTPF-M4F-OK\n");
    return 0;
}
