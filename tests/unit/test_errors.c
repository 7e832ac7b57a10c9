/* Every error path of every public function (hstpf.h, common.h): each
 * documented code, and after every failing call the objects it was given
 * are byte-for-byte unchanged (memcmp with a copy taken before) and the next
 * good step proceeds exactly as on a twin instance that never saw the bad
 * call. The distribution and RNG errors are in test_dist.c and test_rng.c. */
#include <stdlib.h>
#include <string.h>

#include "testbuild.h"
#include "testutil.h"

/* ~200 kB each: static, as on a target */
static hstpf_t f_a, f_b, f_copy, f_zero;
static hstpf_theta_t models[HSTPF_MAX_MODELS + 1];
static hstpf_track_seg_t track[HSTPF_MAX_TRACK_SEGMENTS + 1];

static void good_config(hstpf_config_t *c)
{
    static const char *const names[3] = {"SS1/SS3/SS4", "CRH3", "SS8"};
    tu_config_rows(c, models, names, 3);
    c->n_particles = 40;
    c->seed = 77;
    c->engine = HSTPF_ENGINE_PARTICLE; /* hstpf_particles() needs particles */
    tu_workspace(c, 2);                /* the twins take 0 and 1 */
}

/* A and B hold the same state: the instances but for their workspace
 * pointers, and the particles in their workspaces. */
static int twins_equal(void)
{
    static hstpf_t a, b;
    const size_t ws = HSTPF_PARTICLE_WS_BYTES(f_a.cfg.n_models, f_a.cfg.n_particles);
    hstpf_t *const ab[2] = {&a, &b};
    int k, l;
    a = f_a;
    b = f_b;
    for (k = 0; k < 2; ++k) {
        hstpf_t *x = ab[k];
        x->cfg.workspace = NULL;
        for (l = 0; l < HSTPF_MAX_MODELS; ++l) {
            x->m[l].s = x->m[l].v = x->m[l].lw = NULL;
        }
        x->scratch = x->nz_s = x->nz_v = NULL;
        x->counts = NULL;
    }
    return memcmp(&a, &b, sizeof a) == 0 && f_a.cfg.workspace != f_b.cfg.workspace &&
           memcmp(f_a.cfg.workspace, f_b.cfg.workspace, ws) == 0;
}

static void good_step(hstpf_t *f, double y)
{
    const hstpf_input_t in = tu_input(1.0, 10.0, y, 1);
    int32_t err = hstpf_step(f, &in);
    if (err != HSTPF_OK) {
        fail_msg("good step failed: %s", hstpf_strerror(err));
    }
}

/* A (and its twin B) initialised and run for a few steps. */
static void make_twins(const hstpf_config_t *c)
{
    hstpf_config_t cw = *c;
    int k;
    tu_workspace(&cw, 0);
    assert_int_equal(hstpf_init(&f_a, sizeof f_a, &cw), HSTPF_OK);
    tu_workspace(&cw, 1);
    assert_int_equal(hstpf_init(&f_b, sizeof f_b, &cw), HSTPF_OK);
    for (k = 0; k < 5; ++k) {
        good_step(&f_a, 100.0 + 2.0 * k);
        good_step(&f_b, 100.0 + 2.0 * k);
    }
    assert_true(twins_equal());
}

/* ---- hstpf_init ---------------------------------------------------------- */

static void expect_init(const hstpf_config_t *c, int32_t want, const char *what)
{
    int32_t got;
    /* on a running instance: unchanged, and it still steps like its twin */
    f_copy = f_a;
    got = hstpf_init(&f_a, sizeof f_a, c);
    if (got != want) {
        fail_msg("%s: hstpf_init returned %d (%s), expected %d (%s)", what, got, hstpf_strerror(got), want,
                 hstpf_strerror(want));
    }
    if (want == HSTPF_OK) {
        f_a = f_copy;
        return;
    }
    if (memcmp(&f_a, &f_copy, sizeof f_a) != 0) {
        fail_msg("%s: instance changed by a failing hstpf_init", what);
    }
    /* on a zeroed instance: still zero */
    memset(&f_zero, 0, sizeof f_zero);
    assert_int_equal(hstpf_init(&f_zero, sizeof f_zero, c), want);
    {
        static const hstpf_t zero; /* all zero */
        if (memcmp(&f_zero, &zero, sizeof zero) != 0) {
            fail_msg("%s: zeroed instance changed by a failing hstpf_init", what);
        }
    }
}

