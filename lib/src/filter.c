/* The bank of particle filters and the model-weight update (paper Table 2). */
#include <math.h>
#include <string.h>

#include "dist_impl.h"
#include "hstpf/hstpf.h"
#include "internal.h"
#include "rng_impl.h"

#define HSTPF_MAGIC 0x48535446u /* "HSTF" */
#define G_ACC 9.81
#define REBASE_M 1024.0 /* re-centre the float positions past this distance */

typedef hstpf_real_t real;

static int fin(double x)
{
    return isfinite(x) ? 1 : 0;
}

int32_t hstpf_config_default(hstpf_config_t *cfg)
{
    if (cfg == NULL) {
        return HSTPF_E_NULL;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->n_particles = 100;
    cfg->seed = 1;
    cfg->engine = HSTPF_ENGINE_AUTO;
    cfg->bank = HSTPF_BANK_INDEPENDENT;
    cfg->gamma_rot = 0.06;
    cfg->noise_s.kind = HSTPF_DIST_GAUSSIAN;
    cfg->noise_s.sd = sqrt(0.02);
    cfg->noise_v.kind = HSTPF_DIST_GAUSSIAN;
    cfg->noise_v.sd = sqrt(0.05);
    cfg->noise_e.kind = HSTPF_DIST_GAUSSIAN;
    cfg->noise_e.sd = sqrt(5.0);
    cfg->dt_nominal_s = 1.0;
    cfg->init_speed_mps = 0.0;
    cfg->init_speed_sd = 1.0;
    cfg->resample = HSTPF_RESAMPLE_ESS;
    cfg->ess_threshold = 0.5;
    cfg->roughening_k = 0.2;
    cfg->weight_method = HSTPF_WEIGHT_MARGINAL;
    cfg->q_floor = 1e-9;
    cfg->declare_threshold = 0.99;
    cfg->declare_hold_s = 30.0;
    cfg->withdraw_threshold = 0.5;
    cfg->max_gap_s = 30.0;
    cfg->gate_m = 1000.0;
    cfg->reacquire_after = 5;
    return HSTPF_OK;
}

static int32_t check_theta(const hstpf_theta_t *t)
{
    if (!fin(t->c0) || !fin(t->c1) || !fin(t->c2)) {
        return HSTPF_E_NONFINITE;
    }
    if (t->c0 < 0.0 || t->c0 > 50.0 || t->c1 < 0.0 || t->c1 > 1.0 || t->c2 < 0.0 || t->c2 > 0.01) {
        return HSTPF_E_RANGE;
    }
    return HSTPF_OK;
}

static int all_gaussian(const hstpf_config_t *c)
{
    return c->noise_s.kind == HSTPF_DIST_GAUSSIAN && c->noise_v.kind == HSTPF_DIST_GAUSSIAN &&
           c->noise_e.kind == HSTPF_DIST_GAUSSIAN;
}

static int32_t check_config(const hstpf_config_t *c)
{
    const double nums[] = {c->e_blur_sd, c->gamma_rot, c->dt_nominal_s, c->init_speed_mps, c->init_speed_sd,
                           c->ess_threshold, c->roughening_k, c->rough_min_s, c->rough_min_v,
                           c->q_floor, c->declare_threshold, c->declare_hold_s, c->gate_m};
    uint32_t i;
    int32_t err;
    if (c->models == NULL || (c->n_track > 0u && c->track == NULL)) {
        return HSTPF_E_NULL;
    }
    if (c->n_models < 1u || c->n_models > HSTPF_MAX_MODELS || c->n_particles < 2u ||
        c->n_particles > HSTPF_MAX_PARTICLES || c->n_track > HSTPF_MAX_TRACK_SEGMENTS) {
        return HSTPF_E_SIZE;
    }
    for (i = 0; i < sizeof nums / sizeof nums[0]; ++i) {
        if (!fin(nums[i])) {
            return HSTPF_E_NONFINITE;
        }
    }
    for (i = 0; i < c->n_models; ++i) {
        err = check_theta(&c->models[i]);
        if (err != HSTPF_OK) {
            return err;
        }
    }
    if (c->gamma_rot < 0.0 || c->gamma_rot > 1.0 || fabs(c->init_speed_mps) > HSTPF_SPEED_MAX ||
        c->init_speed_sd < 0.0 || c->init_speed_sd > HSTPF_SPEED_MAX) {
        return HSTPF_E_RANGE;
    }
    if ((c->engine != HSTPF_ENGINE_PARTICLE && c->engine != HSTPF_ENGINE_KALMAN &&
         c->engine != HSTPF_ENGINE_AUTO) ||
        (c->engine == HSTPF_ENGINE_KALMAN && !all_gaussian(c)) ||
        (c->bank != HSTPF_BANK_INDEPENDENT && c->bank != HSTPF_BANK_PAIRED) || (c->resample != HSTPF_RESAMPLE_ALWAYS && c->resample != HSTPF_RESAMPLE_ESS) ||
        (c->weight_method != HSTPF_WEIGHT_MARGINAL && c->weight_method != HSTPF_WEIGHT_PAPER) ||
        !(c->ess_threshold > 0.0 && c->ess_threshold <= 1.0) || c->roughening_k < 0.0 ||
        c->roughening_k > 10.0 || c->rough_min_s < 0.0 || c->rough_min_v < 0.0 ||
        c->q_floor < 0.0 || c->q_floor * (double)c->n_models >= 1.0 ||
        !(c->declare_threshold > 0.5 && c->declare_threshold < 1.0) || c->declare_hold_s < 0.0 ||
        c->gate_m < 0.0 || !(c->dt_nominal_s > 0.0 && c->dt_nominal_s <= HSTPF_DT_MAX_S) ||
        c->e_blur_sd < 0.0 || (c->e_blur_sd > 0.0 && c->noise_e.kind == HSTPF_DIST_TABLE)) {
        return HSTPF_E_CONFIG;
    }
    for (i = 0; i < c->n_track; ++i) {
        const hstpf_track_seg_t *t = &c->track[i];
        if (!fin(t->start_m) || !fin(t->gradient_permille) || !fin(t->curve_radius_m)) {
            return HSTPF_E_NONFINITE;
        }
        if (fabs(t->start_m) > HSTPF_POS_MAX_M || fabs(t->gradient_permille) > 100.0 ||
            (t->curve_radius_m != 0.0 && t->curve_radius_m < 100.0) ||
            (i > 0u && !(t->start_m > c->track[i - 1u].start_m))) {
            return HSTPF_E_RANGE;
        }
    }
    err = hstpf__dist_check(&c->noise_s);
    if (err == HSTPF_OK) {
        err = hstpf__dist_check(&c->noise_v);
    }
    if (err == HSTPF_OK) {
        err = hstpf__dist_check(&c->noise_e);
    }
    return err;
}

int32_t hstpf_config_check(const hstpf_config_t *cfg, const char **field)
{
    int32_t err;
    if (field != NULL) {
        *field = "";
    }
    if (cfg == NULL) {
        return HSTPF_E_NULL;
    }
    err = check_config(cfg);
    if (err != HSTPF_OK && field != NULL) {
        *field = "config";
    }
    return err;
}

/* Track resistance in acceleration units (m/s^2) per segment, and segment
 * starts relative to the origin: recomputed when the origin moves. */
static void track_rebase(hstpf_t *f)
{
    uint16_t j;
    for (j = 0; j < f->cfg.n_track; ++j) {
        f->track_rel[j] = (real)(f->track[j].start_m - f->origin_m);
    }
}

static real track_acc(const hstpf_t *f, uint16_t *hint, real s)
{
    uint16_t j = *hint;
    const uint16_t n = f->cfg.n_track;
    while (j + 1u < n && s >= f->track_rel[j + 1u]) {
        ++j;
    }
    while (j > 0u && s < f->track_rel[j]) {
        --j;
    }
    *hint = j;
    return s < f->track_rel[0] ? (real)0 : f->track_acc[j];
}

static double seg_resistance(const hstpf_track_seg_t *t)
{
    return t->gradient_permille + (t->curve_radius_m > 0.0 ? 600.0 / t->curve_radius_m : 0.0);
}

static void reset_state(hstpf_t *f)
{
    uint16_t l;
    const double lq = -log((double)f->cfg.n_models);
    for (l = 0; l < f->cfg.n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        m->logq = lq;
        m->s_mean = m->v_mean = m->loglik = 0;
        m->ess = (real)f->cfg.n_particles;
        m->floor_hits = 0;
        m->floor_run = 0;
        m->track_hint = 0;
    }
    f->origin_m = 0.0;
    f->time_s = 0.0;
    f->held_s = 0.0;
    f->decision_time_s = -1.0;
    f->steps = 0;
    f->leader = -1;
    f->declared = -1;
    f->status = HSTPF_STATUS_UNDECIDED;
    f->have_fix = 0;
    f->outlier_run = 0;
}

int32_t hstpf_init(hstpf_t *f, size_t f_size, const hstpf_config_t *cfg)
{
    int32_t err;
    uint16_t l;
    if (f == NULL || cfg == NULL) {
        return HSTPF_E_NULL;
    }
    if (f_size != sizeof(hstpf_t)) {
        return HSTPF_E_ABI;
    }
    err = check_config(cfg);
    if (err != HSTPF_OK) {
        return err;
    }
    memset(f, 0, sizeof *f);
    f->cfg = *cfg;
    f->cfg.models = NULL; /* copied below: the caller's arrays need not live on */
    f->cfg.track = NULL;
    f->xi = G_ACC / (1.0 + cfg->gamma_rot) / 1000.0;
    f->kalman = (uint8_t)(cfg->engine == HSTPF_ENGINE_KALMAN ||
                          (cfg->engine == HSTPF_ENGINE_AUTO && all_gaussian(cfg)));
    for (l = 0; l < cfg->n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        f->theta[l] = cfg->models[l];
        /* a = xi u - k0 - k1 v - k2 v^2 with v in m/s */
        m->k0 = (real)(f->xi * cfg->models[l].c0);
        m->k1 = (real)(f->xi * cfg->models[l].c1 * 3.6);
        m->k2 = (real)(f->xi * cfg->models[l].c2 * 12.96);
        (void)hstpf_rng_seed(&m->rng, cfg->seed, l);
    }
    (void)hstpf_rng_seed(&f->rng, cfg->seed, HSTPF_MAX_MODELS);
    for (l = 0; l < cfg->n_track; ++l) {
        f->track[l] = cfg->track[l];
        f->track_acc[l] = (real)(f->xi * seg_resistance(&cfg->track[l]));
    }
    {
        hstpf_dist_spec_t unit;
        memset(&unit, 0, sizeof unit);
        unit.kind = HSTPF_DIST_GAUSSIAN;
        unit.sd = 1.0;
        /* specs were checked above, so these cannot fail */
        (void)hstpf_dist_init(&f->ds, &cfg->noise_s);
        (void)hstpf_dist_init(&f->dv, &cfg->noise_v);
        if (cfg->e_blur_sd > 0.0 && !f->kalman && cfg->noise_e.kind == HSTPF_DIST_GAUSSIAN) {
            /* a blurred Gaussian is a wider Gaussian (the first fix draws from it too) */
            hstpf_dist_spec_t e2 = cfg->noise_e;
            e2.sd = sqrt(e2.sd * e2.sd + cfg->e_blur_sd * cfg->e_blur_sd);
            (void)hstpf_dist_init(&f->de, &e2);
        } else {
            (void)hstpf_dist_init(&f->de, &cfg->noise_e);
            if (cfg->e_blur_sd > 0.0 && !f->kalman) {
                (void)hstpf__dist_blur(&f->de, &cfg->noise_e, cfg->e_blur_sd);
            }
        }
        (void)hstpf_dist_init(&f->unit, &unit);
    }
    reset_state(f);
    f->magic = HSTPF_MAGIC;
    return HSTPF_OK;
}

int32_t hstpf_reset(hstpf_t *f)
{
    if (f == NULL) {
        return HSTPF_E_NULL;
    }
    if (f->magic != HSTPF_MAGIC) {
        return HSTPF_E_INIT;
    }
    reset_state(f);
    return HSTPF_OK;
}

/* Draws for a cloud at a fix: measurement-noise samples into nz_s and unit
 * Gaussians into nz_v, interleaved per particle. */
static void draw_fix(hstpf_t *f, hstpf_rng_t *rng)
{
    uint16_t i;
    for (i = 0; i < f->cfg.n_particles; ++i) {
        f->nz_s[i] = hstpf__dist_sample(&f->de, hstpf__rng_next(rng));
        f->nz_v[i] = hstpf__dist_sample(&f->unit, hstpf__rng_next(rng));
    }
}

/* A cloud at the fix yr from the draws: s = yr - e_i, so that the prior is
 * the measurement's own posterior; v = v0 + init_speed_sd z_i; equal weights. */
static void place_cloud(hstpf_t *f, hstpf_model_t *m, real yr, real v0)
{
    const uint16_t n = f->cfg.n_particles;
    const real lw0 = (real)-log((double)n);
    double ss = 0.0, sv = 0.0;
    uint16_t i;
    if (f->kalman) {
        /* the same prior as the cloud's, as a Gaussian */
        const double sde = f->cfg.noise_e.sd, sdv = f->cfg.init_speed_sd;
        m->kx[0] = (double)yr - f->cfg.noise_e.mean;
        m->kx[1] = (double)v0;
        m->kp[0] = sde * sde;
        m->kp[1] = 0.0;
        m->kp[2] = sdv * sdv;
        m->s_mean = (real)m->kx[0];
        m->v_mean = (real)m->kx[1];
        m->ess = (real)n;
        return;
    }
    for (i = 0; i < n; ++i) {
        m->s[i] = yr - f->nz_s[i];
        m->v[i] = v0 + (real)f->cfg.init_speed_sd * f->nz_v[i];
        m->lw[i] = lw0;
        ss += (double)m->s[i];
        sv += (double)m->v[i];
    }
    m->s_mean = (real)(ss / n);
    m->v_mean = (real)(sv / n);
    m->ess = (real)n;
}

/* The paired bank's common draws and resampling: particles only. */
static int paired_bank(const hstpf_t *f)
{
    return !f->kalman && f->cfg.bank == HSTPF_BANK_PAIRED;
}

/* Particles from the first fix, with the speed prior. The paired bank gives
 * every model the same particles. */
static void first_fix(hstpf_t *f, double y)
{
    uint16_t l;
    const int paired = paired_bank(f);
    real yr;
    f->origin_m = floor(y);
    yr = (real)(y - f->origin_m);
    track_rebase(f);
    if (paired) {
        draw_fix(f, &f->rng);
    }
    for (l = 0; l < f->cfg.n_models; ++l) {
        if (!paired && !f->kalman) {
            draw_fix(f, &f->m[l].rng);
        }
        place_cloud(f, &f->m[l], yr, (real)f->cfg.init_speed_mps);
    }
    f->have_fix = 1;
}

/* A model whose every particle has been at the floor for
 * model_reacquire_after measurements has lost the train (its dynamics are
 * wrong, or the train changed): its particles are drawn again at the fix,
 * with the blended speed, so that it can recover if it becomes right. Its
 * weight is kept. */
static void model_reacquire(hstpf_t *f, hstpf_model_t *m, real yr, real v0)
{
    if (!f->kalman) {
        draw_fix(f, &m->rng);
    }
    place_cloud(f, m, yr, v0);
    m->floor_run = 0;
    ++m->reacquired;
}

/* The cumulative count is clamped to [previous, n]; a particle of weight 0
 * never gets a copy, and what round-off leaves of n at the end goes to the
 * last particle of positive weight, so nothing can index past the end. */
void hstpf__resample_counts(const real *w, uint16_t n, real u0, uint16_t *cnt)
{
    real c = 0;
    uint16_t i, prev = 0;
    int32_t last = -1;
    for (i = 0; i < n; ++i) {
        int32_t k = prev;
        if (w[i] > (real)0) {
            c += w[i];
            last = i;
            const real x = c * (real)n - u0; /* > -1 */
            k = (int32_t)x;                  /* ceil without libm: */
            k += (real)k < x ? 1 : 0;        /* a double call on an M4 */
            k = k < (int32_t)prev ? (int32_t)prev : (k > (int32_t)n ? (int32_t)n : k);
        }
        cnt[i] = (uint16_t)(k - (int32_t)prev);
        prev = (uint16_t)k;
    }
    if (last < 0) {
        for (i = 0; i < n; ++i) {
            cnt[i] = 1; /* no usable weight: keep every particle */
        }
    } else if (prev < n) {
        cnt[last] = (uint16_t)(cnt[last] + (n - prev));
    }
}

void hstpf__replicate(real *s, real *v, real *lw, const uint16_t *cnt, uint16_t n)
{
    uint16_t i, dead = 0;
    for (i = 0; i < n; ++i) {
        uint16_t extra = cnt[i] > 0u ? (uint16_t)(cnt[i] - 1u) : 0u;
        while (extra > 0u) {
            while (cnt[dead] != 0u) {
                ++dead;
            }
            s[dead] = s[i];
            v[dead] = v[i];
            if (lw != NULL) {
                lw[dead] = lw[i];
            }
            ++dead; /* a filled slot keeps count 0: never copied again */
            --extra;
        }
    }
}

/* This step's process noise into nz_s / nz_v, scaled to the step. */
static void draw_noise(hstpf_t *f, hstpf_rng_t *rng, real scale)
{
    uint16_t i;
    for (i = 0; i < f->cfg.n_particles; ++i) {
        f->nz_s[i] = scale * hstpf__dist_sample(&f->ds, hstpf__rng_next(rng));
        f->nz_v[i] = scale * hstpf__dist_sample(&f->dv, hstpf__rng_next(rng));
    }
}

/* Unit Gaussian draws for roughening, into nz_s / nz_v (free by then). */
static void draw_unit(hstpf_t *f, hstpf_rng_t *rng)
{
    uint16_t i;
    for (i = 0; i < f->cfg.n_particles; ++i) {
        f->nz_s[i] = hstpf__dist_sample(&f->unit, hstpf__rng_next(rng));
        f->nz_v[i] = hstpf__dist_sample(&f->unit, hstpf__rng_next(rng));
    }
}

static int roughening_on(const hstpf_t *f)
{
    return f->cfg.roughening_k > 0.0 || f->cfg.rough_min_s > 0.0 || f->cfg.rough_min_v > 0.0;
}

/* Roughening (Gordon et al. 1993): jitter of sd k * spread * n^(-1/2),
 * with the unit draws in nz_s / nz_v. */
static void roughen(hstpf_t *f, hstpf_model_t *m)
{
    const uint16_t n = f->cfg.n_particles;
    real smin = m->s[0], smax = m->s[0], vmin = m->v[0], vmax = m->v[0], ks, kv;
    const real k = (real)(f->cfg.roughening_k / sqrt((double)n));
    uint16_t i;
    for (i = 1; i < n; ++i) {
        smin = m->s[i] < smin ? m->s[i] : smin;
        smax = m->s[i] > smax ? m->s[i] : smax;
        vmin = m->v[i] < vmin ? m->v[i] : vmin;
        vmax = m->v[i] > vmax ? m->v[i] : vmax;
    }
    ks = k * (smax - smin);
    kv = k * (vmax - vmin);
    ks = ks > (real)f->cfg.rough_min_s ? ks : (real)f->cfg.rough_min_s;
    kv = kv > (real)f->cfg.rough_min_v ? kv : (real)f->cfg.rough_min_v;
    for (i = 0; i < n; ++i) {
        m->s[i] += ks * f->nz_s[i];
        m->v[i] += kv * f->nz_v[i];
    }
}

/* Normalises m->lw, whose maximum is lmax; the linear weights go to w.
 * Returns log of the sum before normalising (the likelihood increment when
 * lw held lw + l). */
static real normalise(const hstpf_t *f, hstpf_model_t *m, real *w, real lmax)
{
    const uint16_t n = f->cfg.n_particles;
    real sum = 0, lsum, inv;
    uint16_t i;
    for (i = 0; i < n; ++i) {
        w[i] = hstpf__exp_neg(m->lw[i] - lmax);
        sum += w[i];
    }
    /* sum >= 1: the best particle contributes exp(0) */
    lsum = lmax + (real)log((double)sum);
    inv = (real)1 / sum;
    for (i = 0; i < n; ++i) {
        m->lw[i] -= lsum;
        w[i] *= inv;
    }
    return lsum;
}

static real max_of(const real *x, uint16_t n)
{
    real mx = x[0];
    uint16_t i;
    for (i = 1; i < n; ++i) {
        mx = x[i] > mx ? x[i] : mx;
    }
    return mx;
}

/* One model: propagate with the drawn noise, weight by the measurement,
 * estimate. The log-likelihood increment goes to m->loglik (0 without a
 * measurement); the normalised weights are left in w. */
static void model_update(hstpf_t *f, hstpf_model_t *m, real dt, real xu, int has_y, real yr, real *w)
{
    const uint16_t n = f->cfg.n_particles;
    real sw2 = 0, ms = 0, mv = 0, inc = 0, lmax = (real)-3e38;
    uint16_t i, at_floor = 0;
    const int track = f->cfg.n_track > 0u;

    for (i = 0; i < n; ++i) {
        const real s = m->s[i], v = m->v[i];
        real a = xu - m->k0 - (m->k1 + m->k2 * v) * v, vd;
        if (track) {
            a -= track_acc(f, &m->track_hint, s);
        }
        vd = v + dt * a;
        if (v >= (real)0 && vd < (real)0) {
            vd = 0; /* resistance and braking cannot reverse the train */
        }
        m->s[i] = s + dt * v + f->nz_s[i];
        m->v[i] = vd + f->nz_v[i];
        if (has_y) {
            const real l = hstpf__dist_logpdf(&f->de, yr - m->s[i]);
            at_floor = (uint16_t)(at_floor + (l <= f->de.floor));
            m->lw[i] += l;
        }
        lmax = m->lw[i] > lmax ? m->lw[i] : lmax;
    }
    if (has_y && at_floor == n) {
        ++m->floor_hits;
        ++m->floor_run;
    } else if (has_y) {
        m->floor_run = 0;
    }
    /* lw was normalised, so the log of the new sum is log sum W_i p(y|x_i) */
    inc = normalise(f, m, w, lmax);
    for (i = 0; i < n; ++i) {
        sw2 += w[i] * w[i];
        ms += w[i] * m->s[i];
        mv += w[i] * m->v[i];
    }
    m->s_mean = ms;
    m->v_mean = mv;
    m->ess = (real)1 / sw2;
    if (!has_y) {
        inc = 0;
    } else if (f->cfg.weight_method == HSTPF_WEIGHT_PAPER) {
        inc = hstpf__dist_logpdf(&f->de, yr - ms);
    }
    m->loglik = inc;
}

/* Kalman engine: one extended Kalman step of a model, with the same
 * dynamics as the particles (the clamp included, its Jacobian then 0).
 * Noise moments are scaled to the step as the particle draws are (mean by
 * `scale`, variance by scale^2). The log-likelihood is the Gaussian
 * predictive density with the particle engine's floor: at floor_depth nats
 * below the peak it turns into a slope of 1 nat per sd; beyond that point
 * the innovation is clipped for the update (Huber). */
static void kalman_update(hstpf_t *f, hstpf_model_t *m, double dt, double xu, int has_y, double yr,
                          double scale)
{
    const hstpf_config_t *c = &f->cfg;
    const double s = m->kx[0], v = m->kx[1];
    const double pss = m->kp[0], psv = m->kp[1], pvv = m->kp[2];
    const double sc2 = scale * scale;
    double a = xu - (double)m->k0 - ((double)m->k1 + (double)m->k2 * v) * v, vd, fvv, ns, nv;
    double qss, qsv, qvv;
    if (c->n_track > 0u) {
        a -= (double)track_acc(f, &m->track_hint, (real)s);
    }
    vd = v + dt * a;
    fvv = 1.0 - dt * ((double)m->k1 + 2.0 * (double)m->k2 * v);
    if (v >= 0.0 && vd < 0.0) {
        vd = 0.0;
        fvv = 0.0;
    }
    ns = s + dt * v + scale * c->noise_s.mean;
    nv = vd + scale * c->noise_v.mean;
    /* P = F P F' + Q with F = [1 dt; 0 fvv] */
    qss = pss + 2.0 * dt * psv + dt * dt * pvv + sc2 * c->noise_s.sd * c->noise_s.sd;
    qsv = fvv * (psv + dt * pvv);
    qvv = fvv * fvv * pvv + sc2 * c->noise_v.sd * c->noise_v.sd;
    m->loglik = 0;
    if (has_y) {
        const double sy = qss + c->noise_e.sd * c->noise_e.sd;
        const double sd = sqrt(sy);
        const double depth = (double)(f->de.lp_max - f->de.floor);
        const double zf = sqrt(2.0 * depth);
        double z = (yr - c->noise_e.mean - ns) / sd, az = fabs(z), ll, ks, kv;
        if (az <= zf) {
            ll = -0.5 * z * z;
            m->floor_run = 0;
        } else {
            ll = -depth - ((az < 1e4 ? az : 1e4) - zf);
            z = z > 0.0 ? zf : -zf;
            ++m->floor_hits;
            ++m->floor_run;
        }
        m->loglik = (real)(ll - 0.5 * log(6.283185307179586 * sy));
        ks = qss / sy;
        kv = qsv / sy;
        ns += ks * z * sd;
        nv += kv * z * sd;
        /* Joseph-free form: P - K S K', kept symmetric */
        qvv -= kv * qsv;
        qsv -= ks * qsv;
        qss -= ks * qss;
        qvv = qvv > 0.0 ? qvv : 0.0;
        qss = qss > 0.0 ? qss : 0.0;
    }
    m->kx[0] = ns;
    m->kx[1] = nv;
    m->kp[0] = qss;
    m->kp[1] = qsv;
    m->kp[2] = qvv;
    m->s_mean = (real)ns;
    m->v_mean = (real)nv;
    m->ess = (real)c->n_particles;
}

/* Independent bank: each model resamples on its own weights and stream. */
static void resample_own(hstpf_t *f, hstpf_model_t *m, const real *w)
{
    const uint16_t n = f->cfg.n_particles;
    const real lw0 = (real)-log((double)n);
    uint16_t i;
    hstpf__resample_counts(w, n, hstpf__rng_uniform(&m->rng), f->counts);
    hstpf__replicate(m->s, m->v, NULL, f->counts, n);
    for (i = 0; i < n; ++i) {
        m->lw[i] = lw0;
    }
    if (roughening_on(f)) {
        draw_unit(f, &m->rng);
        roughen(f, m);
    }
}

/* Paired bank: one set of ancestors for all models, drawn from the
 * defensive mixture a; each model keeps the correction W_l / a. */
static void resample_paired(hstpf_t *f)
{
    const uint16_t n = f->cfg.n_particles, nm = f->cfg.n_models;
    real *a = f->scratch;
    uint16_t i, l;
    for (i = 0; i < n; ++i) {
        a[i] = 0;
    }
    for (l = 0; l < nm; ++l) {
        const hstpf_model_t *m = &f->m[l];
        const real mix = (real)(0.5 * exp(m->logq) + 0.5 / (double)nm);
        for (i = 0; i < n; ++i) {
            a[i] += mix * hstpf__exp_neg(m->lw[i]);
        }
    }
    hstpf__resample_counts(a, n, hstpf__rng_uniform(&f->rng), f->counts);
    for (i = 0; i < n; ++i) {
        a[i] = f->counts[i] > 0u ? hstpf__log_pos(a[i]) : (real)0; /* chosen => a > 0 */
    }
    for (l = 0; l < nm; ++l) {
        hstpf_model_t *m = &f->m[l];
        for (i = 0; i < n; ++i) {
            m->lw[i] -= a[i];
        }
        hstpf__replicate(m->s, m->v, m->lw, f->counts, n);
    }
    if (roughening_on(f)) {
        draw_unit(f, &f->rng);
    }
    for (l = 0; l < nm; ++l) {
        hstpf_model_t *m = &f->m[l];
        (void)normalise(f, m, a, max_of(m->lw, n));
        if (roughening_on(f)) {
            roughen(f, m);
        }
    }
}

static void update_model_weights(hstpf_t *f)
{
    const uint16_t nm = f->cfg.n_models;
    const double lfloor = f->cfg.q_floor > 0.0 ? log(f->cfg.q_floor) : -HUGE_VAL;
    double mx = -HUGE_VAL, sum = 0.0, lsum;
    uint16_t l;
    int pass;
    for (l = 0; l < nm; ++l) {
        f->m[l].logq += (double)f->m[l].loglik;
    }
    /* Eq. 14 by log-sum-exp; then the floor, and normalise again */
    for (pass = 0; pass < 2; ++pass) {
        mx = -HUGE_VAL;
        sum = 0.0;
        for (l = 0; l < nm; ++l) {
            mx = f->m[l].logq > mx ? f->m[l].logq : mx;
        }
        for (l = 0; l < nm; ++l) {
            sum += exp(f->m[l].logq - mx);
        }
        lsum = mx + log(sum);
        for (l = 0; l < nm; ++l) {
            f->m[l].logq -= lsum;
            if (pass == 0 && f->m[l].logq < lfloor) {
                f->m[l].logq = lfloor;
            }
        }
    }
}

static void update_declaration(hstpf_t *f, double dt)
{
    int16_t best = 0;
    uint16_t l;
    for (l = 1; l < f->cfg.n_models; ++l) {
        if (f->m[l].logq > f->m[best].logq) {
            best = (int16_t)l;
        }
    }
    if (exp(f->m[best].logq) > f->cfg.declare_threshold) {
        if (best == f->leader) {
            f->held_s += dt;
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
}

/* Weights for blended estimates: q_l less the floor, normalised. The floor
 * keeps a model able to recover; it must not let a model that lost the
 * train pull the estimates. */
static void blend_weights(const hstpf_t *f, double *wb)
{
    double sum = 0.0;
    uint16_t l;
    for (l = 0; l < f->cfg.n_models; ++l) {
        const double q = exp(f->m[l].logq) - f->cfg.q_floor;
        wb[l] = q > 0.0 ? q : 0.0;
        sum += wb[l];
    }
    for (l = 0; l < f->cfg.n_models; ++l) {
        wb[l] = sum > 0.0 ? wb[l] / sum : 1.0 / (double)f->cfg.n_models;
    }
}

static double blended_position(const hstpf_t *f, double dt_ahead)
{
    double s = 0.0, wb[HSTPF_MAX_MODELS];
    uint16_t l;
    blend_weights(f, wb);
    for (l = 0; l < f->cfg.n_models; ++l) {
        const hstpf_model_t *m = &f->m[l];
        s += wb[l] * ((double)m->s_mean + dt_ahead * (double)m->v_mean);
    }
    return s;
}

/* Keep float positions small: shift the origin by whole metres. */
static void rebase(hstpf_t *f)
{
    const double rel = blended_position(f, 0.0);
    real d;
    uint16_t l, i;
    if (fabs(rel) < REBASE_M) {
        return;
    }
    d = (real)floor(rel);
    for (l = 0; l < f->cfg.n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        for (i = 0; i < f->cfg.n_particles; ++i) {
            m->s[i] -= d;
        }
        m->s_mean -= d;
        m->kx[0] -= (double)d;
    }
    f->origin_m += (double)d;
    track_rebase(f);
}

int32_t hstpf_step(hstpf_t *f, const hstpf_input_t *in)
{
    const int has_y = (in != NULL && in->has_position) ? 1 : 0;
    real scale, yr = 0;
    uint16_t l;
    if (f == NULL || in == NULL) {
        return HSTPF_E_NULL;
    }
    if (f->magic != HSTPF_MAGIC) {
        return HSTPF_E_INIT;
    }
    if (!fin(in->dt_s) || !fin(in->traction) || (has_y && !fin(in->position_m))) {
        return HSTPF_E_NONFINITE;
    }
    if (!(in->dt_s > 0.0 && in->dt_s <= HSTPF_DT_MAX_S)) {
        return HSTPF_E_DT;
    }
    if (fabs(in->traction) > HSTPF_U_MAX || (has_y && fabs(in->position_m) > HSTPF_POS_MAX_M)) {
        return HSTPF_E_RANGE;
    }
    if (!f->have_fix) {
        if (has_y) {
            first_fix(f, in->position_m);
            update_declaration(f, in->dt_s);
        }
        f->time_s += in->dt_s;
        ++f->steps;
        return HSTPF_OK;
    }
    if (has_y && f->cfg.gate_m > 0.0 &&
        fabs(in->position_m - f->origin_m - blended_position(f, in->dt_s)) > f->cfg.gate_m) {
        if (f->cfg.reacquire_after == 0u || f->outlier_run < f->cfg.reacquire_after) {
            ++f->outliers;
            ++f->outlier_run;
            return HSTPF_E_OUTLIER;
        }
        /* the reference really moved: start the particles again there */
        f->outlier_run = 0;
        ++f->reacquired;
        first_fix(f, in->position_m);
        f->time_s += in->dt_s;
        ++f->steps;
        return HSTPF_OK;
    }
    if (has_y) {
        f->outlier_run = 0;
    }
    /* all checks passed: from here on the step cannot fail */
    scale = (real)sqrt(in->dt_s / f->cfg.dt_nominal_s);
    if (has_y) {
        yr = (real)(in->position_m - f->origin_m);
    }
    {
        const int paired = paired_bank(f);
        const real dt = (real)in->dt_s, xu = (real)(f->xi * in->traction);
        const real thr = (real)f->cfg.ess_threshold * (real)f->cfg.n_particles;
        double ess_mix = 0.0;
        if (paired) {
            draw_noise(f, &f->rng, scale);
        }
        for (l = 0; l < f->cfg.n_models; ++l) {
            hstpf_model_t *m = &f->m[l];
            if (f->kalman) {
                kalman_update(f, m, in->dt_s, f->xi * in->traction, has_y,
                              in->position_m - f->origin_m, (double)scale);
                continue;
            }
            if (!paired) {
                draw_noise(f, &m->rng, scale);
            }
            model_update(f, m, dt, xu, has_y, yr, f->scratch);
            if (!paired && has_y && (f->cfg.resample == HSTPF_RESAMPLE_ALWAYS || m->ess < thr)) {
                resample_own(f, m, f->scratch);
            }
        }
        if (has_y) {
            update_model_weights(f);
        }
        if (has_y && f->cfg.model_reacquire_after > 0u) {
            double wb[HSTPF_MAX_MODELS], vb = 0.0;
            blend_weights(f, wb);
            for (l = 0; l < f->cfg.n_models; ++l) {
                vb += wb[l] * (double)f->m[l].v_mean;
            }
            for (l = 0; l < f->cfg.n_models; ++l) {
                if (f->m[l].floor_run >= f->cfg.model_reacquire_after) {
                    model_reacquire(f, &f->m[l], yr, (real)vb);
                }
            }
        }
        for (l = 0; paired && l < f->cfg.n_models; ++l) {
            ess_mix += exp(f->m[l].logq) * (double)f->m[l].ess;
        }
        if (paired && has_y && (f->cfg.resample == HSTPF_RESAMPLE_ALWAYS || ess_mix < (double)thr)) {
            resample_paired(f);
        }
    }
    f->time_s += in->dt_s;
    ++f->steps;
    update_declaration(f, in->dt_s);
    rebase(f);
    return HSTPF_OK;
}

int32_t hstpf_estimate(const hstpf_t *f, hstpf_estimate_t *out)
{
    uint16_t l;
    double v = 0.0, th[3] = {0.0, 0.0, 0.0};
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
    double wb[HSTPF_MAX_MODELS];
    blend_weights(f, wb);
    for (l = 0; l < f->cfg.n_models; ++l) {
        const hstpf_model_t *m = &f->m[l];
        const double q = wb[l];
        hstpf_model_out_t *o = &out->model[l];
        o->q = (real)exp(m->logq);
        o->position_m = f->origin_m + (double)m->s_mean;
        o->speed_mps = m->v_mean;
        o->ess = m->ess;
        o->loglik = m->loglik;
        o->floor_hits = m->floor_hits;
        o->reacquired = m->reacquired;
        v += q * (double)m->v_mean;
        th[0] += q * f->theta[l].c0;
        th[1] += q * f->theta[l].c1;
        th[2] += q * f->theta[l].c2;
        if (m->logq > f->m[best].logq) {
            best = (int16_t)l;
        }
    }
    out->position_m = f->have_fix ? f->origin_m + blended_position(f, 0.0) : 0.0;
    out->speed_mps = (real)v;
    out->theta[0] = (real)th[0];
    out->theta[1] = (real)th[1];
    out->theta[2] = (real)th[2];
    {
        const hstpf_theta_t t = {NULL, th[0], th[1], th[2]};
        out->resistance = (real)hstpf_resistance(&t, v);
    }
    out->best = best;
    out->declared = f->declared;
    out->status = f->status;
    out->decision_time_s = f->decision_time_s;
    out->outliers = f->outliers;
    out->reacquired = f->reacquired;
    return HSTPF_OK;
}

int32_t hstpf_particles(const hstpf_t *f, uint16_t model, double *s, hstpf_real_t *v, hstpf_real_t *w)
{
    uint16_t i;
    if (f == NULL || s == NULL || v == NULL) {
        return HSTPF_E_NULL;
    }
    if (f->magic != HSTPF_MAGIC) {
        return HSTPF_E_INIT;
    }
    if (model >= f->cfg.n_models) {
        return HSTPF_E_SIZE;
    }
    if (f->kalman) {
        return HSTPF_E_CONFIG;
    }
    for (i = 0; i < f->cfg.n_particles; ++i) {
        s[i] = f->origin_m + (double)f->m[model].s[i];
        v[i] = f->m[model].v[i];
        if (w != NULL) {
            w[i] = hstpf__exp_neg(f->m[model].lw[i]);
        }
    }
    return HSTPF_OK;
}

int32_t hstpf_track_resistance(const hstpf_t *f, double pos_m, double *g_out)
{
    uint16_t j;
    double g = 0.0;
    if (f == NULL || g_out == NULL) {
        return HSTPF_E_NULL;
    }
    if (f->magic != HSTPF_MAGIC) {
        return HSTPF_E_INIT;
    }
    for (j = 0; j < f->cfg.n_track && pos_m >= f->track[j].start_m; ++j) {
        g = seg_resistance(&f->track[j]);
    }
    *g_out = g;
    return HSTPF_OK;
}
