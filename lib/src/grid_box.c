/* Grid engine: where each step's new grid goes (step 1 of docs/grid.md):
 * the box between quantiles of the predicted marginals, the posterior's
 * box with a measurement, and the reach to a measurement that pulls. */
#include <math.h>
#include <string.h>

#include "grid.h"

/* Bins of a histogram on [x0, x1] at spacing at least h0, so that at most
 * nmax bins and a noise of range r fits the kernel capacity. */
static real bin_width(real x0, real x1, real h0, real r, int nmax)
{
    real h = h0;
    const real hb = (x1 - x0) / (real)(nmax - 2), hk = r / (real)(HSTPF__GRID_K - 4);
    h = hb > h ? hb : h;
    return hk > h ? hk : h;
}

/* Output bin b (0 .. n + nk - 2) of hist convolved with the kernel k:
 * sum_kk k[kk] hist[b - kk]. */
static real conv_bin(const real *hist, int n, const real *k, int nk, int b)
{
    real o = 0;
    int kk;
    for (kk = b - n + 1 > 0 ? b - n + 1 : 0; kk < nk && kk <= b; ++kk) {
        o += k[kk] * hist[b - kk];
    }
    return o;
}

/* The cut_lo and 1 - cut_hi quantiles of a histogram (bins of width h from
 * x0, n bins) convolved with the noise scale * X: the support of a
 * predicted marginal. Output bin b covers x0 + (b + m0) h .. + h. With conv
 * (n + nk - 1 values) every bin is computed and kept there, for the
 * posterior box; without, only the bins the two scans reach. */
static int noisy_quantiles(const real *hist, int n, real x0, real h, const hstpf_dist_quantiles_t *d, real scale, real tail,
                           real cut_lo, real cut_hi, real *k, int *m0_out, real *lo, real *hi, real *conv)
{
    int m0, nk, b;
    real c = 0;
    nk = hstpf__grid_kernel(d, scale, h, HSTPF__GRID_K, tail, k, &m0);
    *m0_out = m0;
    if (conv) {
        for (b = 0; b < n + nk - 1; ++b) {
            conv[b] = conv_bin(hist, n, k, nk, b);
        }
    }
    for (b = 0; b < n + nk - 1; ++b) {
        c += conv ? conv[b] : conv_bin(hist, n, k, nk, b);
        if (c > cut_lo) {
            break;
        }
    }
    *lo = x0 + (real)(b + m0) * h;
    c = 0;
    for (b = n + nk - 2; b >= 0; --b) {
        c += conv ? conv[b] : conv_bin(hist, n, k, nk, b);
        if (c > cut_hi) {
            break;
        }
    }
    *hi = x0 + (real)(b + m0 + 1) * h;
    if (*hi <= *lo) {
        *hi = *lo + h;
    }
    return nk;
}

/* With a measurement, the position box only needs to hold the posterior:
 * the predicted position marginal (hist convolved with the noise) times the
 * measurement density over each bin, cut at GRID_TAIL per side. Predicted
 * mass left outside then carries at most 2 GRID_TAIL of the likelihood, so
 * the increment changes by less than 3e-5 nats, while the cells shrink to
 * the posterior's width (Case 2: centimetres inside a metre-wide
 * prediction, whose width is the Gamma(0.02) noise's rare long jumps).
 * Nothing changes when the measurement misses the prediction (the retry
 * and the reach to the measurement handle that). */
