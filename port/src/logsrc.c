/* hstpfd: candump log file source. */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "candump.h"
#include "source.h"

/* Characters read between two looks at the stop flag in an endless line */
#define STOP_EVERY 65536L

/* One line into line[size] (its newline dropped): 1, 0 at the end of the
 * input, -1 for a bad line: longer than the buffer (the rest of it read and
 * dropped) or with a NUL in it (docs/daemon.md; its text before the NUL
 * could pass for a frame). By bytes, so a NUL inside a line ends only that
 * line (fgets' strchr could not tell it from the end and took the next
 * line for the rest of a long one); *stop is seen inside an endless line. */
static int read_line(FILE *fp, char *line, size_t size, volatile sig_atomic_t *stop)
{
    size_t k = 0;
    long seen = 0;
    int ch, bad = 0;
    while ((ch = getc(fp)) != EOF && ch != '\n') {
        bad |= ch == '\0';
        if (k + 1 < size) {
            line[k++] = (char)ch;
        } else {
            bad = 1;
        }
        if (++seen % STOP_EVERY == 0 && *stop) {
            break;
        }
    }
    line[k] = '\0';
    if (ch == EOF && k == 0 && !bad) {
        return 0;
    }
    return bad ? -1 : 1;
}

int hstpfd_run_log(hstpfd_core_t *c, const char *path, volatile sig_atomic_t *stop, const char **end)
{
    FILE *fp = strcmp(path, "-") == 0 ? stdin : fopen(path, "r");
    char line[1024];
    int first = 1, got;
    *end = HSTPFD_END_ERROR;
    if (fp == NULL) {
        fprintf(stderr, "hstpfd: cannot open log %s: %s\n", path, strerror(errno));
        return -1;
    }
    while (!*stop && (got = read_line(fp, line, sizeof line, stop)) != 0) {
        hstpfd_frame_t f;
        char ifc[HSTPFD_NAME_MAX];
        int rc;
        if (got < 0) { /* longer than any valid line: counted */
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
