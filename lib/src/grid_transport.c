/* Grid engine: the time update's transport (step 2 of docs/grid.md): each
 * cell moved by the deterministic dynamics and its mass shared among the
 * new cells it overlaps (a conservative remap). */
#include <math.h>
#include <string.h>

#include "grid.h"

/* floor(x) for x within int32_t's range, without a branch (so that a loop
 * calling it still vectorises) */
static int32_t floor_i(real x)
{
    const int32_t k = (int32_t)x;
    return k - ((real)k > x);
}

/* The remap below for w = 1 (input cells as wide as the output's: the box's
 * position histogram, nearly always), when input cell i0 + t lands on
 * output cells k0 + t and k0 + t + 1 for every t. Each cell's two shares
 * are those of the loop below, computed without a conditional on a float
 * (under C's default trapping maths that keeps a loop from being
 * vectorised). The upper shares are added first, then the lower, which
 * gives every output cell its additions in the loop's order (the upper
 * share of cell t - 1, then the lower of cell t), in two contiguous loops
 * that vectorise. Returns 0 (nothing added) otherwise. The same for any
 * w <= 1, with the shares added through their indices, cost more
 * instructions than the loop (callgrind). */
static int remap_unit(const real *in, int i0, int i1, real a, real *out, int n_out)
{
    real lo[NS], up[NS];
    const int n = i1 - i0 + 1;
    int t, k0;
    int32_t bad = 0;
    if (n < 1 || n > NS || !(a + (real)i0 >= (real)0) || !(a + (real)i1 < (real)(n_out - 1))) {
        return 0; /* (and every conversion below is in range) */
    }
    k0 = floor_i(a + (real)i0);
    for (t = 0; t < n; ++t) {
        const real x0 = a + (real)(i0 + t), m = in[i0 + t];
        const int32_t k = floor_i(x0);
        const real fr = (real)(k + 1) - x0;       /* times 1 / w = 1; <= 1, so the loop's cap is a no-op */
        const real keep = (real)!(m <= MASS_MIN); /* the loop skips these: add zeros */
        const real pl = m * fr;
        bad |= k ^ (k0 + t);
        lo[t] = pl * keep;
        up[t] = (m - pl) * keep;
    }
    if (bad != 0) {
        return 0;
    }
    for (t = 0; t < n; ++t) {
        out[k0 + 1 + t] += up[t];
    }
    for (t = 0; t < n; ++t) {
        out[k0 + t] += lo[t];
    }
    return 1;
}

/* Conservative remap: input cell i covers [a + i w, a + (i + 1) w] in units
 * of output cells; its mass goes to the output cells it overlaps, in
 * proportion. Mass beyond the output is dropped, and all of it where a or
 * w is not finite (a state gone non-finite, which the bank then resets:
 * floor_i() of a NaN is undefined; the fuzz harness found one through the
 * speed box's images) */
void hstpf__grid_remap(const real *in, int i0, int i1, real a, real w, real *out, int n_out)
{
    const real inv = (real)1 / w;
    int i;
    if (!(a > (real)-3e38 && a < (real)3e38 && w > (real)0 && w < (real)3e38)) {
        return;
    }
    if (w == (real)1 && remap_unit(in, i0, i1, a, out, n_out)) {
        return;
    }
    for (i = i0; i <= i1; ++i) {
        const real x0 = a + (real)i * w, x1 = x0 + w, m = in[i];
        int k;
        if (m <= MASS_MIN || x1 <= (real)0 || x0 >= (real)n_out) {
            continue;
        }
        k = floor_i(x0);
        if (w <= (real)1 && k >= 0 && k + 1 < n_out) { /* one or two cells, without a branch on which */
            real fr = ((real)(k + 1) - x0) * inv;
            fr = fr < (real)1 ? fr : (real)1;
            out[k] += m * fr;
            out[k + 1] += m - m * fr;
        } else if (x1 <= (real)(k + 1)) { /* inside one output cell */
            out[k] += m;
        } else if (w <= (real)1 || x1 <= (real)(k + 2)) { /* across one edge */
            const real fr = ((real)(k + 1) - x0) * inv;
            if (k >= 0) {
                out[k] += m * fr;
            }
            if (k + 1 < n_out) {
                out[k + 1] += m - m * fr;
            }
        } else {
            for (k = k > 0 ? k : 0; k < n_out && (real)k < x1; ++k) {
                const real lo = x0 > (real)k ? x0 : (real)k;
                const real hi = x1 < (real)(k + 1) ? x1 : (real)(k + 1);
                if (hi > lo) {
                    out[k] += m * (hi - lo) * inv;
                }
            }
        }
    }
}

/* Step 2: the cells transported by the dynamics into f->grid.work, on the
 * new grid ng (from hstpf__grid_new_box, which set first/last and vimg);
 * the mass that comes to rest goes to rnew (held) and rpend (to be
 * diffused). tot, rtot: the model's mass and its mass at rest. Returns the
 * fraction of the mass held or come to rest. */
