/* hstpfd: candump log line parser and writer. */
#include "candump.h"

#include <stdio.h>
#include <string.h>

static int hexval(char c)
{
    if (c >= '0' && c <= '9') {
        return c - '0';
    }
    if (c >= 'a' && c <= 'f') {
        return c - 'a' + 10;
    }
    if (c >= 'A' && c <= 'F') {
        return c - 'A' + 10;
    }
    return -1;
}

static int is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

static const char *skip_space(const char *p)
{
    while (is_space(*p)) {
        ++p;
    }
    return p;
}

/* "(sec.frac)" -> microseconds; fraction digits beyond 6 are truncated. */
static const char *parse_time(const char *p, int64_t *t_us)
{
    int64_t sec = 0, frac = 0;
    int nd = 0, nf = 0;
    if (*p++ != '(') {
        return NULL;
    }
    while (*p >= '0' && *p <= '9') {
        if (nd >= 12) { /* beyond year 30000: not a timestamp */
            return NULL;
        }
        sec = sec * 10 + (*p++ - '0');
        ++nd;
    }
    if (nd == 0) {
        return NULL;
    }
    if (*p == '.') {
        ++p;
        while (*p >= '0' && *p <= '9') {
            if (nf < 6) {
                frac = frac * 10 + (*p - '0');
            }
            ++nf;
            ++p;
        }
        if (nf == 0) {
            return NULL;
        }
    }
    for (; nf < 6; ++nf) {
        frac *= 10;
    }
    if (*p++ != ')') {
        return NULL;
    }
    *t_us = sec * 1000000 + frac;
    return p;
}

static int fd_len_ok(unsigned n)
{
    return n <= 8u || n == 12u || n == 16u || n == 20u || n == 24u || n == 32u || n == 48u || n == 64u;
}

int hstpfd_candump_parse(const char *line, hstpfd_frame_t *f, char *iface, size_t iface_size)
{
    const char *p, *q;
    uint32_t id = 0;
    unsigned nid = 0, n = 0, max;
    size_t k;

    if (line == NULL || f == NULL) {
        return HSTPFD_CANDUMP_BAD;
    }
    memset(f, 0, sizeof *f);
    p = skip_space(line);
    if (*p == '\0' || *p == '#' || *p == ';') {
        return HSTPFD_CANDUMP_EMPTY;
    }
    p = parse_time(p, &f->t_us);
    if (p == NULL || !is_space(*p)) {
        return HSTPFD_CANDUMP_BAD;
    }
    p = skip_space(p);
    q = p;
    while (*p != '\0' && !is_space(*p)) {
        ++p;
    }
    if (p == q) {
        return HSTPFD_CANDUMP_BAD;
    }
    if (iface != NULL && iface_size > 0) {
        k = (size_t)(p - q);
        if (k >= iface_size) {
            k = iface_size - 1;
        }
        memcpy(iface, q, k);
        iface[k] = '\0';
    }
    p = skip_space(p);
    while (hexval(*p) >= 0) {
        if (nid >= 8u) {
            return HSTPFD_CANDUMP_BAD;
        }
        id = (id << 4) | (uint32_t)hexval(*p++);
        ++nid;
    }
    if (nid == 0 || *p++ != '#') {
        return HSTPFD_CANDUMP_BAD;
    }
    if (nid <= 3u) {
        if (id > 0x7FFu) {
            return HSTPFD_CANDUMP_BAD;
        }
    } else if (id & 0x20000000u) {
        f->flags |= HSTPFD_FRAME_ERR;
        id &= 0x1FFFFFFFu;
    } else {
        f->flags |= HSTPFD_FRAME_EXT;
        id &= 0x1FFFFFFFu; /* a printed CAN_EFF_FLAG is tolerated */
    }
    f->id = id;
    max = 8u;
    if (*p == '#') { /* CAN FD: one flags digit follows */
        ++p;
        if (hexval(*p) < 0) {
            return HSTPFD_CANDUMP_BAD;
        }
        ++p;
        f->flags |= HSTPFD_FRAME_FD;
        max = HSTPFD_FRAME_MAX_DATA;
    } else if (*p == 'R' || *p == 'r') {
        ++p;
        f->flags |= HSTPFD_FRAME_RTR;
        if (*p >= '0' && *p <= '8') {
            f->len = (uint8_t)(*p++ - '0');
        }
        goto tail;
    }
    for (;;) {
        int hi, lo;
        if (*p == '.') {
            ++p;
            continue;
        }
        hi = hexval(p[0]);
        if (hi < 0) {
            break;
        }
        lo = hexval(p[1]);
        if (lo < 0 || n >= max) {
            return HSTPFD_CANDUMP_BAD;
        }
        f->data[n++] = (uint8_t)((hi << 4) | lo);
        p += 2;
    }
    if ((f->flags & HSTPFD_FRAME_FD) && !fd_len_ok(n)) {
        return HSTPFD_CANDUMP_BAD;
    }
    f->len = (uint8_t)n;
    if (*p == '_' && !(f->flags & HSTPFD_FRAME_FD)) { /* len8_dlc: "_X" */
        if (hexval(p[1]) < 0) {
            return HSTPFD_CANDUMP_BAD;
        }
        p += 2;
    }
tail:
    if (*p != '\0' && !is_space(*p)) {
        return HSTPFD_CANDUMP_BAD;
    }
    p = skip_space(p);
    if ((*p == 'R' || *p == 'T' || *p == 'r' || *p == 't') && (p[1] == '\0' || is_space(p[1]))) {
        p = skip_space(p + 1); /* python-can's direction: rx / tx */
    }
    return *p == '\0' ? HSTPFD_CANDUMP_OK : HSTPFD_CANDUMP_BAD;
}

