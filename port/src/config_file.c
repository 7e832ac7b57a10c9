/* hstpfd: configuration lines, files and texts ("key = value", comments,
 * [sections], quoted values), each key through hstpfd_config_set. */
#include "config_internal.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

/* A value in double quotes (as hstpfd_config_write puts values holding '#',
 * ';' or '"'): \" and \\ inside; blanks and a comment may follow. The
 * unquoted text replaces the quoted one in place. Returns 0 or -1. */
static int unquote(char *v, char *err, size_t err_size)
{
    char *r = v + 1, *w = v;
    for (;;) {
        if (*r == '\0') {
            hstpfd__fail(err, err_size, "value without its closing '\"'");
            return -1;
        }
        if (*r == '"') {
            break;
        }
        if (*r == '\\' && (r[1] == '"' || r[1] == '\\')) {
            ++r;
        }
        *w++ = *r++;
    }
    ++r;
    while (*r == ' ' || *r == '\t' || *r == '\r' || *r == '\n') {
        ++r;
    }
    if (*r != '\0' && *r != '#' && *r != ';') {
        hstpfd__fail(err, err_size, "text after the closing '\"'");
        return -1;
    }
    *w = '\0';
    return 0;
}

int hstpfd_config_line(hstpfd_config_t *c, const char *line, char *err, size_t err_size)
{
    char buf[HSTPFD_LINE_MAX];
    char *p, *eq;
    const char *key;
    size_t n = strlen(line);
    if (n >= sizeof buf) {
        hstpfd__fail(err, err_size, "line too long");
        return -1;
    }
    memcpy(buf, line, n + 1);
    p = hstpfd__trim(buf);
    if (*p == '\0' || *p == '#' || *p == ';') {
        return 0;
    }
    if (*p == '[') {
        if (p[strlen(p) - 1] != ']') {
            hstpfd__fail(err, err_size, "section line without ']'");
            return -1;
        }
        return 0;
    }
    eq = strchr(p, '=');
    if (eq == NULL) {
        hstpfd__fail(err, err_size, "expected key = value");
        return -1;
    }
    *eq = '\0';
    key = hstpfd__trim(p);
    if (*key == '\0') {
        hstpfd__fail(err, err_size, "missing key before '='");
        return -1;
    }
    /* an inline comment needs a blank before it: "x = 1  # note" */
    {
        char *v = eq + 1, *h;
        while (*v == ' ' || *v == '\t') {
            ++v;
        }
        if (*v == '"') {
            if (unquote(v, err, err_size) != 0) {
                return -1;
            }
            return hstpfd_config_set(c, key, v, err, err_size);
        }
        for (h = v; *h != '\0'; ++h) {
            if ((*h == '#' || *h == ';') && h > v && (h[-1] == ' ' || h[-1] == '\t')) {
                *h = '\0';
                break;
            }
        }
        return hstpfd_config_set(c, key, v, err, err_size);
    }
}

/* One past the last non-zero byte of a zero-filled buffer: where the text
 * fgets read ends when it did not end in a newline. */
static size_t last_byte(const char *buf, size_t size)
{
    while (size > 0 && buf[size - 1] == '\0') {
        --size;
    }
    return size;
}

int hstpfd_config_load(hstpfd_config_t *c, const char *path, char *err, size_t err_size)
{
    FILE *fp = fopen(path, "r");
    char line[HSTPFD_LINE_MAX];
    char e[HSTPFD_ERR_MAX];
    unsigned lineno = 0;
    if (fp == NULL) {
        hstpfd__fail(err, err_size, "%s: %s", path, strerror(errno));
        return -1;
    }
    for (;;) {
        const char *nl, *text = line;
        memset(line, 0, sizeof line); /* so that a NUL inside a line can be told from its end */
        if (fgets(line, sizeof line, fp) == NULL) {
            break;
        }
        ++lineno;
        nl = memchr(line, '\n', sizeof line);
        if (nl == NULL && !feof(fp)) {
            hstpfd__fail(err, err_size, "%s:%u: line too long", path, lineno);
            (void)fclose(fp);
            return -1;
        }
        if (strlen(line) < (nl != NULL ? (size_t)(nl - line) : last_byte(line, sizeof line))) {
            hstpfd__fail(err, err_size, "%s:%u: a NUL byte in the line", path, lineno);
            (void)fclose(fp);
            return -1;
        }
        if (lineno == 1u && memcmp(line, "\xEF\xBB\xBF", 3) == 0) {
            text += 3; /* the UTF-8 byte-order mark an editor may write */
        }
        if (hstpfd_config_line(c, text, e, sizeof e) != 0) {
            hstpfd__fail(err, err_size, "%s:%u: %s", path, lineno, e);
            (void)fclose(fp);
            return -1;
        }
    }
    if (ferror(fp)) {
        hstpfd__fail(err, err_size, "%s: read error", path);
        (void)fclose(fp);
        return -1;
    }
    (void)fclose(fp);
    return 0;
}

int hstpfd_config_text(hstpfd_config_t *c, const char *text, char *err, size_t err_size)
{
    char line[HSTPFD_LINE_MAX];
    char e[HSTPFD_ERR_MAX];
    unsigned lineno = 0;
    while (*text != '\0') {
        const char *nl = strchr(text, '\n');
        const size_t n = nl != NULL ? (size_t)(nl - text) : strlen(text);
        ++lineno;
        if (n >= sizeof line) {
            hstpfd__fail(err, err_size, "line %u: line too long", lineno);
            return -1;
        }
        memcpy(line, text, n);
        line[n] = '\0';
        if (hstpfd_config_line(c, line, e, sizeof e) != 0) {
            hstpfd__fail(err, err_size, "line %u: %s", lineno, e);
            return -1;
        }
        text += n + (nl != NULL ? 1u : 0u);
    }
    return 0;
}
