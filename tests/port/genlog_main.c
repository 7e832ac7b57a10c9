/* hstpfd-genlog: writes the test log of genlog.h.
 * usage: hstpfd-genlog OUT.log [--duration S] [--faults] [--time-div K]
 *                              [--no-fix-time] [--jitter-ms M]
 *                              [--seed N] [--mass-t T] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "genlog.h"

int main(int argc, char **argv)
{
    genlog_t g = {NULL, 600, 0, 1, 1, 500.0, 0, 0, 0, 0, 0, 0, 0};
    int i;
    for (i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--faults") == 0) {
            g.faults = 1;
        } else if (i + 1 < argc && strcmp(argv[i], "--duration") == 0) {
            g.duration_s = atoi(argv[++i]);
        } else if (i + 1 < argc && strcmp(argv[i], "--time-div") == 0) {
            g.time_div = atoi(argv[++i]);
        } else if (i + 1 < argc && strcmp(argv[i], "--seed") == 0) {
            g.seed = strtoull(argv[++i], NULL, 0);
        } else if (strcmp(argv[i], "--no-fix-time") == 0) {
            g.no_fix_time = 1;
        } else if (i + 1 < argc && strcmp(argv[i], "--jitter-ms") == 0) {
            g.jitter_ms = atoi(argv[++i]);
        } else if (i + 1 < argc && strcmp(argv[i], "--mass-t") == 0) {
            g.mass_t = atof(argv[++i]);
        } else if (g.path == NULL && argv[i][0] != '-') {
            g.path = argv[i];
        } else {
            g.path = NULL;
            break;
        }
    }
    if (g.path == NULL || g.duration_s <= 0 || g.time_div <= 0 || !(g.mass_t > 0.0)) {
        fprintf(stderr, "usage: hstpfd-genlog OUT.log [--duration S] [--faults] [--time-div K] [--seed N] "
                        "[--mass-t T] [--no-fix-time] [--jitter-ms M]\n");
        return 2;
    }
    return genlog(&g) == 0 ? 0 : 1;
}
