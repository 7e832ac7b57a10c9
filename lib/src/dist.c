/* Noise tables, built once at start-up with libm; look-ups in dist_impl.h. */
#include <math.h>

#include "dist_impl.h"

/* ---- exact distribution functions (double, init time only) ---------- */

/* Regularised incomplete gamma: *p = P(k, x), *q = Q(k, x) = 1 - P. Series
 * below k + 1, Lentz continued fraction above, so each tail keeps its
 * relative precision. */
static void gamma_pq(double k, double x, double *p, double *q)
{
    const double tiny = 1e-300;
    double lead;
    int n;
    if (x <= 0.0) {
        *p = 0.0;
        *q = 1.0;
        return;
    }
    lead = exp(k * log(x) - x - lgamma(k));
    if (x < k + 1.0) {
        double ap = k, term = 1.0 / k, sum = term;
        for (n = 0; n < 10000; ++n) {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if (term < sum * 1e-17) {
                break;
            }
        }
        *p = sum * lead;
        *q = 1.0 - *p;
    } else {
        double b = x + 1.0 - k, c = 1.0 / tiny, d = 1.0 / b, h = d;
        for (n = 1; n < 10000; ++n) {
            const double an = -(double)n * ((double)n - k);
            double del;
            b += 2.0;
            d = an * d + b;
            if (fabs(d) < tiny) {
                d = tiny;
            }
            c = b + an / c;
            if (fabs(c) < tiny) {
                c = tiny;
            }
            d = 1.0 / d;
            del = d * c;
            h *= del;
            if (fabs(del - 1.0) < 1e-16) {
                break;
            }
        }
        *q = lead * h;
        *p = 1.0 - *q;
    }
}

/* Piecewise-linear table density: CDF at x (normalised by `mass`). */
static double table_cdf(const hstpf_dist_spec_t *sp, double mass, double x)
{
    double c = 0.0;
    uint16_t j;
    if (x <= sp->table_x[0]) {
        return 0.0;
    }
    for (j = 0; j + 1u < sp->table_n; ++j) {
        const double x0 = sp->table_x[j], x1 = sp->table_x[j + 1u];
        const double p0 = sp->table_p[j], p1 = sp->table_p[j + 1u];
        if (x < x1) {
            const double d = x - x0;
            c += p0 * d + 0.5 * (p1 - p0) / (x1 - x0) * d * d;
            return c / mass;
        }
        c += 0.5 * (p0 + p1) * (x1 - x0);
    }
    return 1.0;
}

static double table_pdf(const hstpf_dist_spec_t *sp, double mass, double x)
{
    uint16_t j;
    if (x < sp->table_x[0] || x > sp->table_x[sp->table_n - 1u]) {
        return 0.0;
    }
    for (j = 0; j + 1u < sp->table_n; ++j) {
        const double x0 = sp->table_x[j], x1 = sp->table_x[j + 1u];
        if (x <= x1) {
            const double f = (x - x0) / (x1 - x0);
            return (sp->table_p[j] + f * (sp->table_p[j + 1u] - sp->table_p[j])) / mass;
        }
    }
    return 0.0;
}

static double table_mass(const hstpf_dist_spec_t *sp)
{
    double m = 0.0;
    uint16_t j;
    for (j = 0; j + 1u < sp->table_n; ++j) {
        m += 0.5 * (sp->table_p[j] + sp->table_p[j + 1u]) * (sp->table_x[j + 1u] - sp->table_x[j]);
    }
    return m;
}

/* Lower (upper = 0) or upper (upper = 1) tail probability at x. */
static double tail_prob(const hstpf_dist_spec_t *sp, double mass, double x, int upper)
{
    double p, q;
    switch (sp->kind) {
    case HSTPF_DIST_GAUSSIAN:
        return 0.5 * erfc((upper ? 1.0 : -1.0) * (x - sp->mean) / (sp->sd * sqrt(2.0)));
    case HSTPF_DIST_GAMMA:
        gamma_pq(sp->shape, (x - sp->loc) / sp->scale, &p, &q);
        return upper ? q : p;
    default:
        p = table_cdf(sp, mass, x);
        return upper ? 1.0 - p : p;
    }
}

