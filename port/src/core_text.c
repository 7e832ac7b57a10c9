/* hstpfd: the text of the daemon's outputs: names of codes and states, and
 * JSON / CSV value writers (used by the step stream and the summary). */
#include "core_internal.h"

#include <math.h>

const char *const hstpfd__err_names[11] = {"other",        "E_NULL",  "E_INIT",   "E_SIZE",
                                           "E_NONFINITE",  "E_DT",    "E_RANGE",  "E_ABI",
                                           "E_DIST",       "E_CONFIG", "E_OUTLIER"};

const char *const hstpfd__class_names[HSTPFD_ERR_N_CLASSES] = {
    "tx_timeout", "lost_arbitration", "controller", "protocol", "transceiver",
    "no_ack",     "bus_off",          "bus_error",  "restarted"};

const char *hstpfd_err_class_name(unsigned i)
{
    return i < HSTPFD_ERR_N_CLASSES ? hstpfd__class_names[i] : "unknown";
}

const char *hstpfd_err_name(int32_t code)
{
    if (code == HSTPF_OK) {
        return "OK";
    }
    if (code < 0 && code >= -10) {
        return hstpfd__err_names[-code];
    }
    return hstpfd__err_names[0];
}

const char *hstpfd__status_name(hstpf_status_t s)
{
    switch (s) {
    case HSTPF_STATUS_DECLARED:
        return "declared";
    case HSTPF_STATUS_CHANGED:
        return "changed";
    case HSTPF_STATUS_WITHDRAWN:
        return "withdrawn";
    default:
        return "undecided";
    }
}

const char *hstpfd__fit_name(hstpf_fit_t fit)
{
    return fit == HSTPF_FIT_TABLE ? "table" : fit == HSTPF_FIT_NONE ? "none" : "unknown";
}

/* Bytes of the well-formed UTF-8 sequence at s (RFC 3629: no overlong
 * form, no surrogate, at most U+10FFFF), 0 if there is none. */
static size_t utf8_len(const unsigned char *s)
{
    size_t n, i;
    unsigned long cp;
    if (s[0] < 0x80u) {
        return 1;
    }
    if (s[0] >= 0xC2u && s[0] <= 0xDFu) {
        n = 2;
        cp = s[0] & 0x1Fu;
    } else if (s[0] >= 0xE0u && s[0] <= 0xEFu) {
        n = 3;
        cp = s[0] & 0x0Fu;
    } else if (s[0] >= 0xF0u && s[0] <= 0xF4u) {
        n = 4;
        cp = s[0] & 0x07u;
    } else {
        return 0;
    }
    for (i = 1; i < n; ++i) {
        if ((s[i] & 0xC0u) != 0x80u) { /* also a NUL: the string ends inside it */
            return 0;
        }
        cp = (cp << 6) | (s[i] & 0x3Fu);
    }
    if ((n == 3 && (cp < 0x800u || (cp >= 0xD800u && cp <= 0xDFFFu))) || (n == 4 && (cp < 0x10000u || cp > 0x10FFFFu))) {
        return 0;
    }
    return n;
}

/* A JSON string; a byte that is not well-formed UTF-8 (a Latin-1 file
 * name) is written as U+FFFD, so that the output stays UTF-8 JSON. */
void hstpfd__json_str(FILE *fp, const char *s)
{
    const unsigned char *p = (const unsigned char *)s;
    fputc('"', fp);
    while (*p != '\0') {
        const size_t n = utf8_len(p);
        if (*p == '"' || *p == '\\') {
            fputc('\\', fp);
            fputc(*p, fp);
        } else if (*p < 0x20u) {
            fprintf(fp, "\\u%04x", (unsigned)*p);
        } else if (n == 0) {
            fputs("\\ufffd", fp);
        } else {
            (void)fwrite(p, 1, n, fp);
            p += n - 1;
        }
        ++p;
    }
    fputc('"', fp);
}

void hstpfd__json_num(FILE *fp, double x)
{
    if (x == x && x < HUGE_VAL && x > -HUGE_VAL) {
        fprintf(fp, "%.9g", x);
    } else {
        fputs("null", fp);
    }
}

void hstpfd__json_time(FILE *fp, int64_t t_us)
{
    const int64_t s = t_us >= 0 ? t_us / 1000000 : -((-t_us + 999999) / 1000000);
    fprintf(fp, "%lld.%06ld", (long long)s, (long)(t_us - s * 1000000));
}

void hstpfd__csv_str(FILE *fp, const char *s)
{
    fputc('"', fp);
    for (; *s != '\0'; ++s) {
        if (*s == '"') {
            fputc('"', fp);
        }
        fputc(*s, fp);
    }
    fputc('"', fp);
}

/* A number of the step stream: %.*g, or, if it is not finite, JSON null /
 * an empty CSV cell (the line's valid field is then 0). */
void hstpfd__out_num(FILE *fp, int csv, double x, int prec)
{
    if (isfinite(x)) {
        fprintf(fp, "%.*g", prec, x);
    } else if (!csv) {
        fputs("null", fp);
    }
}
