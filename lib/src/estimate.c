/* The published estimate: the blend over the models (weights less the
 * floor), the mixture's sd, theta with its covariance and the W(v) band,
 * and the validity of every published value. */
#include <math.h>
#include <string.h>

#include "bank.h"
#include "refine.h"

/* Weights for blended estimates: q less the floor, normalised, for the
 * rows (wb[0..n-1]) and the continuous hypothesis (wb[n], 0 when off). The
 * floor keeps a model able to recover; it must not let a model that lost
 * the train pull the estimates. */
void hstpf__blend_weights(const hstpf_t *f, double *wb)
{
    const uint16_t n = f->cfg.n_models, nh = hstpf__n_hyp(f);
    double sum = 0.0;
    uint16_t l;
    wb[n] = 0.0;
    for (l = 0; l < nh; ++l) {
        const double q = exp(l < n ? f->m[l].logq : f->rf.logq) - f->cfg.q_floor;
        wb[l] = q > 0.0 ? q : 0.0;
        sum += wb[l];
    }
    for (l = 0; l < nh; ++l) {
        wb[l] = sum > 0.0 ? wb[l] / sum : 1.0 / (double)nh;
    }
}

/* The bank's predictive log-likelihood of this fix: the weighted models'
 * increments mixed by the weights before this step's update. */
double hstpf__bank_loglik(const hstpf_t *f)
{
    double wb[HSTPF_MAX_MODELS + 1], mx = -HUGE_VAL, sum = 0.0;
    uint16_t l;
    const uint16_t nh = hstpf__n_hyp(f);
    hstpf__blend_weights(f, wb);
    for (l = 0; l < nh; ++l) {
        const double ll = l < f->cfg.n_models ? (double)f->m[l].loglik : f->rf.loglik;
        mx = wb[l] > 0.0 && ll > mx ? ll : mx;
    }
    for (l = 0; l < nh; ++l) {
        const double ll = l < f->cfg.n_models ? (double)f->m[l].loglik : f->rf.loglik;
        sum += wb[l] > 0.0 ? wb[l] * exp(ll - mx) : 0.0;
    }
    return mx + log(sum);
}

double hstpf__blended_position(const hstpf_t *f, double dt_ahead, double *var, double *speed)
{
    double s = 0.0, m2 = 0.0, pv = 0.0, sv = 0.0, ps, wb[HSTPF_MAX_MODELS + 1];
    const double t2 = dt_ahead * dt_ahead;
    uint16_t l;
    hstpf__blend_weights(f, wb);
    for (l = 0; l < f->cfg.n_models; ++l) {
        const hstpf_model_t *m = &f->m[l];
        ps = (double)m->s_mean + dt_ahead * (double)m->v_mean;
        s += wb[l] * ps;
        if (speed != NULL) {
            sv += wb[l] * (double)m->v_mean;
        }
        if (var != NULL) {
            m2 += wb[l] * ps * ps;
            pv += wb[l] * 2.0 * ((double)m->s_var + t2 * (double)m->v_var);
        }
    }
    if (f->rf.active) {
        double rs, rv, pss, pvv;
        const double w = wb[f->cfg.n_models];
        hstpf__refine_sv(f, &rs, &rv, &pss, &pvv);
        ps = rs + dt_ahead * rv;
        s += w * ps;
        sv += w * rv;
        if (var != NULL) {
            m2 += w * ps * ps;
            pv += w * 2.0 * (pss + t2 * pvv);
        }
    }
    if (var != NULL) {
        *var = pv + (m2 > s * s ? m2 - s * s : 0.0);
    }
    if (speed != NULL) {
        *speed = sv;
    }
    return s;
}

/* A position, speed or weight as the header bounds it (finite too). */
static int pos_ok(double x)
{
    return fabs(x) <= HSTPF_POS_MAX_M;
}
static int speed_ok(double x)
{
    return x >= 0.0 && x <= HSTPF_SPEED_MAX;
}
static int prob_ok(double x)
{
    return x >= 0.0 && x <= 1.0;
}

/* Every published value finite and within the header's ranges: the
 * blend, theta with its covariance, the hypothesis' weight and gain, and
 * each model's output (NaN fails every comparison below). */
