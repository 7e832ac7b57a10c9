/* The continuous-theta hypothesis ("a train that is not on the table"): one
 * extended Kalman filter on z = (s, v, c0, c1, c2, k), k the gain of the
 * reported traction, with Table 1 as its prior. Given the speed the dynamics
 * are linear in (c0, c1, c2, k) (Eq. 6), so the augmented EKF is close to
 * the exact conjugate update; its predictive density is the hypothesis'
 * likelihood, compared in the bank with the rows' (docs/model.md,
 * "Trains that are not on Table 1"). On the Kalman engine the rows'
 * likelihoods are the same kind; on the grid engine the hypothesis is
 * scored through a yardstick (hstpf__refine_anchor). */
#include <math.h>
#include <string.h>

#include "dist_impl.h"
#include "internal.h"
#include "refine.h"
#include "track.h"

#define NZ HSTPF_REFINE_NZ

/* Prior of (c0, c1, c2): the moment-matched mixture of N(theta_l,
 * diag(rho theta_l)^2) over the configured rows (mean mu, covariance cov,
 * row-major 3x3). */
static void prior(const hstpf_t *f, double *mu, double *cov)
{
    const uint16_t n = f->cfg.n_models;
    const double rho = f->cfg.refine_spread;
    uint16_t l;
    int i, j;
    memset(cov, 0, sizeof(double) * 9);
    mu[0] = mu[1] = mu[2] = 0.0;
    for (l = 0; l < n; ++l) {
        const double th[3] = {f->theta[l].c0, f->theta[l].c1, f->theta[l].c2};
        for (i = 0; i < 3; ++i) {
            mu[i] += th[i] / n;
        }
    }
    for (l = 0; l < n; ++l) {
        const double th[3] = {f->theta[l].c0, f->theta[l].c1, f->theta[l].c2};
        for (i = 0; i < 3; ++i) {
            for (j = 0; j < 3; ++j) {
                cov[3 * i + j] += (th[i] - mu[i]) * (th[j] - mu[j]) / n;
            }
            cov[4 * i] += rho * rho * th[i] * th[i] / n;
        }
    }
}

void hstpf__refine_place(hstpf_t *f)
{
    hstpf_refine_t *r = &f->rf;
    double mu[3], cov[9];
    int i, j;
    prior(f, mu, cov);
    memset(r->kz, 0, sizeof r->kz);
    memset(r->kp, 0, sizeof r->kp);
    r->kz[2] = mu[0];
    r->kz[3] = mu[1];
    r->kz[4] = mu[2];
    r->kz[5] = 1.0;
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) {
            r->kp[(2 + i) * NZ + 2 + j] = cov[3 * i + j];
        }
    }
    r->kp[5 * NZ + 5] = f->cfg.refine_gain_sd * f->cfg.refine_gain_sd;
    r->held = 0;
    memset(&r->rest, 0, sizeof r->rest);
}

/* The consist may have changed (p) or not (1 - p): theta's moments under
 * that mixture of its posterior and Table 1's prior; s, v and k are the
 * train's, the same either way. The sum of the two components' covariances
 * stays positive semi-definite: (1 - p) P + p diag(P_sv, P0) + p (1 - p) d d'. */
void hstpf__refine_consist(hstpf_t *f, double p)
{
    hstpf_refine_t *r = &f->rf;
    double mu[3], cov[9], d[3];
    int i, j;
    prior(f, mu, cov);
    for (i = 0; i < 3; ++i) {
        d[i] = r->kz[2 + i] - mu[i];
    }
    for (i = 0; i < NZ; ++i) {
        for (j = 0; j < NZ; ++j) {
            const int ti = i >= 2 && i <= 4, tj = j >= 2 && j <= 4;
            double *pij = &r->kp[i * NZ + j];
            if (ti && tj) {
                *pij = (1.0 - p) * *pij + p * cov[3 * (i - 2) + (j - 2)] + p * (1.0 - p) * d[i - 2] * d[j - 2];
            } else if (ti || tj) {
                *pij *= 1.0 - p;
            }
        }
    }
    for (i = 0; i < 3; ++i) {
        r->kz[2 + i] -= p * d[i];
    }
}

/* Keep the place of a previous posterior of theta and k (a re-acquisition
 * keeps what was learnt about the train) and place only (s, v). */