static void posterior_box(hstpf_t *f, real *out, int nb, real x0, real h, int m0, real yr, real *s_lo, real *s_hi)
{
    const real lfloor = hstpf__exp_neg(f->de.floor - f->de.lp_max);
    real sum = 0, cut, c;
    int b, bl, bh;
    for (b = 0; b < nb; ++b) { /* bin b covers x0 + (b + m0) h .. + h; out[b] the predicted mass */
        const real x = x0 + (real)(b + m0) * h, o = out[b];
        real lik;
        lik = o > (real)0 ? hstpf__grid_cell_loglik(&f->de, yr - (x + h), yr - x) - f->de.lp_max : (real)-3e38;
        lik = lik > (real)-80 ? hstpf__exp_neg(lik < (real)0 ? lik : (real)0) : (real)0;
        out[b] = lik > lfloor ? o * lik : (real)0;
        sum += out[b];
    }
    if (!(sum > (real)0)) {
        return;
    }
    cut = GRID_TAIL * sum;
    for (bl = 0, c = 0; bl < nb - 1 && c + out[bl] <= cut; ++bl) {
        c += out[bl];
    }
    for (bh = nb - 1, c = 0; bh > bl && c + out[bh] <= cut; --bh) {
        c += out[bh];
    }
    *s_lo = x0 + (real)(bl + m0) * h;
    *s_hi = x0 + (real)(bh + m0 + 1) * h;
}

/* The box of the predicted density: the f->grid.tail quantiles of its two
 * marginals, from the occupied cells (f->grid.first/last, vimg) moved by the
 * dynamics and convolved with the noise. On entry *s_lo.. hold the bounding
 * box of the moved cells. Uses f->grid.work as scratch. Quantiles, not mean
 * +- k sd: a one-sided noise's spike stays inside. */
