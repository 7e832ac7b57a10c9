/* Measurement blur (cfg.e_blur_sd, particle engine): the density of
 * Gamma + N(0, sd) built once at init by quadrature into a noise table. */
#include <math.h>

#include "dist_impl.h"

/* Density of Gamma(k, th) + N(0, sd) at x (loc removed), by quadrature.
 * For shape k < 1 the part [0, gc = sd] is integrated in u = (g/th)^k,
 * where the density is bounded (the edge singularity removed). The rest,
 * up to gmax, on a fixed midpoint grid of steps h = min(sd, sv) / 16, sv
 * the scale on which the Gamma's density varies; only the steps within
 * x +- 9 sd (the kernel's mass beyond is below 1e-17) and above glo (the
 * Gamma's mass below is negligible) are visited, so the work per node is
 * bounded whatever th / sd: 2 x 9 x 16 steps when sd <= sv, else the
 * Gamma's own span [glo, gmax] in steps of sv / 16 (about 1500 at most).
 * Init time only. */
#define BLUR_Z 9.0
#define BLUR_STEPS 16.0
#define BLUR_NU 256
#define BLUR_MAX_STEPS 1e7 /* never reached in the ranges; keeps the casts defined */
typedef struct {
    double k, th, sd;  /* shape, scale, blur */
    double gc, gmax;   /* u-part [0, gc]; grid part [gc, gmax] */
    double glo;        /* no Gamma mass worth counting below */
    double dg, ng;     /* grid step and number of steps */
    double ig, lnorm;  /* 1 / (Gamma(k) th^k) and its log */
} blur_q_t;

static double gamma_blur_pdf(const blur_q_t *q, double x)
{
    const double k = q->k, th = q->th, sd = q->sd;
    const double inorm = 1.0 / (sd * sqrt(2.0 * 3.14159265358979323846));
    double acc = 0.0, z, jlo, jhi;
    int j, j0, j1;
    if (q->gc > 0.0) {
        /* p_G dg = e^(-g/th) du / Gamma(k + 1) */
        const double umax = pow(q->gc / th, k);
        const double lgk1 = lgamma(k + 1.0);
        for (j = 0; j < BLUR_NU; ++j) {
            const double u = umax * ((double)j + 0.5) / (double)BLUR_NU, g = th * pow(u, 1.0 / k);
            z = (x - g) / sd;
            acc += exp(-g / th - lgk1) * (umax / (double)BLUR_NU) * exp(-0.5 * z * z) * inorm;
        }
    }
    if (q->ng < 1.0) {
        return acc;
    }
    /* the grid steps that can lie within x +- 9 sd, one spare on each side */
    jlo = floor(((x - BLUR_Z * sd > q->glo ? x - BLUR_Z * sd : q->glo) - q->gc) / q->dg) - 1.0;
    jhi = ceil((x + BLUR_Z * sd - q->gc) / q->dg) + 1.0;
    jlo = jlo > 0.0 ? jlo : 0.0;
    jhi = jhi < q->ng ? jhi : q->ng;
    if (!(jhi > jlo)) {
        return acc;
    }
    j0 = (int)jlo;
    j1 = (int)jhi;
    for (j = j0; j < j1; ++j) {
        const double g = q->gc + q->dg * ((double)j + 0.5);
        z = (x - g) / sd;
        if (z > -BLUR_Z && z < BLUR_Z) {
            if (k < 1.0) { /* p_G(g) = ig g^(k-1) e^(-g/th): bounded for g >= gc */
                acc += q->ig * pow(g, k - 1.0) * exp(-g / th) * q->dg * exp(-0.5 * z * z) * inorm;
            } else { /* in logs: g^(k-1) and Gamma(k) overflow for large shapes */
                acc += exp(q->lnorm + (k - 1.0) * log(g) - g / th - 0.5 * z * z) * q->dg * inorm;
            }
        }
    }
    return acc;
}