int hstpfd_candump_format(const hstpfd_frame_t *f, const char *iface, char *buf, size_t size)
{
    int n;
    size_t pos;
    unsigned i;
    const int64_t sec = f->t_us >= 0 ? f->t_us / 1000000 : -((-f->t_us + 999999) / 1000000);
    const long usec = (long)(f->t_us - sec * 1000000);

    if (f->flags & HSTPFD_FRAME_ERR) {
        n = snprintf(buf, size, "(%lld.%06ld) %s %08lX#", (long long)sec, usec, iface,
                     (unsigned long)(0x20000000u | (f->id & 0x1FFFFFFFu)));
    } else if (f->flags & HSTPFD_FRAME_EXT) {
        n = snprintf(buf, size, "(%lld.%06ld) %s %08lX#", (long long)sec, usec, iface,
                     (unsigned long)(f->id & 0x1FFFFFFFu));
    } else {
        n = snprintf(buf, size, "(%lld.%06ld) %s %03lX#", (long long)sec, usec, iface,
                     (unsigned long)(f->id & 0x7FFu));
    }
    if (n < 0 || (size_t)n >= size) {
        return -1;
    }
    pos = (size_t)n;
    if (f->flags & HSTPFD_FRAME_RTR) {
        /* candump -L writes a requested length 1..8 after the R */
        if (f->len > 8u) {
            return -1;
        }
        n = f->len > 0u ? snprintf(buf + pos, size - pos, "R%u\n", (unsigned)f->len)
                        : snprintf(buf + pos, size - pos, "R\n");
    } else {
        if (f->flags & HSTPFD_FRAME_FD) {
            if (pos + 2 >= size) {
                return -1;
            }
            buf[pos++] = '#';
            buf[pos++] = '0';
        }
        for (i = 0; i < f->len && i < HSTPFD_FRAME_MAX_DATA; ++i) {
            if (pos + 3 > size) {
                return -1;
            }
            (void)snprintf(buf + pos, 3, "%02X", (unsigned)f->data[i]);
            pos += 2;
        }
        n = snprintf(buf + pos, size - pos, "\n");
    }
    if (n < 0 || pos + (size_t)n >= size) {
        return -1;
    }
    return (int)(pos + (size_t)n);
}

/* A guess at what a log that is not candump text is, for the message. */
static const char *other_format(const char *head, size_t n, const char *line)
{
    if (n >= 4 && memcmp(head, "LOGG", 4) == 0) {
        return "Vector BLF";
    }
    if (n >= 8 && memcmp(head, "MDF     ", 8) == 0) {
        return "ASAM MF4";
    }
    if (memchr(head, '\0', n) != NULL) {
        return "binary";
    }
    if (strncmp(line, "date ", 5) == 0 || strncmp(line, "base ", 5) == 0) {
        return "Vector ASC";
    }
    if (n >= 13 && memcmp(head, ";$FILEVERSION", 13) == 0) {
        return "PEAK TRC";
    }
    if (strncmp(line, "timestamp,", 10) == 0) {
        return "python-can CSV";
    }
    return "unknown";
}

int hstpfd_candump_sniff(const char *head, size_t n, const char *name, char *msg, size_t msg_size)
{
    char line[256];
    size_t i = 0;
    unsigned data_lines = 0;
    const char *what = NULL;
    char first[sizeof line] = "";

    while (i < n) { /* a NUL in a log with frames is a bad line, not a binary file */
        const char *nl = memchr(head + i, '\n', n - i);
        size_t k;
        hstpfd_frame_t f;
        int rc;
        if (nl == NULL && n == HSTPFD_CANDUMP_SNIFF_BYTES) {
            break; /* a line cut by the end of the head: not judged */
        }
        k = (nl != NULL ? (size_t)(nl - head) : n) - i;
        if (k >= sizeof line) {
            k = sizeof line - 1; /* too long for a candump line: judged BAD */
        }
        memcpy(line, head + i, k);
        line[k] = '\0';
        i = nl != NULL ? (size_t)(nl - head) + 1 : n;
        rc = hstpfd_candump_parse(line, &f, NULL, 0);
        if (rc == HSTPFD_CANDUMP_OK) {
            return 0; /* one frame is enough: other lines are counted as bad later */
        }
        if (rc == HSTPFD_CANDUMP_BAD) {
            if (data_lines++ == 0) {
                memcpy(first, line, k + 1);
            }
        }
    }
    if (data_lines == 0 && memchr(head, '\0', n) == NULL) {
        return 0; /* empty, comments only, or not decided within the head */
    }
    what = other_format(head, n, first); /* no frame: NUL bytes say binary */
    if (msg != NULL && msg_size > 0) {
        (void)snprintf(msg, msg_size,
                       "%s is not a candump log (format: %s); convert it first: "
                       "python -m can.logconvert %s out.log",
                       name, what, name);
    }
    return -1;
}

int hstpfd_candump_check_file(const char *path, char *msg, size_t msg_size)
{
    char head[HSTPFD_CANDUMP_SNIFF_BYTES];
    size_t n;
    FILE *fp;
    if (strcmp(path, "-") == 0) {
        return 0; /* stdin cannot be read twice */
    }
    fp = fopen(path, "rb");
    if (fp == NULL) {
        return 0; /* the log source reports it with its reason */
    }
    n = fread(head, 1, sizeof head, fp);
    (void)fclose(fp);
    return hstpfd_candump_sniff(head, n, path, msg, msg_size);
}
