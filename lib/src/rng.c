#include "rng_impl.h"

uint64_t hstpf_splitmix64(uint64_t *state)
{
    uint64_t z = (*state += UINT64_C(0x9E3779B97F4A7C15));
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}

int32_t hstpf_rng_seed(hstpf_rng_t *rng, uint64_t seed, uint32_t stream)
{
    uint64_t st = seed, a, b;
    uint32_t i;
    if (rng == NULL) {
        return HSTPF_E_NULL;
    }
    for (i = 0; i < stream; ++i) { /* skip the streams before this one */
        (void)hstpf_splitmix64(&st);
        (void)hstpf_splitmix64(&st);
    }
    a = hstpf_splitmix64(&st);
    b = hstpf_splitmix64(&st);
    rng->s[0] = (uint32_t)a;
    rng->s[1] = (uint32_t)(a >> 32);
    rng->s[2] = (uint32_t)b;
    rng->s[3] = (uint32_t)(b >> 32);
    /* never all zero (the one state xoshiro cannot leave): splitmix64's
     * output is a bijection of its state, so a and b, from two different
     * states, are not both 0 */
    return HSTPF_OK;
}

int32_t hstpf_rng_set_state(hstpf_rng_t *rng, const uint32_t state[4])
{
    if (rng == NULL || state == NULL) {
        return HSTPF_E_NULL;
    }
    if ((state[0] | state[1] | state[2] | state[3]) == 0u) {
        return HSTPF_E_RANGE;
    }
    rng->s[0] = state[0];
    rng->s[1] = state[1];
    rng->s[2] = state[2];
    rng->s[3] = state[3];
    return HSTPF_OK;
}

uint32_t hstpf_rng_next(hstpf_rng_t *rng)
{
    return hstpf__rng_next(rng);
}

hstpf_real_t hstpf_rng_uniform(hstpf_rng_t *rng)
{
    return hstpf__rng_uniform(rng);
}
