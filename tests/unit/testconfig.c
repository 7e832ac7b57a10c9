#include "testconfig.h"

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
