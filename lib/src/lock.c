/* Lock on the train: acquisition from the first fixes (or a speed prior),
 * dropping and regaining it (an outage, a clock step, a run of gated
 * fixes, a non-finite state), a model that lost the train placed again,
 * and the origin that keeps float positions small (docs/model.md,
 * "Acquisition and lock"). */
#include <math.h>

#include "bank.h"
#include "dist_impl.h"
#include "engine.h"
#include "refine.h"
#include "track.h"

#define REBASE_M 1024.0 /* re-centre the float positions past this distance */
/* Two fixes closer than this carry no speed: the speed's variance 2R/t^2
 * would overflow (a step of 1e-309 s is in dt's documented range); the
 * later fix waits for the next instead. 1e-6 s: the shortest time the
 * configuration takes (dt_nominal_s, max_gap_s). */
#define ACQ_T12_MIN 1e-6

/* How far two fixes of a train at rest lie apart at most but in about 2 of
 * 1000 pairs: the fix noise's 2^-10 .. 1 - 2^-10 quantile range. */
static double fix_range(const hstpf_t *f)
{
    const int k = HSTPF_DIST_TAILN - 3; /* F^-1(2^(k - 32)) = F^-1(2^-10) */
    return hstpf__dist_range(&f->de.qt, k);
}

/* The fix noise's 2^-10 quantile: a fix of a train at s lies above s plus
 * this but in about 1 of 1000 (the noise's offset, a Gaussian's mean or a
 * Gamma's location, included). */
static double fix_lo(const hstpf_t *f)
{
    return (double)f->de.qt.tail_lo[HSTPF_DIST_TAILN - 3];
}

/* Lock from fixes: with a configured speed prior the first fix starts the
 * filter; otherwise, and whenever the lock is regained (the prior speaks of
 * the start: a train stopped at power-up may be at speed after an outage),
 * a fix waits for the next one (at most max_gap_s later, with a speed that
 * is physically possible) and both place the models. The model weights and
 * the declaration are kept. Returns 1 when locked now. */
int hstpf__acquire(hstpf_t *f, double y, double xu)
{
    hstpf__acq_t q;
    int behind = 0;
    q.xu = xu;
    q.v0 = f->cfg.init_speed_mps;
    q.t12 = 0.0;
    if (f->cfg.init_speed_sd <= 0.0 || f->ever_locked) {
        const double t = f->pend_age_s; /* >= this step's dt > 0: time advanced first */
        /* a train does not run backwards: a pair of fixes that credibly
         * does is a reference that falls in the direction of travel
         * (hstpf.h); a pair behind the furthest the estimate has been may
         * be a reference that restarted, or fixes that fall slowly: the
         * lock is taken on probation (hstpf__probation) */
        const int back = f->have_pend && y - f->pend_y < -fix_range(f);
        behind = f->have_pend && y - fix_lo(f) < f->top_m - fix_range(f);
        f->backward += (uint32_t)(back || behind);
        if (back || !f->have_pend || !(t <= f->cfg.max_gap_s) || !(t >= ACQ_T12_MIN) ||
            fabs(y - f->pend_y) > HSTPF_SPEED_MAX * t) {
            f->have_pend = 1;
            f->pend_y = y;
            f->pend_age_s = 0.0;
            return 0;
        }
        q.t12 = t;
    }
    f->origin_m = floor(y);
    hstpf__track_rebase(f);
    q.y1 = f->pend_y - f->origin_m;
    q.y2 = y - f->origin_m;
    if (f->rf.active && !f->rf.placed) {
        /* theta from the prior the first time, kept from what was learnt
         * afterwards; before the engine's placement, which places the
         * hypothesis' grid (if it has one) at that theta */
        hstpf__refine_place(f);
        f->rf.placed = 1;
    }
    hstpf__engine_of(f)->place_all(f, &q);
    if (f->rf.active) { /* (s, v) as the rows' filters have them */
        const hstpf_model_t *m0 = &f->m[0];
        hstpf__refine_replace_sv(f, m0->kx[0], m0->kx[1], m0->kp[0], m0->kp[1], m0->kp[2]);
    }
    f->have_pend = 0;
    /* a prior's lock keeps its fix: a gated next fix pairs with it */
    f->prior_lock = (uint8_t)(q.t12 == 0.0);
    f->pend_y = y;
    f->pend_age_s = 0.0;
    f->fix_age_s = 0.0;
    f->fix_gap_s = 0.0;
    f->have_fix = 1;
    f->ever_locked = 1;
    f->outlier_run = 0;
    ++f->acquisitions;
    f->pr.active = (uint8_t)behind;
    if (behind) {
        /* the furthest point is this lock's own from here: what the fix
         * allows, so that a drop before its first fitted fix keeps it */
        f->top_m = y - fix_lo(f);
        f->pr.based = 0;
        f->pr.no_timer = f->pr.timed;
    }
    return 1;
}