void hstpf__refine_replace_sv(hstpf_t *f, double s, double v, double pss, double psv, double pvv)
{
    hstpf_refine_t *r = &f->rf;
    int i;
    for (i = 0; i < NZ; ++i) {
        r->kp[i] = r->kp[i * NZ] = 0.0;
        r->kp[NZ + i] = r->kp[i * NZ + 1] = 0.0;
    }
    r->kz[0] = s;
    r->kz[1] = v;
    r->kp[0] = pss;
    r->kp[1] = r->kp[NZ] = psv;
    r->kp[NZ + 1] = pvv;
    r->held = 0;
    memset(&r->rest, 0, sizeof r->rest);
}

/* P = F P F' + Q with F the identity but for rows 0 and 1, in place: only
 * rows and columns 0 and 1 change. Each of their entries is the mean of
 * (F P F')[i][j] and [j][i], which differ by rounding. */
static void propagate(double *p, const double *f0, const double *f1, double qs, double qv)
{
    double fp[2][NZ], b00 = 0.0, b01 = 0.0, b10 = 0.0, b11 = 0.0;
    int i, j;
    for (j = 0; j < NZ; ++j) { /* rows 0, 1 of F P */
        fp[0][j] = 0.0;
        fp[1][j] = 0.0;
        for (i = 0; i < NZ; ++i) {
            fp[0][j] += f0[i] * p[i * NZ + j];
            fp[1][j] += f1[i] * p[i * NZ + j];
        }
    }
    for (j = 0; j < NZ; ++j) {
        b00 += fp[0][j] * f0[j];
        b01 += fp[0][j] * f1[j];
        b10 += fp[1][j] * f0[j];
        b11 += fp[1][j] * f1[j];
    }
    for (i = 2; i < NZ; ++i) { /* (P F')[i][0, 1] from row i, read before it is written */
        double a = 0.0, b = 0.0;
        for (j = 0; j < NZ; ++j) {
            a += p[i * NZ + j] * f0[j];
            b += p[i * NZ + j] * f1[j];
        }
        p[i * NZ] = p[i] = 0.5 * (a + fp[0][i]);
        p[i * NZ + 1] = p[NZ + i] = 0.5 * (b + fp[1][i]);
    }
    p[0] = b00 + qs;
    p[1] = p[NZ] = 0.5 * (b10 + b01);
    p[NZ + 1] = b11 + qv;
}

