/* Track profile (gradient and curve resistance) in the filter's units. */
#ifndef HSTPF_TRACK_H
#define HSTPF_TRACK_H

#include "hstpf/hstpf.h"

/* i + 600 / R of one segment, N/kN. */
double hstpf__seg_resistance(const hstpf_track_seg_t *t);

/* Copies the caller's profile into the instance with each segment's
 * resistance in acceleration units (xi must be set). */
void hstpf__track_init(hstpf_t *f, const hstpf_track_seg_t *track, uint16_t n);

/* Segment starts relative to the origin: recomputed when the origin moves. */
void hstpf__track_rebase(hstpf_t *f);

/* Track acceleration xi (i + 600/R) at relative position s, m/s^2; *hint is
 * the caller's segment cursor, walked from where it was (O(segments moved)). */
hstpf_real_t hstpf__track_acc(const hstpf_t *f, uint16_t *hint, hstpf_real_t s);

#endif