real hstpf__grid_transport(hstpf_t *f, const hstpf_model_t *m, uint16_t l, real dt, real acc, const real *ng, real tot,
                           real rtot)
{
    const real *p = f->grid.p[l], *g = f->grid.geom[l], *rest = f->grid.rest[l];
    real *w = f->grid.work, *row = f->grid.row;
    const real *vimg = f->grid.vimg;
    const int16_t *first = f->grid.first, *last = f->grid.last;
    int16_t *box = f->grid.box;
    const real a0 = acc - m->k0;                           /* net acceleration at rest */
    const real rest_v = a0 > (real)0 ? dt * a0 : (real)-1; /* < 0: the rest mass is held */
    real held = 0;
    int i, j;
    memset(w, 0, sizeof(real) * NS * NV);
    memset(f->grid.rnew, 0, sizeof f->grid.rnew);
    memset(f->grid.rpend, 0, sizeof f->grid.rpend);
    box[0] = NV; /* rows, then columns, of work that receive mass */
    box[1] = -1;
    box[2] = NS;
    box[3] = -1;
    for (j = 0; j < NV; ++j) {
        real lo_v, hi_v, f0 = 0, rm = 0, ta, tb;
        const real a = (g[0] + dt * (g[2] + ((real)j + (real)0.5) * g[3]) - ng[0]) / ng[1];
        int k, c0, c1;
        if (first[j] > last[j]) {
            continue;
        }
        lo_v = vimg[j] < vimg[j + 1] ? vimg[j] : vimg[j + 1];
        hi_v = vimg[j] < vimg[j + 1] ? vimg[j + 1] : vimg[j];
        if (hi_v <= (real)0) { /* the whole row comes to rest within the step */
            f0 = 1;
        } else if (lo_v < (real)0) {
            f0 = -lo_v / (hi_v - lo_v);
            lo_v = 0;
        }
        /* columns this row reaches */
        c0 = (int)(a + (real)first[j] * g[1] / ng[1]);
        c1 = (int)(a + (real)(last[j] + 1) * g[1] / ng[1]);
        c0 = c0 < 0 ? 0 : (c0 > NS - 1 ? NS - 1 : c0);
        c1 = c1 < 0 ? 0 : (c1 > NS - 1 ? NS - 1 : c1);
        memset(row, 0, sizeof f->grid.row);
        hstpf__grid_remap(p + j * NS, first[j], last[j], a, g[1] / ng[1], row, NS);
        if (f0 > (real)0) { /* s' = s + T v, v' = 0: to rest, position noise to come */
            for (i = c0; i <= c1; ++i) {
                f->grid.rpend[i] += f0 * row[i];
                rm += row[i];
            }
            held += f0 * rm;
            if (f0 >= (real)1) {
                continue;
            }
        }
        box[2] = (int16_t)(c0 < box[2] ? c0 : box[2]);
        box[3] = (int16_t)(c1 > box[3] ? c1 : box[3]);
        ta = (lo_v - ng[2]) / ng[3];
        tb = (hi_v - ng[2]) / ng[3];
        if (tb - ta < (real)1e-6) { /* the whole row maps to one speed */
            ta = tb = ta < (real)0 ? (real)0 : (ta > (real)(NV - 1) ? (real)(NV - 1) : ta);
        }
        for (k = ta > (real)0 ? (int32_t)ta : 0; k < NV && (k == (int32_t)ta || (real)k < tb); ++k) {
            const real lo = ta > (real)k ? ta : (real)k, hi = tb < (real)(k + 1) ? tb : (real)(k + 1);
            const real frac = (tb > ta ? (hi - lo) / (tb - ta) : (real)1) * ((real)1 - f0);
            if (frac > (real)0) {
                hstpf__grid_axpy_row(w + k * NS, row, frac);
                box[0] = (int16_t)(k < box[0] ? k : box[0]);
                box[1] = (int16_t)(k > box[1] ? k : box[1]);
            }
        }
    }
    if (rtot > (real)0) { /* the mass at rest, on the new position cells */
        memset(row, 0, sizeof f->grid.row);
        hstpf__grid_remap(rest, 0, NS - 1, (g[0] - ng[0]) / ng[1], g[1] / ng[1], row, NS);
        if (rest_v < (real)0) { /* held: s' = s, v' = 0, no process noise */
            for (i = 0; i < NS; ++i) {
                f->grid.rnew[i] += row[i];
            }
            held += rtot;
        } else { /* starts moving: v' = T a0 + noise */
            int k = (int32_t)((rest_v - ng[2]) / ng[3]);
            k = k < 0 ? 0 : (k > NV - 1 ? NV - 1 : k);
            for (i = 0; i < NS; ++i) {
                w[k * NS + i] += row[i];
            }
            box[0] = (int16_t)(k < box[0] ? k : box[0]);
            box[1] = (int16_t)(k > box[1] ? k : box[1]);
            box[2] = 0;
            box[3] = NS - 1;
        }
    }
    return tot > (real)0 ? held / tot : (real)0;
}
