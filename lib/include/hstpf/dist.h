/**
 * @file dist.h
 * @brief Table-driven noise distributions: sampling and log-density.
 *
 * A distribution is specified as Gaussian(mean, sd), Gamma(shape, scale,
 * location) or a caller-supplied density table, and built once by
 * hstpf_dist_init() into fixed-size tables. Afterwards sampling and
 * log-density evaluation use table look-ups and linear interpolation only:
 * no log, exp or pow.
 *
 * Sampling: inverse CDF. The unit interval is cut into 2^HSTPF_DIST_QBITS
 * equal bins whose end points are exact quantiles; the two extreme bins are
 * refined by tail tables whose nodes lie at tail probabilities 2^-32, 2^-31,
 * ..., 2^-QBITS. The sampled distribution therefore has exactly the target
 * probability at every node; between nodes the quantile is interpolated
 * linearly. Accuracy (tested): Kolmogorov-Smirnov distance between the
 * sampled and the exact CDF below 2e-3 for the Gaussian and for Gamma with
 * shape >= 0.02 in the float build (the double build resolves quantiles
 * below 1e-30 that a bin interpolates linearly across many decades: 3.3e-3
 * for Gamma shape 0.02); sampled extremes reach the 2^-32 quantile (6.2 sd
 * for a Gaussian).
 *
 * Log-density: HSTPF_DIST_LN nodes on a uniform grid over the body of the
 * distribution (Gaussian: mean +- 8 sd; Gamma: location to its 1 - 1e-9
 * quantile; table: its own range), interpolated linearly. Interpolation
 * error per cell is at most dx^2/8 * max|(log p)''|: below 1.2e-4 nats for a
 * Gaussian; for Gamma with shape < 1 the first cell, where the density is
 * unbounded, holds the cell-average instead. Beyond the grid: the Gaussian
 * continues with its exact quadratic, the Gamma's right tail linearly with
 * its end slope; left of a hard support edge (the Gamma's location, a
 * table's ends) the value falls as a Gaussian of width edge_soft from the
 * edge value, or jumps straight to the floor when edge_soft is 0. The floor
 * is lp_max - floor_depth at the grid's edges and falls by 1 nat per
 * standard deviation of the distribution beyond them, up to 1e4 standard
 * deviations (then constant, so nothing overflows): never -inf or NaN, so
 * particles far from a measurement are still ranked by their distance.
 * Inside the grid nothing is below lp_max - floor_depth.
 */
#ifndef HSTPF_DIST_H
#define HSTPF_DIST_H

#include "hstpf/common.h"

