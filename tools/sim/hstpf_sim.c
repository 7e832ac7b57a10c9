#include "hstpf_sim.h"

#include <math.h>
#include <string.h>

#define SIM_STREAM 0x5151u /* far from the filter's streams 0..16 */

static double u01(hstpf_rng_t *r) /* (0, 1), 53 bits */
{
    const uint64_t hi = hstpf_rng_next(r) >> 5, lo = hstpf_rng_next(r) >> 6;
    return ((double)(hi * 67108864u + lo) + 0.5) / 9007199254740992.0;
}

double hstpf_sim_gauss(hstpf_rng_t *r)
{
    return sqrt(-2.0 * log(u01(r))) * cos(6.283185307179586 * u01(r));
}

/* Marsaglia and Tsang (2000); shape < 1 via Gamma(k+1) * U^(1/k). */
double hstpf_sim_gamma(hstpf_rng_t *r, double k)
{
    double boost = 1.0, d, c;
    if (k < 1.0) {
        boost = exp(log(u01(r)) / k);
        k += 1.0;
    }
    d = k - 1.0 / 3.0;
    c = 1.0 / sqrt(9.0 * d);
    for (;;) {
        double x, v, u;
        do {
            x = hstpf_sim_gauss(r);
            v = 1.0 + c * x;
        } while (v <= 0.0);
        v = v * v * v;
        u = u01(r);
        if (log(u) < 0.5 * x * x + d - d * v + d * log(v)) {
            return d * v * boost;
        }
    }
}

double hstpf_sim_noise(hstpf_rng_t *r, const hstpf_dist_spec_t *d)
{
    if (d->kind == HSTPF_DIST_GAMMA) {
        return d->loc + d->scale * hstpf_sim_gamma(r, d->shape);
    }
    return d->mean + d->sd * hstpf_sim_gauss(r);
}

double hstpf_sim_heavy_pdf(const hstpf_sim_heavy_t *h, double x)
{
    static const double pi = 3.14159265358979323846;
    if (h->kind == HSTPF_SIM_HEAVY_T) {
        const double z = x / h->scale, nu = h->nu;
        const double lc = lgamma(0.5 * (nu + 1.0)) - lgamma(0.5 * nu) - 0.5 * log(nu * pi);
        return exp(lc - 0.5 * (nu + 1.0) * log1p(z * z / nu)) / h->scale;
    }
    {
        const double a = x / h->sd, b = x / h->wide_sd, k = 1.0 / sqrt(2.0 * pi);
        return (1.0 - h->p_wide) * k * exp(-0.5 * a * a) / h->sd + h->p_wide * k * exp(-0.5 * b * b) / h->wide_sd;
    }
}

double hstpf_sim_heavy_draw(hstpf_rng_t *r, const hstpf_sim_heavy_t *h)
{
    if (h->kind == HSTPF_SIM_HEAVY_T) {
        /* z / sqrt(chi2(nu) / nu), chi2(nu) = 2 Gamma(nu / 2) */
        const double z = hstpf_sim_gauss(r), g = hstpf_sim_gamma(r, 0.5 * h->nu);
        return h->scale * z / sqrt(2.0 * g / h->nu);
    }
    {
        const int wide = u01(r) < h->p_wide; /* the component first, then its draw */
        return (wide ? h->wide_sd : h->sd) * hstpf_sim_gauss(r);
    }
}

void hstpf_sim_heavy_table(const hstpf_sim_heavy_t *h, hstpf_sim_table_t *tab, hstpf_dist_spec_t *spec)
{
    const double c = h->kind == HSTPF_SIM_HEAVY_T ? h->scale : h->sd;
    const double a = asinh(h->range / c);
    int i;
    for (i = 0; i < HSTPF_SIM_TABLE_N; ++i) {
        const int j = i - HSTPF_SIM_TABLE_N / 2; /* symmetric: x[mid] = 0 exactly */
        const double x = c * sinh(a * (double)j / (double)(HSTPF_SIM_TABLE_N / 2));
        tab->x[i] = x;
        tab->p[i] = hstpf_sim_heavy_pdf(h, x);
    }
    memset(spec, 0, sizeof *spec);
    spec->kind = HSTPF_DIST_TABLE;
    spec->table_x = tab->x;
    spec->table_p = tab->p;
    spec->table_n = HSTPF_SIM_TABLE_N;
}

static void gauss(hstpf_dist_spec_t *d, double var)
{
    memset(d, 0, sizeof *d);
    d->kind = HSTPF_DIST_GAUSSIAN;
    d->sd = sqrt(var);
}

