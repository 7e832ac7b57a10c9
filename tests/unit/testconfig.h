/* Configuration builders shared by the unit tests. */
#ifndef HSTPF_TESTCONFIG_H
#define HSTPF_TESTCONFIG_H

#include <stdint.h>

#include "hstpf/hstpf.h"

/* hstpf_config_default(c) (asserted HSTPF_OK), then the models: the Table 1
 * rows named in names[0..n-1], copied into models[0..n-1] (caller-owned; it
 * must outlive c). A name that is not in Table 1 fails the test. */
void tu_config_rows(hstpf_config_t *c, hstpf_theta_t *models, const char *const *names, uint16_t n);

#endif
