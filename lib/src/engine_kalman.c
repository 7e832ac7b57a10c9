/* Kalman engine: one extended Kalman filter per model on (s, v). With
 * Gaussian noise the model likelihood is exact up to the linearisation of
 * c2 V^2: no Monte Carlo noise (the Rao-Blackwellised limit of the particle
 * engine). */
#include <math.h>

#include "dist_impl.h"
#include "engine.h"
#include "track.h"

typedef hstpf_real_t real;

void hstpf__kalman_publish(const hstpf_t *f, hstpf_model_t *m)
{
    m->s_mean = (real)m->kx[0];
    m->v_mean = (real)m->kx[1];
    m->s_var = (real)m->kp[0];
    m->v_var = (real)m->kp[2];
    m->ess = (real)f->cfg.n_particles;
}

/* Net deterministic acceleration of a model at (s, v), m/s^2. */
static double accel(hstpf_t *f, hstpf_model_t *m, double xu, double s, double v)
{
    double a = xu - (double)m->k0 - ((double)m->k1 + (double)m->k2 * v) * v;
    if (f->cfg.n_track > 0u) {
        a -= (double)hstpf__track_acc(f, &m->track_hint, (real)s);
    }
    return a;
}

/* Two fixes, diffuse speed: s2 = y2 - e2, and with the model's Euler step
 * s2 = s1 + t v1 + w_s, v2 = v1 + t a + w_v, s1 = y1 - e1:
 *   v2 = (y2 - y1 - mu_s)/t + t a + mu_v + (e1 - e2 - w_s)/t + w_v,
 *   P = [R, R/t; R/t, (2R + Q_s)/t^2 + Q_v]. A single fix takes the
 * configured prior. The speed is then kept >= 0. */
void hstpf__kalman_place(hstpf_t *f, hstpf_model_t *m, const hstpf__acq_t *q)
{
    const hstpf_config_t *c = &f->cfg;
    const double *nm = f->noise_mom;
    const double r = nm[5] * nm[5];
    m->kx[0] = q->y2 - nm[4];
    m->kp[0] = r;
    if (q->t12 > 0.0) {
        const double t = q->t12, sc = sqrt(t / c->dt_nominal_s);
        const double qs = sc * sc * nm[1] * nm[1];
        const double qv = sc * sc * nm[3] * nm[3];
        const double v1 = (q->y2 - q->y1 - sc * nm[0]) / t;
        m->kx[1] = v1 + t * accel(f, m, q->xu, m->kx[0], v1 > 0.0 ? v1 : 0.0) + sc * nm[2];
        m->kp[1] = r / t;
        m->kp[2] = (2.0 * r + qs) / (t * t) + qv;
    } else {
        m->kx[1] = q->v0;
        m->kp[1] = 0.0;
        m->kp[2] = c->init_speed_sd * c->init_speed_sd;
    }
    m->kx[1] = m->kx[1] > 0.0 ? m->kx[1] : 0.0;
    memset(&m->rest, 0, sizeof m->rest);
}

static void place_one(hstpf_t *f, hstpf_model_t *m, const hstpf__acq_t *q)
{
    hstpf__kalman_place(f, m, q);
    m->held = 0;
    hstpf__kalman_publish(f, m);
}

static void place_all(hstpf_t *f, const hstpf__acq_t *a)
{
    uint16_t l;
    for (l = 0; l < f->cfg.n_models; ++l) {
        place_one(f, &f->m[l], a);
    }
}

/* One extended Kalman step of a model, with the same dynamics as the
 * particles (the clamp included, its Jacobian then 0). Noise moments are
 * scaled to the step as the particle draws are (mean by `scale`, variance
 * by scale^2). The log-likelihood is the Gaussian predictive density with
 * the particle engine's floor: at floor_depth nats below the peak it turns
 * into a slope of 1 nat per sd; beyond that point the innovation is clipped
 * for the update (Huber). */
