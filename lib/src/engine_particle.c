/* Particle engine: a bootstrap particle filter per model (the paper's
 * Section 3.1), for any noise densities. Its model likelihoods are Monte
 * Carlo estimates. The paired bank (HSTPF_BANK_PAIRED) shares each step's
 * draws and one set of ancestors across the models. */
#include <math.h>

#include "dist_impl.h"
#include "engine.h"
#include "internal.h"
#include "rng_impl.h"
#include "track.h"

typedef hstpf_real_t real;

/* The paired bank's common draws and resampling. */
static int paired_bank(const hstpf_t *f)
{
    return f->cfg.bank == HSTPF_BANK_PAIRED;
}

/* Draws for a cloud: per particle, a measurement-noise sample into nz_s
 * and either a second one (two fixes) or a unit Gaussian (one fix with the
 * speed prior) into nz_v. */
static void draw_fix(hstpf_t *f, hstpf_rng_t *rng, int two)
{
    const hstpf_dist_quantiles_t *d2 = two ? &f->de.qt : &f->unit;
    uint16_t i;
    for (i = 0; i < f->cfg.n_particles; ++i) {
        f->nz_s[i] = hstpf__dist_sample(&f->de.qt, hstpf__rng_next(rng));
        f->nz_v[i] = hstpf__dist_sample(d2, hstpf__rng_next(rng));
    }
}

static real accel(hstpf_t *f, hstpf_model_t *m, real xu, real s, real v)
{
    real a = xu - m->k0 - (m->k1 + m->k2 * v) * v;
    if (f->cfg.n_track > 0u) {
        a -= hstpf__track_acc(f, &m->track_hint, s);
    }
    return a;
}

/* Weighted moments of the cloud from the normalised weights w (NULL:
 * equal weights). */
static void moments(hstpf_t *f, hstpf_model_t *m, const real *w)
{
    const uint16_t n = f->cfg.n_particles;
    real ms = 0, mv = 0, vs = 0, vv = 0, sw2 = 0;
    uint16_t i;
    for (i = 0; i < n; ++i) {
        const real wi = w != NULL ? w[i] : (real)1 / (real)n;
        ms += wi * m->s[i];
        mv += wi * m->v[i];
        sw2 += wi * wi;
    }
    for (i = 0; i < n; ++i) {
        const real wi = w != NULL ? w[i] : (real)1 / (real)n;
        const real ds = m->s[i] - ms, dv = m->v[i] - mv;
        vs += wi * ds * ds;
        vv += wi * dv * dv;
    }
    m->s_mean = (real)ms;
    m->v_mean = (real)mv;
    m->s_var = (real)vs;
    m->v_var = (real)vv;
    m->ess = (real)1 / sw2;
}

/* A cloud from the draws, equal weights. One fix: s = y2 - e_i, so that the
 * prior is the measurement's own posterior, v = v0 + init_speed_sd z_i. Two
 * fixes t12 apart: s = y2 - e2_i, and by the model's Euler step from
 * s1 = y1 - e1_i the speed v = (s - s1 - mu_s)/t12 + t12 a + mu_v, kept
 * >= 0 (the process noise over t12 is left out of the spread: it is small
 * beside the measurement noise's). */
static void place_cloud(hstpf_t *f, hstpf_model_t *m, const hstpf__acq_t *q)
{
    const hstpf_config_t *c = &f->cfg;
    const uint16_t n = c->n_particles;
    const real lw0 = (real)-log((double)n);
    const real y2 = (real)q->y2;
    uint16_t i;
    for (i = 0; i < n; ++i) {
        real v;
        m->s[i] = y2 - f->nz_s[i];
        if (q->t12 > 0.0) {
            const double sc = sqrt(q->t12 / c->dt_nominal_s);
            const real t = (real)q->t12;
            /* the noises' own means: a Gamma spec leaves its mean field 0 */
            const real v1 = ((real)(q->y2 - q->y1 - sc * f->noise_mom[0]) - f->nz_s[i] + f->nz_v[i]) / t;
            v = v1 + t * accel(f, m, (real)q->xu, m->s[i], v1 > (real)0 ? v1 : (real)0) +
                (real)(sc * f->noise_mom[2]);
        } else {
            v = (real)q->v0 + (real)c->init_speed_sd * f->nz_v[i];
        }
        m->v[i] = v > (real)0 ? v : (real)0;
        m->lw[i] = lw0;
    }
    m->held = 0;
    moments(f, m, NULL);
}