/* x with lower (or upper) tail probability prob, by bisection. The Gamma is
 * bisected in log(x - loc) so that quantiles near its edge (1e-300 for
 * small shapes) stay exact. */
double hstpf__dist_quantile(const hstpf_dist_spec_t *sp, double mass, double prob, int upper)
{
    double a, b;
    int i, logscale = 0;
    switch (sp->kind) {
    case HSTPF_DIST_GAUSSIAN:
        a = sp->mean - 40.0 * sp->sd;
        b = sp->mean + 40.0 * sp->sd;
        break;
    case HSTPF_DIST_GAMMA:
        logscale = 1; /* in log((x - loc) / scale): the bracket is in scales */
        a = -745.0;
        b = log(sp->shape + 40.0 * sqrt(sp->shape) + 800.0);
        break;
    default:
        a = sp->table_x[0];
        b = sp->table_x[sp->table_n - 1u];
        break;
    }
    for (i = 0; i < 200; ++i) {
        const double mid = 0.5 * (a + b);
        const double x = logscale ? sp->loc + sp->scale * exp(mid) : mid;
        const double tp = tail_prob(sp, mass, x, upper);
        /* the lower tail grows with x, the upper one shrinks */
        if ((upper == 0) == (tp < prob)) {
            a = mid;
        } else {
            b = mid;
        }
    }
    return logscale ? sp->loc + sp->scale * exp(0.5 * (a + b)) : 0.5 * (a + b);
}

static double exact_logpdf(const hstpf_dist_spec_t *sp, double mass, double x)
{
    double z, p;
    switch (sp->kind) {
    case HSTPF_DIST_GAUSSIAN:
        z = (x - sp->mean) / sp->sd;
        return -0.5 * z * z - log(sp->sd * sqrt(2.0 * 3.14159265358979323846));
    case HSTPF_DIST_GAMMA:
        z = (x - sp->loc) / sp->scale;
        if (z <= 0.0) {
            return -HUGE_VAL;
        }
        return (sp->shape - 1.0) * log(z) - z - log(sp->scale) - lgamma(sp->shape);
    default:
        p = table_pdf(sp, mass, x);
        return p > 0.0 ? log(p) : -HUGE_VAL;
    }
}

int hstpf__dist_finite(double x)
{
    return isfinite(x) ? 1 : 0;
}

/* A spread (sd, scale, support width, soft edge) the float tables can hold
 * around an offset (mean, location, table end). */
int hstpf__dist_spread_ok(double spread, double offset)
{
    return spread >= HSTPF_DIST_SPREAD_MIN && spread <= HSTPF_DIST_SPREAD_MAX &&
           spread >= HSTPF_DIST_REL_MIN * fabs(offset);
}

int32_t hstpf__dist_check(const hstpf_dist_spec_t *sp)
{
    uint16_t j;
    if (sp == NULL) {
        return HSTPF_E_NULL;
    }
    if (!hstpf__dist_finite(sp->floor_depth) || !hstpf__dist_finite(sp->edge_soft)) {
        return HSTPF_E_NONFINITE;
    }
    if (sp->floor_depth < 0.0 || sp->floor_depth > HSTPF_DIST_FLOOR_MAX || sp->edge_soft < 0.0 ||
        (sp->edge_soft > 0.0 && !hstpf__dist_spread_ok(sp->edge_soft, 0.0))) {
        return HSTPF_E_DIST;
    }
    switch (sp->kind) {
    case HSTPF_DIST_GAUSSIAN:
        if (!hstpf__dist_finite(sp->mean) || !hstpf__dist_finite(sp->sd)) {
            return HSTPF_E_NONFINITE;
        }
        return fabs(sp->mean) <= HSTPF_DIST_X_MAX && hstpf__dist_spread_ok(sp->sd, sp->mean) ? HSTPF_OK : HSTPF_E_DIST;
    case HSTPF_DIST_GAMMA:
        if (!hstpf__dist_finite(sp->shape) || !hstpf__dist_finite(sp->scale) || !hstpf__dist_finite(sp->loc)) {
            return HSTPF_E_NONFINITE;
        }
        return (sp->shape >= 1e-3 && sp->shape <= 1e4 && fabs(sp->loc) <= HSTPF_DIST_X_MAX &&
                hstpf__dist_spread_ok(sp->scale, sp->loc))
                   ? HSTPF_OK
                   : HSTPF_E_DIST;
    case HSTPF_DIST_TABLE:
        if (sp->table_x == NULL || sp->table_p == NULL) {
            return HSTPF_E_NULL;
        }
        if (sp->table_n < 2u || sp->table_n > HSTPF_DIST_TABLE_MAX) {
            return HSTPF_E_SIZE;
        }
        for (j = 0; j < sp->table_n; ++j) {
            if (!hstpf__dist_finite(sp->table_x[j]) || !hstpf__dist_finite(sp->table_p[j])) {
                return HSTPF_E_NONFINITE;
            }
            if (sp->table_p[j] < 0.0 || fabs(sp->table_x[j]) > HSTPF_DIST_X_MAX ||
                (j > 0u && !(sp->table_x[j] > sp->table_x[j - 1u]))) {
                return HSTPF_E_DIST;
            }
        }
        {
            const double x0 = sp->table_x[0], x1 = sp->table_x[sp->table_n - 1u];
            const double mass = table_mass(sp); /* overflows to inf for huge densities */
            return hstpf__dist_spread_ok(x1 - x0, fabs(x0) > fabs(x1) ? x0 : x1) && mass > 0.0 && hstpf__dist_finite(mass)
                       ? HSTPF_OK
                       : HSTPF_E_DIST;
        }
    default:
        return HSTPF_E_DIST;
    }
}