static void predicted_box(hstpf_t *f, uint16_t l, real dt, real scale, real tot, int has_y, real yr, real mid,
                          real rest_v, real *s_lo, real *s_hi, real *v_lo, real *v_hi)
{
    const real *p = f->grid.p[l], *g = f->grid.geom[l], *rest = f->grid.rest[l];
    const int nmax = NS * NV / 4;
    real *hist = f->grid.work;
    const real tail = f->grid.tail; /* the kernels reach as far as the box */
    const real rs = scale * (hstpf__grid_tail_quantile(&f->ds, 1, tail) - hstpf__grid_tail_quantile(&f->ds, 0, tail));
    const real rv = scale * (hstpf__grid_tail_quantile(&f->dv, 1, tail) - hstpf__grid_tail_quantile(&f->dv, 0, tail));
    real h, x0;
    int n, j, b, pull = 0;
    /* positions: each occupied row shifted by T times its centre speed */
    x0 = *s_lo;
    h = bin_width(*s_lo, *s_hi, g[1], rs, nmax);
    {
        const real nn = (*s_hi - *s_lo) / h; /* NaN-safe: never more than nmax bins */
        n = nn >= (real)0 && nn < (real)(nmax - 2) ? (int)nn + 2 : nmax;
    }
    memset(hist, 0, (size_t)n * sizeof *hist);
    for (j = 0; j < NV; ++j) {
        const real sh = dt * (g[2] + ((real)j + (real)0.5) * g[3]);
        if (f->grid.first[j] <= f->grid.last[j]) {
            hstpf__grid_remap(p + j * NS, f->grid.first[j], f->grid.last[j], (g[0] + sh - x0) / h, g[1] / h, hist, n);
        }
    }
    hstpf__grid_remap(rest, 0, NS - 1, (g[0] - x0) / h, g[1] / h, hist, n); /* at rest: no shift */
    {
        /* the side the measurement lies on keeps its tail to WIDE_TAIL: a
         * model the measurements pull away from its prediction has its
         * posterior there (cutting it would bias every misfit model) */
        real cut_lo = tail * tot, cut_hi = cut_lo;
        if (has_y) {
            double m1 = 0.0, m2 = 0.0, sd;
            for (b = 0; b < n; ++b) {
                const double x = (double)x0 + ((double)b + 0.5) * (double)h;
                m1 += (double)hist[b] * x;
                m2 += (double)hist[b] * x * x;
            }
            m1 /= (double)tot;
            sd = sqrt(fmax(m2 / (double)tot - m1 * m1, 0.0) + (double)(scale * f->ds.sd) * (double)(scale * f->ds.sd));
            m1 += (double)(scale * f->ds.mean);
            if ((double)mid > m1 + PULL_SD * sd) {
                cut_hi = WIDE_TAIL * tot;
                pull = 1;
            } else if ((double)mid < m1 - PULL_SD * sd) {
                cut_lo = WIDE_TAIL * tot;
                pull = -1;
            }
        }
        const int post = has_y && tail > WIDE_TAIL;
        real *conv = post ? f->grid.work + NS * NV / 2 : NULL; /* after hist's nmax bins */
        int m0, nk = noisy_quantiles(hist, n, x0, h, &f->ds, scale, tail, cut_lo, cut_hi, f->grid.ks, &m0, s_lo, s_hi, conv);
        if (post) { /* the predicted box's convolution, weighted in place */
            posterior_box(f, conv, n + nk - 1, x0, h, m0, yr, s_lo, s_hi);
        }
    }
    /* speeds: each occupied row spread over its image [vimg_j, vimg_j+1] */
    x0 = *v_lo;
    h = bin_width(*v_lo, *v_hi, g[3], rv, nmax);
    {
        const real nn = (*v_hi - *v_lo) / h;
        n = nn >= (real)0 && nn < (real)(nmax - 2) ? (int)nn + 2 : nmax;
    }
    memset(hist, 0, (size_t)n * sizeof *hist);
    for (j = 0; j < NV; ++j) {
        real ta, tb, rm;
        if (f->grid.first[j] > f->grid.last[j]) {
            continue;
        }
        rm = hstpf__grid_sum(p + j * NS + f->grid.first[j], f->grid.last[j] - f->grid.first[j] + 1);
        ta = ((f->grid.vimg[j] > (real)0 ? f->grid.vimg[j] : (real)0) - x0) / h;
        tb = ((f->grid.vimg[j + 1] > (real)0 ? f->grid.vimg[j + 1] : (real)0) - x0) / h;
        if (ta > tb) {
            const real t = ta;
            ta = tb;
            tb = t;
        }
        if (tb - ta < (real)1e-6) {
            b = ta > (real)0 ? (int32_t)ta : 0;
            hist[b < n ? b : n - 1] += rm;
            continue;
        }
        hstpf__grid_remap(&rm, 0, 0, ta, tb - ta, hist, n);
    }
    if (rest_v >= (real)0) { /* the mass at rest starts moving */
        real rm = 0;
        for (j = 0; j < NS; ++j) {
            rm += rest[j];
        }
        {
            const real bb = (rest_v - x0) / h; /* NaN-safe: a box gone non-finite takes bin 0 */
            b = bb > (real)0 ? (bb < (real)(n - 1) ? (int32_t)bb : n - 1) : 0;
        }
        hist[b] += rm;
    }
    /* the pull moves the speed the same way (through the s-v correlation) */
    (void)noisy_quantiles(hist, n, x0, h, &f->dv, scale, tail, (pull < 0 ? WIDE_TAIL : tail) * tot,
                          (pull > 0 ? WIDE_TAIL : tail) * tot, f->grid.kv, &j, v_lo, v_hi, NULL);
}

/* The geometry g = (s0, ds, v0, dv) of the box [s_lo, s_hi] x [v_lo,
 * v_hi], its cells no narrower than DS_MIN and DV_MIN (widened about the
 * centre, the speeds kept at 0 or above). */
void hstpf__grid_geometry(real s_lo, real s_hi, real v_lo, real v_hi, real *g)
{
    if (s_hi - s_lo < DS_MIN * (real)NS) {
        s_lo = (real)0.5 * (s_lo + s_hi) - (real)0.5 * DS_MIN * (real)NS;
        s_hi = s_lo + DS_MIN * (real)NS;
    }
    if (v_hi - v_lo < DV_MIN * (real)NV) {
        v_lo = (real)0.5 * (v_lo + v_hi) - (real)0.5 * DV_MIN * (real)NV;
        v_lo = v_lo > (real)0 ? v_lo : (real)0;
        v_hi = v_lo + DV_MIN * (real)NV;
    }
    g[0] = s_lo;
    g[1] = (s_hi - s_lo) / (real)NS;
    g[2] = v_lo;
    g[3] = (v_hi - v_lo) / (real)NV;
}