/* Every model from the acquisition fixes; the paired bank gives every model
 * the same draws. */
static void place_all(hstpf_t *f, const hstpf__acq_t *q)
{
    const int paired = paired_bank(f), two = q->t12 > 0.0;
    uint16_t l;
    if (paired) {
        draw_fix(f, &f->rng, two);
    }
    for (l = 0; l < f->cfg.n_models; ++l) {
        if (!paired) {
            draw_fix(f, &f->m[l].rng, two);
        }
        place_cloud(f, &f->m[l], q);
    }
}

/* One model that lost the train, from its own stream. */
static void place_one(hstpf_t *f, hstpf_model_t *m, const hstpf__acq_t *q)
{
    draw_fix(f, &m->rng, q->t12 > 0.0);
    place_cloud(f, m, q);
}

/* The cumulative count grows with c and is clamped to n; a particle of weight 0
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
            k = k > (int32_t)n ? (int32_t)n : k; /* >= prev: c only grows */
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
static void draw_noise(hstpf_t *f, hstpf_rng_t *rng, real scale, real acc_sd)
{
    uint16_t i;
    for (i = 0; i < f->cfg.n_particles; ++i) {
        f->nz_s[i] = scale * hstpf__dist_sample(&f->ds, hstpf__rng_next(rng));
        f->nz_v[i] = scale * hstpf__dist_sample(&f->dv, hstpf__rng_next(rng));
    }
    if (acc_sd > (real)0) { /* the traction unknown: a zero-mean Gaussian acceleration too */
        for (i = 0; i < f->cfg.n_particles; ++i) {
            f->nz_v[i] += acc_sd * hstpf__dist_sample(&f->unit, hstpf__rng_next(rng));
        }
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
        const real vn = m->v[i] + kv * f->nz_v[i];
        m->s[i] += ks * f->nz_s[i];
        m->v[i] = vn > (real)0 ? vn : (real)0; /* a train never reverses */
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
    real inc = 0, lmax = (real)-3e38;
    uint16_t i, at_floor = 0, held = 0;

    for (i = 0; i < n; ++i) {
        const real s = m->s[i], v = m->v[i];
        const real a = accel(f, m, xu, s, v);
        const real vd = v + dt * a;
        if (v <= (real)0 && a <= (real)0) {
            m->v[i] = 0; /* held at rest: no motion, no process noise */
            ++held;
        } else if (vd < (real)0) {
            m->s[i] = s + dt * v + f->nz_s[i];
            m->v[i] = 0; /* comes to rest within the step: no W in s' or v' */
            ++held;
        } else {
            const real vn = vd + f->nz_v[i];
            m->s[i] = s + dt * v + f->nz_s[i];
            m->v[i] = vn > (real)0 ? vn : (real)0; /* a train never reverses */
        }
        if (has_y) {
            const real l = hstpf__dist_logpdf(&f->de, yr - m->s[i]);
            at_floor = (uint16_t)(at_floor + (l <= f->de.floor));
            m->lw[i] += l;
        }
        lmax = m->lw[i] > lmax ? m->lw[i] : lmax;
    }
    m->held = (uint8_t)(held == n);
    if (has_y && at_floor == n) {
        ++m->floor_hits;
        ++m->floor_run;
    } else if (has_y) {
        m->floor_run = 0;
    }
    /* lw was normalised, so the log of the new sum is log sum W_i p(y|x_i) */
    inc = normalise(f, m, w, lmax);
    moments(f, m, w);
    if (!has_y) {
        inc = 0;
    } else if (f->cfg.weight_method == HSTPF_WEIGHT_PAPER) {
        inc = hstpf__dist_logpdf(&f->de, yr - m->s_mean);
    }
    m->loglik = inc;
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

static void predict_update(hstpf_t *f, const hstpf__step_t *st)
{
    const int paired = paired_bank(f);
    const real dt = (real)st->dt, yr = (real)st->yr, scale = (real)st->scale;
    const real thr = (real)f->cfg.ess_threshold * (real)f->cfg.n_particles, acc_sd = (real)sqrt(st->acc_var);
    uint16_t l;
    if (paired) {
        draw_noise(f, &f->rng, scale, acc_sd);
    }
    for (l = 0; l < f->cfg.n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        if (!paired) {
            draw_noise(f, &m->rng, scale, acc_sd);
        }
        model_update(f, m, dt, (real)hstpf__step_xu(f, m, st), st->has_y, yr, f->scratch);
        if (!paired && st->has_y && (f->cfg.resample == HSTPF_RESAMPLE_ALWAYS || m->ess < thr)) {
            resample_own(f, m, f->scratch);
        }
    }
}

/* The paired bank resamples on the mixture, which needs the new weights. */
static void after_weights(hstpf_t *f, const hstpf__step_t *st)
{
    const real thr = (real)f->cfg.ess_threshold * (real)f->cfg.n_particles;
    double ess_mix = 0.0;
    uint16_t l;
    if (!paired_bank(f)) {
        return;
    }
    for (l = 0; l < f->cfg.n_models; ++l) {
        ess_mix += exp(f->m[l].logq) * (double)f->m[l].ess;
    }
    if (st->has_y && (f->cfg.resample == HSTPF_RESAMPLE_ALWAYS || ess_mix < (double)thr)) {
        resample_paired(f);
    }
}

static void shift(hstpf_t *f, real d)
{
    uint16_t l, i;
    for (l = 0; l < f->cfg.n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        for (i = 0; i < f->cfg.n_particles; ++i) {
            m->s[i] -= d;
        }
        m->s_mean -= d;
    }
}

/* Each particle's position moved by a draw of N(0, var); the paired bank
 * moves every model's i-th particle by the same draw. */
static void spread(hstpf_t *f, double var)
{
    const real sd = (real)sqrt(var);
    const int paired = paired_bank(f);
    uint16_t l, i;
    if (paired) {
        draw_unit(f, &f->rng);
    }
    for (l = 0; l < f->cfg.n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        if (!paired) {
            draw_unit(f, &m->rng);
        }
        for (i = 0; i < f->cfg.n_particles; ++i) {
            m->s[i] += sd * f->nz_s[i];
        }
    }
}

static size_t ws_bytes(const hstpf_config_t *c)
{
    return HSTPF_PARTICLE_WS_BYTES(c->n_models, c->n_particles);
}

/* The layout HSTPF_PARTICLE_WS_BYTES counts: s, v, lw of each model, then
 * scratch, nz_s, nz_v and the counts. */
static void attach(hstpf_t *f, void *ws)
{
    const uint16_t n = f->cfg.n_particles;
    real *r = (real *)ws;
    uint16_t l;
    for (l = 0; l < f->cfg.n_models; ++l) {
        f->m[l].s = r;
        f->m[l].v = r + n;
        f->m[l].lw = r + 2 * n;
        r += 3 * n;
    }
    f->scratch = r;
    f->nz_s = r + n;
    f->nz_v = r + 2 * n;
    f->counts = (uint16_t *)(void *)(r + 3 * n);
}

const hstpf__engine_t hstpf__engine_particle = {place_all, place_one, predict_update, after_weights,
                                                 shift,     spread,    ws_bytes,       attach};

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
    if (hstpf__engine_of(f) != &hstpf__engine_particle) {
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