int32_t hstpf_dist_init(hstpf_dist_t *d, const hstpf_dist_spec_t *sp)
{
    const double depth = (sp != NULL && sp->floor_depth > 0.0) ? sp->floor_depth : HSTPF__DIST_FLOOR_DEPTH;
    double mass = 1.0, lo, hi, dx, lpmax = -HUGE_VAL, mean, var;
    int32_t err;
    uint32_t i;
    int k;

    if (d == NULL) {
        return HSTPF_E_NULL;
    }
    err = hstpf__dist_check(sp);
    if (err != HSTPF_OK) {
        return err;
    }
    if (sp->kind == HSTPF_DIST_TABLE) {
        mass = table_mass(sp);
    }

    /* inverse CDF: body nodes, then the two geometric tail tables */
    for (i = 1; i < HSTPF_DIST_QN; ++i) {
        const double u = (double)i / (double)HSTPF_DIST_QN;
        d->qt.q[i] = (hstpf_real_t)(u <= 0.5 ? hstpf__dist_quantile(sp, mass, u, 0) : hstpf__dist_quantile(sp, mass, 1.0 - u, 1));
    }
    for (k = 0; k < HSTPF_DIST_TAILN; ++k) {
        const double p = ldexp(1.0, k - 32);
        d->qt.tail_lo[k] = (hstpf_real_t)hstpf__dist_quantile(sp, mass, p, 0);
        d->qt.tail_hi[k] = (hstpf_real_t)hstpf__dist_quantile(sp, mass, p, 1);
    }
    d->qt.q[0] = d->qt.tail_lo[0];
    d->qt.q[HSTPF_DIST_QN] = d->qt.tail_hi[0];

    /* log-density grid over the body, and the tails beyond it */
    switch (sp->kind) {
    case HSTPF_DIST_GAUSSIAN:
        lo = sp->mean - 8.0 * sp->sd;
        hi = sp->mean + 8.0 * sp->sd;
        break;
    case HSTPF_DIST_GAMMA:
        lo = sp->loc;
        hi = hstpf__dist_quantile(sp, mass, HSTPF__GAMMA_TOP_TAIL, 1);
        break;
    default:
        lo = sp->table_x[0];
        hi = sp->table_x[sp->table_n - 1u];
        break;
    }
    dx = (hi - lo) / (double)(HSTPF_DIST_LN - 1);
    for (i = 0; i < HSTPF_DIST_LN; ++i) {
        double v = exact_logpdf(sp, mass, lo + dx * (double)i);
        if (i == 0u && sp->kind == HSTPF_DIST_GAMMA && sp->shape < 1.0) {
            /* unbounded density at the edge: average over the half cell */
            double p, q;
            gamma_pq(sp->shape, 0.5 * dx / sp->scale, &p, &q);
            v = log(p / (0.5 * dx));
        }
        if (v > lpmax) {
            lpmax = v;
        }
        d->lp[i] = (hstpf_real_t)v; /* -inf until clamped below */
    }
    d->lp_max = (hstpf_real_t)lpmax;
    d->floor = (hstpf_real_t)(lpmax - depth);
    for (i = 0; i < HSTPF_DIST_LN; ++i) {
        if (!(d->lp[i] > d->floor)) {
            d->lp[i] = d->floor;
        }
    }
    d->lo = (hstpf_real_t)lo;
    d->dx = (hstpf_real_t)dx;
    d->inv_dx = (hstpf_real_t)(1.0 / dx);

    switch (sp->kind) {
    case HSTPF_DIST_GAUSSIAN: /* exact quadratic continuation */
        d->hard[0] = d->hard[1] = 0u;
        d->tail_b[0] = d->tail_b[1] = (hstpf_real_t)(-8.0 / sp->sd);
        d->tail_c[0] = d->tail_c[1] = (hstpf_real_t)(-0.5 / (sp->sd * sp->sd));
        mean = sp->mean;
        var = sp->sd * sp->sd;
        break;
    case HSTPF_DIST_GAMMA:
        d->hard[0] = 1u;
        d->hard[1] = 0u;
        d->tail_b[1] = (hstpf_real_t)((sp->shape - 1.0) / (hi - lo) - 1.0 / sp->scale);
        d->tail_c[1] = 0;
        mean = sp->loc + sp->shape * sp->scale;
        var = sp->shape * sp->scale * sp->scale;
        break;
    default: {
        uint16_t j;
        double m0 = 0.0, m1 = 0.0, m2 = 0.0, pmax = 0.0;
        const double x0 = sp->table_x[0];
        d->hard[0] = d->hard[1] = 1u;
        for (j = 0; j < sp->table_n; ++j) {
            pmax = sp->table_p[j] > pmax ? sp->table_p[j] : pmax;
        }
        /* exact moments of a piecewise-linear density, about x[0] and with
         * p / max p: no overflow for densities up to 1e308 or offsets 1e9 */
        for (j = 0; j + 1u < sp->table_n; ++j) {
            const double a = sp->table_x[j] - x0, b = sp->table_x[j + 1u] - x0;
            const double pa = sp->table_p[j] / pmax, pb = sp->table_p[j + 1u] / pmax, h = b - a;
            m0 += 0.5 * (pa + pb) * h;
            m1 += h * (pa * (2.0 * a + b) + pb * (a + 2.0 * b)) / 6.0;
            m2 += h * (pa * (3.0 * a * a + 2.0 * a * b + b * b) + pb * (a * a + 2.0 * a * b + 3.0 * b * b)) / 12.0;
        }
        mean = m1 / m0;
        var = m2 / m0 - mean * mean;
        mean += x0;
        break;
    }
    }
    for (k = 0; k < 2; ++k) {
        if (d->hard[k]) {
            d->tail_b[k] = 0;
            d->tail_c[k] = sp->edge_soft > 0.0 ? (hstpf_real_t)(-0.5 / (sp->edge_soft * sp->edge_soft)) : (hstpf_real_t)0;
        }
    }
    d->qt.mean = (hstpf_real_t)mean;
    d->qt.sd = (hstpf_real_t)sqrt(var > 0.0 ? var : 0.0);
    d->floor_slope = (hstpf_real_t)(var > 0.0 ? 1.0 / sqrt(var) : 1.0 / dx);
    d->dd_max = (hstpf_real_t)(1e4 * (var > 0.0 ? sqrt(var) : dx));
    return HSTPF_OK;
}

hstpf_real_t hstpf_dist_sample(const hstpf_dist_t *d, uint32_t r)
{
    return hstpf__dist_sample(&d->qt, r);
}

hstpf_real_t hstpf_dist_logpdf(const hstpf_dist_t *d, hstpf_real_t x)
{
    return hstpf__dist_logpdf(d, x);
}

hstpf_real_t hstpf_exp_neg(hstpf_real_t x)
{
    return hstpf__exp_neg(x);
}
