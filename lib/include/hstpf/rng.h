/**
 * @file rng.h
 * @brief xoshiro128** pseudo-random generator, seeded through splitmix64.
 *
 * xoshiro128** (Blackman and Vigna, 2018) has 128 bits of state, only 32-bit
 * operations per draw (cheap on a Cortex-M) and passes BigCrush. Streams are
 * derived from a 64-bit seed and a stream number through splitmix64, so that
 * each model of a filter bank draws from its own stream and results do not
 * depend on loop order. Output is bit-identical on every platform.
 */
#ifndef HSTPF_RNG_H
#define HSTPF_RNG_H

#include "hstpf/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Generator state. Never all zero once seeded. */
typedef struct {
    uint32_t s[4];
} hstpf_rng_t;

/**
 * @brief One step of splitmix64: advances *state and returns the next output.
 * @param state 64-bit counter state (any value); must not be NULL.
 * Cost O(1); no memory. Used for seeding; exposed for tests and tools.
 */
uint64_t hstpf_splitmix64(uint64_t *state);

/**
 * @brief Seeds a generator for stream `stream` of `seed`.
 *
 * The state is the 2*stream-th and (2*stream+1)-th splitmix64 outputs of
 * `seed` (low word first); never all zero (splitmix64's output is a
 * bijection of its state, so two consecutive outputs are not both 0).
 * @return HSTPF_OK, or HSTPF_E_NULL if rng is NULL.
 * Cost O(stream); no memory besides *rng.
 */
int32_t hstpf_rng_seed(hstpf_rng_t *rng, uint64_t seed, uint32_t stream);

/**
 * @brief Sets the raw state (for reference vectors).
 * @return HSTPF_OK; HSTPF_E_NULL if a pointer is NULL; HSTPF_E_RANGE if all
 * four words are zero (the one state xoshiro cannot leave).
 */
int32_t hstpf_rng_set_state(hstpf_rng_t *rng, const uint32_t state[4]);

/**
 * @brief Next 32-bit output of xoshiro128**. rng must be seeded (not checked:
 * this is the hot path). Cost: 9 integer operations; no memory.
 */
uint32_t hstpf_rng_next(hstpf_rng_t *rng);

/**
 * @brief Uniform variate in [0, 1) with 24 random bits (exact in float).
 * Cost: one hstpf_rng_next(); no memory.
 */
hstpf_real_t hstpf_rng_uniform(hstpf_rng_t *rng);

#ifdef __cplusplus
}
#endif

#endif /* HSTPF_RNG_H */
