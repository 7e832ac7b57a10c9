/* The traction unknown (hstpf_input_t.traction_unknown, or a traction
 * the check took for wrong): what each model is given instead, its own
 * balance, and the unknown acceleration's variance on the speed. */
#include "bank.h"
#include "refine.h"
#include "track.h"

/* What balances model m's resistance at speed v and the track's force at
 * its mean position, m/s^2 (a held bank's grade too: a hair is added by
 * the callers, HSTPF__FREE_HAIR). */
static double balance(const hstpf_t *f, const hstpf_model_t *m, double v, uint16_t *hint)
{
    const double g = f->have_fix && f->cfg.n_track > 0u ? (double)hstpf__track_acc(f, hint, m->s_mean) : 0.0;
    return (double)m->k0 + ((double)m->k1 + (double)m->k2 * v) * v + g;
}

/* xi u (m/s^2) for an acquisition whose traction is unknown: what
 * balances the largest resistance among the models at speed v (each
 * model's own when v < 0), plus the hair. Over the pair's second or so the
 * models' spread in W is small against the pair's speed variance; a
 * step's own is hstpf__step_xu's. */
double hstpf__free_xu(const hstpf_t *f, double v)
{
    double xu = -HUGE_VAL;
    uint16_t l, hint = 0;
    for (l = 0; l < f->cfg.n_models + (uint16_t)hstpf__refine_on_grid(f); ++l) {
        const hstpf_model_t *m = &f->m[l];
        const double vl = v >= 0.0 ? v : ((double)m->v_mean > 0.0 ? (double)m->v_mean : 0.0);
        const double w = balance(f, m, vl, &hint);
        xu = w > xu ? w : xu;
    }
    return xu + HSTPF__FREE_HAIR;
}

double hstpf__step_xu(const hstpf_t *f, const hstpf_model_t *m, const hstpf__step_t *st)
{
    uint16_t hint = 0;
    double v;
    if (!st->free_run) {
        return st->xu;
    }
    /* within the speed range (NaN to 0): a model gone far out gave an
     * infinite balance, and its grid a non-finite box (the fuzz harness) */
    v = (double)m->v_mean > 0.0 ? ((double)m->v_mean < HSTPF_SPEED_MAX ? (double)m->v_mean : HSTPF_SPEED_MAX) : 0.0;
    return balance(f, m, v, &hint) + HSTPF__FREE_HAIR;
}

double hstpf__acc_tau(const hstpf_t *f)
{
    return f->cfg.dt_nominal_s > HSTPF__ACC_PERSIST_S ? f->cfg.dt_nominal_s : HSTPF__ACC_PERSIST_S;
}

double hstpf__free_acc_var(hstpf_t *f, double dt, int has_y)
{
    /* the unknown acceleration as a zero-mean Gaussian on the speed, a
     * random walk like the noises (variance in proportion to T): sd
     * accel_unknown_sd tau over a step of tau (hstpf__acc_tau); the
     * configured noises keep their shape and mean. Across steps without a
     * fix it persists (a brake or a traction is held for tens of seconds,
     * not redrawn each step): over a span t without one its variance on
     * the speed is accel_unknown_sd^2 t max(t, tau), the random walk's up
     * to tau and (sd t)^2 beyond. The random walk alone made a minute
     * without any input at 300 km/h, the train braking in it, 13-23 m/s
     * off at 3-6 sd (hstpf-mc --scenario silent) */
    const double a2 = f->cfg.accel_unknown_sd * f->cfg.accel_unknown_sd, tau = hstpf__acc_tau(f);
    /* no longer than it takes the acceleration to span the speed range:
     * beyond, the spread grew without bound and the grid's box went
     * non-finite (the fuzz harness, a NaN cast in grid_box.c) */
    const double t_max = HSTPF_SPEED_MAX / f->cfg.accel_unknown_sd;
    const double u = f->free_s < t_max ? f->free_s : t_max, w = u + dt < t_max ? u + dt : t_max;
    f->free_s = has_y ? 0.0 : w;
    return a2 * (w * (w > tau ? w : tau) - u * (u > tau ? u : tau));
}