int32_t hstpf__dist_blur(hstpf_dist_t *d, const hstpf_dist_spec_t *sp, double sd)
{
    const double depth = sp->floor_depth > 0.0 ? sp->floor_depth : HSTPF__DIST_FLOOR_DEPTH;
    const double k = sp->shape, th = sp->scale;
    double lo, hi, right, dx, lpmax = -HUGE_VAL, var, slope, sv, h;
    blur_q_t q;
    uint32_t i;
    if (!hstpf__dist_finite(sd) || !hstpf__dist_spread_ok(sd, 0.0) || sp->kind != HSTPF_DIST_GAMMA || hstpf__dist_check(sp) != HSTPF_OK) {
        return HSTPF_E_DIST; /* a Gaussian stays Gaussian: the caller adds the variances */
    }
    /* Grid from 6 sd left of the edge to the Gamma's 1 - 1e-9 quantile hi
     * (or 8 sd beyond its mean when the blur is that wide); the
     * convolution integrated 10 sd beyond, but not beyond 50 scales past
     * hi (1e-30 of the Gamma's mass there). A blur narrower than an eighth
     * of the grid's spacing cannot show between two nodes: it is widened
     * to hi / 4088. */
    hi = hstpf__dist_quantile(sp, 1.0, HSTPF__GAMMA_TOP_TAIL, 1) - sp->loc;
    q.sd = hi / (8.0 * (double)(HSTPF_DIST_LN - 1));
    q.sd = sd > q.sd ? sd : q.sd;
    right = k * th + 8.0 * q.sd;
    right = right > hi ? right : hi;
    lo = -6.0 * q.sd;
    dx = (right - lo) / (double)(HSTPF_DIST_LN - 1);
    q.k = k;
    q.th = th;
    q.gmax = right + 10.0 * q.sd;
    q.gmax = q.gmax < hi + 50.0 * th ? q.gmax : hi + 50.0 * th;
    q.gc = k < 1.0 ? (q.sd < q.gmax ? q.sd : q.gmax) : 0.0;
    /* a large shape's left tail 12 sd below its mean is below e^-72 */
    q.glo = k > 144.0 ? (k - 12.0 * sqrt(k)) * th : 0.0;
    sv = th * sqrt(k > 1.0 ? k : 1.0);
    h = (q.sd < sv ? q.sd : sv) / BLUR_STEPS;
    q.ng = ceil((q.gmax - q.gc) / h);
    q.ng = q.ng < BLUR_MAX_STEPS ? q.ng : BLUR_MAX_STEPS;
    q.dg = q.ng >= 1.0 ? (q.gmax - q.gc) / q.ng : 0.0;
    q.ig = 1.0 / (exp(lgamma(k)) * pow(th, k)); /* used for k < 1 only: finite there */
    q.lnorm = -lgamma(k) - k * log(th);
    for (i = 0; i < HSTPF_DIST_LN; ++i) {
        const double p = gamma_blur_pdf(&q, lo + dx * (double)i);
        const double v = p > 0.0 ? log(p) : -HUGE_VAL;
        lpmax = v > lpmax ? v : lpmax;
        d->lp[i] = (hstpf_real_t)v;
    }
    d->lp_max = (hstpf_real_t)lpmax;
    d->floor = (hstpf_real_t)(lpmax - depth);
    for (i = 0; i < HSTPF_DIST_LN; ++i) {
        if (!(d->lp[i] > d->floor)) {
            d->lp[i] = d->floor;
        }
    }
    d->lo = (hstpf_real_t)(lo + sp->loc);
    d->dx = (hstpf_real_t)dx;
    d->inv_dx = (hstpf_real_t)(1.0 / dx);
    /* left: the Gaussian's quadratic from the edge's slope; right: linear,
     * the Gamma's own slope, or the end slope when the grid was widened for
     * a wide blur; neither rising away from the grid */
    d->hard[0] = d->hard[1] = 0u;
    slope = ((double)d->lp[1] - (double)d->lp[0]) / dx;
    d->tail_b[0] = (hstpf_real_t)(-slope < 0.0 ? -slope : 0.0);
    d->tail_c[0] = (hstpf_real_t)(-0.5 / (q.sd * q.sd));
    slope = right > hi ? ((double)d->lp[HSTPF_DIST_LN - 1] - (double)d->lp[HSTPF_DIST_LN - 2]) / dx
                       : (k - 1.0) / hi - 1.0 / th;
    d->tail_b[1] = (hstpf_real_t)(slope < 0.0 ? slope : 0.0);
    d->tail_c[1] = 0;
    var = k * th * th + q.sd * q.sd;
    d->qt.sd = (hstpf_real_t)sqrt(var);
    d->floor_slope = (hstpf_real_t)(1.0 / sqrt(var));
    d->dd_max = (hstpf_real_t)(1e4 * sqrt(var));
    return HSTPF_OK;
}
