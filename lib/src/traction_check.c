/* Whether the reported traction can be what moves the train. A traction
 * that is present but wrong (its sign swapped, a unit reporting another
 * train's effort) drove every model the wrong way: the fixes dragged the
 * estimate along, metres and m/s off while published as valid, and the
 * weights moved on the misfit to a wrong type (hstpf-mc --scenario
 * tracsign: every run). A shadow filter that does not use the traction
 * (the acceleration unknown, as hstpf_input_t.traction_unknown has it)
 * scores each fix beside the bank; a CUSUM of the log-likelihood ratio
 * (each step's clipped at HSTPF__TRAC_CLIP nats, so that a lone outlier
 * in a heavy tail cannot do it) past HSTPF__TRAC_NATS says the traction
 * explains the fixes worse than no traction at all. From then on, for
 * HSTPF_TRAC_RETRY_S, the steps run as if the traction were unknown (the
 * weights wait, the declaration's hold does not run); then it is believed
 * and tested again (found again within that time after a retry: the next
 * wait is twice as long, up to 4 times). Steps whose traction the caller
 * reports unknown test nothing and keep the fault and the evidence. Why
 * not a test of the traction coming right: docs/model.md, "A traction that
 * cannot be right". */
#include <math.h>
#include <string.h>

#include "bank.h"
#include "engine.h"
#include "refine.h"
#include "track.h"

/* Not on the particle engine: its likelihoods are Monte Carlo estimates, a
 * few nats low at M = 100, and the test fired on a true traction (paper
 * Case 1: 2 of 3 runs). Not under non-Gaussian process noise: the shadow,
 * a Gaussian filter, would be weighed against the grid's exact densities
 * (Case 2: it never came near) */
static int checking(const hstpf_t *f)
{
    return f->cfg.traction_check && f->engine != (uint8_t)HSTPF_ENGINE_PARTICLE && hstpf__process_gaussian(&f->cfg);
}

/* The shadow's traction: none, only what balances the track's force at s
 * (its W is 0), and a hair so that nothing holds it at rest. */
static double shadow_xu(const hstpf_t *f, uint16_t *hint, double s)
{
    return (f->cfg.n_track > 0u ? (double)hstpf__track_acc(f, hint, (real)s) : 0.0) + HSTPF__FREE_HAIR;
}

/* The shadow placed at the leading row's posterior (every engine publishes
 * its means and variances). */
static void place(hstpf_t *f)
{
    hstpf_trac_check_t *c = &f->tc;
    const hstpf_model_t *m = &f->m[hstpf__leading_row(f)];
    memset(&c->sh, 0, sizeof c->sh);
    c->sh.kx[0] = (double)m->s_mean;
    c->sh.kx[1] = (double)m->v_mean;
    c->sh.kp[0] = (double)m->s_var;
    c->sh.kp[2] = (double)m->v_var;
    c->placed = 1;
    c->settle = HSTPF__TRAC_SETTLE;
}

void hstpf__trac_check_reset(hstpf_t *f)
{
    memset(&f->tc, 0, sizeof f->tc);
}

void hstpf__trac_check_snapshot(hstpf_t *f)
{
    uint16_t l;
    for (l = 0; l < hstpf__n_hyp(f); ++l) {
        f->tc.logq0[l] = *hstpf__logq_of(f, l);
    }
}

void hstpf__trac_check_begin(hstpf_t *f, int traction_known, double xu, double dt)
{
    hstpf_trac_check_t *c = &f->tc;
    if (!checking(f)) {
        c->fault = 0;
        c->release = 0;
        c->placed = 0;
        return;
    }
    if (c->release && traction_known) {
        /* the traction caught up when it can move the leading row */
        const hstpf_model_t *m = &f->m[hstpf__leading_row(f)];
        uint16_t hint = m->track_hint;
        const double g = f->cfg.n_track > 0u ? (double)hstpf__track_acc(f, &hint, m->s_mean) : 0.0;
        if (xu > (double)m->k0 + g) {
            c->release = 0;
            c->rel_run = 0;
        }
    }
    c->since_retry_s += dt;
    c->fault_s += c->fault ? dt : 0.0;
    if (!traction_known) {
        /* nothing to test; the fault and the evidence stand (a sender that
         * reported its traction unknown every 10th step, when such a step
         * wiped them, hid a swapped sign from the check: a review), and
         * the shadow, which does not use the traction, steps on */
        return;
    }
    if (c->fault) {
        if (c->fault_s < c->retry_s) {
            return;
        }
        c->fault = 0; /* believed again, and tested again */
        c->cusum = 0.0;
        c->placed = 0;
        c->since_retry_s = 0.0;
    }
    if (!c->placed) {
        place(f); /* its CUSUM kept: a lock lost and taken again (a wrong
                   * traction loses it) does not wipe the evidence */
    }
}

