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

void hstpfd__json_str(FILE *fp, const char *s)
{
    fputc('"', fp);
    for (; *s != '\0'; ++s) {
        const unsigned char ch = (unsigned char)*s;
        if (ch == '"' || ch == '\\') {
            fputc('\\', fp);
            fputc(ch, fp);
        } else if (ch < 0x20u) {
            fprintf(fp, "\\u%04x", (unsigned)ch);
        } else {
            fputc(ch, fp);
        }
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