void hstpf__refine_update(hstpf_t *f, const hstpf__step_t *st)
{
    const hstpf_config_t *c = &f->cfg;
    const double *nm = f->noise_mom;
    hstpf_refine_t *r = &f->rf;
    double *z = r->kz, *p = r->kp;
    const double dt = st->dt, sc2 = st->scale * st->scale, xi = f->xi;
    const double v = z[1], vk = 3.6 * v, c0 = z[2], c1 = z[3], c2 = z[4], k = z[5];
    double g = 0.0, a, vd, s_pred, p_pred;
    double f0[NZ] = {1.0, 0.0, 0.0, 0.0, 0.0, 0.0}, f1[NZ];
    int i;
    r->floored = 0;
    if (c->n_track > 0u) {
        g = (double)hstpf__track_acc(f, &r->track_hint, (hstpf_real_t)z[0]);
    }
    /* st->xu = xi u: the gain k scales the reported traction. With the
     * traction unknown the acceleration is 0 with st->acc_var on the speed, not a
     * function of theta: the step tells theta nothing but through what
     * the fix says of (s, v) */
    a = st->free_run ? 0.0 : k * st->xu - xi * (c0 + c1 * vk + c2 * vk * vk) - g;
    vd = v + dt * a;
    f0[1] = dt;
    /* the traction unknown: v' = v + noise, theta out of it (acc_var 0 otherwise) */
    f1[0] = 0.0;
    f1[1] = st->free_run ? 1.0 : 1.0 - dt * xi * 3.6 * (c1 + 2.0 * c2 * vk);
    f1[2] = st->free_run ? 0.0 : -dt * xi;
    f1[3] = st->free_run ? 0.0 : -dt * xi * vk;
    f1[4] = st->free_run ? 0.0 : -dt * xi * vk * vk;
    f1[5] = st->free_run ? 0.0 : dt * st->xu;
    r->held = (uint8_t)(!st->free_run && v <= 0.0 && p[NZ + 1] <= 0.0 && a <= 0.0);
    if (!r->held) {
        /* the step without the speed noise: y = v + T a, its variance in
         * p[NZ + 1]; then the speed (kalman_rest.c: at rest, perhaps, or
         * moving with its noise) */
        z[0] += dt * v + st->scale * nm[0];
        propagate(p, f0, f1, sc2 * nm[1] * nm[1], 0.0);
        r->held = hstpf__kalman_rest_speed(z, p, NZ, v, vd, st->free_run, st->scale * nm[2], sc2 * nm[3] * nm[3],
                                           st->acc_var, dt, &r->rest);
    }
    r->loglik = 0.0;
    s_pred = z[0];
    p_pred = p[0];
    if (st->has_y && hstpf__fix_exact(f)) {
        hstpf__fix_t fx;
        double rg[NZ], shrink;
        const double zf = sqrt(2.0 * (double)(f->de.lp_max - f->de.floor));
        double zz = (st->yr - nm[4] - z[0]) / sqrt(p[0] + nm[5] * nm[5]);
        int j;
        zz = zz > zf ? zf : (zz < -zf ? -zf : zz);
        hstpf__kalman_fix(f, z[0], p[0], st->yr, &fx);
        r->loglik = fx.loglik;
        r->floored = (uint8_t)fx.floored;
        r->nis = 0.98 * r->nis + 0.02 * zz * zz; /* on the moments, as below */
        shrink = p[0] - fx.var;
        for (i = 0; i < NZ; ++i) { /* each component's regression on the position */
            rg[i] = p[0] > 0.0 ? p[i * NZ] / p[0] : 0.0;
        }
        for (i = 0; i < NZ; ++i) {
            z[i] += rg[i] * fx.ds;
        }
        for (i = 0; i < NZ; ++i) {
            for (j = 0; j < NZ; ++j) {
                p[i * NZ + j] -= rg[i] * rg[j] * shrink;
            }
        }
        for (i = 0; i < NZ; ++i) {
            p[i * NZ + i] = p[i * NZ + i] > 0.0 ? p[i * NZ + i] : 0.0;
        }
    } else if (st->has_y) {
        hstpf__fixm_t fm;
        double sy, zz, sd, gain[NZ];
        int j;
        hstpf__fix_moments(f, z[0], p[0], st->yr, &fm);
        r->loglik = fm.loglik;
        r->floored = (uint8_t)(r->floored || fm.floored);
        sy = fm.sy;
        sd = fm.sd;
        zz = fm.z; /* clipped: Huber */
        r->nis = 0.98 * r->nis + 0.02 * zz * zz;
        for (i = 0; i < NZ; ++i) {
            gain[i] = p[i * NZ] / sy;
        }
        for (i = 0; i < NZ; ++i) {
            z[i] += gain[i] * zz * sd;
        }
        for (i = 0; i < NZ; ++i) {
            for (j = 0; j < NZ; ++j) {
                p[i * NZ + j] -= gain[i] * gain[j] * sy;
            }
        }
        for (i = 0; i < NZ; ++i) {
            p[i * NZ + i] = p[i * NZ + i] > 0.0 ? p[i * NZ + i] : 0.0;
        }
    }
    if (st->has_y) {
        r->rest.zp = 0; /* its z only across steps without a fix (kalman_rest.c) */
        hstpf__settle_fix(f, &r->rest, s_pred, p_pred, st->yr);
    }
    z[1] = z[1] > 0.0 ? z[1] : 0.0; /* a train never reverses */
    if (z[1] == 0.0 && r->held) {
        for (i = 0; i < NZ; ++i) {
            p[NZ + i] = p[i * NZ + 1] = 0.0;
        }
    }
}

/* The hypothesis' likelihood is Gaussian: on the grid engine the rows'
 * are exact, and comparing the two would score the noise model, not the
 * train. So each row also runs as the Kalman engine's filter on the
 * noise's moments (m->kx, m->kp; the grid engine steps, places and shifts
 * them with its cells), and
 * the hypothesis is scored against the leading row l in that one currency:
 * its increment is l's exact increment plus log(p_gauss(hypothesis) /
 * p_gauss(l)). With the truth on row l the ratio is the Gaussian's Occam
 * cost, off every row it is the evidence for being off. */