static void gam(hstpf_dist_spec_t *d, double shape, double scale)
{
    memset(d, 0, sizeof *d);
    d->kind = HSTPF_DIST_GAMMA;
    d->shape = shape;
    d->scale = scale;
}

void hstpf_sim_case1(hstpf_sim_config_t *c)
{
    gauss(&c->noise_s, 0.02);
    gauss(&c->noise_v, 0.05);
    gauss(&c->noise_e, 5.0);
}

void hstpf_sim_case2(hstpf_sim_config_t *c)
{
    gam(&c->noise_s, 0.02, 0.1);
    gam(&c->noise_v, 0.1, 0.05);
    gam(&c->noise_e, 0.5, 0.2);
}

void hstpf_sim_heavy(hstpf_sim_config_t *c, hstpf_sim_heavy_kind_t k, hstpf_sim_table_t *tab)
{
    hstpf_sim_heavy_t *h = &c->heavy_e;
    hstpf_sim_case1(c);
    memset(h, 0, sizeof *h);
    h->kind = k;
    h->nu = HSTPF_SIM_T_NU;
    h->scale = HSTPF_SIM_T_SCALE;
    h->sd = sqrt(5.0);
    h->wide_sd = HSTPF_SIM_MIX_WIDE * h->sd;
    h->p_wide = HSTPF_SIM_MIX_P;
    h->range = HSTPF_SIM_HEAVY_RANGE;
    hstpf_sim_heavy_table(h, tab, &c->noise_e);
}

void hstpf_sim_default(hstpf_sim_config_t *c)
{
    memset(c, 0, sizeof *c);
    c->truth = hstpf_train_types[2]; /* CRH3 */
    c->gamma_rot = 0.06;
    hstpf_sim_case1(c);
    c->profile = HSTPF_PROFILE_PAPER;
    c->dt_s = 1.0;
    c->seed = 1;
    c->hold_brake = HSTPF_SIM_HOLD_BRAKE;
}

void hstpf_sim_init(hstpf_sim_t *sim, const hstpf_sim_config_t *c)
{
    memset(sim, 0, sizeof *sim);
    sim->cfg = *c;
    sim->xi = 9.81 / (1.0 + c->gamma_rot) / 1000.0;
    sim->v = c->v0_mps > 0.0 ? c->v0_mps : 0.0;
    sim->leg = c->first_dwell_s >= 0.0 ? -1 : 0;
    sim->phase = sim->leg < 0 ? HSTPF_SIM_DWELL : HSTPF_SIM_RUN;
    sim->phase_t0 = sim->leg < 0 && sim->v > 0.0 ? -1.0 : 0.0;
    (void)hstpf_rng_seed(&sim->rng, c->seed, SIM_STREAM);
}

#define KMH(x) ((x) / 3.6)
#define A_PAPER (KMH(350.0) / 396.0) /* 0 -> 350 km/h in 396 s */
#define KP 0.5                       /* speed-holding gain, 1/s */

static double track_to(double target, double v, double amax, double bmax)
{
    double a = KP * (target - v);
    return a > amax ? amax : (a < -bmax ? -bmax : a);
}

double hstpf_sim_accel_cmd(hstpf_profile_t p, double t, double v, int *coast)
{
    *coast = 0;
    switch (p) {
    case HSTPF_PROFILE_COAST_BRAKE:
        if (t < 600.0) {
            return track_to(KMH(300.0), v, 0.3, 0.5);
        }
        if (t < 900.0) {
            *coast = 1;
            return 0.0;
        }
        if (t < 1100.0) {
            return track_to(KMH(150.0), v, 0.3, 0.5);
        }
        if (t < 1500.0) {
            return track_to(KMH(350.0), v, 0.3, 0.5);
        }
        if (t < 1650.0) {
            *coast = 1;
            return 0.0;
        }
        return track_to(KMH(200.0), v, 0.3, 0.5);
    case HSTPF_PROFILE_STOPS: {
        /* 600 s cycle: run at 250 km/h, brake to a stop, dwell 60 s */
        const double tc = fmod(t, 600.0);
        if (tc < 420.0) {
            return track_to(KMH(250.0), v, 0.3, 0.5);
        }
        if (tc < 540.0) {
            return v > 0.0 ? track_to(0.0, v, 0.3, 0.6) : 0.0;
        }
        return v > 0.0 ? -0.3 : 0.0;
    }
    default:
        return track_to(KMH(350.0), v, A_PAPER, 0.5);
    }
}

/* The journey's commanded acceleration at the current sample (advancing the
 * timetable); *hold set while standing (the holding brake is reported). */