static int in_ranges(const hstpf_estimate_t *o)
{
    const double vals[] = {o->position_sd_m, (double)o->speed_sd_mps, (double)o->resistance, (double)o->gain,
                           (double)o->gain_sd, o->time_s};
    const double th_max[3] = {HSTPF_C0_MAX, HSTPF_C1_MAX, HSTPF_C2_MAX};
    uint32_t i;
    for (i = 0; i < sizeof vals / sizeof vals[0]; ++i) {
        if (!hstpf__fin(vals[i])) {
            return 0;
        }
    }
    for (i = 0; i < 6u; ++i) {
        if (!hstpf__fin((double)o->theta_cov[i])) {
            return 0;
        }
    }
    for (i = 0; i < 3u; ++i) {
        if (!((double)o->theta[i] >= 0.0 && (double)o->theta[i] <= th_max[i])) {
            return 0;
        }
    }
    for (i = 0; i < o->n_models; ++i) {
        const hstpf_model_out_t *m = &o->model[i];
        if (!pos_ok(m->position_m) || !speed_ok((double)m->speed_mps) || !prob_ok((double)m->q) ||
            !hstpf__fin((double)m->ess) || !hstpf__fin((double)m->loglik)) {
            return 0;
        }
    }
    /* (the sds are square roots of values clamped at 0: never negative) */
    return pos_ok(o->position_m) && speed_ok((double)o->speed_mps) && prob_ok((double)o->q_offtable);
}

/* A row's spread for the band: its likelihood is computed at the nominal
 * coefficients, but a real train of that type is spread around them (load,
 * wear, wind, coupling: refine_spread, docs/model.md) by more than the data can resolve
 * (Cramer-Rao, docs/results.md). With cfg.refine, also where the engine
 * or the noise leaves the continuous hypothesis out (the spread is the
 * trains', not the hypothesis'); without it the rows are the paper's
 * points. */
static void row_spread(const hstpf_t *f, uint16_t l, double w, double *cov)
{
    const double rho = f->cfg.refine_spread;
    const double c[3] = {f->theta[l].c0, f->theta[l].c1, f->theta[l].c2};
    int i;
    if (!f->cfg.refine) {
        return;
    }
    for (i = 0; i < 3; ++i) {
        cov[4 * i] += w * rho * rho * c[i] * c[i];
    }
}

/* The published theta and its covariance: the mixture of the rows (their
 * spread, row_spread()) and the continuous hypothesis (Gaussian); a
 * declared row's theta is its own, with its spread. */
static void theta_mixture(const hstpf_t *f, const double *wb, double *th, double *cov)
{
    const uint16_t n = f->cfg.n_models;
    double rth[3] = {0.0, 0.0, 0.0}, rcov[9];
    uint16_t l;
    int i, j;
    memset(cov, 0, sizeof(double) * 9);
    th[0] = th[1] = th[2] = 0.0;
    if (f->declared >= 0) {
        /* Table 2, State A(2): the declared type's own coefficients */
        th[0] = f->theta[f->declared].c0;
        th[1] = f->theta[f->declared].c1;
        th[2] = f->theta[f->declared].c2;
        row_spread(f, (uint16_t)f->declared, 1.0, cov);
        return;
    }
    if (f->rf.active) {
        hstpf__refine_theta(f, rth, rcov);
    }
    for (l = 0; l < n; ++l) {
        th[0] += wb[l] * f->theta[l].c0;
        th[1] += wb[l] * f->theta[l].c1;
        th[2] += wb[l] * f->theta[l].c2;
    }
    for (i = 0; i < 3; ++i) {
        th[i] += wb[n] * rth[i];
    }
    for (l = 0; l <= n; ++l) {
        const double d[3] = {(l < n ? f->theta[l].c0 : rth[0]) - th[0],
                             (l < n ? f->theta[l].c1 : rth[1]) - th[1],
                             (l < n ? f->theta[l].c2 : rth[2]) - th[2]};
        if (!(wb[l] > 0.0)) {
            continue;
        }
        for (i = 0; i < 3; ++i) {
            for (j = 0; j < 3; ++j) {
                cov[3 * i + j] += wb[l] * (d[i] * d[j] + (l < n ? 0.0 : rcov[3 * i + j]));
            }
        }
        if (l < n) {
            row_spread(f, l, wb[l], cov);
        }
    }
}

int32_t hstpf_resistance_band(const hstpf_estimate_t *e, double v_mps, double *w, double *sd)
{
    double h[3], var = 0.0;
    const double *c;
    double cv[6];
    int i, j;
    static const uint8_t idx[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
    if (e == NULL || w == NULL || sd == NULL) {
        return HSTPF_E_NULL;
    }
    if (!hstpf__fin(v_mps)) {
        return HSTPF_E_NONFINITE;
    }
    h[0] = 1.0;
    h[1] = 3.6 * v_mps;
    h[2] = h[1] * h[1];
    for (i = 0; i < 6; ++i) {
        cv[i] = (double)e->theta_cov[i];
    }
    c = cv;
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) {
            var += h[i] * h[j] * c[idx[i][j]];
        }
    }
    {
        const double wv = (double)e->theta[0] + (double)e->theta[1] * h[1] + (double)e->theta[2] * h[2];
        if (!hstpf__fin(wv) || !hstpf__fin(var)) {
            return HSTPF_E_NONFINITE; /* a NaN variance must not read as a band of width 0 */
        }
        *w = wv;
        *sd = sqrt(var > 0.0 ? var : 0.0);
    }
    return HSTPF_OK;
}