void hstpf__refine_anchor(hstpf_t *f, const hstpf__step_t *st)
{
    const hstpf_model_t *m = &f->m[hstpf__leading_row(f)];
    hstpf_refine_t *r = &f->rf;
    if (hstpf__kalman_lost(m, r->kz[0], r->kz[1], r->kp[0], r->kp[NZ + 1])) {
        /* the EKF lost the train (engine.h): (s, v) placed again at the
         * leading row's, theta kept, with its flags; this step tells
         * nothing of the hypothesis: the leading row's increment */
        hstpf__refine_replace_sv(f, (double)m->s_mean, (double)m->v_mean, (double)m->s_var, 0.0, (double)m->v_var);
        r->held = m->held;
        r->floored = (uint8_t)(m->floor_run > 0u); /* read only with a fix */
        r->loglik = (double)m->loglik; /* 0 without a fix */
    } else if (st->has_y && !m->k_placed) { /* the grid engine stepped the rows' filters: m->kll */
        r->loglik += (double)m->loglik - m->kll;
    } /* the leader's yardstick placed again: the EKF's own increment, against the leader's exact one */
}

/* theta's error is the same at every step, not drawn afresh: as a fresh
 * speed noise per step it counts for about this many steps' worth of sd
 * (paper Case 2 seeds 1-100 and off15-case2 seeds 1-3 per truth, factor
 * 0.5 / 1 / 2 / 4 / 8: a type declared in 25 / 16 / 12 / 18 / 45 % of the
 * off-table runs, paper Case 2's p90 170 / 173 / 168 / 166 / 163 s and
 * slowest 396 / 396 / 203 / 193 / 186 s; checked on other seeds,
 * docs/results.md) */
#define THETA_PERSIST 2.0

/* The grid then predicts with theta's mean, and its speeds spread by the
 * acceleration's sd under theta's covariance, so that it scores the
 * hypothesis (theta unknown within its posterior) rather than one plug-in
 * theta: early on, with theta still the prior's, the rows are not all
 * better by far; and under a one-sided w_v (Case 2) the grid can still
 * slow down more than its mean says (an unmodelled climb), which no row
 * can. The gain k (fixed at 1 by default) scales the traction in the EKF
 * only. */
void hstpf__refine_grid_theta(hstpf_t *f)
{
    const double *z = f->rf.kz;
    hstpf__model_set_theta(f, &f->m[f->cfg.n_models], z[2] > 0.0 ? z[2] : 0.0, z[3] > 0.0 ? z[3] : 0.0,
                           z[4] > 0.0 ? z[4] : 0.0);
}

double hstpf__refine_theta_sd(const hstpf_t *f, const hstpf__step_t *st)
{
    const double *p = f->rf.kp;
    const double vk = 3.6 * (double)f->m[f->cfg.n_models].v_mean;
    double g[4], var = 0.0;
    int i, j;
    /* a = k xu - xi (c0 + c1 V + c2 V^2) - g: its gradient in (c0, c1, c2, k) */
    g[0] = -f->xi;
    g[1] = -f->xi * vk;
    g[2] = -f->xi * vk * vk;
    g[3] = st->free_run ? 0.0 : st->xu; /* no reported traction for k to scale */
    for (i = 0; i < 4; ++i) {
        for (j = 0; j < 4; ++j) {
            var += g[i] * g[j] * p[(2 + i) * NZ + 2 + j];
        }
    }
    return var > 0.0 ? THETA_PERSIST * st->dt * sqrt(var) : 0.0;
}

void hstpf__refine_from_grid(hstpf_t *f, const hstpf__step_t *st)
{
    const hstpf_model_t *mh = &f->m[f->cfg.n_models];
    f->rf.loglik = (double)mh->loglik;
    f->rf.floored = (uint8_t)(st->has_y && mh->floor_run > 0u);
    f->rf.held = mh->held;
}

void hstpf__refine_sv(const hstpf_t *f, double *s, double *v, double *pss, double *pvv)
{
    if (hstpf__refine_on_grid(f)) {
        const hstpf_model_t *m = &f->m[f->cfg.n_models];
        *s = (double)m->s_mean;
        *v = (double)m->v_mean;
        *pss = (double)m->s_var;
        *pvv = (double)m->v_var;
    } else {
        *s = f->rf.kz[0];
        *v = f->rf.kz[1];
        *pss = f->rf.kp[0];
        *pvv = f->rf.kp[NZ + 1];
    }
}

void hstpf__refine_theta(const hstpf_t *f, double *th, double *cov)
{
    const hstpf_refine_t *r = &f->rf;
    int i, j;
    for (i = 0; i < 3; ++i) {
        th[i] = r->kz[2 + i] > 0.0 ? r->kz[2 + i] : 0.0;
        for (j = 0; j < 3; ++j) {
            cov[3 * i + j] = r->kp[(2 + i) * NZ + 2 + j];
        }
    }
}