static void window_start(hstpf_probation_t *p, double t, double s)
{
    p->t0_s = t;
    p->top_m = s;
    p->sum[0] = p->sum[1] = p->sum[2] = p->sum[3] = p->sum[4] = 0.0;
}

/* The fall of the window's fixes over its span, from their least-squares
 * line (the noise's offset cancels); 0 with fewer than three. */
static double window_fall(const hstpf_probation_t *p, double span)
{
    const double n = p->sum[0];
    double stt;
    if (n < 3.0) {
        return 0.0;
    }
    stt = p->sum[3] - p->sum[1] * p->sum[1] / n;
    return stt > 0.0 ? -(p->sum[4] - p->sum[1] * p->sum[2] / n) / stt * span : 0.0;
}

/* After a locked step with a fix y (absolute m; s: the posterior), while
 * a lock taken behind the furthest point is on probation, or the last one
 * ended on its timer. The lock is a new reference once the train has come
 * forward two fix ranges W from the posterior at its first fix (fixes that
 * fall, however slowly, cannot take it there: the model has no reversal),
 * or after HSTPF_REF_PROBATION_S of time (not of steps with fixes) in
 * which the posterior has not fallen W / 2 behind its furthest and the
 * fixes' least-squares line has not fallen W / 4: at rest the model holds
 * the posterior still, so only the fixes tell a creep (0.12 m/s over 30 s
 * for the default noise, 2.5 sd of that line's fall). A fall restarts the
 * window. A creep slower than that ends one window; a lock taken behind
 * again before the train has come forward 2 W then ends only by coming
 * forward. Until it ends the estimate is not valid and the weights wait. */
void hstpf__probation(hstpf_t *f, double s, double y)
{
    hstpf_probation_t *p = &f->pr;
    const double w = fix_range(f);
    if (!p->active) { /* timed: has the train come forward since? */
        p->timed = (uint8_t)(s - p->end_m <= 2.0 * w);
        return;
    }
    if (!p->based) {
        p->based = 1;
        p->base_m = s;
        window_start(p, f->time_s, s);
    }
    if (s - p->base_m > 2.0 * w) {
        p->active = 0;
        p->timed = 0;
        return;
    }
    {
        const double t = f->time_s - p->t0_s, yr = y - p->base_m;
        p->sum[0] += 1.0;
        p->sum[1] += t;
        p->sum[2] += yr;
        p->sum[3] += t * t;
        p->sum[4] += t * yr;
    }
    p->top_m = s > p->top_m ? s : p->top_m;
    if (s < p->top_m - 0.5 * w) {
        window_start(p, f->time_s, s);
    } else if (!p->no_timer && f->time_s - p->t0_s >= HSTPF_REF_PROBATION_S) {
        if (window_fall(p, f->time_s - p->t0_s) > 0.25 * w) {
            window_start(p, f->time_s, s);
        } else {
            p->active = 0;
            p->timed = 1;
            p->end_m = s;
        }
    }
}

/* After a step on fix y: the posterior position s went back more than two
 * fix ranges behind the furthest point the train is known to have passed
 * (at rest the posterior averages many fixes, and the model never moves it
 * back), so the fixes run backwards: the lock is dropped (the estimate
 * goes invalid) until fixes come forward past that point again
 * (hstpf__acquire). The point is the posterior capped by what the fix
 * allows (y less the noise's 2^-10 quantile): a filter that ran ahead of
 * the train (braking the traction does not report) and lost it set a point
 * the train never reached, and the lost-run re-acquisition at the stop was
 * refused the whole stop (a review's harness: valid at 12 of 899 steps).
 * s, y: absolute m. Returns 1 when dropped. */