static double journey_accel(hstpf_sim_t *sim, int *hold)
{
    const hstpf_sim_config_t *c = &sim->cfg;
    *hold = 0;
    if (sim->phase == HSTPF_SIM_DWELL) {
        const double dwell = sim->leg < 0 ? c->first_dwell_s : c->legs[sim->leg].dwell_s;
        if (sim->phase_t0 < 0.0 && sim->v == 0.0) {
            sim->phase_t0 = sim->t; /* came to rest: the dwell starts */
        }
        if (sim->phase_t0 < 0.0 || sim->t - sim->phase_t0 < dwell || sim->leg + 1 >= (int)c->n_legs) {
            *hold = 1;
            return 0.0;
        }
        ++sim->leg; /* depart */
        sim->phase = HSTPF_SIM_RUN;
        sim->phase_t0 = sim->t;
    }
    if (sim->phase == HSTPF_SIM_RUN) {
        const hstpf_sim_leg_t *l = &c->legs[sim->leg];
        if (l->dwell_s < 0.0 || sim->t - sim->phase_t0 < l->run_s) {
            return track_to(KMH(l->cruise_kmh), sim->v, HSTPF_SIM_ACCEL, HSTPF_SIM_BRAKE);
        }
        sim->phase = HSTPF_SIM_BRAKING;
    }
    if (sim->v > HSTPF_SIM_BRAKE * c->dt_s) {
        return -HSTPF_SIM_BRAKE;
    }
    /* the next step would stop the train: the holding brake from here */
    sim->phase = HSTPF_SIM_DWELL;
    sim->phase_t0 = sim->v == 0.0 ? sim->t : -1.0;
    *hold = 1;
    return 0.0;
}

int hstpf_sim_held(const hstpf_theta_t *truth, double v, double u, double g)
{
    return v == 0.0 && u - truth->c0 - g <= 0.0;
}

double hstpf_sim_track(const hstpf_sim_config_t *c, double s)
{
    double g = 0.0;
    uint16_t j;
    for (j = 0; j < c->n_track && s >= c->track[j].start_m; ++j) {
        g = c->track[j].gradient_permille +
            (c->track[j].curve_radius_m > 0.0 ? 600.0 / c->track[j].curve_radius_m : 0.0);
    }
    return g;
}

void hstpf_sim_next(hstpf_sim_t *sim, hstpf_sim_sample_t *o)
{
    const hstpf_sim_config_t *c = &sim->cfg;
    const double w = hstpf_resistance(&c->truth, sim->v);
    const double g = hstpf_sim_track(c, sim->s);
    int coast = 0, hold = 0;
    double a, ws, wv;
    if (c->profile == HSTPF_PROFILE_JOURNEY && c->n_legs > 0u) {
        a = journey_accel(sim, &hold);
    } else {
        a = hstpf_sim_accel_cmd(c->profile, sim->t, sim->v, &coast);
    }
    /* traction that gives the commanded acceleration at the true state */
    o->u = hold ? c->hold_brake : (coast ? 0.0 : a / sim->xi + w + g);
    if (o->u > HSTPF_U_MAX) {
        o->u = HSTPF_U_MAX;
    } else if (o->u < -HSTPF_U_MAX) {
        o->u = -HSTPF_U_MAX;
    }
    o->t = sim->t;
    o->s = sim->s;
    o->v = sim->v;
    o->y = sim->s + (c->heavy_e.kind != HSTPF_SIM_HEAVY_NONE ? hstpf_sim_heavy_draw(&sim->rng, &c->heavy_e)
                                                              : hstpf_sim_noise(&sim->rng, &c->noise_e));
    o->has_y = !(c->loss_rate > 0.0 && u01(&sim->rng) < c->loss_rate);
    o->held = hstpf_sim_held(&c->truth, sim->v, o->u, g);
    /* drawn on every step, so the stream does not depend on the stops */
    ws = hstpf_sim_noise(&sim->rng, &c->noise_s);
    wv = hstpf_sim_noise(&sim->rng, &c->noise_v);
    if (!o->held) {
        /* the model of the filter, with the true coefficients */
        const double vd = sim->v + c->dt_s * sim->xi * (o->u - w - g) + wv;
        sim->s += c->dt_s * sim->v + ws;
        sim->v = vd > 0.0 ? vd : 0.0;
    }
    sim->t += c->dt_s;
    ++sim->k;
}

void hstpf_sim_next_input(hstpf_sim_t *sim, hstpf_sim_sample_t *smp, hstpf_input_t *in)
{
    in->dt_s = sim->k == 0u ? 1.0 : sim->cfg.dt_s;
    hstpf_sim_next(sim, smp);
    in->traction = sim->u_prev;
    in->position_m = smp->y;
    in->has_position = (uint8_t)smp->has_y;
    in->traction_unknown = 0;
    sim->u_prev = smp->u;
}