void hstpf__trac_check_end(hstpf_t *f, const hstpf__step_t *bank_st, int test, int standstill)
{
    hstpf_trac_check_t *c = &f->tc;
    hstpf__step_t st = *bank_st;
    uint16_t hint = c->sh.track_hint;
    uint8_t held;
    int floored;
    double ll_sh, r, clip;
    if (!checking(f) || c->fault || !c->placed) {
        return;
    }
    /* the shadow does not use the traction: acceleration 0 with accel_unknown_sd */
    st.free_run = 1;
    st.xu = shadow_xu(f, &hint, c->sh.kx[0]);
    st.acc_var = f->cfg.accel_unknown_sd * f->cfg.accel_unknown_sd * st.dt * hstpf__acc_tau(f);
    {
        /* in the bank's parts (bank.c): in one, a long step's unknown
         * acceleration left out its T^2 spread of the position, and a
         * wrong traction was found a minute later at a fix every 10 s (a
         * review) */
        const uint32_t n = hstpf__substeps(f, st.dt);
        if (n > 1u) {
            hstpf__step_t sub = hstpf__step_part(f, &st, n);
            uint32_t i;
            for (i = 1; i < n; ++i) {
                (void)hstpf__kalman_step(f, &c->sh, &sub, &held, &floored);
                sub.xu = shadow_xu(f, &hint, c->sh.kx[0]); /* the track where this part ends */
            }
            sub.has_y = st.has_y;
            st = sub;
        }
    }
    ll_sh = hstpf__kalman_step(f, &c->sh, &st, &held, &floored);
    if (!(isfinite(ll_sh) && isfinite(c->sh.kx[0]) && isfinite(c->sh.kx[1]))) {
        c->placed = 0;
        return;
    }
    if (hstpf__kalman_lost(&f->m[hstpf__leading_row(f)], c->sh.kx[0], c->sh.kx[1], c->sh.kp[0], c->sh.kp[2]) &&
        !(st.has_y && !standstill && f->lost_run == 0u && ll_sh > hstpf__bank_loglik(f))) {
        /* far from the bank (engine.h's rule) and not nearer the fix than
         * the bank: placed again, its CUSUM kept. One nearer, while the
         * bank moves and fits, is the bank that lost the train (a sign
         * swapped: the bank 250 m behind, the shadow placed back on it at
         * every step, the CUSUM frozen for 70 s). Not at a standstill nor
         * while the bank is lost: kept only when it wins, the shadow only
         * added to the CUSUM, and a step in the fixes the rule missed at a
         * stop, or a late brake release, raised the fault on a true
         * traction (a review: stopstep12 3 830 -> 19 452 fault steps) */
        place(f);
        return;
    }
    if (st.has_y) {
        /* Held, while the fixes run ahead of the held position: a holding
         * brake reported late or stuck at a departure, a train that rolls.
         * The held models cannot follow (only a traction above c0 starts
         * them): a one-sided CUSUM of the fixes' standardised lead over the
         * leading row, less HSTPF__RELEASE_K, past HSTPF__RELEASE_H takes
         * the traction as unknown until it can move the train, or the
         * models find the train standing again. A held position a few
         * metres off (a stop taken a step early) is pulled to the fixes
         * within a few of them and adds little. */
        const hstpf_model_t *m = &f->m[hstpf__leading_row(f)];
        const double sd_e = f->noise_mom[5] > 0.0 ? f->noise_mom[5] : 1.0;
        if (!c->release) {
            double z = (st.yr - f->noise_mom[4] - (double)m->s_mean) / sd_e;
            z = (z < HSTPF__RELEASE_CLIP ? z : HSTPF__RELEASE_CLIP) - HSTPF__RELEASE_K; /* a heavy tail's outlier */
            c->rel_d = standstill && c->rel_d + z > 0.0 ? c->rel_d + z : 0.0;
            if (c->rel_d > HSTPF__RELEASE_H) {
                c->release = 1;
                c->rel_d = 0.0;
                c->rel_run = 0;
            }
        } else {
            const double v = (double)m->v_mean, sd_v = sqrt((double)m->v_var > 0.0 ? (double)m->v_var : 0.0);
            const int still = v < sd_v || v < HSTPF__RELEASE_STOP;
            c->rel_run = (uint8_t)(still ? c->rel_run + 1u : 0u);
            if (c->rel_run >= HSTPF__RELEASE_STILL) {
                c->release = 0;
                c->rel_run = 0;
            }
        }
    }
    if (!test || !st.has_y || c->release) {
        return; /* released this step: the traction is no longer what is tested */
    }
    if (c->settle > 0u) {
        /* a shadow just placed predicts the next position from the bank's
         * speed, not yet from its own acceleration, and with the bank's
         * spread: its first fixes tell little */
        --c->settle;
        return;
    }
    /* positive: no traction explains the fix better than the bank with it */
    r = ll_sh - hstpf__bank_loglik(f);
    clip = standstill ? HSTPF__TRAC_CLIP_HELD : HSTPF__TRAC_CLIP;
    r = r > clip ? clip : (r < -clip ? -clip : r);
    c->cusum = c->cusum + r > 0.0 ? c->cusum + r : 0.0;
    if (c->cusum == 0.0) {
        /* the traction fits: the weights so far are the last it can have
         * misled (this step's update comes after) */
        hstpf__trac_check_snapshot(f);
    }
    {
        /* In doubt (the CUSUM past HSTPF__TRAC_DOUBT, below the fault's
         * 25 nats) the weights wait and the declaration's holds start
         * again: a traction frozen at its cruise value while the train
         * braked gave the rows with more resistance the weight, and they
         * were declared (hstpf-mc --scenario stuck30: 191 of 1 700 runs,
         * whose CUSUM mostly never reached 25; 1 with the doubt). Not back
         * to the snapshot here: one minutes old fitted the fixes worse than
         * the bank had learnt to, the CUSUM climbed on that and raised
         * the fault with a true traction (a review: gain-20 in 5 runs) */
        const uint8_t was = c->doubt;
        c->doubt = (uint8_t)(c->cusum > HSTPF__TRAC_DOUBT);
        if (c->doubt && !was) {
            f->held_s = 0.0;
            f->fit_held_s = 0.0;
        }
    }
    if (c->cusum > HSTPF__TRAC_NATS) {
        uint16_t l;
        /* the weights moved on the wrong traction while the CUSUM rose
         * (a traction stuck at its cruise value as the train brakes: a
         * wrong row at q = 1.000 within 10 s, declared 14 s after the
         * retry, a review): back to where they were, the declaration's
         * hold and the "no type fits" hold from scratch */
        for (l = 0; l < hstpf__n_hyp(f); ++l) {
            *hstpf__logq_of(f, l) = c->logq0[l];
        }
        f->held_s = 0.0;
        f->fit_held_s = 0.0;
        /* found again soon after a retry: the fault stands, wait longer
         * before the next (each retry publishes the wrong traction's
         * estimate until it is found again) */
        const double base = HSTPF_TRAC_RETRY_S;
        c->retry_s = c->changes > 0u && c->since_retry_s < base ? 2.0 * c->retry_s : base;
        c->retry_s = c->retry_s < 4.0 * base ? c->retry_s : 4.0 * base;
        c->fault = 1;
        c->fault_s = 0.0;
        c->cusum = 0.0;
        c->doubt = 0;
        c->placed = 0;
        ++c->changes;
    }
}

void hstpf__trac_check_shift(hstpf_t *f, double d)
{
    f->tc.sh.kx[0] -= d;
}
