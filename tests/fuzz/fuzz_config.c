/* Fuzz target: the daemon's configuration parser (port/src/config_*.c) and
 * the --print-config round trip. The input is config-file text applied
 * line by line (errors are fine and must leave a usable configuration);
 * what hstpfd_config_write() prints must read back, through
 * hstpfd_config_text(), to a configuration that prints the same text. */
#include "config.h"
#include "fuzz.h"

static hstpfd_config_t a, b;
static char text_a[16384], text_b[16384];

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char text[16384];
    char err[HSTPFD_ERR_MAX];
    size_t i = 0, n;
    int wa, wb;
    if (size >= sizeof text) {
        size = sizeof text - 1;
    }
    memcpy(text, data, size);
    text[size] = '\0';
    n = strlen(text);
    hstpfd_config_default(&a);
    while (i < n) {
        char line[HSTPFD_LINE_MAX + 16];
        const char *nl = strchr(text + i, '\n');
        size_t k = (nl != NULL ? (size_t)(nl - text) : n) - i;
        if (k >= sizeof line) {
            k = sizeof line - 1;
        }
        memcpy(line, text + i, k);
        line[k] = '\0';
        i += k + 1;
        err[0] = '\0';
        if (hstpfd_config_line(&a, line, err, sizeof err) != 0) {
            FUZZ_CHECK(err[0] != '\0' && strchr(err, '\n') == NULL, "error without a one-line message");
        }
        /* the same text as a command-line override: key=value */
        {
            char *eq = strchr(line, '=');
            if (eq != NULL) {
                *eq = '\0';
                (void)hstpfd_config_set(&a, line, eq + 1, err, sizeof err);
            }
        }
    }
    FUZZ_CHECK(a.n_models >= 1 && a.n_models <= HSTPF_MAX_MODELS, "n_models %u", (unsigned)a.n_models);
    for (i = 0; i < a.n_models; ++i) {
        FUZZ_CHECK(a.models[i].name == a.model_name[i], "model name pointer %u", (unsigned)i);
    }
    wa = hstpfd_config_write(&a, text_a, sizeof text_a);
    FUZZ_CHECK(wa > 0, "the configuration cannot be printed");
    hstpfd_config_default(&b);
    FUZZ_CHECK(hstpfd_config_text(&b, text_a, err, sizeof err) == 0, "printed configuration refused: %s\n%s", err,
               text_a);
    wb = hstpfd_config_write(&b, text_b, sizeof text_b);
    FUZZ_CHECK(wb == wa && strcmp(text_a, text_b) == 0, "print -> parse -> print differs:\n%s---\n%s", text_a,
               text_b);
    return 0;
}
