/* A step in the fixes' reference: a GNSS bias that changes (a satellite
 * set, a receiver's mode), a map-matching or balise correction. The fixes
 * jump by metres from one epoch to the next while the train does not.
 * Moving, every filter took the jump for speed: a 20 m step gave a speed
 * 4 m/s off at 8-12 sd, published valid (a review's harness). At rest,
 * the held models could not follow it, and the traction check blamed the
 * traction for minutes (hstpf-mc --scenario stopstep-12).
 *
 * A fix beyond the reach of the fix noise (its 2^-17 quantiles, a
 * Gaussian's 4.3 sd, with the prediction's spread) is held: not used, the
 * estimate not valid. When the next fix lies on the same side beyond the
 * 2^-11 quantiles (3.3 sd) at about the same offset, the two are a step:
 * the position moves by their mean offset and the speed does not.
 * Otherwise the held fix was a lone outlier. Only a jump is held: the fix
 * before it was not beyond the 2^-8 quantiles (2.7 sd) on the same side,
 * so that dynamics that are wrong (a traction stuck, a train that rolls
 * while held), whose innovations grow a little each step, are not taken
 * for steps. A jump beyond STEP_RANGES of the noise's 2^-10 range is not a
 * step: a reference that restarted, fixes that run backwards, a train
 * lost (lock.c's rules).
 *
 * A heavy-tailed noise's quantiles reach far (a Student-t(3)'s 2^-17 one
 * is 50 of its scales): no single fix is beyond them, and a 12 m step at a
 * platform was taken for the train moving off at 0.7 m/s, published valid
 * for a minute (hstpf-mc --scenario stopstep12-t). There a run of fixes
 * tells: the last 2-6 used, on one side after one that fitted, level, each
 * favouring it, are a step when "the reference moved by their mean
 * offset" explains them better than "it did not" by RUN_LLR nats under the
 * fix noise's own density; ahead of a bank at standstill only all six (a
 * train leaving under a reported brake is the release's). A Gaussian's
 * run is a step only behind a bank at standstill: a step the hold rule
 * missed there left the traction blamed for minutes (fixbias10). */
#include <math.h>

#include "bank.h"
#include "dist_impl.h"
#include "refine.h"
#include "track.h"

/* tail tables' nodes F^-1(2^(k - 32)) and a Gaussian's sd there, by
 * which the prediction's spread is scaled alike */
#define HOLD_TAIL 15 /* 2^-17, 7.6e-6: 4.33 sd */
#define HOLD_Z 4.33
#define STEP_TAIL 21 /* 2^-11, 4.9e-4: 3.30 sd */
#define STEP_Z 3.30
#define FIT_TAIL 24 /* 2^-8, 3.9e-3: 2.66 sd */
#define FIT_Z 2.66
#define RANGE_TAIL 22 /* 2^-10: the range of lock.c's rules */
#define STEP_RANGES 4.0 /* a step is at most this many such ranges (Case 1: 59 m) */
#define STEP_ACC 1.0 /* m/s^2 the blend's s + T v leaves out over a step, at most */
#define RUN_MAX 6     /* fixes in a run, at most (f->fs.run holds one more: the fix before) */
/* a run's evidence for a step: a Gaussian's GLR exceeds it by chance
 * with P(chi2_1 > 40) = 2.5e-10 per run tried */
#define RUN_LLR 20.0
/* The run rule is for noises whose hold quantiles lie beyond RUN_HEAVY_Z
 * sd on both sides. A light tail beyond RUN_LIGHT_Z sd on both sides (a
 * Gaussian's: HOLD_Z) has it only behind a bank at standstill: a step
 * there that the hold rule missed (a -10 m step at a platform is 4.5 of
 * Case 1's sd, and a prediction's spread lifts its reach) left the held
 * models behind the fixes and the traction blamed for minutes (fixbias10,
 * stopstep-12); ahead, and moving, a Gaussian's evidence grows with the
 * square of an offset, so a drift (a train leaving while the brake is
 * reported) passes RUN_LLR within a few fixes (test_held_but_moving), and
 * moving the filters take up a fix before a run can tell (fixbias10 at
 * 300 km/h: 8 more steps in 340, no fewer wrong speeds). A noise with an
 * edge (the paper's Gamma) scores a prediction a few cm past it as
 * impossible, which any step then explains (stops-case2: 786 false steps
 * in 340 runs). */
#define RUN_HEAVY_Z (1.5 * HOLD_Z)
#define RUN_LIGHT_Z 3.0
#define RUN_SLOPE_Z 2.0 /* a flat run's slope lies beyond it in 2.3 % (a Gaussian's) */
typedef char hstpf__run_fits[sizeof(((hstpf_fix_step_t *)0)->run) == (RUN_MAX + 1) * sizeof(real) &&
                                     sizeof(((hstpf_fix_step_t *)0)->run_dt) == (RUN_MAX + 1) * sizeof(real)
                                 ? 1
                                 : -1];
