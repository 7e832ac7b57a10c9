/* Test helper: candump log of a simulated run (see genlog.h). */
#include "genlog.h"

#include <stdio.h>
#include <string.h>

#include "candump.h"
#include "hstpf_can.h"
#include "hstpf_e2e.h"
#include "hstpf_frames.h"
#include "hstpf_sim.h"

#define T0_US GENLOG_T0_US

static FILE *logf_;
static int time_div_ = 1;
static int jitter_ms_ = 0;
static int64_t last_rx_ = 0;
static uint32_t lcg_ = 1u;

static void put(int64_t t_us, uint32_t id, uint8_t flags, const uint8_t *d, uint8_t len)
{
    hstpfd_frame_t f;
    char line[256];
    memset(&f, 0, sizeof f);
    f.t_us = T0_US + (t_us - T0_US) / time_div_;
    if (jitter_ms_ > 0) { /* a delay; a frame is never stamped before the one sent ahead of it */
        lcg_ = lcg_ * 1103515245u + 12345u;
        f.t_us += (int64_t)((lcg_ >> 8) % (uint32_t)(jitter_ms_ * 1000 + 1));
        if (f.t_us < last_rx_) {
            f.t_us = last_rx_;
        }
        last_rx_ = f.t_us;
    }
    f.id = id;
    f.flags = flags;
    f.len = len;
    memcpy(f.data, d, len);
    if (hstpfd_candump_format(&f, "vcan0", line, sizeof line) > 0) {
        fputs(line, logf_);
    }
}

/* The fault plan (gen_t.faults), by whole second k of the run. */
static int in(int k, const int *set, int n)
{
    int i;
    for (i = 0; i < n; ++i) {
        if (set[i] == k) {
            return 1;
        }
    }
    return 0;
}
static const int bad_crc_pos[] = {100, 150, 200, 250, 300};
static const int bad_crc_trac[] = {170, 270};
static const int repeated_pos[] = {120, 220, 320};
static const int short_pos[] = {130, 230};
static const int unknown_at[] = {140, 141, 142, 143};
static const int errframe_at[] = {160, 260};
#define SILENCE_FROM 400 /* position frames lost in [400, 403) */
#define SILENCE_TO 403

/* Case 1 (CRH3, the paper's profile and noise) at 1 s, sent as 100 ms
 * frames: position at the whole second carries the measurement y_k, the
 * nine frames after it a straight line to y_k+1; traction u_k in all ten. */
int genlog(const genlog_t *g)
{
    hstpf_sim_config_t sc;
    hstpf_sim_t sim;
    hstpf_sim_sample_t cur, next;
    hstpf_e2e_tx_t tx_pos, tx_trac;
    int k, j;

    logf_ = fopen(g->path, "w");
    if (logf_ == NULL) {
        return -1;
    }
    time_div_ = g->time_div;
    jitter_ms_ = g->jitter_ms;
    last_rx_ = 0;
    lcg_ = 1u;
    hstpf_sim_default(&sc);
    sc.seed = g->seed;
    hstpf_sim_init(&sim, &sc);
    (void)hstpf_e2e_tx_init(&tx_pos, HSTPF_FRAME_POSITION_DATA_ID);
    (void)hstpf_e2e_tx_init(&tx_trac, HSTPF_FRAME_TRACTION_DATA_ID);
    fputs("# hstpfd test log: Case 1, CRH3\n", logf_);
    hstpf_sim_next(&sim, &cur);
    for (k = 0; k < g->duration_s; ++k) {
        hstpf_sim_next(&sim, &next);
        for (j = 0; j < 10; ++j) {
            const int64_t t = T0_US + (int64_t)k * 1000000 + (int64_t)j * 100000;
            struct hstpf_can_position_t p;
            struct hstpf_can_traction_t tr;
            uint8_t d[8];
            const double y = cur.y + (next.y - cur.y) * j / 10.0;
            const int lost = g->n_lost > 0 && k * 10 + j >= g->lost_from_frame && k * 10 + j < g->lost_from_frame + g->n_lost;
            const int silent = (g->faults && k >= SILENCE_FROM && k < SILENCE_TO) || lost;

            (void)hstpf_can_position_init(&p);
            p.pos_valid = 1;
            p.pos_quality = 2;
            p.position = hstpf_frames_position_position_raw(y);
            if (k >= g->over_from_s && k < g->over_to_s) {
                p.position = INT64_C(17000000000); /* raw, past the DBC's 1e8 m: the s35 signal reaches 1.7e8 m */
            }
            if (!g->no_fix_time) { /* the measurement's own time, ms modulo the wrap */
                const int stuck = g->stuck_fix_from_s > 0 && k >= g->stuck_fix_from_s;
                p.fix_time_valid = 1;
                p.fix_time = (uint16_t)((unsigned)(stuck ? g->stuck_fix_from_s * 1000 : k * 1000 + j * 100) %
                                        HSTPF_FIX_TIME_WRAP_MS);
            }
            (void)hstpf_can_position_pack(d, &p, 8);
            (void)hstpf_e2e_protect(&tx_pos, d, 8);
            if (!silent) {
                if (g->faults && j == 0 && in(k, bad_crc_pos, 5)) {
                    d[0] ^= 0x5A;
                }
                put(t, HSTPF_FRAME_POSITION_ID, 0, d, g->faults && j == 0 && in(k, short_pos, 2) ? 7 : 8);
                if (g->faults && j == 0 && in(k, repeated_pos, 3)) {
                    put(t + 1000, HSTPF_FRAME_POSITION_ID, 0, d, 8);
                }
            }
            (void)hstpf_can_traction_init(&tr);
            tr.tract_valid = 1;
            tr.tract_force = hstpf_frames_traction_tract_force_raw(cur.u * g->mass_t * 9.81 / 1000.0);
            (void)hstpf_can_traction_pack(d, &tr, 8);
            (void)hstpf_e2e_protect(&tx_trac, d, 8);
            if (g->faults && j == 5 && in(k, bad_crc_trac, 2)) {
                d[0] ^= 0x01;
            }
            put(t, HSTPF_FRAME_TRACTION_ID, 0, d, 8);
            if (g->faults && j == 3 && in(k, unknown_at, 4)) {
                static const uint8_t junk[8] = {1, 2, 3, 4, 5, 6, 7, 8};
                put(t + 500, 0x1F0, 0, junk, 8);
            }
            if (g->faults && j == 7 && in(k, errframe_at, 2)) {
                static const uint8_t zero[8] = {0};
                put(t + 700, HSTPFD_ERR_BUSOFF | HSTPFD_ERR_CRTL, HSTPFD_FRAME_ERR, zero, 8);
            }
        }
        if (g->faults && (k == 50 || k == 51 || k == 52)) {
            fputs(k == 50 ? "this is not a frame\n" : k == 51 ? "(12.3 vcan0 100#00\n" : "(51.0) vcan0 XYZ#00\n",
                  logf_);
        }
        cur = next;
    }
    fclose(logf_);
    logf_ = NULL;
    return 0;
}

