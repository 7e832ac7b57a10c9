/* End to end: a run simulated by tools/sim (exact samplers, double
 * precision, its own RNG stream, apart from the filter's) is identified.
 * Built twice: E2E_CASE=1 (the paper's Case 1, Gaussian noise, models
 * {SS1/SS3/SS4, CRH3, SS8}) and E2E_CASE=2 (Case 2, Gamma noise, models
 * {CRH1, CRH3, CRH5}); the truth is CRH3 on the paper's profile (0 -> 350
 * km/h in 396 s, then cruise), 1200 s, filter with the library defaults
 * (engine auto: Kalman for Case 1, the grid for Case 2; 100 particles,
 * declaration at q > 0.99 held 30 s) and the case's noise model, as in the
 * paper. E2E_ENGINE=HSTPF_ENGINE_PARTICLE builds a case with particles.
 *
 * Seeds are fixed in advance: simulation seeds 1..5, filter seed 1000 +
 * the simulation seed. Every seed must pass; a failure is a finding.
 *
 * Per seed:
 *  - every step is accepted (no error, no gated measurement);
 *  - CRH3 is declared, and from its declaration to the end of the run the
 *    declared type is CRH3 at every step; no other type is declared at any
 *    time (a wrong declaration is a wrong identification, even if revised);
 *  - the blended theta = sum q_l theta_l is within 5 % of CRH3's c0, c1, c2
 *    at the end (the paper's Fig. 4: relative errors within +-5 %);
 *  - the RMS error of the blended position over 300 s < t <= 1200 s is below
 *    the RMS error of the raw measurement, sqrt(E e^2): sqrt(5) = 2.24 m for
 *    Case 1 (a steady-state Kalman filter for this random walk reaches
 *    1.35 m), sqrt(0.5 * 0.2^2 + (0.5 * 0.2)^2) = 0.173 m for Case 2 (the
 *    Gamma(0.5, 0.2) error has mean 0.1 m and sd 0.141 m). An estimator that
 *    does worse than the measurement it is given has failed.
 *
 * E2E_STRICT=0 keeps only what the Monte Carlo study supports for every
 * seed (docs/results.md): CRH3 declared at the end, theta within 5 % at the
 * end, every step accepted. Case 2 is built both ways; the particle engine
 * passes only the non-strict build (a wrong early declaration in 3 % of
 * Monte Carlo runs, docs/results.md; sim seed 1 declares CRH5 at 138 s
 * before CRH3 wins).
 * Settings: the library defaults plus the study's e_blur_sd = 0.2 m and
 * roughening_k = 0.7, for both cases. */
#include <stdio.h>
#include <string.h>

#include "hstpf_sim.h"
#include "testbuild.h"
#include "testutil.h"

#ifndef E2E_CASE
#define E2E_CASE 1
#endif
#ifndef E2E_ENGINE
#define E2E_ENGINE HSTPF_ENGINE_AUTO
#endif
#ifndef E2E_STRICT
#define E2E_STRICT 1
#endif

#define DURATION_S 1200.0
#define RMS_FROM_S 300.0
#define THETA_REL_TOL 0.05
#define N_SEEDS 5

static hstpf_t filt; /* static, as on a target */

typedef struct {
    double decision_time_s, rms_m, theta_rel[3];
    int32_t declared;
    /* failures, each with the sample time and the declared index */
    double err_t, wrong_t, left_t;
    int32_t err, wrong_idx, left_idx;
    int n_fail;
    char why[256];
} run_result_t;

static void add_why(run_result_t *r, const char *what)
{
    const size_t used = strlen(r->why);
    ++r->n_fail;
    (void)snprintf(r->why + used, sizeof r->why - used, "%s%s", used ? "; " : "", what);
}