typedef char hstpf__step_tails_fit[FIT_TAIL < HSTPF_DIST_TAILN && RANGE_TAIL < HSTPF_DIST_TAILN &&
                                           HOLD_TAIL < STEP_TAIL && STEP_TAIL < FIT_TAIL
                                       ? 1
                                       : -1];

/* d (the fix less the prediction) beyond the reach: the noise's tail
 * quantile k from its median and z prediction sd, root-sum-square (a
 * Gaussian's z sd of the two together). -1 below, 1 above, 0 within. */
static int beyond(const hstpf_t *f, double d, double var, int k, double z)
{
    const hstpf_dist_quantiles_t *q = &f->de.qt;
    const double med = (double)hstpf__dist_sample(q, 0x80000000u);
    const double hi = (double)q->tail_hi[k] - med, lo = med - (double)q->tail_lo[k];
    const double p2 = z * z * var;
    d -= med;
    if (d > 0.0) {
        return d * d > hi * hi + p2 ? 1 : 0;
    }
    return d * d > lo * lo + p2 ? -1 : 0;
}

/* The step's offset, the mean of k fixes, has the variance of one over
 * k: each Gaussian filter's position takes it in (the Kalman rows, the
 * grid's stand-ins, the continuous hypothesis, the traction check's
 * shadow), and the grid's cells and the particles are spread by it.
 * Without it a train at rest was published 2-3 m off with an sd of 0.2 m
 * for a minute after a step (a review; on the grid, stopstep12-t). */
static void step_spread(hstpf_t *f, double v)
{
    const hstpf__engine_t *e = hstpf__engine_of(f);
    uint16_t l;
    if (e->spread != NULL) {
        e->spread(f, v);
    }
    for (l = 0; l <= f->cfg.n_models; ++l) {
        hstpf_model_t *m = &f->m[l];
        m->kp[0] += v;
        if (m->rest.p > (real)0) { /* a settle timer's "stood still" too */
            m->rest.p = (real)((double)m->rest.p + v);
        }
        if (f->engine == (uint8_t)HSTPF_ENGINE_KALMAN && l < f->cfg.n_models) {
            m->s_var = (real)((double)m->s_var + v);
        }
    }
    if (f->rf.active) {
        f->rf.kp[0] += v;
        if (f->rf.rest.p > (real)0) {
            f->rf.rest.p = (real)((double)f->rf.rest.p + v);
        }
    }
    f->tc.sh.kp[0] += v;
}

/* The reference moved by step (variance v): the position moves, the
 * speed does not. */
static void take_step(hstpf_t *f, double step, double v)
{
    f->origin_m += step;
    f->top_m += step;
    hstpf__track_rebase(f);
    ++f->fs.steps;
    step_spread(f, v);
    f->fs.run_n = 0;
}

/* After a step, this fix on the new reference (offset d) begins the run's
 * ring again: a run back then has a fix that fitted before it, so a two-fix
 * excursion is undone two fixes after its return (without it, a 100 m
 * multipath excursion at speed under Student-t fixes stood as a step,
 * published 99 m off for 9-13 steps: a review). */
static void ring_restart(hstpf_t *f, double d, double pred, double vel, double dt)
{
    f->fs.run[0] = (real)d;
    f->fs.run_p[0] = (real)pred;
    f->fs.run_v[0] = (real)vel;
    f->fs.run_dt[0] = (real)dt;
    f->fs.run_n = 1;
}

/* Whether the last k fixes used (k >= 2, the one before them too) are a
 * step; its size into *step. In float where it can be: the M4F's double
 * is soft-float. */