/* The speed cells of ng moved onto the lattice of the old cells' images
 * under the model's map (vimg, from the first occupied row): their width
 * the images' times 2^k, the smallest that holds ng's speed range with a
 * cell to spare, and the origin on that lattice. The transport then moves
 * each row onto whole cells (halves or pairs), instead of sharing it
 * between two at every step: that smear, about a cell per step, washed
 * out the 1 mm/s per step by which CRH3 and CRH5 differ at the start of
 * paper Case 2 (docs/grid.md, "Where paper Case 2's seconds go"). Left as
 * it is (a remap, this step) when no row is occupied, when the cells would
 * be narrower than DV_MIN or coarser than LATTICE_COARSEST times the box's
 * own (the lattice's cells are up to twice as wide: resolution traded for
 * the smear, and uncapped it once declared CRH5 for 40 s on paper Case 2,
 * seed 1766), or when the lattice's box would start below 0. */
void hstpf__grid_speed_lattice(const int16_t *first, const int16_t *last, const real *vimg, real *ng)
{
    const real need = ng[3] * (real)NV;
    int j, k;
    for (j = 0; j < NV && first[j] > last[j]; ++j) {
    }
    if (j == NV) {
        return;
    }
    {
        const real a = vimg[j];
        real h = vimg[j + 1] - vimg[j];
        for (k = 0; k < 16 && h > (real)0 && (real)(NV - 1) * h < need; ++k) {
            h *= (real)2;
        }
        for (k = 0; k < 16 && (real)(NV - 1) * h * (real)0.5 >= need; ++k) {
            h *= (real)0.5;
        }
        if (h >= DV_MIN && (real)(NV - 1) * h >= need && h <= LATTICE_COARSEST * ng[3]) {
            const real v0 = a + (real)floor((double)((ng[2] - a) / h)) * h;
            /* the second test follows from the floor but for its rounding */
            if (v0 >= (real)0 && v0 + (real)NV * h >= ng[2] + need) {
                ng[2] = v0;
                ng[3] = h;
            }
        }
    }
}

/* Step 1: the new box from the transported support plus the noise
 * quantiles, into ng (s0, ds, v0, dv); sets f->grid.first/last (the
 * occupied cells of each row) and vimg for the transport. A cell is
 * occupied when it holds more than f->grid.tail / cells of the mass, so
 * that at most the box's own tail is left behind; the box is the bounding box of the
 * occupied cells after the dynamics (each row moved by T times its centre
 * speed), so a correlated posterior does not inflate it. */