int hstpf__ran_backwards(hstpf_t *f, double s, double y)
{
    const double reach = y - fix_lo(f);
    if (f->lost_run > 0u) {
        return 0;
    }
    if (s >= f->top_m) {
        f->top_m = s < reach ? s : reach;
        return 0;
    }
    if (s >= f->top_m - 2.0 * fix_range(f)) {
        return 0;
    }
    ++f->backward;
    hstpf__drop_lock(f, 0);
    return 1;
}

/* Drops the lock; the next fixes acquire again. keep_pend: the last fix
 * (a gated one) belongs to the new time base and may pair with the next. */
void hstpf__drop_lock(hstpf_t *f, int keep_pend)
{
    f->have_fix = 0;
    f->prior_lock = 0;
    if (!keep_pend) {
        f->have_pend = 0;
    }
    f->standstill = 0;
    f->weights_wait = 0;
    f->arrival_s = 0.0;
    f->lost_run = 0;
    f->pr.active = 0;
    f->fs.pend = 0;
    f->fs.side = 2;
    f->fs.run_n = 0;
    f->tc.placed = 0; /* placed again at the new lock; a fault stands */
}

/* Keep float positions small: shift the origin by whole metres (rel: the
 * blended position from the origin). */
void hstpf__rebase(hstpf_t *f, double rel)
{
    real d;
    if (fabs(rel) < REBASE_M) {
        return;
    }
    d = (real)floor(rel);
    hstpf__engine_of(f)->shift(f, d);
    f->rf.kz[0] -= (double)d;
    f->rf.rest.s -= d;
    hstpf__trac_check_shift(f, (double)d);
    hstpf__fix_step_shift(f, d);
    f->origin_m += (double)d;
    hstpf__track_rebase(f);
}

/* A model whose every particle has been at the floor for
 * model_reacquire_after measurements has lost the train (its dynamics are
 * wrong, or the train changed): it is placed again at the fix, with the
 * blended speed, so that it can recover if it becomes right. Its weight is
 * kept. */
void hstpf__models_reacquire(hstpf_t *f, real yr)
{
    const hstpf__engine_t *e = hstpf__engine_of(f);
    double wb[HSTPF_MAX_MODELS + 1], vb = 0.0;
    uint16_t l;
    hstpf__blend_weights(f, wb);
    for (l = 0; l < f->cfg.n_models; ++l) {
        vb += wb[l] * (double)f->m[l].v_mean;
    }
    for (l = 0; l < f->cfg.n_models + hstpf__refine_on_grid(f); ++l) {
        hstpf_model_t *m = &f->m[l];
        if (m->floor_run >= f->cfg.model_reacquire_after) {
            hstpf__acq_t q;
            q.y1 = q.y2 = (double)yr;
            q.t12 = 0.0;
            q.xu = 0.0;
            q.v0 = vb;
            e->place_one(f, m, &q);
            m->floor_run = 0;
            ++m->reacquired;
        }
    }
}

int32_t hstpf_reacquire(hstpf_t *f)
{
    if (f == NULL) {
        return HSTPF_E_NULL;
    }
    if (f->magic != HSTPF_MAGIC) {
        return HSTPF_E_INIT;
    }
    hstpf__drop_lock(f, 0);
    f->top_m = -HUGE_VAL; /* the caller's word: the reference may have turned round */
    f->pr.timed = 0;
    return HSTPF_OK;
}

/* A filter that went non-finite starts again from the next fixes: uniform
 * weights if those are lost too. Counted in nonfinite_resets. */
void hstpf__nonfinite_reset(hstpf_t *f)
{
    uint16_t l;
    const uint16_t nh = hstpf__n_hyp(f);
    for (l = 0; l < nh; ++l) {
        if (!hstpf__fin(*hstpf__logq_of(f, l))) {
            for (l = 0; l < nh; ++l) {
                *hstpf__logq_of(f, l) = -log((double)nh);
            }
            break;
        }
    }
    f->rf.placed = 0; /* its theta too may be what went non-finite */
    hstpf__trac_check_snapshot(f); /* never back to weights that were not finite */
    ++f->nonfinite_resets;
    hstpf__drop_lock(f, 0);
}