double hstpf__kalman_step(hstpf_t *f, hstpf_model_t *m, const hstpf__step_t *st, uint8_t *held, int *floored)
{
    const double *nm = f->noise_mom;
    const double dt = st->dt, scale = st->scale;
    const double s = m->kx[0], v = m->kx[1];
    const double pss = m->kp[0], psv = m->kp[1], pvv = m->kp[2];
    const double sc2 = scale * scale;
    const double a = accel(f, m, hstpf__step_xu(f, m, st), s, v);
    const double vd = v + dt * a, fvv = 1.0 - dt * ((double)m->k1 + 2.0 * (double)m->k2 * v);
    double ns, nv, loglik = 0.0, qss, qsv, qvv, s_pred, p_pred;
    *held = (uint8_t)(v <= 0.0 && pvv <= 0.0 && a <= 0.0);
    *floored = 0;
    if (*held) {
        /* at rest and nothing can start it: no motion, no process noise */
        ns = s;
        nv = 0.0;
        qss = pss;
        qsv = 0.0;
        qvv = 0.0;
    } else {
        /* P = F P F' + Q with F = [1 dt; 0 fvv]; the speed from y = v + T a
         * by the one rule of kalman_rest.c (at rest within the step: s' =
         * s + dt v and v' = 0 do not involve W, so for the weights this is
         * standstill too; perhaps; or moving with its noise) */
        double x[2], p[4];
        ns = s + dt * v + scale * nm[0];
        qss = pss + 2.0 * dt * psv + dt * dt * pvv + sc2 * nm[1] * nm[1];
        x[0] = ns;
        x[1] = vd;
        p[0] = qss;
        p[1] = p[2] = fvv * (psv + dt * pvv);
        p[3] = fvv * fvv * pvv;
        *held = hstpf__kalman_rest_speed(x, p, 2, v, vd, st->free_run, scale * nm[2], sc2 * nm[3] * nm[3], st->acc_var, dt,
                                         &m->rest);
        nv = x[1];
        qsv = p[1];
        qvv = p[3];
    }
    s_pred = ns;
    p_pred = qss;
    if (st->has_y && hstpf__fix_exact(f)) {
        hstpf__fix_t fx;
        const double b = qss > 0.0 ? qsv / qss : 0.0; /* the speed's regression on the position */
        hstpf__kalman_fix(f, ns, qss, st->yr, &fx);
        loglik = fx.loglik;
        *floored = fx.floored;
        ns += fx.ds;
        nv += b * fx.ds;
        qvv -= b * b * (qss - fx.var);
        qvv = qvv > 0.0 ? qvv : 0.0;
        qsv = b * fx.var;
        qss = fx.var;
    } else if (st->has_y) {
        hstpf__fixm_t fm;
        double sy, z, sd, ks, kv;
        hstpf__fix_moments(f, ns, qss, st->yr, &fm);
        loglik = fm.loglik;
        *floored = fm.floored;
        sy = fm.sy;
        sd = fm.sd;
        z = fm.z;
        ks = qss / sy;
        kv = qsv / sy;
        ns += ks * z * sd;
        nv += kv * z * sd;
        /* Joseph-free form: P - K S K', kept symmetric */
        qvv -= kv * qsv;
        qsv -= ks * qsv;
        qss -= ks * qss;
        qvv = qvv > 0.0 ? qvv : 0.0;
        /* qss (1 - qss / sy) with qss <= sy: never below 0, even rounded */
    }
    if (st->has_y) {
        hstpf__kalman_rest_fix(&m->rest, p_pred, ns - s_pred, qss);
        hstpf__settle_fix(f, &m->rest, s_pred, p_pred, st->yr);
    }
    m->kx[0] = ns;
    m->kx[1] = nv > 0.0 ? nv : 0.0; /* a train never reverses */
    m->kp[0] = qss;
    m->kp[1] = qsv;
    m->kp[2] = qvv;
    return loglik;
}

static void update_model(hstpf_t *f, hstpf_model_t *m, const hstpf__step_t *st)
{
    int floored;
    const double ll = hstpf__kalman_step(f, m, st, &m->held, &floored);
    m->loglik = (real)ll;
    if (st->has_y) {
        if (floored) {
            ++m->floor_hits;
            ++m->floor_run;
        } else {
            m->floor_run = 0;
        }
    }
    hstpf__kalman_publish(f, m);
}

static void predict_update(hstpf_t *f, const hstpf__step_t *st)
{
    uint16_t l;
    for (l = 0; l < f->cfg.n_models; ++l) {
        update_model(f, &f->m[l], st);
    }
}

static void shift(hstpf_t *f, real d)
{
    uint16_t l;
    for (l = 0; l < f->cfg.n_models; ++l) {
        f->m[l].kx[0] -= (double)d;
        f->m[l].s_mean -= d;
        f->m[l].rest.s -= d; /* its timer's "stood still" too */
    }
}

/* The state is in hstpf_model_t: no workspace. */
static size_t ws_bytes(const hstpf_config_t *c)
{
    (void)c;
    return 0;
}

static void attach(hstpf_t *f, void *ws)
{
    (void)f;
    (void)ws;
}

const hstpf__engine_t hstpf__engine_kalman = {place_all, place_one, predict_update, NULL, shift, NULL, ws_bytes, attach};