void hstpf__grid_new_box(hstpf_t *f, const hstpf_model_t *m, uint16_t l, real dt, real acc, real scale, int has_y,
                         real yr, real *ng, real *tot_out, real *rtot_out)
{
    const real *p = f->grid.p[l], *g = f->grid.geom[l], *rest = f->grid.rest[l];
    real *vimg = f->grid.vimg;
    int16_t *first = f->grid.first, *last = f->grid.last;
    real tot = 0, rtot = 0, thr, s_lo = (real)3e38, s_hi = (real)-3e38, v_lo = (real)3e38,
         v_hi = (real)-3e38;
    const real mid = yr - hstpf__dist_sample(&f->de.qt, 0x80000000u); /* y less e's median */
    const real a0 = acc - m->k0;                                   /* net acceleration at rest */
    const real rest_v = a0 > (real)0 ? dt * a0 : (real)-1;         /* < 0: the rest mass is held */
    int i, j, any = 0, held;
    tot = hstpf__grid_sum(p, NS * NV);
    rtot = hstpf__grid_sum(rest, NS);
    tot += rtot;
    thr = f->grid.tail * tot / (real)(NS * NV);
    for (j = 0; j < NV; ++j) {
        const real *r = p + j * NS, sh = dt * (g[2] + ((real)j + (real)0.5) * g[3]);
        int a = 0, b = NS - 1;
        while (a <= b && r[a] <= thr) {
            ++a;
        }
        while (b >= a && r[b] <= thr) {
            --b;
        }
        first[j] = (int16_t)a;
        last[j] = (int16_t)b;
        if (a > b) {
            continue;
        }
        any = 1;
        vimg[j] = hstpf__grid_speed_map(m, g[2] + (real)j * g[3], dt, acc);
        vimg[j + 1] = hstpf__grid_speed_map(m, g[2] + (real)(j + 1) * g[3], dt, acc);
        s_lo = g[0] + (real)a * g[1] + sh < s_lo ? g[0] + (real)a * g[1] + sh : s_lo;
        s_hi = g[0] + (real)(b + 1) * g[1] + sh > s_hi ? g[0] + (real)(b + 1) * g[1] + sh : s_hi;
        for (i = j; i <= j + 1; ++i) {
            const real vi = vimg[i] > (real)0 ? vimg[i] : (real)0; /* never below 0 */
            v_lo = vi < v_lo ? vi : v_lo;
            v_hi = vi > v_hi ? vi : v_hi;
        }
    }
    held = !any && rest_v < (real)0; /* every occupied cell at rest and held */
    if (rtot > thr) { /* the mass at rest: no shift; it starts at rest_v if it moves */
        int a = 0, b = NS - 1;
        while (a < b && rest[a] <= thr) {
            ++a;
        }
        while (b > a && rest[b] <= thr) {
            --b;
        }
        s_lo = g[0] + (real)a * g[1] < s_lo ? g[0] + (real)a * g[1] : s_lo;
        s_hi = g[0] + (real)(b + 1) * g[1] > s_hi ? g[0] + (real)(b + 1) * g[1] : s_hi;
        v_lo = rest_v > (real)0 && rest_v < v_lo ? rest_v : (v_lo < (real)3e38 ? v_lo : (real)0);
        v_hi = rest_v > v_hi ? rest_v : (v_hi > (real)-3e38 ? v_hi : (real)0);
        any = 1;
        if (held && has_y) {
            /* held: the prediction is the posterior itself (no motion, no
             * noise), so the new box is the part of these cells the
             * measurement leaves above the tail, at their own width; a box
             * from the noisy prediction (the noise's range in bins, and a
             * reach to the measurement) re-gridded a train standing still
             * onto cells of centimetres at every fix, smearing it by a
             * cell each time (docs/grid.md, pitfall 5) */
            memcpy(f->grid.work, rest, sizeof(real) * NS);
            posterior_box(f, f->grid.work, NS, g[0], g[1], 0, yr, &s_lo, &s_hi);
        }
    }
    if (!any) { /* cannot happen (normalised mass); keep the old box */
        s_lo = g[0];
        s_hi = g[0] + (real)NS * g[1];
        v_lo = g[2];
        v_hi = g[2] + (real)NV * g[3];
    } else if (!held) {
        predicted_box(f, l, dt, scale, tot, has_y, yr, mid, rtot > (real)0 ? rest_v : (real)-1, &s_lo, &s_hi, &v_lo,
                      &v_hi);
    }
    if (has_y && !held) {
        /* a measurement whose middle lies beyond the predicted box pulls
         * the posterior out of it: the box reaches to the measurement's
         * 1 %..99 % range, or the model could never catch up */
        if (mid < s_lo || mid > s_hi) {
            const real e_hi = hstpf__dist_sample(&f->de.qt, 0xFD70A3D7u), e_lo = hstpf__dist_sample(&f->de.qt, 0x028F5C29u);
            s_lo = yr - e_hi < s_lo ? yr - e_hi : s_lo;
            s_hi = yr - e_lo > s_hi ? yr - e_lo : s_hi;
        }
    }
    v_lo = v_lo > (real)0 ? v_lo : (real)0; /* a train never reverses: the box starts at 0 at most */
    hstpf__grid_geometry(s_lo, s_hi, v_lo, v_hi, ng);
    if (f->cfg.grid_speed_lattice && !held) {
        hstpf__grid_speed_lattice(first, last, vimg, ng);
    }
    *tot_out = tot;
    *rtot_out = rtot;
}
