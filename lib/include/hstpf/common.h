/**
 * @file common.h
 * @brief hstpf: scalar type, error codes and compile-time capacities.
 *
 * Every hstpf function that can fail returns an int32_t: HSTPF_OK (0) on
 * success or one of the negative HSTPF_E_* codes below. A function that
 * fails leaves every object it was given exactly as it was, with one
 * exception: hstpf_step()'s HSTPF_E_OUTLIER reports a step that WAS taken
 * without its gated fix (do not repeat it).
 */
#ifndef HSTPF_COMMON_H
#define HSTPF_COMMON_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Library version, semantic: major.minor.patch. */
#define HSTPF_VERSION_MAJOR 0
#define HSTPF_VERSION_MINOR 2
#define HSTPF_VERSION_PATCH 0

/*
 * Scalar type of the filter arithmetic. float32 by default (single-precision
 * FPU of a Cortex-M4F); define HSTPF_USE_DOUBLE=1 when building the library
 * AND everything that includes this header to get double.
 */
#if defined(HSTPF_USE_DOUBLE) && HSTPF_USE_DOUBLE
typedef double hstpf_real_t;
#else
typedef float hstpf_real_t;
#endif

/*
 * Compile-time capacities. Override with -D when building the library and
 * its users (they size hstpf_t and HSTPF_WORKSPACE_MAX_BYTES; hstpf_init()
 * rejects a mismatch of sizeof(hstpf_t)).
 */
#ifndef HSTPF_MAX_MODELS
#define HSTPF_MAX_MODELS 17 /**< models (train types) per instance */
#endif
#ifndef HSTPF_MAX_PARTICLES
#define HSTPF_MAX_PARTICLES 256 /**< particles per model (a bound: they are in the workspace) */
#endif
#ifndef HSTPF_DIST_QBITS
#define HSTPF_DIST_QBITS 8 /**< log2 of the inverse-CDF table's bins */
#endif
#ifndef HSTPF_DIST_LN
#define HSTPF_DIST_LN 512 /**< nodes of the log-density table */
#endif
#ifndef HSTPF_DIST_TABLE_MAX
#define HSTPF_DIST_TABLE_MAX 256 /**< points of a caller-supplied density */
#endif
#ifndef HSTPF_MAX_TRACK_SEGMENTS
#define HSTPF_MAX_TRACK_SEGMENTS 64 /**< track profile segments */
#endif

/** Error codes: 0 is success, every failure is negative. */
enum {
    HSTPF_OK = 0,           /**< success */
    HSTPF_E_NULL = -1,      /**< a required pointer is NULL */
    HSTPF_E_INIT = -2,      /**< instance not initialised (or overwritten) */
    HSTPF_E_SIZE = -3,      /**< a count is 0 or above its capacity, or a buffer too small */
    HSTPF_E_NONFINITE = -4, /**< an input is NaN or infinite */
    HSTPF_E_DT = -5,        /**< step length not in (0, HSTPF_DT_MAX_S] */
    HSTPF_E_RANGE = -6,     /**< a value is outside its physical range */
    HSTPF_E_ABI = -7,       /**< caller and library disagree on sizeof(hstpf_t) */
    HSTPF_E_DIST = -8,      /**< invalid noise distribution specification */
    HSTPF_E_CONFIG = -9,    /**< invalid option (enum, probability, ...) */
    HSTPF_E_OUTLIER = -10   /**< measurement beyond the gate from the prediction */
};

/**
 * @brief Short English text for an error code.
 * @param err any value returned by an hstpf function.
 * @return a static, NUL-terminated string; "unknown error" for other values.
 * Cost O(1); no memory.
 */
const char *hstpf_strerror(int32_t err);

#ifdef __cplusplus
}
#endif

#endif /* HSTPF_COMMON_H */
