#include <string.h>

#include "hstpf/hstpf.h"

/* Table 1 of Xie et al.: c0 N/kN, c1 N/kN per km/h, c2 N/kN per (km/h)^2. */
const hstpf_theta_t hstpf_train_types[HSTPF_N_TRAIN_TYPES] = {
    {"CRH1", 0.53, 0.0026, 0.000069},
    {"CRH2", 0.88, 0.0074, 0.000114},
    {"CRH3", 0.79, 0.0064, 0.000115},
    {"CRH5", 0.69, 0.0063, 0.000146},
    {"SS1/SS3/SS4", 2.25, 0.0190, 0.000320},
    {"SS7", 1.40, 0.0038, 0.000348},
    {"SS8", 1.02, 0.0035, 0.000426},
    {"DF", 2.93, 0.0073, 0.000271},
    {"DF4/DF4B/DF4C/DF7D", 2.28, 0.0293, 0.000178},
    {"DF8", 2.40, 0.0022, 0.000391},
    {"DF11", 0.86, 0.0054, 0.000218},
    {"ND5", 1.31, 0.0167, 0.000391},
    {"ND2", 2.98, 0.0202, 0.000033},
    {"DFH3", 2.40, 0.0095, 0.000673},
    {"Xian Feng", 1.65, 0.0001, 0.000179},
    {"Star EMU Central Plains", 1.28, 0.0012, 0.000195},
    {"China Star", 1.16, 0.00534, 0.000182},
};

int32_t hstpf_train_type_find(const char *name)
{
    int32_t i;
    if (name == NULL) {
        return -1;
    }
    for (i = 0; i < HSTPF_N_TRAIN_TYPES; ++i) {
        if (strcmp(hstpf_train_types[i].name, name) == 0) {
            return i;
        }
    }
    return -1;
}

double hstpf_resistance(const hstpf_theta_t *th, double v_mps)
{
    double vk;
    if (th == NULL) {
        return 0.0;
    }
    vk = 3.6 * v_mps;
    return th->c0 + th->c1 * vk + th->c2 * vk * vk;
}
