/* Fuzz target: the candump log reader (port/src/candump.c). Every line the
 * parser accepts must be written back by the writer and read again to the
 * same frame and interface (write/read round trip), and the text written
 * must be a fixed point; the log sniffer must judge any head of bytes. */
#include "candump.h"
#include "fuzz.h"

static void same_frame(const hstpfd_frame_t *a, const hstpfd_frame_t *b, const char *line)
{
    FUZZ_CHECK(a->t_us == b->t_us && a->id == b->id && a->flags == b->flags && a->len == b->len &&
                   memcmp(a->data, b->data, a->len) == 0,
               "frame changed in a round trip of '%s'", line);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char text[8192];
    char msg[512];
    size_t n, i = 0;
    if (size >= sizeof text) {
        size = sizeof text - 1;
    }
    memcpy(text, data, size);
    text[size] = '\0';
    n = size < HSTPFD_CANDUMP_SNIFF_BYTES ? size : HSTPFD_CANDUMP_SNIFF_BYTES;
    if (hstpfd_candump_sniff(text, n, "fuzz.log", msg, sizeof msg) != 0) {
        FUZZ_CHECK(strstr(msg, "python -m can.logconvert") != NULL && strchr(msg, '\n') == NULL,
                   "sniff message '%s'", msg);
    }
    n = strlen(text); /* the lines end at the first NUL, as fgets would see them */
    while (i < n) {
        char line[1024], out[1024], out2[1024], ifc[32], ifc2[32];
        hstpfd_frame_t f, g;
        const char *nl = strchr(text + i, '\n');
        size_t k = (nl != NULL ? (size_t)(nl - text) : n) - i;
        int w, w2;
        if (k >= sizeof line) {
            k = sizeof line - 1;
        }
        memcpy(line, text + i, k);
        line[k] = '\0';
        i += k + 1;
        if (hstpfd_candump_parse(line, &f, ifc, sizeof ifc) != HSTPFD_CANDUMP_OK) {
            continue;
        }
        FUZZ_CHECK(f.len <= (f.flags & HSTPFD_FRAME_FD ? 64u : 8u), "length %u in '%s'", (unsigned)f.len, line);
        w = hstpfd_candump_format(&f, ifc, out, sizeof out);
        FUZZ_CHECK(w > 0 && (size_t)w == strlen(out) && out[w - 1] == '\n', "cannot write back '%s'", line);
        FUZZ_CHECK(hstpfd_candump_parse(out, &g, ifc2, sizeof ifc2) == HSTPFD_CANDUMP_OK,
                   "'%s' written as '%s' does not read back", line, out);
        same_frame(&f, &g, line);
        FUZZ_CHECK(strcmp(ifc, ifc2) == 0, "interface '%s' read back as '%s'", ifc, ifc2);
        w2 = hstpfd_candump_format(&g, ifc2, out2, sizeof out2);
        FUZZ_CHECK(w2 == w && strcmp(out, out2) == 0, "'%s' then '%s'", out, out2);
        /* a buffer one byte short is refused, never overrun */
        FUZZ_CHECK(hstpfd_candump_format(&f, ifc, out2, (size_t)w) == -1, "short buffer accepted");
    }
    return 0;
}