#define BAD(stmt, code)                       \
    do {                                      \
        hstpf_config_t bc_ = good;            \
        stmt;                                 \
        expect_init(&bc_, (code), #stmt);     \
    } while (0)

static void test_init_errors(void **state)
{
    const double nan = NAN, inf = INFINITY;
    hstpf_config_t good;
    int i;
    (void)state;
    good_config(&good);
    make_twins(&good);

    assert_int_equal(hstpf_config_default(NULL), HSTPF_E_NULL);
    f_copy = f_a;
    assert_int_equal(hstpf_init(NULL, sizeof f_a, &good), HSTPF_E_NULL);
    assert_int_equal(hstpf_init(&f_a, sizeof f_a, NULL), HSTPF_E_NULL);
    assert_memory_equal(&f_a, &f_copy, sizeof f_a);
    /* ABI: the caller's sizeof(hstpf_t) differs */
    assert_int_equal(hstpf_init(&f_a, sizeof f_a - 1u, &good), HSTPF_E_ABI);
    assert_int_equal(hstpf_init(&f_a, sizeof f_a + 1u, &good), HSTPF_E_ABI);
    assert_int_equal(hstpf_init(&f_a, 0u, &good), HSTPF_E_ABI);
    assert_memory_equal(&f_a, &f_copy, sizeof f_a);

    BAD(bc_.models = NULL, HSTPF_E_NULL);
    /* the workspace: missing, one byte short, misaligned */
    BAD(bc_.workspace = NULL, HSTPF_E_NULL);
    BAD(bc_.workspace_size = HSTPF_PARTICLE_WS_BYTES(3, 40) - 1u, HSTPF_E_SIZE);
    BAD(bc_.workspace_size = HSTPF_PARTICLE_WS_BYTES(3, 40), HSTPF_OK);
    BAD((bc_.workspace = (unsigned char *)bc_.workspace + 4, bc_.workspace_size -= 8u), HSTPF_E_SIZE);
    BAD((bc_.engine = HSTPF_ENGINE_KALMAN, bc_.workspace = NULL, bc_.workspace_size = 0), HSTPF_OK);
    BAD((bc_.track = NULL, bc_.n_track = 1), HSTPF_E_NULL);
    /* sizes */
    BAD(bc_.n_models = 0, HSTPF_E_SIZE);
    BAD(bc_.n_models = HSTPF_MAX_MODELS + 1, HSTPF_E_SIZE);
    BAD(bc_.n_particles = 0, HSTPF_E_SIZE);
    BAD(bc_.n_particles = 1, HSTPF_E_SIZE);
    BAD(bc_.n_particles = HSTPF_MAX_PARTICLES + 1, HSTPF_E_SIZE);
    BAD((bc_.track = track, bc_.n_track = HSTPF_MAX_TRACK_SEGMENTS + 1), HSTPF_E_SIZE);
    /* NaN and Inf in every number */
    for (i = 0; i < 3; ++i) {
        const double b = i == 0 ? nan : i == 1 ? inf : -inf;
        BAD(bc_.gamma_rot = b, HSTPF_E_NONFINITE);
        BAD(bc_.dt_nominal_s = b, HSTPF_E_NONFINITE);
        BAD(bc_.init_speed_mps = b, HSTPF_E_NONFINITE);
        BAD(bc_.init_speed_sd = b, HSTPF_E_NONFINITE);
        BAD(bc_.ess_threshold = b, HSTPF_E_NONFINITE);
        BAD(bc_.roughening_k = b, HSTPF_E_NONFINITE);
        BAD(bc_.rough_min_s = b, HSTPF_E_NONFINITE);
        BAD(bc_.rough_min_v = b, HSTPF_E_NONFINITE);
        BAD(bc_.q_floor = b, HSTPF_E_NONFINITE);
        BAD(bc_.e_blur_sd = b, HSTPF_E_NONFINITE);
        BAD(bc_.declare_threshold = b, HSTPF_E_NONFINITE);
        BAD(bc_.declare_hold_s = b, HSTPF_E_NONFINITE);
        BAD(bc_.gate_m = b, HSTPF_E_NONFINITE);
        BAD(bc_.noise_s.sd = b, HSTPF_E_NONFINITE);
        BAD(bc_.noise_v.mean = b, HSTPF_E_NONFINITE);
        BAD(bc_.noise_e.floor_depth = b, HSTPF_E_NONFINITE);
        models[3] = models[0];
        models[3].c0 = b;
        BAD((bc_.models = models + 1, bc_.n_models = 3), HSTPF_E_NONFINITE);
        models[3] = models[0];
        models[3].c1 = b;
        BAD((bc_.models = models + 1, bc_.n_models = 3), HSTPF_E_NONFINITE);
        models[3] = models[0];
        models[3].c2 = b;
        BAD((bc_.models = models + 1, bc_.n_models = 3), HSTPF_E_NONFINITE);
        track[0].start_m = 0.0, track[0].gradient_permille = 0.0, track[0].curve_radius_m = 0.0;
        track[1].start_m = b, track[1].gradient_permille = 1.0, track[1].curve_radius_m = 0.0;
        BAD((bc_.track = track, bc_.n_track = 2), HSTPF_E_NONFINITE);
        track[1].start_m = 10.0, track[1].gradient_permille = b;
        BAD((bc_.track = track, bc_.n_track = 2), HSTPF_E_NONFINITE);
        track[1].gradient_permille = 1.0, track[1].curve_radius_m = b;
        BAD((bc_.track = track, bc_.n_track = 2), HSTPF_E_NONFINITE);
    }
    /* physical ranges */
    {
        static const double c0s[] = {-0.01, 50.01}, c1s[] = {-1e-9, 1.01}, c2s[] = {-1e-12, 0.0101};
        for (i = 0; i < 2; ++i) {
            models[3] = models[0];
            models[3].c0 = c0s[i];
            BAD((bc_.models = models + 1, bc_.n_models = 3), HSTPF_E_RANGE);
            models[3] = models[0];
            models[3].c1 = c1s[i];
            BAD((bc_.models = models + 1, bc_.n_models = 3), HSTPF_E_RANGE);
            models[3] = models[0];
            models[3].c2 = c2s[i];
            BAD((bc_.models = models + 1, bc_.n_models = 3), HSTPF_E_RANGE);
        }
        models[3] = models[0];
    }
    BAD(bc_.gamma_rot = -0.01, HSTPF_E_RANGE);
    BAD(bc_.gamma_rot = 1.01, HSTPF_E_RANGE);
    BAD(bc_.init_speed_mps = HSTPF_SPEED_MAX + 0.1, HSTPF_E_RANGE);
    BAD(bc_.init_speed_mps = -HSTPF_SPEED_MAX - 0.1, HSTPF_E_RANGE);
    BAD(bc_.init_speed_sd = -0.1, HSTPF_E_RANGE);
    BAD(bc_.init_speed_sd = HSTPF_SPEED_MAX + 0.1, HSTPF_E_RANGE);
    track[0].start_m = 0.0, track[0].gradient_permille = 0.0, track[0].curve_radius_m = 0.0;
    track[1].start_m = 10.0, track[1].gradient_permille = 100.1, track[1].curve_radius_m = 0.0;
    BAD((bc_.track = track, bc_.n_track = 2), HSTPF_E_RANGE);
    track[1].gradient_permille = -100.1;
    BAD((bc_.track = track, bc_.n_track = 2), HSTPF_E_RANGE);
    track[1].gradient_permille = 0.0, track[1].curve_radius_m = 99.0; /* R in (0, 100) */
    BAD((bc_.track = track, bc_.n_track = 2), HSTPF_E_RANGE);
    track[1].curve_radius_m = -500.0;
    BAD((bc_.track = track, bc_.n_track = 2), HSTPF_E_RANGE);
    track[1].curve_radius_m = 0.0, track[1].start_m = HSTPF_POS_MAX_M * 1.001;
    BAD((bc_.track = track, bc_.n_track = 2), HSTPF_E_RANGE);
    track[1].start_m = 0.0; /* not increasing: equal */
    BAD((bc_.track = track, bc_.n_track = 2), HSTPF_E_RANGE);
    track[1].start_m = -5.0; /* decreasing */
    BAD((bc_.track = track, bc_.n_track = 2), HSTPF_E_RANGE);
    /* options */
    BAD(bc_.bank = (hstpf_bank_t)2, HSTPF_E_CONFIG);
    BAD(bc_.resample = (hstpf_resample_t)2, HSTPF_E_CONFIG);
    BAD(bc_.weight_method = (hstpf_weight_method_t)2, HSTPF_E_CONFIG);
    BAD(bc_.ess_threshold = 0.0, HSTPF_E_CONFIG);
    BAD(bc_.ess_threshold = -0.5, HSTPF_E_CONFIG);
    BAD(bc_.ess_threshold = 1.0001, HSTPF_E_CONFIG);
    BAD(bc_.roughening_k = -0.1, HSTPF_E_CONFIG);
    BAD(bc_.roughening_k = 10.1, HSTPF_E_CONFIG);
    BAD(bc_.rough_min_s = -1e-3, HSTPF_E_CONFIG);
    BAD(bc_.rough_min_v = -1e-3, HSTPF_E_CONFIG);
    BAD(bc_.q_floor = -1e-9, HSTPF_E_CONFIG);
    BAD(bc_.q_floor = 1.0 / 3.0, HSTPF_E_CONFIG); /* must be < 1 / n_models */
    BAD(bc_.declare_threshold = 0.5, HSTPF_E_CONFIG);
    BAD(bc_.declare_threshold = 1.0, HSTPF_E_CONFIG);
    BAD(bc_.declare_hold_s = -1.0, HSTPF_E_CONFIG);
    BAD(bc_.gate_m = -1.0, HSTPF_E_CONFIG);
    BAD(bc_.dt_nominal_s = 0.0, HSTPF_E_CONFIG);
    BAD(bc_.dt_nominal_s = -1.0, HSTPF_E_CONFIG);
    BAD(bc_.dt_nominal_s = HSTPF_DT_MAX_S + 0.1, HSTPF_E_CONFIG);
    BAD(bc_.engine = (hstpf_engine_t)4, HSTPF_E_CONFIG);
    BAD((bc_.engine = HSTPF_ENGINE_KALMAN, bc_.noise_v.kind = HSTPF_DIST_GAMMA, bc_.noise_v.shape = 0.1,
         bc_.noise_v.scale = 0.05), HSTPF_E_CONFIG);
    BAD(bc_.e_blur_sd = -0.1, HSTPF_E_CONFIG);
    BAD((bc_.noise_e.kind = HSTPF_DIST_TABLE, bc_.e_blur_sd = 0.1), HSTPF_E_CONFIG);
    /* noise specifications (hstpf_dist_init's checks) */
    BAD(bc_.noise_s.sd = 0.0, HSTPF_E_DIST);
    BAD(bc_.noise_v.kind = (hstpf_dist_kind_t)7, HSTPF_E_DIST);
    BAD((bc_.noise_e.kind = HSTPF_DIST_GAMMA, bc_.noise_e.shape = 0.0, bc_.noise_e.scale = 1.0), HSTPF_E_DIST);
    BAD((bc_.noise_e.kind = HSTPF_DIST_TABLE, bc_.noise_e.table_x = NULL), HSTPF_E_NULL);
    BAD(bc_.noise_e.floor_depth = -1.0, HSTPF_E_DIST);

    /* limits that are accepted */
    BAD(bc_.n_particles = 2, HSTPF_OK);
    BAD(bc_.n_particles = HSTPF_MAX_PARTICLES, HSTPF_OK);
    for (i = 0; i < HSTPF_MAX_MODELS; ++i) {
        models[i] = hstpf_train_types[i % HSTPF_N_TRAIN_TYPES];
    }
    BAD(bc_.n_models = HSTPF_MAX_MODELS, HSTPF_OK);
    good_config(&good);
    for (i = 0; i < HSTPF_MAX_TRACK_SEGMENTS; ++i) {
        track[i].start_m = 100.0 * i, track[i].gradient_permille = 100.0 * (i % 2 ? 1 : -1);
        track[i].curve_radius_m = i % 3 ? 100.0 : 0.0;
    }
    BAD((bc_.track = track, bc_.n_track = HSTPF_MAX_TRACK_SEGMENTS), HSTPF_OK);
    BAD(bc_.q_floor = 0.333, HSTPF_OK);
    BAD(bc_.dt_nominal_s = HSTPF_DT_MAX_S, HSTPF_OK);
    BAD((bc_.init_speed_mps = -HSTPF_SPEED_MAX, bc_.init_speed_sd = HSTPF_SPEED_MAX), HSTPF_OK);

    /* after all that, A still steps exactly like its twin */
    good_step(&f_a, 110.0);
    good_step(&f_b, 110.0);
    assert_true(twins_equal());
}

/* ---- hstpf_step ---------------------------------------------------------- */

/* A failing step leaves A unchanged; then a good step on A and its twin B
 * gives identical instances. */
static void expect_step(const hstpf_input_t *in, int32_t want, const char *what, double y_next)
{
    static unsigned char ws_copy[HSTPF_WORKSPACE_MAX_BYTES];
    const size_t ws = HSTPF_PARTICLE_WS_BYTES(f_a.cfg.n_models, f_a.cfg.n_particles);
    int32_t got;
    f_copy = f_a;
    memcpy(ws_copy, f_a.cfg.workspace, ws);
    got = hstpf_step(&f_a, in);
    if (got != want) {
        fail_msg("%s: hstpf_step returned %d (%s), expected %d (%s)", what, got, hstpf_strerror(got), want,
                 hstpf_strerror(want));
    }
    if (memcmp(&f_a, &f_copy, sizeof f_a) != 0 || memcmp(f_a.cfg.workspace, ws_copy, ws) != 0) {
        fail_msg("%s: instance or workspace changed by a failing hstpf_step", what);
    }
    good_step(&f_a, y_next);
    good_step(&f_b, y_next);
    if (!twins_equal()) {
        fail_msg("%s: the next good step differs from the twin's", what);
    }
}

static void test_step_errors(void **state)
{
    const double nan = NAN, inf = INFINITY;
    hstpf_config_t good;
    hstpf_input_t in = {0};
    double y = 120.0;
    int i;
    (void)state;
    good_config(&good);
    make_twins(&good);

    in = tu_input(1.0, 0.0, y, 1);
    assert_int_equal(hstpf_step(NULL, &in), HSTPF_E_NULL);
    expect_step(NULL, HSTPF_E_NULL, "in NULL", y += 2.0);
    /* use before init: a zeroed or overwritten instance */
    memset(&f_zero, 0, sizeof f_zero);
    f_copy = f_zero;
    assert_int_equal(hstpf_step(&f_zero, &in), HSTPF_E_INIT);
    assert_memory_equal(&f_zero, &f_copy, sizeof f_zero);
    memset(&f_zero, 0xFF, sizeof f_zero);
    f_copy = f_zero;
    assert_int_equal(hstpf_step(&f_zero, &in), HSTPF_E_INIT);
    assert_memory_equal(&f_zero, &f_copy, sizeof f_zero);

    for (i = 0; i < 3; ++i) {
        const double b = i == 0 ? nan : i == 1 ? inf : -inf;
        in = tu_input(b, 0.0, y, 1);
        expect_step(&in, HSTPF_E_NONFINITE, "dt non-finite", y += 2.0);
        in = tu_input(1.0, b, y, 1);
        expect_step(&in, HSTPF_E_NONFINITE, "traction non-finite", y += 2.0);
        in = tu_input(1.0, 0.0, b, 1);
        expect_step(&in, HSTPF_E_NONFINITE, "position non-finite", y += 2.0);
        in = tu_input(b, 0.0, y, 0);
        expect_step(&in, HSTPF_E_NONFINITE, "dt non-finite, no position", y += 2.0);
    }
    in = tu_input(0.0, 0.0, y, 1);
    expect_step(&in, HSTPF_E_DT, "dt 0", y += 2.0);
    in = tu_input(-0.0, 0.0, y, 1);
    expect_step(&in, HSTPF_E_DT, "dt -0", y += 2.0);
    in = tu_input(-1.0, 0.0, y, 1);
    expect_step(&in, HSTPF_E_DT, "dt < 0", y += 2.0);
    in = tu_input(HSTPF_DT_MAX_S * (1.0 + 1e-12), 0.0, y, 1);
    expect_step(&in, HSTPF_E_DT, "dt > max", y += 2.0);
    in = tu_input(1e300, 0.0, y, 0);
    expect_step(&in, HSTPF_E_DT, "dt 1e300", y += 2.0);
    in = tu_input(1.0, HSTPF_U_MAX + 1e-9, y, 1);
    expect_step(&in, HSTPF_E_RANGE, "traction > max", y += 2.0);
    in = tu_input(1.0, -HSTPF_U_MAX - 1e-9, y, 1);
    expect_step(&in, HSTPF_E_RANGE, "braking > max", y += 2.0);
    in = tu_input(1.0, 0.0, HSTPF_POS_MAX_M * (1.0 + 1e-12), 1);
    expect_step(&in, HSTPF_E_RANGE, "position > max", y += 2.0);
    in = tu_input(1.0, 0.0, -HSTPF_POS_MAX_M * (1.0 + 1e-12), 1);
    expect_step(&in, HSTPF_E_RANGE, "position < -max", y += 2.0);
    /* a NaN position without has_position is not read */
    in = tu_input(1.0, 0.0, nan, 0);
    assert_int_equal(hstpf_step(&f_a, &in), HSTPF_OK);
    assert_int_equal(hstpf_step(&f_b, &in), HSTPF_OK);
    assert_true(twins_equal());
    y += 2.0; /* the predicted step */
    /* limits that are accepted */
    in = tu_input(HSTPF_DT_MAX_S, HSTPF_U_MAX, y += 2.0, 0);
    assert_int_equal(hstpf_step(&f_a, &in), HSTPF_OK);
    in = tu_input(1e-9, -HSTPF_U_MAX, 0.0, 0);
    assert_int_equal(hstpf_step(&f_a, &in), HSTPF_OK);
    /* the position limits on a fresh instance (first fix there) */
    assert_int_equal(hstpf_init(&f_zero, sizeof f_zero, &good), HSTPF_OK);
    in = tu_input(1.0, 0.0, HSTPF_POS_MAX_M, 1);
    assert_int_equal(hstpf_step(&f_zero, &in), HSTPF_OK);
    assert_int_equal(hstpf_init(&f_zero, sizeof f_zero, &good), HSTPF_OK);
    in = tu_input(1.0, 0.0, -HSTPF_POS_MAX_M, 1);
    assert_int_equal(hstpf_step(&f_zero, &in), HSTPF_OK);
}

/* Errors before the first fix leave the instance untouched as well. */
static void test_step_errors_before_fix(void **state)
{
    hstpf_config_t good;
    hstpf_input_t in = {0};
    (void)state;
    good_config(&good);
    tu_workspace(&good, 0);
    assert_int_equal(hstpf_init(&f_a, sizeof f_a, &good), HSTPF_OK);
    tu_workspace(&good, 1);
    assert_int_equal(hstpf_init(&f_b, sizeof f_b, &good), HSTPF_OK);
    in = tu_input(NAN, 0.0, 10.0, 1);
    expect_step(&in, HSTPF_E_NONFINITE, "before the fix: dt NaN", 10.0);
    in = tu_input(1.0, 0.0, 2e8, 1);
    expect_step(&in, HSTPF_E_RANGE, "after the fix: position", 12.0);
}

/* Two instances carry the same estimate: every model's particles and
 * weights, and the model weights. */
static void assert_same_estimate(const hstpf_t *a, const hstpf_t *b)
{
    static double sa[HSTPF_MAX_PARTICLES], sb[HSTPF_MAX_PARTICLES];
    static hstpf_real_t va[HSTPF_MAX_PARTICLES], vb[HSTPF_MAX_PARTICLES];
    static hstpf_real_t wa[HSTPF_MAX_PARTICLES], wb[HSTPF_MAX_PARTICLES];
    hstpf_estimate_t ea, eb;
    uint16_t l;
    assert_int_equal(hstpf_estimate(a, &ea), HSTPF_OK);
    assert_int_equal(hstpf_estimate(b, &eb), HSTPF_OK);
    assert_true(ea.position_m == eb.position_m && ea.speed_mps == eb.speed_mps);
    assert_true(ea.time_s == eb.time_s && ea.step == eb.step);
    for (l = 0; l < ea.n_models; ++l) {
        assert_true(ea.model[l].q == eb.model[l].q);
        assert_int_equal(hstpf_particles(a, l, sa, va, wa), HSTPF_OK);
        assert_int_equal(hstpf_particles(b, l, sb, vb, wb), HSTPF_OK);
        assert_memory_equal(sa, sb, sizeof sa);
        assert_memory_equal(va, vb, sizeof va);
        assert_memory_equal(wa, wb, sizeof wa);
    }
}

/* The gate. hstpf.h: a gated fix returns HSTPF_E_OUTLIER and the step is
 * taken without it (a prediction: time and the models move on exactly as
 * for a step with no position), the outlier counters advance and the fix
 * is remembered for a re-acquisition. Checked against a twin that steps
 * with has_position = 0. */
static void test_outlier_gate(void **state)
{
    hstpf_config_t good;
    hstpf_input_t in = {0};
    hstpf_estimate_t est;
    double y = 120.0;
    int k;
    (void)state;
    good_config(&good);
    good.reacquire_after = 3;
    make_twins(&good);
    for (k = 0; k < 3; ++k) {
        in = tu_input(1.0, 10.0, y + 5000.0, 1);
        assert_int_equal(hstpf_step(&f_a, &in), HSTPF_E_OUTLIER);
        in = tu_input(1.0, 10.0, 0.0, 0);
        assert_int_equal(hstpf_step(&f_b, &in), HSTPF_OK);
        assert_same_estimate(&f_a, &f_b);
        assert_int_equal(hstpf_estimate(&f_a, &est), HSTPF_OK);
        assert_int_equal(est.outliers, (uint32_t)k + 1u);
        assert_int_equal(est.valid, 0); /* the fixes disagree with it */
    }
    /* a good measurement ends the run; it then steps like the twin */
    good_step(&f_a, y += 8.0);
    good_step(&f_b, y);
    assert_same_estimate(&f_a, &f_b);
    assert_int_equal(hstpf_estimate(&f_a, &est), HSTPF_OK);
    assert_int_equal(est.valid, 1);
    assert_int_equal(est.outliers, 3u);
    assert_int_equal(est.reacquired, 0u);
    /* three in a row are rejected, the fourth re-acquires from the last
     * two: position and speed of the new reference (30 m/s) */
    for (k = 0; k < 3; ++k) {
        in = tu_input(1.0, 10.0, 90000.0 + 30.0 * k, 1);
        assert_int_equal(hstpf_step(&f_a, &in), HSTPF_E_OUTLIER);
    }
    in = tu_input(1.0, 10.0, 90090.0, 1);
    assert_int_equal(hstpf_step(&f_a, &in), HSTPF_OK);
    assert_int_equal(hstpf_estimate(&f_a, &est), HSTPF_OK);
    assert_int_equal(est.reacquired, 1u);
    assert_int_equal(est.outliers, 6u);
    assert_int_equal(est.valid, 1);
    TU_CLOSE(est.position_m, 90090.0, 6.3 * sqrt(5.0)); /* particles y - e, |e| < 6.23 sd */
    /* v = (e1 - e2 + 30)/1 + a: |e1 - e2| < 2 x 6.23 sd, a ~ xi u */
    TU_CLOSE(est.speed_mps, 30.0, 12.5 * sqrt(5.0));
    good_step(&f_a, 90120.0);
    /* reacquire_after = 0: never re-acquire */
    good.reacquire_after = 0;
    make_twins(&good);
    for (k = 0; k < 20; ++k) {
        in = tu_input(1.0, 10.0, 50000.0, 1);
        assert_int_equal(hstpf_step(&f_a, &in), HSTPF_E_OUTLIER);
    }
    /* gate_m = 0: no gate */
    good.gate_m = 0.0;
    make_twins(&good);
    in = tu_input(1.0, 10.0, 50000.0, 1);
    assert_int_equal(hstpf_step(&f_a, &in), HSTPF_OK);
    /* a measurement just inside the gate (1000 m) is accepted */
    good.gate_m = 1000.0;
    make_twins(&good);
    assert_int_equal(hstpf_estimate(&f_a, &est), HSTPF_OK);
    in = tu_input(1.0, 10.0, est.position_m + est.speed_mps * 1.0 + 900.0, 1);
    assert_int_equal(hstpf_step(&f_a, &in), HSTPF_OK);
}

/* ---- the other entry points --------------------------------------------- */

static void test_reset_estimate_particles_track(void **state)
{
    static double s[HSTPF_MAX_PARTICLES], s_copy[HSTPF_MAX_PARTICLES];
    static hstpf_real_t v[HSTPF_MAX_PARTICLES], w[HSTPF_MAX_PARTICLES];
    static hstpf_real_t v_copy[HSTPF_MAX_PARTICLES], w_copy[HSTPF_MAX_PARTICLES];
    hstpf_config_t good;
    hstpf_estimate_t est, est_copy;
    double g = 42.0;
    (void)state;
    good_config(&good);
    make_twins(&good);
    memset(&f_zero, 0, sizeof f_zero);

    /* reset */
    assert_int_equal(hstpf_reset(NULL), HSTPF_E_NULL);
    f_copy = f_zero;
    assert_int_equal(hstpf_reset(&f_zero), HSTPF_E_INIT);
    assert_memory_equal(&f_zero, &f_copy, sizeof f_zero);

    /* estimate: out untouched on error */
    memset(&est, 0x5A, sizeof est);
    est_copy = est;
    assert_int_equal(hstpf_estimate(NULL, &est), HSTPF_E_NULL);
    assert_int_equal(hstpf_estimate(&f_a, NULL), HSTPF_E_NULL);
    assert_int_equal(hstpf_estimate(&f_zero, &est), HSTPF_E_INIT);
    assert_memory_equal(&est, &est_copy, sizeof est);

    /* particles */
    memset(s, 0x5A, sizeof s);
    memset(v, 0x5A, sizeof v);
    memset(w, 0x5A, sizeof w);
    memcpy(s_copy, s, sizeof s);
    memcpy(v_copy, v, sizeof v);
    memcpy(w_copy, w, sizeof w);
    assert_int_equal(hstpf_particles(NULL, 0, s, v, w), HSTPF_E_NULL);
    assert_int_equal(hstpf_particles(&f_a, 0, NULL, v, w), HSTPF_E_NULL);
    assert_int_equal(hstpf_particles(&f_a, 0, s, NULL, w), HSTPF_E_NULL);
    assert_int_equal(hstpf_particles(&f_zero, 0, s, v, w), HSTPF_E_INIT);
    assert_int_equal(hstpf_particles(&f_a, 3, s, v, w), HSTPF_E_SIZE); /* n_models = 3 */
    assert_int_equal(hstpf_particles(&f_a, 65535u, s, v, w), HSTPF_E_SIZE);
    assert_memory_equal(s, s_copy, sizeof s);
    assert_memory_equal(v, v_copy, sizeof v);
    assert_memory_equal(w, w_copy, sizeof w);
    assert_int_equal(hstpf_particles(&f_a, 2, s, v, NULL), HSTPF_OK); /* w optional */
    assert_int_equal(hstpf_particles(&f_a, 2, s, v, w), HSTPF_OK);

    /* track resistance */
    assert_int_equal(hstpf_track_resistance(NULL, 0.0, &g), HSTPF_E_NULL);
    assert_int_equal(hstpf_track_resistance(&f_a, 0.0, NULL), HSTPF_E_NULL);
    assert_int_equal(hstpf_track_resistance(&f_zero, 0.0, &g), HSTPF_E_INIT);
    TU_CLOSE(g, 42.0, 0.0);
    assert_int_equal(hstpf_track_resistance(&f_a, 0.0, &g), HSTPF_OK);
    TU_CLOSE(g, 0.0, 0.0); /* no profile */

    /* none of these touched the instances */
    f_copy = f_a;
    assert_int_equal(hstpf_estimate(&f_a, &est), HSTPF_OK);
    assert_memory_equal(&f_a, &f_copy, sizeof f_a);

    /* a good reset: uniform weights, no declaration, next fix redraws */
    assert_int_equal(hstpf_reset(&f_a), HSTPF_OK);
    assert_int_equal(hstpf_estimate(&f_a, &est), HSTPF_OK);
    TU_CLOSE(est.model[0].q, 1.0 / 3.0, 1e-6);
    assert_int_equal(est.declared, -1);
    assert_int_equal(est.status, HSTPF_STATUS_UNDECIDED);
    TU_CLOSE(est.position_m, 0.0, 0.0);
    good_step(&f_a, 5000.0); /* a fix far away: not gated after a reset */
    assert_int_equal(hstpf_estimate(&f_a, &est), HSTPF_OK);
    TU_CLOSE(est.position_m, 5000.0, 6.3 * sqrt(5.0));
}

static void test_strerror(void **state)
{
    static const int32_t codes[] = {HSTPF_OK,     HSTPF_E_NULL,  HSTPF_E_INIT,     HSTPF_E_SIZE,
                                    HSTPF_E_NONFINITE, HSTPF_E_DT, HSTPF_E_RANGE, HSTPF_E_ABI,
                                    HSTPF_E_DIST, HSTPF_E_CONFIG, HSTPF_E_OUTLIER};
    const char *unknown = hstpf_strerror(1);
    size_t i, j;
    (void)state;
    assert_non_null(unknown);
    assert_string_equal(unknown, "unknown error");
    assert_string_equal(hstpf_strerror(-11), "unknown error");
    assert_string_equal(hstpf_strerror(INT32_MIN), "unknown error");
    assert_string_equal(hstpf_strerror(INT32_MAX), "unknown error");
    for (i = 0; i < sizeof codes / sizeof codes[0]; ++i) {
        const char *m = hstpf_strerror(codes[i]);
        assert_non_null(m);
        assert_true(strlen(m) > 0u);
        assert_true(strcmp(m, unknown) != 0);
        for (j = 0; j < i; ++j) {
            assert_true(strcmp(m, hstpf_strerror(codes[j])) != 0); /* distinct */
        }
    }
    /* the codes themselves: 0 and distinct negatives */
    for (i = 1; i < sizeof codes / sizeof codes[0]; ++i) {
        assert_true(codes[i] == -(int32_t)i);
    }
}

/* Table 1 rows by name; NULL and unknown names; W(v) by hand:
 * CRH3 at 50 m/s (180 km/h): 0.79 + 0.0064*180 + 0.000115*32400 = 5.668. */
static void test_train_types(void **state)
{
    static const char *names[HSTPF_N_TRAIN_TYPES] = {
        "CRH1", "CRH2", "CRH3", "CRH5", "SS1/SS3/SS4", "SS7", "SS8", "DF", "DF4/DF4B/DF4C/DF7D",
        "DF8", "DF11", "ND5", "ND2", "DFH3", "Xian Feng", "Star EMU Central Plains", "China Star"};
    int32_t i;
    (void)state;
    for (i = 0; i < HSTPF_N_TRAIN_TYPES; ++i) {
        assert_int_equal(hstpf_train_type_find(names[i]), i);
    }
    assert_int_equal(hstpf_train_type_find(NULL), -1);
    assert_int_equal(hstpf_train_type_find("crh3"), -1);
    assert_int_equal(hstpf_train_type_find(""), -1);
    TU_CLOSE(hstpf_resistance(NULL, 50.0), 0.0, 0.0);
    TU_CLOSE(hstpf_resistance(&hstpf_train_types[2], 50.0), 5.668, 1e-12);
    /* Table 1 values of the three models of Case 1 */
    TU_CLOSE(hstpf_train_types[4].c0, 2.25, 0.0);
    TU_CLOSE(hstpf_train_types[4].c1, 0.019, 0.0);
    TU_CLOSE(hstpf_train_types[4].c2, 0.000320, 0.0);
    TU_CLOSE(hstpf_train_types[6].c2, 0.000426, 0.0);
}

/* ---- hstpf_workspace_size ------------------------------------------------ */

/* The sizes the engines ask for, counted by hand from their layouts. */
static void test_workspace_size(void **state)
{
    const size_t r = sizeof(hstpf_real_t);
    hstpf_config_t c;
    size_t n = 1;
    (void)state;
    good_config(&c); /* 3 models, 40 particles */
    assert_int_equal(hstpf_workspace_size(&c, &n), HSTPF_OK);
    /* s, v, lw of 3 models and scratch, nz_s, nz_v: 12 x 40 reals; 40 counts */
    assert_true(n == ((12u * 40u * r + 80u + 7u) / 8u) * 8u);
    assert_true(n == HSTPF_PARTICLE_WS_BYTES(3, 40));
    c.engine = HSTPF_ENGINE_GRID; /* 3 + 2 grids of cells, 3 + 1 rows of rest, 4 */
    assert_int_equal(hstpf_workspace_size(&c, &n), HSTPF_OK);
    assert_true(n == ((r * (5u * HSTPF_GRID_NS * HSTPF_GRID_NV + 4u * HSTPF_GRID_NS + 4u) + 7u) / 8u) * 8u);
    assert_true(n <= HSTPF_WORKSPACE_MAX_BYTES);
    assert_true(n <= HSTPF_WORKSPACE_ANY_BYTES(3, 40));
    assert_true(HSTPF_PARTICLE_WS_BYTES(3, 40) <= HSTPF_WORKSPACE_ANY_BYTES(3, 40));
    assert_true(HSTPF_WORKSPACE_WORDS(n) * 8u == n); /* already rounded to 8 */
    assert_true(HSTPF_WORKSPACE_WORDS(9u) == 2u);
    c.engine = HSTPF_ENGINE_KALMAN;
    assert_int_equal(hstpf_workspace_size(&c, &n), HSTPF_OK);
    assert_true(n == 0u);
    c.engine = HSTPF_ENGINE_AUTO; /* Gaussian: Kalman */
    assert_int_equal(hstpf_workspace_size(&c, &n), HSTPF_OK);
    assert_true(n == 0u);
    c.noise_e.kind = HSTPF_DIST_GAMMA; /* not: the grid */
    c.noise_e.shape = 0.5;
    c.noise_e.scale = 2.0;
    assert_int_equal(hstpf_workspace_size(&c, &n), HSTPF_OK);
    assert_true(n == HSTPF_GRID_WS_BYTES(3));
    /* errors: those of the configuration, and NULL; n untouched */
    n = 7;
    c.n_models = 0;
    assert_int_equal(hstpf_workspace_size(&c, &n), HSTPF_E_SIZE);
    assert_int_equal(hstpf_workspace_size(NULL, &n), HSTPF_E_NULL);
    assert_int_equal(hstpf_workspace_size(&c, NULL), HSTPF_E_NULL);
    assert_true(n == 7u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_init_errors),
        cmocka_unit_test(test_workspace_size),
        cmocka_unit_test(test_step_errors),
        cmocka_unit_test(test_step_errors_before_fix),
        cmocka_unit_test(test_outlier_gate),
        cmocka_unit_test(test_reset_estimate_particles_track),
        cmocka_unit_test(test_strerror),
        cmocka_unit_test(test_train_types),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
