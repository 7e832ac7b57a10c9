/* Library-internal functions, exposed for the unit tests only. */
#ifndef HSTPF_INTERNAL_H
#define HSTPF_INTERNAL_H

#include "hstpf/hstpf.h"

/* Systematic resampling counts: counts[i] copies of particle i for the
 * normalised weights w[0..n-1] and the offset u0 in [0, 1). Always sums to
 * n, whatever the round-off of w. */
void hstpf__resample_counts(const hstpf_real_t *w, uint16_t n, hstpf_real_t u0, uint16_t *counts);

/* In place: each survivor keeps its slot, extra copies fill the slots of
 * particles with count 0; s, v and (if not NULL) lw move together.
 * counts[] is not changed, so the same counts can be applied to several
 * models. */
void hstpf__replicate(hstpf_real_t *s, hstpf_real_t *v, hstpf_real_t *lw, const uint16_t *counts,
                      uint16_t n);

#endif
