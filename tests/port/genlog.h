/* Test helper: writes a candump log of a simulated run (the paper's model,
 * tools/sim, Case 1 truth CRH3), packed with the codec and E2E-protected,
 * optionally with a fixed plan of faults. Used by test_daemon and by the
 * vcan test (as the program hstpfd-genlog). */
#ifndef HSTPFD_GENLOG_H
#define HSTPFD_GENLOG_H

#include <stdint.h>

#define GENLOG_T0_US INT64_C(1700000000000000)

typedef struct {
    const char *path;
    int duration_s;
    int faults;      /* inject the fault plan (genlog.c) */
    int time_div;    /* timestamps compressed this many times (a sped-up capture) */
    uint64_t seed;   /* simulator seed */
    double mass_t;   /* train mass for the traction force */
    int no_fix_time; /* 1: position frames without a fix time (FixTimeValid 0) */
    int jitter_ms;   /* receive stamps delayed by a pseudo-random 0..jitter_ms (a loaded gateway; order kept) */
    int over_from_s, over_to_s; /* positions of [from, to) s sent as the signal's largest, 1.7e8 m */
    int stuck_fix_from_s;       /* > 0: the fix time stops moving from this second on */
    int lost_from_frame, n_lost; /* n_lost > 0: position frames lost from this frame on (10 a second) */
} genlog_t;

/* Returns 0, or -1 if the file cannot be written. */
int genlog(const genlog_t *g);

#endif