int32_t hstpf_estimate(const hstpf_t *f, hstpf_estimate_t *out)
{
    uint16_t l;
    double s = 0.0, v = 0.0, vs = 0.0, vv = 0.0, th[3] = {0.0, 0.0, 0.0}, cov[9];
    double wb[HSTPF_MAX_MODELS + 1], rs = 0.0, rv = 0.0, rpss = 0.0, rpvv = 0.0;
    int16_t best = 0;
    if (f == NULL || out == NULL) {
        return HSTPF_E_NULL;
    }
    if (f->magic != HSTPF_MAGIC) {
        return HSTPF_E_INIT;
    }
    memset(out, 0, sizeof *out);
    out->step = f->steps;
    out->time_s = f->time_s;
    out->n_models = f->cfg.n_models;
    hstpf__blend_weights(f, wb);
    for (l = 0; l < f->cfg.n_models; ++l) {
        const hstpf_model_t *m = &f->m[l];
        hstpf_model_out_t *o = &out->model[l];
        o->q = (real)exp(m->logq);
        o->position_m = f->origin_m + (double)m->s_mean;
        o->speed_mps = m->v_mean;
        o->ess = m->ess;
        o->loglik = m->loglik;
        o->floor_hits = m->floor_hits;
        o->reacquired = m->reacquired;
        s += wb[l] * (double)m->s_mean;
        v += wb[l] * (double)m->v_mean;
        if (m->logq > f->m[best].logq) {
            best = (int16_t)l;
        }
    }
    if (f->rf.active) {
        hstpf__refine_sv(f, &rs, &rv, &rpss, &rpvv);
        s += wb[f->cfg.n_models] * rs;
        v += wb[f->cfg.n_models] * rv;
    }
    /* the mixture's variance: within each model plus between the models */
    for (l = 0; l < f->cfg.n_models; ++l) {
        const hstpf_model_t *m = &f->m[l];
        const double ds = (double)m->s_mean - s, dv = (double)m->v_mean - v;
        vs += wb[l] * ((double)m->s_var + ds * ds);
        vv += wb[l] * ((double)m->v_var + dv * dv);
    }
    if (f->rf.active) {
        const double wr = wb[f->cfg.n_models], ds = rs - s, dv = rv - v;
        vs += wr * (rpss + ds * ds);
        vv += wr * (rpvv + dv * dv);
        out->q_offtable = (real)exp(f->rf.logq);
        out->gain = (real)f->rf.kz[5];
        out->gain_sd = (real)sqrt(f->rf.kp[HSTPF_REFINE_NZ * HSTPF_REFINE_NZ - 1]);
    } else {
        out->gain = 1;
    }
    theta_mixture(f, wb, th, cov);
    out->theta_cov[0] = (real)cov[0];
    out->theta_cov[1] = (real)cov[1];
    out->theta_cov[2] = (real)cov[2];
    out->theta_cov[3] = (real)cov[4];
    out->theta_cov[4] = (real)cov[5];
    out->theta_cov[5] = (real)cov[8];
    out->fit = (hstpf_fit_t)f->fit;
    out->off_what = f->fit == (uint8_t)HSTPF_FIT_NONE ? hstpf__off_what(f) : 0u;
    out->position_m = f->ever_locked ? f->origin_m + s : (f->have_pend ? f->pend_y : 0.0);
    out->speed_mps = (real)v;
    out->position_sd_m = sqrt(vs > 0.0 ? vs : 0.0);
    out->speed_sd_mps = (real)sqrt(vv > 0.0 ? vv : 0.0);
    out->theta[0] = (real)th[0];
    out->theta[1] = (real)th[1];
    out->theta[2] = (real)th[2];
    {
        const hstpf_theta_t t = {NULL, th[0], th[1], th[2]};
        out->resistance = (real)hstpf_resistance(&t, v);
    }
    out->standstill = f->standstill;
    out->traction_fault = (uint8_t)(f->tc.fault ? 1u : (f->tc.release ? 2u : 0u));
    out->best = best;
    out->declared = f->declared;
    out->status = f->status;
    out->decision_time_s = f->decision_time_s;
    out->outliers = f->outliers;
    out->reacquired = f->reacquired;
    out->fix_steps = f->fs.steps;
    out->acquisitions = f->acquisitions;
    out->backward = f->backward;
    out->nonfinite_resets = f->nonfinite_resets;
    /* a gated last fix: the fixes and the estimate disagree beyond the
     * gate (a reference jump, or a time base that stepped), so the estimate
     * is not to be trusted until they agree again or it re-acquires */
    out->valid = (uint8_t)(f->have_fix && !f->prior_lock && f->outlier_run == 0u && f->lost_run == 0u && !f->pr.active &&
                           in_ranges(out));
    return HSTPF_OK;
}
