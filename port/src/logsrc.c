/* hstpfd: candump log file source. */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "candump.h"
#include "source.h"

int hstpfd_run_log(hstpfd_core_t *c, const char *path, volatile sig_atomic_t *stop, const char **end)
{
    FILE *fp = strcmp(path, "-") == 0 ? stdin : fopen(path, "r");
    char line[1024];
    int first = 1;
    *end = HSTPFD_END_ERROR;
    if (fp == NULL) {
        fprintf(stderr, "hstpfd: cannot open log %s: %s\n", path, strerror(errno));
        return -1;
    }
    while (!*stop && fgets(line, sizeof line, fp) != NULL) {
        hstpfd_frame_t f;
        char ifc[HSTPFD_NAME_MAX];
        int rc;
        if (strchr(line, '\n') == NULL && !feof(fp)) {
            int ch; /* longer than any valid line: skip the rest, count it */
            while ((ch = fgetc(fp)) != EOF && ch != '\n') {
            }
            ++c->n.bad_lines;
            continue;
        }
        rc = hstpfd_candump_parse(line, &f, ifc, sizeof ifc);
        if (rc == HSTPFD_CANDUMP_EMPTY) {
            continue;
        }
        if (rc != HSTPFD_CANDUMP_OK) {
            ++c->n.bad_lines;
            continue;
        }
        if (first) { /* output frames are logged on the input's bus */
            (void)snprintf(c->bus, sizeof c->bus, "%s", ifc);
            first = 0;
        }
        hstpfd_core_frame(c, &f);
    }
    if (*stop) {
        *end = HSTPFD_END_SIGNAL;
    } else if (ferror(fp)) {
        fprintf(stderr, "hstpfd: read error on %s\n", path);
        ++c->n.read_errors;
        if (fp != stdin) {
            (void)fclose(fp);
        }
        return -1;
    } else {
        *end = HSTPFD_END_EOF;
    }
    if (fp != stdin) {
        (void)fclose(fp);
    }
    return 0;
}
