/* A Gaussian filter's speed at a stop. Eq. 6 with the standstill rule
 * (docs/model.md) ends a step at rest exactly when v + T a < 0, and the
 * process noise moves only a train that still moves. With a Gaussian
 * prediction of y = v + T a that is a point mass P(y < 0) at v' = 0 and
 * the rest y + w_v: the filter keeps one Gaussian, matched to the two
 * together, until the point mass holds all but HSTPF__REST_EPS of it. The
 * old rule (at rest once the mean of y fell below 0, with no speed spread)
 * published 0 +- 0 m/s a step or two before the train stopped, at nearly
 * every stop. */
#include <math.h>

#include "engine.h"

#define ALPHA_MIN (-6.0) /* P(y < 0) below Phi(-6) = 1e-9: the plain Kalman step */

int hstpf__kalman_rest(double vd, double pyy, double mu_w, double q_w, hstpf__rest_t *out)
{
    double sd, alpha, pr, qm, phi, m1, m2, ev, ev2, eyv;
    if (!(pyy > 0.0)) {
        return vd < 0.0 ? HSTPF__REST_AT_REST : HSTPF__REST_MOVING;
    }
    sd = sqrt(pyy);
    alpha = -vd / sd;
    if (alpha < ALPHA_MIN) {
        return HSTPF__REST_MOVING;
    }
    qm = 0.5 * erfc(alpha / sqrt(2.0)); /* P(y >= 0) */
    pr = 1.0 - qm;
    if (pr >= 1.0 - HSTPF__REST_EPS) {
        return HSTPF__REST_AT_REST;
    }
    phi = exp(-0.5 * alpha * alpha) / sqrt(2.0 * 3.14159265358979323846);
    m1 = vd * qm + sd * phi;                  /* E[y; y >= 0] */
    m2 = (vd * vd + pyy) * qm + vd * sd * phi; /* E[y^2; y >= 0] */
    ev = m1 + qm * mu_w;                       /* v' = (y + w) 1{y >= 0} */
    ev2 = m2 + 2.0 * mu_w * m1 + qm * (q_w + mu_w * mu_w);
    eyv = m2 + mu_w * m1;
    out->p_rest = pr;
    out->v = ev;
    out->var = ev2 - ev * ev > 0.0 ? ev2 - ev * ev : 0.0;
    /* anything jointly Gaussian with y covaries with v' through y alone:
     * cov(x, v') = cov(x, y) cov(y, v') / var(y) */
    out->kappa = (eyv - vd * ev) / pyy;
    return HSTPF__REST_MIXED;
}

/* hstpf__kalman_rest with the timer (*rest_s, kept by the caller, 0 at
 * placing: engine.h) */
static int kalman_rest_timed(double vd, double pyy, double mu_w, double q_w, double dt, double *rest_s,
                             hstpf__rest_t *out)
{
    const int rest = hstpf__kalman_rest(vd, pyy, mu_w, q_w, out);
    if (rest != HSTPF__REST_MIXED || (out->p_rest < 0.5 && out->v * out->v > HSTPF__REST_SD2 * out->var)) {
        *rest_s = 0.0;
        return rest;
    }
    *rest_s += out->p_rest >= 0.5 ? dt : HSTPF__REST_SD_RATE * dt;
    if (*rest_s >= HSTPF__REST_SETTLE_S) {
        *rest_s = 0.0;
        return HSTPF__REST_AT_REST;
    }
    return rest;
}

uint8_t hstpf__kalman_rest_speed(double *x, double *p, int n, double vd, int free_run, double mu_w, double q_w,
                                 double acc_var, double dt, double *rest_s)
{
    hstpf__rest_t rs;
    /* with the traction unknown no model holds the train (bank.c) */
    const int rest = free_run ? (vd < 0.0 ? HSTPF__REST_AT_REST : HSTPF__REST_MOVING)
                              : kalman_rest_timed(vd, p[n + 1], mu_w, q_w, dt, rest_s, &rs);
    int i;
    if (rest == HSTPF__REST_AT_REST) { /* v' = 0 exactly, no speed spread */
        x[1] = 0.0;
        for (i = 0; i < n; ++i) {
            p[i * n + 1] = p[n + i] = 0.0;
        }
        return HSTPF__HELD_YES;
    }
    if (rest == HSTPF__REST_MIXED) {
        x[1] = rs.v;
        for (i = 0; i < n; ++i) {
            p[i * n + 1] = p[n + i] = rs.kappa * p[i * n + 1];
        }
        p[n + 1] = rs.var;
        return rs.p_rest >= HSTPF__REST_EPS ? HSTPF__HELD_STOPPING : HSTPF__HELD_NO;
    }
    x[1] = vd + mu_w;
    p[n + 1] += q_w + acc_var;
    return HSTPF__HELD_NO;
}