static int run_is_step(const hstpf_t *f, int k, int light, real shrink, real spread, real *step)
{
    const real *r = f->fs.run, mean = (real)f->noise_mom[4];
    real sum = 0, llr = 0, pair = 0;
    int i, side;
    for (i = 0; i < k; ++i) {
        sum += r[i];
    }
    *step = sum / (real)k - mean;
    side = *step > (real)0 ? 1 : -1;
    /* one side, after a fix that fitted: a jump, not dynamics that drift */
    if (beyond(f, (double)r[k], 0.0, FIT_TAIL, 0.0) == side) {
        return 0;
    }
    /* ahead of a bank at standstill, the whole run: a train leaving while
     * the brake is still reported gives that too, and four Student-t fixes
     * of it lay level by chance (test_fix_step_heavy's departure, seed
     * 10); over six its ramp shows (the release's, traction_check.c) */
    if (side > 0 && f->standstill && k < RUN_MAX) {
        return 0;
    }
    /* a light tail: only behind a bank at standstill (run_rule), where no
     * departure is mistaken for one (ahead, a Gaussian's evidence for a
     * train leaving under a reported brake passes RUN_LLR within a few
     * fixes: test_held_but_moving); and only the whole run (run_rule),
     * whose slope tells a train running backwards at 3 m/s from a step
     * (over fewer, steps followed it, valid at rest:
     * test_backward_fixes_not_valid) */
    if (light && side > 0) {
        return 0;
    }
    /* and flat: the fixes against the run's first prediction carried on
     * at its speed (a held bank's prediction follows the fixes with a lag,
     * so that the offsets of a train leaving while the brake is still
     * reported stay level: test_fix_step_heavy's departure), their
     * least-squares slope over time not beyond RUN_SLOPE_Z of its sd in
     * the step's direction, the noise's spread taken robustly (its
     * quartiles: a Student-t(3)'s sd is 1.7 of its scale, its quartiles'
     * 1.1) with the prediction's. A train that leaves under a reported
     * brake, or a traction stuck or swapped, drags the fixes along a
     * ramp, and a heavy-tailed noise's fix before the run fits far out (a
     * review: late60, stuck30 and tracsign under such fixes took ramps
     * for steps) */
    {
        const real *p = f->fs.run_p, *v = f->fs.run_v, *dt = f->fs.run_dt;
        real a[RUN_MAX], tt[RUN_MAX], am = 0, tm = 0, sxy = 0, sxx = 0, t = 0;
        for (i = k - 1; i >= 0; --i) {
            t += i < k - 1 ? dt[i] : (real)0;
            tt[i] = t;
            a[i] = r[i] + p[i] - (p[k - 1] + v[k - 1] * t);
            am += a[i] / (real)k;
            tm += t / (real)k;
        }
        for (i = 0; i < k; ++i) {
            sxy += (tt[i] - tm) * (a[i] - am);
            sxx += (tt[i] - tm) * (tt[i] - tm);
        }
        if ((real)side * sxy > (real)RUN_SLOPE_Z * spread * (real)sqrt((double)sxx)) {
            return 0; /* slope sxy / sxx against its sd spread / sqrt(sxx) */
        }
    }
    /* each scored as if the prediction were exact, its spread taken out
     * by shrinking the offsets as a Gaussian's would be: + log p(e - step)
     * (i even) - log p(e) (i odd), e the noise if the reference did not
     * move (one call of the inlined density: flash). Each fix must favour
     * the step: one wild fix (a Student-t's 277 m) carried a run's mean and
     * its evidence alone, and the position stepped 141 m (stopstep12-t,
     * China Star, seed 33). */
    for (i = 0; i < 2 * k; ++i) {
        const real e = r[i / 2] - mean;
        const real lp = hstpf__dist_logpdf(&f->de, mean + shrink * (e - (i & 1 ? (real)0 : *step)));
        if ((e > (real)0 ? 1 : -1) != side) {
            return 0;
        }
        if (!(i & 1)) {
            pair = lp;
        } else if (!(pair > lp)) {
            return 0;
        } else {
            llr += pair - lp;
        }
    }
    return llr >= (real)RUN_LLR;
}

/* A run of fixes that the filters used, each beyond the noise's usual but
 * none beyond its reach: d joins the run; a step is taken when the run
 * shows one. */
static void run_rule(hstpf_t *f, double d, double var, double pred, double vel, double dt)
{
    hstpf_fix_step_t *s = &f->fs;
    const hstpf_dist_quantiles_t *q = &f->de.qt;
    const real sd = (real)f->noise_mom[5], med = hstpf__dist_sample(q, 0x80000000u);
    const real hold_hi = q->tail_hi[HOLD_TAIL] - med, hold_lo = med - q->tail_lo[HOLD_TAIL];
    const real shrink = sd / (real)sqrt((double)(sd * sd) + var);
    const real iq = (hstpf__dist_sample(q, 0xC0000000u) - hstpf__dist_sample(q, 0x40000000u)) / (real)1.349;
    const real spread = (real)sqrt((double)(iq * iq) + var);
    const real reach = (real)f->cfg.gate_m; /* a run's evidence holds a jump of any size the gate lets in */
    const real tails = hold_hi < hold_lo ? hold_hi : hold_lo;
    const int light = !(tails > (real)RUN_HEAVY_Z * sd);
    int k;
    if (light && !(tails > (real)RUN_LIGHT_Z * sd && f->standstill)) {
        s->run_n = 0; /* a run is of fixes in a row: not one from a stop before */
        return;       /* an edge, or a light tail moving: the hold rule's */
    }
    for (k = RUN_MAX; k > 0; --k) {
        s->run[k] = s->run[k - 1];
        s->run_p[k] = s->run_p[k - 1];
        s->run_v[k] = s->run_v[k - 1];
        s->run_dt[k] = s->run_dt[k - 1];
    }
    s->run[0] = (real)d;
    s->run_p[0] = (real)pred;
    s->run_v[0] = (real)vel; /* the blend's speed, from its one pass (the M4F's soft-float exp) */
    s->run_dt[0] = (real)dt;
    s->run_n = (uint8_t)(s->run_n + (s->run_n <= RUN_MAX));
    for (k = light ? RUN_MAX : 2; k <= RUN_MAX && k < (int)s->run_n; ++k) {
        real step;
        if (run_is_step(f, k, light, shrink, spread, &step) && fabs((double)step) <= (double)reach) {
            take_step(f, (double)step, (double)(sd * sd) / (double)k);
            f->fs.side = (int8_t)beyond(f, d - (double)step, var, FIT_TAIL, FIT_Z);
            ring_restart(f, d - (double)step, pred, vel, dt);
            return;
        }
    }
}

