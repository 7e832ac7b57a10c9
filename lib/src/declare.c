/* The declaration state machine of hstpf.h (Table 2, State A(2)) and the
 * "no table type fits" status of the continuous hypothesis. */
#include <math.h>

#include "bank.h"
#include "refine.h"

/* What is off when no row fits, from the continuous hypothesis against the
 * nearest row in W(v) over 0-350 km/h: a gain k credibly away from 1; a
 * difference that is mostly constant in v (c0-like: gradient, offset); or
 * the coefficients in general. */
uint8_t hstpf__off_what(const hstpf_t *f)
{
    const hstpf_refine_t *r = &f->rf;
    double th[3], cov[9], best = HUGE_VAL, d0 = 0.0, dall = 0.0;
    uint16_t l, lb = 0;
    int k;
    uint8_t bits = 0;
    hstpf__refine_theta(f, th, cov);
    for (l = 0; l < f->cfg.n_models; ++l) {
        double e = 0.0;
        for (k = 0; k <= 7; ++k) {
            const double v = 50.0 * k;
            const double d = (th[0] - f->theta[l].c0) + (th[1] - f->theta[l].c1) * v +
                             (th[2] - f->theta[l].c2) * v * v;
            e += d * d;
        }
        if (e < best) {
            best = e;
            lb = l;
        }
    }
    for (k = 0; k <= 7; ++k) {
        const double v = 50.0 * k;
        const double dc0 = th[0] - f->theta[lb].c0;
        const double d = dc0 + (th[1] - f->theta[lb].c1) * v + (th[2] - f->theta[lb].c2) * v * v;
        d0 += (d - dc0) * (d - dc0); /* what is left once the c0 offset is removed */
        dall += d * d;
    }
    if (fabs(r->kz[5] - 1.0) > 3.0 * sqrt(r->kp[HSTPF_REFINE_NZ * HSTPF_REFINE_NZ - 1])) {
        bits |= HSTPF_OFF_GAIN;
    }
    if (d0 < 0.25 * dall) { /* dall = 0 makes d0 = 0: COEF */
        bits |= HSTPF_OFF_C0;
    } else {
        bits |= HSTPF_OFF_COEF;
    }
    if (r->nis > 3.0) {
        bits |= HSTPF_OFF_INNOV;
    }
    return bits;
}

/* "No table type fits": the continuous hypothesis held above
 * declare_threshold as long as a declaration needs; it ends when its weight
 * falls below withdraw_threshold. */
static void update_fit(hstpf_t *f, double dt, int evidence)
{
    if (!f->rf.active) {
        f->fit = (uint8_t)(f->declared >= 0 ? HSTPF_FIT_TABLE : HSTPF_FIT_UNKNOWN);
        return;
    }
    if (exp(f->rf.logq) > f->cfg.declare_threshold) {
        f->fit_held_s += evidence ? dt : 0.0;
    } else {
        f->fit_held_s = 0.0;
    }
    if (f->fit_held_s >= f->cfg.declare_hold_s && f->fit_held_s > 0.0) {
        f->fit = HSTPF_FIT_NONE;
    } else if (f->fit == HSTPF_FIT_NONE && exp(f->rf.logq) >= f->cfg.withdraw_threshold) {
        /* stays until the weight says otherwise */
    } else {
        f->fit = (uint8_t)(f->declared >= 0 ? HSTPF_FIT_TABLE : HSTPF_FIT_UNKNOWN);
    }
}

/* The declaration state machine of hstpf.h. The hold timer runs only on
 * steps that carry evidence: not at standstill, not without a fix. */
void hstpf__update_declaration(hstpf_t *f, double dt, int evidence)
{
    const int16_t best = (int16_t)hstpf__leading_row(f);
    if (f->declared >= 0 && exp(f->m[f->declared].logq) < f->cfg.withdraw_threshold) {
        f->declared = -1;
        f->status = HSTPF_STATUS_WITHDRAWN;
        f->decision_time_s = -1.0;
    }
    if (exp(f->m[best].logq) > f->cfg.declare_threshold) {
        if (best == f->leader) {
            f->held_s += evidence ? dt : 0.0;
        } else {
            f->leader = best;
            f->held_s = 0.0;
        }
    } else {
        f->leader = -1;
        f->held_s = 0.0;
    }
    if (f->leader >= 0 && f->held_s >= f->cfg.declare_hold_s && f->leader != f->declared) {
        f->status = f->declared < 0 ? HSTPF_STATUS_DECLARED : HSTPF_STATUS_CHANGED;
        f->declared = f->leader;
        f->decision_time_s = f->time_s;
    }
    update_fit(f, dt, evidence);
}
