/* hstpfd: the estimate frames: what is valid, the values they carry, when
 * each is due, and sending (with the --frames-out log). */
#include "core_internal.h"

#include <math.h>
#include <string.h>

#include "candump.h"

static int lib_valid(const hstpf_estimate_t *e)
{
#if HSTPFD_LIB_LOCK_API
    return e->valid != 0;
#else
    (void)e;
    return 1;
#endif
}

/* Every number published as valid is finite and within the library's
 * documented ranges, and the filter has lock (docs/daemon.md, "Validity"). */
int hstpfd__est_valid(const hstpfd_core_t *c)
{
    const hstpf_estimate_t *e = &c->est;
    uint16_t l;
    if (!c->have_fix || !lib_valid(e) || !isfinite(e->position_m) || fabs(e->position_m) > HSTPF_POS_MAX_M ||
        !isfinite((double)e->speed_mps) || !isfinite(e->position_sd_m) || !isfinite((double)e->speed_sd_mps)) {
        return 0;
    }
    for (l = 0; l < 3; ++l) {
        if (!isfinite((double)e->theta[l])) {
            return 0;
        }
    }
    for (l = 0; l < e->n_models; ++l) {
        if (!isfinite((double)e->model[l].q)) {
            return 0;
        }
    }
    return 1;
}

static void tx_values(const hstpfd_core_t *c, unsigned i, hstpfd_tx_values_t *v)
{
    const hstpf_estimate_t *e = &c->est;
    const hstpf_e2e_counts_t *p = hstpf_e2e_rx_counts(&c->rx.pos);
    const hstpf_e2e_counts_t *t = hstpf_e2e_rx_counts(&c->rx.trac);
    const hstpf_e2e_counts_t *n = hstpf_e2e_rx_counts(&c->rx.topo);
    memset(v, 0, sizeof *v);
    v->have_fix = c->have_fix;
    v->valid = (uint8_t)hstpfd__est_valid(c);
    v->position_m = e->position_m;
    v->speed_mps = (double)e->speed_mps;
    v->position_sd_m = e->position_sd_m;
    v->speed_sd_mps = (double)e->speed_sd_mps;
    v->sd_valid = (uint8_t)LIB_HAS_SD;
    v->standstill = e->standstill;
    v->acquisitions = e->acquisitions;
    if (c->have_est_fix && c->have_est_t) {
        /* the step's end on the fix clock: the inverse of the fix clock's mapping at the step */
        const int64_t ms = c->est_fix_us / 1000;
        const int64_t w = (int64_t)HSTPFD_FIX_WRAP_MS;
        v->est_time_valid = 1;
        v->est_time_ms = (uint16_t)(((ms % w) + w) % w);
    }
    v->status = e->status;
    /* a weight that is not finite names no type */
    if (e->declared >= 0 && e->declared < (int)e->n_models && isfinite((double)e->model[e->declared].q)) {
        v->declared_row = c->row[e->declared];
        v->declared_q = (double)e->model[e->declared].q;
    } else {
        v->declared_row = -1;
    }
    if (c->have_fix && e->best >= 0 && e->best < (int)e->n_models && isfinite((double)e->model[e->best].q)) {
        v->leader_row = c->row[e->best];
        v->leader_q = (double)e->model[e->best].q;
    } else {
        v->leader_row = -1;
    }
    v->theta[0] = (double)e->theta[0];
    v->theta[1] = (double)e->theta[1];
    v->theta[2] = (double)e->theta[2];
    v->fit = (uint8_t)e->fit;
    v->off_what = (uint8_t)e->off_what;
    if (i == HSTPFD_OUT_BAND) { /* five band evaluations, only for the frame that carries them */
        unsigned k;
        for (k = 0; k < HSTPFD_BAND_N; ++k) {
            double w = 0.0, sd = NAN; /* NaN unless the library gives it: never sent as valid */
            (void)hstpf_resistance_band(e, (double)k * HSTPFD_BAND_STEP_KMH / 3.6, &w, &sd);
            v->w_sd[k] = sd;
        }
    }
    v->pos_stale = c->sched.pos_stale;
    v->trac_stale = c->sched.trac_stale;
    v->trac_fault = c->est.traction_fault;
    /* every input frame refused; staleness only of the two the estimate
     * runs on (the Consist frame is an event, and a bus may have none) */
    v->bad_crc = p->bad_crc + t->bad_crc + n->bad_crc;
    v->repeated = p->repeated + t->repeated + n->repeated;
    v->jump = p->jump + t->jump + n->jump;
    v->wrong_length = p->wrong_length + t->wrong_length + n->wrong_length;
    v->stale_events = p->stale + t->stale;
    v->unknown_id = c->n.unknown;
    v->error_frames = c->n.error;
    v->degeneracy = c->n.degeneracy;
    v->clock_fwd = c->sched.n.clock_fwd;
    v->clock_back = c->sched.n.clock_back;
    v->late = c->sched.n.late;
    v->reacquire = c->n.reacquire;
}

void hstpfd__transmit(hstpfd_core_t *c, unsigned i)
{
    hstpfd_tx_values_t v;
    hstpfd_frame_t f;
    tx_values(c, i, &v);
    if (hstpfd_tx_encode(&c->tx, i, &v, &f) != 0) {
        ++c->n.tx_errors;
        return;
    }
    f.t_us = c->src_now; /* the source's clock, as a bus recording has it */
    if (c->frames_out != NULL) {
        char line[256];
        if (hstpfd_candump_format(&f, c->bus, line, sizeof line) > 0) {
            fputs(line, c->frames_out);
        }
    }
    if (c->send != NULL && c->cfg->send) {
        const int r = c->send(c->send_ctx, &f);
        if (r == 0) {
            ++c->n.tx_frames;
        } else if (r == HSTPFD_SEND_OFFLINE) {
            ++c->n.tx_offline;
        } else {
            ++c->n.tx_errors;
        }
    } else {
        ++c->n.tx_skipped;
    }
}

int64_t hstpfd__state_due(const hstpfd_core_t *c)
{
    const int64_t cyc = hstpfd_tx_cycle_us(0);
    if (!c->state_pending) {
        return -1;
    }
    return c->state_sent ? c->last_state_tx + cyc - cyc / 50 : 0; /* 2 % early: stamps jitter */
}

/* The estimated state (EstState, then EstQuality) of the latest step, if
 * one is pending and due. */
void hstpfd__state_service(hstpfd_core_t *c)
{
    const int64_t due = hstpfd__state_due(c);
    if (due >= 0 && c->t_now >= due) {
        c->state_sent = 1;
        c->state_pending = 0;
        c->last_state_tx = c->t_now;
        hstpfd__transmit(c, 0);
        hstpfd__transmit(c, HSTPFD_OUT_QUALITY);
    }
}

/* The periodic outputs that are due at t_now. */
void hstpfd__tx_service(hstpfd_core_t *c)
{
    unsigned i;
    hstpfd__state_service(c);
    for (i = 1; i < HSTPFD_N_OUTPUTS; ++i) {
        const int64_t cyc = hstpfd_tx_cycle_us(i);
        if (i == HSTPFD_OUT_QUALITY) {
            continue; /* goes with the state */
        }
        if (c->t_now >= c->next_tx[i]) {
            hstpfd__transmit(c, i);
            c->next_tx[i] += cyc;
            if (c->next_tx[i] <= c->t_now) {
                c->next_tx[i] = c->t_now + cyc;
            }
        }
    }
}

void hstpfd_core_send(hstpfd_core_t *c, unsigned i)
{
    hstpfd__transmit(c, i);
}