#ifdef __cplusplus
extern "C" {
#endif

#define HSTPF_DIST_QN (1u << HSTPF_DIST_QBITS)       /**< inverse-CDF bins */

/** @name Ranges of a specification (hstpf_dist_init() answers HSTPF_E_DIST
 * outside them). Noise is in metres or metres per second: no offset (mean,
 * Gamma location, table abscissa) beyond 10 x HSTPF_POS_MAX_M; spreads (sd,
 * Gamma scale, table support width, edge_soft > 0, measurement blur) from a
 * nanometre to 1e9; and a spread at least HSTPF_DIST_REL_MIN of its offset,
 * so that the 512-node float grid over about 10 spreads has a spacing above
 * float's resolution (2^-23 relative) there. The tables then hold only
 * finite floats whatever the specification. @{ */
#define HSTPF_DIST_X_MAX 1e9
#define HSTPF_DIST_SPREAD_MIN 1e-9
#define HSTPF_DIST_SPREAD_MAX 1e9
#define HSTPF_DIST_REL_MIN 1e-5
/** Deepest floor_depth, nats: e^-700 is near the smallest double. */
#define HSTPF_DIST_FLOOR_MAX 700.0
/** @} */
#define HSTPF_DIST_TAILN (32 - HSTPF_DIST_QBITS + 1) /**< nodes per tail table */

/** Kind of distribution. */
typedef enum {
    HSTPF_DIST_GAUSSIAN = 0, /**< Gaussian(mean, sd) */
    HSTPF_DIST_GAMMA = 1,    /**< Gamma(shape, scale) shifted by loc */
    HSTPF_DIST_TABLE = 2     /**< piecewise-linear density given by the caller */
} hstpf_dist_kind_t;

/** Specification of a distribution (input to hstpf_dist_init()). */
typedef struct {
    hstpf_dist_kind_t kind;
    double mean;  /**< Gaussian: mean, |mean| <= HSTPF_DIST_X_MAX */
    double sd;    /**< Gaussian: standard deviation, a spread (see the ranges) */
    double shape; /**< Gamma: shape k, in [1e-3, 1e4] */
    double scale; /**< Gamma: scale theta, a spread */
    double loc;   /**< Gamma: location (left edge of the support), an offset */
    /** Table: n strictly increasing abscissae and density values >= 0
     *  (not necessarily normalised, total mass finite),
     *  2 <= n <= HSTPF_DIST_TABLE_MAX; x[0] and x[n-1] offsets, the width
     *  x[n-1] - x[0] a spread. The density is linear between points and
     *  zero outside [x[0], x[n-1]]. */
    const double *table_x;
    const double *table_p;
    uint16_t table_n;
    /** Log-density floor, in nats below the density's maximum, at most
     *  HSTPF_DIST_FLOOR_MAX. 0 selects the default 30. Bounds how much one
     *  measurement can cost a model. */
    double floor_depth;
    /** Width of the soft edge outside a hard support edge (same unit as the
     *  variate), 0 or a spread; 0: jump to the floor. Ignored by the
     *  Gaussian. */
    double edge_soft;
} hstpf_dist_spec_t;

/** The quantile part of a built distribution: what sampling and the grid
 * engine's probabilities over cells use, without the log-density. An
 * instance keeps only this part of the noises it never evaluates as a
 * density (the process noises). Treat the members as private. */
typedef struct {
    hstpf_real_t q[HSTPF_DIST_QN + 1];      /* quantiles at u = i / QN */
    hstpf_real_t tail_lo[HSTPF_DIST_TAILN]; /* F^-1(2^(k-32)) */
    hstpf_real_t tail_hi[HSTPF_DIST_TAILN]; /* F^-1(1 - 2^(k-32)) */
    hstpf_real_t mean;                      /* exact mean */
    hstpf_real_t sd;                        /* exact standard deviation */
} hstpf_dist_quantiles_t;

/** A built distribution. Treat the members as private. */
typedef struct {
    hstpf_dist_quantiles_t qt;              /* sampling: quantiles, tails, moments */
    hstpf_real_t lp[HSTPF_DIST_LN];         /* log-density nodes */
    hstpf_real_t lo, dx, inv_dx;            /* grid start, spacing, 1 / spacing */
    hstpf_real_t tail_b[2], tail_c[2];      /* tails: left [0], right [1] */
    hstpf_real_t floor;                     /* absolute log-density floor */
    hstpf_real_t floor_slope;               /* floor's fall beyond the grid, 1/sd */
    hstpf_real_t dd_max;                    /* tail distance cap: 1e4 sd */
    hstpf_real_t lp_max;                    /* maximum of lp[] */
    uint8_t hard[2];                        /* tail is a hard support edge */
} hstpf_dist_t;

/**
 * @brief Builds the tables of a distribution.
 * @param d   output, caller-owned (sizeof(hstpf_dist_t) bytes).
 * @param spec the specification; only the members of its kind are read.
 * @return HSTPF_OK; HSTPF_E_NULL (d, spec or a table pointer NULL);
 *   HSTPF_E_NONFINITE (a parameter NaN/Inf); HSTPF_E_SIZE (table_n outside
 *   [2, HSTPF_DIST_TABLE_MAX]); HSTPF_E_DIST (an offset or spread outside
 *   the ranges above, shape outside [1e-3, 1e4], table abscissae not
 *   increasing, a negative density, zero or infinite total mass,
 *   floor_depth outside [0, HSTPF_DIST_FLOOR_MAX], negative edge_soft,
 *   unknown kind).
 *   On error *d is unchanged.
 * Cost: about 10^5..10^6 double operations with libm calls (erfc, lgamma,
 * log, exp): call at start-up, not per step; bounded over the whole range
 * of specifications (worst measured: 53 ms for Gamma shape 1e4 on an
 * x86-64 core, docs/quality.md). Stack below 256 bytes.
 */
int32_t hstpf_dist_init(hstpf_dist_t *d, const hstpf_dist_spec_t *spec);

/**
 * @brief Draws one variate from 32 uniform random bits (one RNG output).
 * d must have been built by hstpf_dist_init() (not checked: hot path).
 * Cost: a few integer operations, one multiply-add; no memory.
 */
hstpf_real_t hstpf_dist_sample(const hstpf_dist_t *d, uint32_t r);

/**
 * @brief Log-density at x, in nats: finite for every finite x, never NaN
 * (NaN x returns the floor); the sloping floor as above. Cost O(1).
 */
hstpf_real_t hstpf_dist_logpdf(const hstpf_dist_t *d, hstpf_real_t x);

/**
 * @brief exp(x) for x <= 0 from a 256-entry table of 2^(-j/256) with linear
 * interpolation, Cody-Waite range reduction and exponent scaling; relative
 * error below 1e-6 wherever the result is a normal float (x >= -87.3 in
 * the float build); returns 0 below -100 and 1 for x >= 0. Used for
 * particle weights. Cost O(1).
 */
hstpf_real_t hstpf_exp_neg(hstpf_real_t x);

#ifdef __cplusplus
}
#endif

#endif /* HSTPF_DIST_H */
