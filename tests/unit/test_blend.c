/* The blended position over a longer, low-noise run (tools/sim: exact
 * samplers, its own RNG stream): truth CRH3 on the paper's profile for
 * 3600 s, measurement N(0, 0.1 m), process noise N(0, 0.01 m) and
 * N(0, 0.01 m/s) per step in the simulation and the filter, the paper's
 * Case 1 models {SS1/SS3/SS4, CRH3, SS8}, 100 particles, sim seeds 1..3
 * (filter seed 1000 + seed), fixed in advance.
 *
 * The caller reads the blended position sum_l q_l s_l. Its RMS error over
 * 600 s < t <= 3600 s, and that of the declared model alone, must both be
 * below the measurement's own RMS error, 0.1 m: an estimate worse than the
 * raw measurement it is given has failed. */
#include "hstpf_sim.h"
#include "testbuild.h"
#include "testutil.h"

static hstpf_t filt; /* static, as on a target */

static void test_long_run_blend(void **state)
{
    static const char *names[3] = {"SS1/SS3/SS4", "CRH3", "SS8"};
    uint64_t seed;
    int failed = 0;
    (void)state;
    for (seed = 1; seed <= 3; ++seed) {
        hstpf_theta_t models[3];
        hstpf_config_t cfg;
        hstpf_sim_config_t sc;
        hstpf_sim_t sim;
        hstpf_sim_sample_t smp;
        hstpf_estimate_t est;
        double se_blend = 0.0, se_decl = 0.0, worst_lost = 0.0;
        long n = 0;
        int i;
        hstpf_sim_default(&sc);
        sc.seed = seed;
        sc.noise_e.sd = 0.1;
        sc.noise_s.sd = 0.01;
        sc.noise_v.sd = 0.01;
        tu_config_rows(&cfg, models, names, 3);
        cfg.noise_s = sc.noise_s;
        cfg.noise_v = sc.noise_v;
        cfg.noise_e = sc.noise_e;
        cfg.seed = 1000u + seed;
        tu_workspace(&cfg, 0);
        assert_int_equal(hstpf_init(&filt, sizeof filt, &cfg), HSTPF_OK);
        hstpf_sim_init(&sim, &sc);
        while (sim.t <= 3600.0) {
            hstpf_input_t in = {0};
            hstpf_sim_next_input(&sim, &smp, &in);
            assert_int_equal(hstpf_step(&filt, &in), HSTPF_OK);
            assert_int_equal(hstpf_estimate(&filt, &est), HSTPF_OK);
            if (smp.t > 600.0 && est.declared >= 0) {
                const double eb = est.position_m - smp.s, ed = est.model[est.declared].position_m - smp.s;
                se_blend += eb * eb;
                se_decl += ed * ed;
                ++n;
                for (i = 0; i < 3; ++i) {
                    const double el = fabs(est.model[i].position_m - smp.s);
                    worst_lost = el > worst_lost ? el : worst_lost;
                }
            }
        }
        assert_true(n > 2000);
        se_blend = sqrt(se_blend / (double)n);
        se_decl = sqrt(se_decl / (double)n);
        print_message("long run seed %u: RMS blended %.3f m, declared model %.3f m (tolerance 0.1 m); "
                      "farthest model cloud %.0f m from the train\n",
                      (unsigned)seed, se_blend, se_decl, worst_lost);
        failed += !(se_blend < 0.1) || !(se_decl < 0.1);
    }
    if (failed) {
        fail_msg("%d of 3 seeds: position RMS not below the measurement's 0.1 m", failed);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_long_run_blend),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
