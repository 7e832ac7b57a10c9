/* Inline xoshiro128** for the hot loop; rng.c exposes the same as functions. */
#ifndef HSTPF_RNG_IMPL_H
#define HSTPF_RNG_IMPL_H

#include "hstpf/rng.h"

static inline uint32_t hstpf__rotl(uint32_t x, int k)
{
    return (x << k) | (x >> (32 - k));
}

static inline uint32_t hstpf__rng_next(hstpf_rng_t *r)
{
    uint32_t *s = r->s;
    const uint32_t result = hstpf__rotl(s[1] * 5u, 7) * 9u;
    const uint32_t t = s[1] << 9;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = hstpf__rotl(s[3], 11);
    return result;
}

/* Uniform in [0, 1) from the top 24 bits: exact in float. */
static inline hstpf_real_t hstpf__rng_uniform(hstpf_rng_t *r)
{
    return (hstpf_real_t)(hstpf__rng_next(r) >> 8) * (hstpf_real_t)(1.0 / 16777216.0);
}

#endif