/* The step rule on d = the fix less the prediction pred (variance var). */
static int fix_step(hstpf_t *f, double d, double var, double dt, double pred, double vel)
{
    const int pend = f->fs.pend, side = f->fs.side;
    int out;
    f->fs.pend = 0;
    f->fs.side = 2; /* unknown: no hold at the next fix */
    /* not while the lock is new, doubted or lost, nor while the traction
     * is in doubt (its innovations jump too: tracsign took 752 such jumps
     * for steps, and published 6 % more wrong speeds). Across a long step
     * too: the acceleration its prediction leaves out, STEP_ACC T^2 / 2,
     * widens the reach (hstpf__fix_gate); left out before, a receive clock
     * that stepped 1-3 s at speed (which hstpfd predicts across) put every
     * later fix 60-196 m behind, and under Student-t fixes the grid
     * published that, valid, for 6-15 steps (a review) */
    if (f->pr.active || f->pr.timed || f->lost_run != 0u || f->tc.doubt || f->tc.fault || f->tc.release ||
        (f->outlier_run != 0u && !pend)) {
        f->fs.run_n = 0;
        return 0;
    }
    if (pend && beyond(f, d, var, STEP_TAIL, STEP_Z) == beyond(f, f->fs.d, 0.0, STEP_TAIL, 0.0) &&
        fabs(d - f->fs.d) <= hstpf__dist_range(&f->de.qt, STEP_TAIL)) {
        /* the second: the reference stepped by their mean offset (less
         * the noise's mean, which the filters expect in every fix) */
        const double step = 0.5 * (d + f->fs.d) - f->noise_mom[4];
        take_step(f, step, 0.5 * f->noise_mom[5] * f->noise_mom[5]);
        ring_restart(f, d - step, pred, vel, dt);
        /* this fix on the new reference: its return next is held (a
         * two-fix excursion was taken for a step, and the return for speed) */
        f->fs.side = (int8_t)beyond(f, d - step, var, FIT_TAIL, FIT_Z);
        return 0;
    }
    out = beyond(f, d, var, HOLD_TAIL, HOLD_Z);
    if (out == 0 || fabs(d) > STEP_RANGES * hstpf__dist_range(&f->de.qt, RANGE_TAIL) ||
        (!pend && (side == 2 || side == out))) {
        /* a held fix before this one was a lone outlier; one beyond it
         * that is not its step is held in its turn (a run of them
         * re-acquires: reacquire_after) */
        f->fs.side = (int8_t)beyond(f, d, var, FIT_TAIL, FIT_Z);
        run_rule(f, d, var, pred, vel, dt);
        return 0;
    }
    f->fs.run_n = 0;
    f->fs.pend = 1;
    f->fs.d = d;
    return 1;
}

void hstpf__fix_step_shift(hstpf_t *f, real d)
{
    int i;
    for (i = 0; i <= RUN_MAX; ++i) {
        f->fs.run_p[i] -= d;
    }
}

int hstpf__fix_gate(hstpf_t *f, double y, double dt)
{
    /* the blend's prediction, and what the acceleration it leaves out adds
     * (no sqrt: the M4F's double is soft-float) */
    const double acc = 0.5 * STEP_ACC * dt * dt;
    double var;
    double vel;
    const double pred = hstpf__blended_position(f, dt, &var, &vel);
    const double d = y - f->origin_m - pred;
    var += acc * acc;
    if (fabs(d) > f->cfg.gate_m) {
        f->fs.pend = 0;
        f->fs.side = 2;
        f->fs.run_n = 0;
        return 1;
    }
    return f->cfg.fix_step ? fix_step(f, d, var, dt, pred, vel) : 0;
}
