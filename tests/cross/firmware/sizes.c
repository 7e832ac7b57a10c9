/* Size probe: compiled for the target with given capacity macros, never
 * linked. The symbol sizes (arm-none-eabi-nm -S) are the type sizes and
 * the engines' workspaces at the capacities. */
#include "hstpf/hstpf.h"

extern char hstpf_sizeof_instance[sizeof(hstpf_t)];
extern char hstpf_sizeof_estimate[sizeof(hstpf_estimate_t)];
extern char hstpf_sizeof_model[sizeof(hstpf_model_t)];
extern char hstpf_sizeof_dist[sizeof(hstpf_dist_t)];
extern char hstpf_sizeof_ws_particle[HSTPF_PARTICLE_WS_BYTES(HSTPF_MAX_MODELS, HSTPF_MAX_PARTICLES)];
/* the grid engine with the library's defaults under non-Gaussian process
 * noise: the rows and the continuous hypothesis' grid; ws_grid_rows: the
 * rows' alone (Gaussian process noise: the hypothesis needs no grid) */
extern char hstpf_sizeof_ws_grid[HSTPF_GRID_WS_BYTES(HSTPF_MAX_MODELS + 1)];
extern char hstpf_sizeof_ws_grid_rows[HSTPF_GRID_WS_BYTES(HSTPF_MAX_MODELS)];

char hstpf_sizeof_instance[sizeof(hstpf_t)];
char hstpf_sizeof_estimate[sizeof(hstpf_estimate_t)];
char hstpf_sizeof_model[sizeof(hstpf_model_t)];
char hstpf_sizeof_dist[sizeof(hstpf_dist_t)];
char hstpf_sizeof_ws_particle[HSTPF_PARTICLE_WS_BYTES(HSTPF_MAX_MODELS, HSTPF_MAX_PARTICLES)];
char hstpf_sizeof_ws_grid[HSTPF_GRID_WS_BYTES(HSTPF_MAX_MODELS + 1)];
char hstpf_sizeof_ws_grid_rows[HSTPF_GRID_WS_BYTES(HSTPF_MAX_MODELS)];
