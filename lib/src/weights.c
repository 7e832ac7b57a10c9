/* The model weights (paper Eq. 14): their update by each step's
 * likelihoods with the floor, the consist's prior mixed in, the holds at a
 * standstill and an arrival, and whether every weighted hypothesis lost a
 * fix. bank.c decides when each runs. */
#include <math.h>

#include "bank.h"
#include "refine.h"

void hstpf__update_model_weights(hstpf_t *f)
{
    const uint16_t nh = hstpf__n_hyp(f);
    const double lfloor = f->cfg.q_floor > 0.0 ? log(f->cfg.q_floor) : -HUGE_VAL;
    double mx = -HUGE_VAL, sum = 0.0, lsum;
    uint16_t l;
    int pass;
    for (l = 0; l < f->cfg.n_models; ++l) {
        f->m[l].logq += (double)f->m[l].loglik;
    }
    if (f->rf.active) {
        f->rf.logq += f->rf.loglik;
    }
    /* Eq. 14 by log-sum-exp; then the floor, and normalise again */
    for (pass = 0; pass < 2; ++pass) {
        mx = -HUGE_VAL;
        sum = 0.0;
        for (l = 0; l < nh; ++l) {
            mx = *hstpf__logq_of(f, l) > mx ? *hstpf__logq_of(f, l) : mx;
        }
        for (l = 0; l < nh; ++l) {
            sum += exp(*hstpf__logq_of(f, l) - mx);
        }
        lsum = mx + log(sum);
        for (l = 0; l < nh; ++l) {
            double *lq = hstpf__logq_of(f, l);
            *lq -= lsum;
            if (pass == 0 && *lq < lfloor) {
                *lq = lfloor;
            }
        }
    }
}

/* The consist may have changed with probability p (p = 1: it did): each
 * hypothesis' weight becomes (1 - p) q + p x its prior weight (the rows'
 * (1 - refine_prior_q) / n, the continuous one's refine_prior_q), and the
 * continuous hypothesis' theta its moments under the same mixture. */
void hstpf__consist_mix(hstpf_t *f, double p)
{
    const uint16_t nh = hstpf__n_hyp(f);
    const double q0 = f->rf.active ? f->cfg.refine_prior_q : 0.0;
    uint16_t l;
    for (l = 0; l < nh; ++l) {
        double *lq = hstpf__logq_of(f, l);
        const double prior = l < f->cfg.n_models ? (1.0 - q0) / (double)f->cfg.n_models : q0;
        *lq = log((1.0 - p) * exp(*lq) + p * prior);
        /* and the weights a traction fault would go back to: the prior is
         * no evidence of the traction's */
        f->tc.logq0[l] = log((1.0 - p) * exp(f->tc.logq0[l]) + p * prior);
    }
    if (f->rf.active && f->rf.placed) {
        hstpf__refine_consist(f, p);
    }
}

/* Standstill: every model that carries weight is held at rest. The data
 * then say nothing about W(v) (docs/model.md), so no model weight moves.
 * Arrival: some weighted models hold the train at rest while others still
 * move it, a few tenths of a m/s apart, or some may have come to rest
 * (HSTPF__HELD_STOPPING). A fix then scores "has it stopped yet", which
 * the fix noise decides, not W(v): the weights wait until the models
 * agree, for at most HSTPF__ARRIVAL_MAX_S counted on fixes (dt: 0 on a
 * step without one; a train that really moves then releases them).
 * Returns 2 at standstill, 1 arriving, else 0. */
static int hold_of(hstpf_t *f, double dt)
{
    double wb[HSTPF_MAX_MODELS + 1];
    uint16_t l, held = 0, moving = 0, stopping = 0;
    hstpf__blend_weights(f, wb);
    for (l = 0; l <= f->cfg.n_models; ++l) {
        const uint8_t h = l < f->cfg.n_models ? f->m[l].held : f->rf.held;
        if (wb[l] > 0.0) {
            held = (uint16_t)(held + (h == HSTPF__HELD_YES));
            moving = (uint16_t)(moving + (h == HSTPF__HELD_NO));
            stopping = (uint16_t)(stopping + (h == HSTPF__HELD_STOPPING));
        }
    }
    if (moving == 0u && stopping == 0u) {
        f->arrival_s = 0.0;
        return 2;
    }
    if (held == 0u && stopping == 0u) {
        f->arrival_s = 0.0;
        return 0;
    }
    f->arrival_s += dt;
    return f->arrival_s <= HSTPF__ARRIVAL_MAX_S ? 1 : 0;
}

int hstpf__weights_hold(hstpf_t *f, double dt, int has_y)
{
    /* the arrival's wait runs on fixes, each the time since the one
     * before but no more than the gap before that (or dt_nominal_s):
     * an outage across a stop spent it with none to weigh, and the
     * first fix after it moved the weights while the rows still
     * disagreed on having stopped (hstpf-mc --scenario outage-stop: TV
     * up to 0.41 across the stop); counted per step with a fix, 10 Hz
     * steps with a fix a second made it 100 s (a review) */
    const double cap = f->fix_gap_s > f->cfg.dt_nominal_s ? f->fix_gap_s : f->cfg.dt_nominal_s;
    int hold;
    f->fix_age_s += dt;
    hold = hold_of(f, has_y ? (f->fix_age_s < cap ? f->fix_age_s : cap) : 0.0);
    if (has_y) {
        f->fix_gap_s = f->fix_age_s;
        f->fix_age_s = 0.0;
    }
    return hold;
}

/* Whether every hypothesis that carries weight put this fix beyond its
 * floor: the rows and, when it carries weight, the continuous one (while
 * it alone carries the weight, the rows' misses say nothing). */
int hstpf__all_lost(const hstpf_t *f)
{
    double wb[HSTPF_MAX_MODELS + 1];
    uint16_t l;
    hstpf__blend_weights(f, wb);
    for (l = 0; l < f->cfg.n_models; ++l) {
        if (wb[l] > 0.0 && f->m[l].floor_run == 0u) {
            return 0;
        }
    }
    return !(f->rf.active && wb[f->cfg.n_models] > 0.0 && !f->rf.floored);
}
