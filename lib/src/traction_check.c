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
 * explains the fixes worse than no traction at all. From then on the
 * steps run as if the traction were unknown (the weights wait, the
 * declaration's hold does not run), and the shadow runs the other way:
 * the reported traction through the blended theta, until it has explained
 * the fixes better than the bank without it by the same margin
 * (docs/model.md, "A traction that cannot be right"). */
#include <math.h>
#include <string.h>

#include "bank.h"
#include "engine.h"
#include "refine.h"
#include "track.h"

/* The shadow placed at the leading row's posterior (every engine publishes
 * its means and variances), with the theta it runs. */
static void place(hstpf_t *f)
{
    hstpf_trac_check_t *c = &f->tc;
    const hstpf_model_t *m = &f->m[hstpf__leading_row(f)];
    double wb[HSTPF_MAX_MODELS + 1], th[3] = {0.0, 0.0, 0.0};
    uint16_t l;
    memset(&c->sh, 0, sizeof c->sh);
    c->sh.kx[0] = (double)m->s_mean;
    c->sh.kx[1] = (double)m->v_mean;
    c->sh.kp[0] = (double)m->s_var;
    c->sh.kp[2] = (double)m->v_var;
    if (c->fault) { /* the reported traction through the blended rows */
        hstpf__blend_weights(f, wb);
        for (l = 0; l < f->cfg.n_models; ++l) {
            th[0] += wb[l] * f->theta[l].c0;
            th[1] += wb[l] * f->theta[l].c1;
            th[2] += wb[l] * f->theta[l].c2;
        }
        hstpf__model_set_theta(f, &c->sh, th[0], th[1], th[2]);
    }
    c->placed = 1;
    c->cusum = 0.0;
}

void hstpf__trac_check_reset(hstpf_t *f)
{
    memset(&f->tc, 0, sizeof f->tc);
}

/* Not on the particle engine: its likelihoods are Monte Carlo estimates, a
 * few nats low at M = 100, and the test fired on a true traction (paper
 * Case 1: 2 of 3 runs). Not under non-Gaussian process noise: the shadow,
 * a Gaussian filter, would be weighed against the grid's exact densities
 * (Case 2: it never came near) */
static int checking(const hstpf_t *f)
{
    return f->cfg.traction_check && f->engine != (uint8_t)HSTPF_ENGINE_PARTICLE && hstpf__process_gaussian(&f->cfg);
}

void hstpf__trac_check_begin(hstpf_t *f, int traction_known)
{
    if (!checking(f) || !traction_known) {
        f->tc.placed = 0; /* nothing to test: placed again at the next known traction */
        return;
    }
    if (!f->tc.placed) {
        place(f);
    }
}

void hstpf__trac_check_end(hstpf_t *f, const hstpf__step_t *bank_st, double traction, int test)
{
    hstpf_trac_check_t *c = &f->tc;
    hstpf__step_t st = *bank_st;
    uint8_t held;
    int floored;
    double ll_sh, r;
    if (!checking(f) || !c->placed) {
        return;
    }
    if (c->fault) { /* the shadow believes the traction */
        st.free_run = 0;
        st.xu = f->xi * traction;
        st.acc_var = 0.0;
    } else { /* the shadow does not: acceleration 0 with accel_unknown_sd */
        uint16_t hint = c->sh.track_hint;
        st.free_run = 1;
        st.xu = (f->cfg.n_track > 0u ? (double)hstpf__track_acc(f, &hint, (real)c->sh.kx[0]) : 0.0) + 1e-3;
        st.acc_var = f->cfg.accel_unknown_sd * f->cfg.accel_unknown_sd * st.dt * f->cfg.dt_nominal_s;
    }
    ll_sh = hstpf__kalman_step(f, &c->sh, &st, &held, &floored);
    if (!(isfinite(ll_sh) && isfinite(c->sh.kx[0]) && isfinite(c->sh.kx[1]))) {
        c->placed = 0;
        return;
    }
    {
        const hstpf_model_t *g = &f->m[hstpf__leading_row(f)];
        if (hstpf__kalman_lost(g, c->sh.kx[0], c->sh.kx[1], c->sh.kp[0], c->sh.kp[2])) {
            /* a wrong traction drove it away from the bank (engine.h's
             * rule): placed again, its CUSUM kept; it tests from the next
             * fix */
            const double keep = c->cusum;
            place(f);
            c->cusum = keep;
            return;
        }
    }
    if (!test || !st.has_y) {
        return;
    }
    /* positive: the shadow (without the traction, or while the fault
     * stands with it) explains the fix better than the bank does */
    r = ll_sh - hstpf__bank_loglik(f);
    r = r > HSTPF__TRAC_CLIP ? HSTPF__TRAC_CLIP : (r < -HSTPF__TRAC_CLIP ? -HSTPF__TRAC_CLIP : r);
    c->cusum = c->cusum + r > 0.0 ? c->cusum + r : 0.0;
    if (c->cusum > (c->fault ? HSTPF__TRAC_NATS_BACK : HSTPF__TRAC_NATS)) {
        c->fault = (uint8_t)!c->fault;
        ++c->changes;
        place(f);
    }
}

void hstpf__trac_check_shift(hstpf_t *f, double d)
{
    f->tc.sh.kx[0] -= d;
}
