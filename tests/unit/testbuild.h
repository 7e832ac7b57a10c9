/* Builders of what the unit tests hand the library: configurations over
 * named Table 1 rows, step inputs. */
#ifndef HSTPF_TESTBUILD_H
#define HSTPF_TESTBUILD_H

#include <stdint.h>

#include "hstpf/hstpf.h"

/* hstpf_config_default(c) (asserted HSTPF_OK), then the models: the Table 1
 * rows named in names[0..n-1], copied into models[0..n-1] (caller-owned; it
 * must outlive c). A name that is not in Table 1 fails the test. */
void tu_config_rows(hstpf_config_t *c, hstpf_theta_t *models, const char *const *names, uint16_t n);

/* Points c's workspace at static buffer `slot` (0..TU_WS_SLOTS-1) of
 * HSTPF_WORKSPACE_MAX_BYTES: enough for any engine at the capacities.
 * Instances alive at the same time use different slots. */
#define TU_WS_SLOTS 3
void tu_workspace(hstpf_config_t *c, int slot);

/* One step's input: length dt s, traction u N/kN, position y m if has_y. */
hstpf_input_t tu_input(double dt, double u, double y, int has_y);

#endif