static void run_case(uint64_t sim_seed, run_result_t *res)
{
    static const char *names1[3] = {"SS1/SS3/SS4", "CRH3", "SS8"};
    static const char *names2[3] = {"CRH1", "CRH3", "CRH5"};
    const char *const *names = E2E_CASE == 1 ? names1 : names2;
    const int truth_idx = 1;
    hstpf_theta_t models[3];
    hstpf_config_t cfg;
    hstpf_sim_config_t sc;
    hstpf_sim_t sim;
    hstpf_sim_sample_t smp;
    hstpf_estimate_t est;
    double se2 = 0.0;
    long n_rms = 0;
    int i, truth_declared = 0;

    memset(res, 0, sizeof *res);
    res->decision_time_s = -1.0;
    hstpf_sim_default(&sc); /* CRH3, paper profile, dt 1 s */
    sc.seed = sim_seed;
    if (E2E_CASE == 2) {
        hstpf_sim_case2(&sc);
    } else {
        hstpf_sim_case1(&sc);
    }
    assert_string_equal(sc.truth.name, "CRH3");
    tu_config_rows(&cfg, models, names, 3);
    cfg.noise_s = sc.noise_s;
    cfg.noise_v = sc.noise_v;
    cfg.noise_e = sc.noise_e;
    cfg.seed = 1000u + sim_seed;
    cfg.engine = E2E_ENGINE;
    /* the Monte Carlo study's settings (docs/results.md), for every case;
     * they act on the particle engine only */
    cfg.e_blur_sd = 0.2;
    cfg.roughening_k = 0.7;
    tu_workspace(&cfg, 0);
    assert_int_equal(hstpf_init(&filt, sizeof filt, &cfg), HSTPF_OK);
    hstpf_sim_init(&sim, &sc);

    while (sim.t <= DURATION_S) {
        hstpf_input_t in = {0};
        int32_t err;
        hstpf_sim_next_input(&sim, &smp, &in); /* traction of the step just ended */
        err = hstpf_step(&filt, &in);
        if (err != HSTPF_OK && res->err == 0) {
            res->err = err;
            res->err_t = smp.t;
        }
        assert_int_equal(hstpf_estimate(&filt, &est), HSTPF_OK);
        if (smp.t > RMS_FROM_S) {
            se2 += (est.position_m - smp.s) * (est.position_m - smp.s);
            ++n_rms;
        }
        if (est.declared >= 0 && est.declared != truth_idx && res->wrong_t == 0.0) {
            res->wrong_t = smp.t; /* another type declared */
            res->wrong_idx = est.declared;
        }
        if (est.declared == truth_idx && !truth_declared) {
            truth_declared = 1;
            res->decision_time_s = est.decision_time_s;
        } else if (truth_declared && est.declared != truth_idx && res->left_t == 0.0) {
            res->left_t = smp.t; /* CRH3 replaced after its declaration */
            res->left_idx = est.declared;
        }
    }
    res->declared = est.declared;
    res->rms_m = sqrt(se2 / (double)n_rms);
    res->theta_rel[0] = (double)est.theta[0] / sc.truth.c0 - 1.0;
    res->theta_rel[1] = (double)est.theta[1] / sc.truth.c1 - 1.0;
    res->theta_rel[2] = (double)est.theta[2] / sc.truth.c2 - 1.0;
    if (res->err != 0) {
        char b[96];
        (void)snprintf(b, sizeof b, "step failed at t = %.0f s: %s", res->err_t, hstpf_strerror(res->err));
        add_why(res, b);
    }
    if (E2E_STRICT && res->wrong_t > 0.0) {
        char b[96];
        (void)snprintf(b, sizeof b, "%s declared at t = %.0f s", names[res->wrong_idx], res->wrong_t);
        add_why(res, b);
    }
    if (E2E_STRICT && res->left_t > 0.0) {
        char b[96];
        (void)snprintf(b, sizeof b, "CRH3 replaced by %s at t = %.0f s", res->left_idx >= 0 ? names[res->left_idx] : "none",
                       res->left_t);
        add_why(res, b);
    }
    if (est.declared != truth_idx) {
        add_why(res, "CRH3 not declared at the end");
    }
    for (i = 0; i < 3; ++i) {
        if (!(fabs(res->theta_rel[i]) <= THETA_REL_TOL)) {
            add_why(res, "blended theta not within 5 % of CRH3");
            break;
        }
    }
    {
        const double rms_tol = E2E_CASE == 1 ? sqrt(5.0) : sqrt(0.5 * 0.2 * 0.2 + 0.1 * 0.1);
        if (E2E_STRICT && !(res->rms_m < rms_tol)) {
            char b[96];
            (void)snprintf(b, sizeof b, "position RMS %.3f m not below the measurement's %.3f m", res->rms_m, rms_tol);
            add_why(res, b);
        }
    }
}

static void test_identify(void **state)
{
    uint64_t seed;
    int failed = 0;
    (void)state;
    for (seed = 1; seed <= N_SEEDS; ++seed) {
        run_result_t r;
        run_case(seed, &r);
        print_message("case %d sim seed %u: %s: CRH3 declared at %.0f s, theta err %+.2f%% %+.2f%% %+.2f%%, "
                      "position RMS (t > %.0f s) %.3f m\n",
                      E2E_CASE, (unsigned)seed, r.n_fail ? "FAIL" : "pass", r.decision_time_s,
                      100.0 * r.theta_rel[0], 100.0 * r.theta_rel[1], 100.0 * r.theta_rel[2], RMS_FROM_S, r.rms_m);
        if (r.n_fail) {
            print_message("    %s\n", r.why);
        }
        failed += r.n_fail > 0;
    }
    if (failed) {
        fail_msg("Case %d: %d of %d fixed seeds failed (see above)", E2E_CASE, failed, N_SEEDS);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_identify),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
