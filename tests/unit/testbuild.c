#include "testbuild.h"

#include <string.h>

#include "testutil.h" /* cmocka */

void tu_config_rows(hstpf_config_t *c, hstpf_theta_t *models, const char *const *names, uint16_t n)
{
    uint16_t i;
    assert_int_equal(hstpf_config_default(c), HSTPF_OK);
    for (i = 0; i < n; ++i) {
        const int32_t k = hstpf_train_type_find(names[i]);
        assert_true(k >= 0);
        models[i] = hstpf_train_types[k];
    }
    c->models = models;
    c->n_models = n;
}

void tu_workspace(hstpf_config_t *c, int slot)
{
    /* uint64_t: aligned to HSTPF_WORKSPACE_ALIGN */
    static uint64_t ws[TU_WS_SLOTS][HSTPF_WORKSPACE_WORDS(HSTPF_WORKSPACE_MAX_BYTES)];
    assert_true(slot >= 0 && slot < TU_WS_SLOTS);
    c->workspace = ws[slot];
    c->workspace_size = sizeof ws[slot];
}

hstpf_input_t tu_input(double dt, double u, double y, int has_y)
{
    hstpf_input_t in;
    memset(&in, 0, sizeof in);
    in.dt_s = dt;
    in.traction = u;
    in.position_m = y;
    in.has_position = (uint8_t)has_y;
    return in;
}
