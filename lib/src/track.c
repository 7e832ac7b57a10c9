/* Track profile: each segment's gradient and curve resistance, looked up by
 * position with a per-model cursor so a step costs O(segments moved). */
#include "track.h"

#include "internal.h"

typedef hstpf_real_t real;

double hstpf__seg_resistance(const hstpf_track_seg_t *t)
{
    return t->gradient_permille + (t->curve_radius_m > 0.0 ? 600.0 / t->curve_radius_m : 0.0);
}

void hstpf__track_init(hstpf_t *f, const hstpf_track_seg_t *track, uint16_t n)
{
    uint16_t j;
    for (j = 0; j < n; ++j) {
        f->track[j] = track[j];
        f->track_acc[j] = (real)(f->xi * hstpf__seg_resistance(&track[j]));
    }
}

void hstpf__track_rebase(hstpf_t *f)
{
    uint16_t j;
    for (j = 0; j < f->cfg.n_track; ++j) {
        f->track_rel[j] = (real)(f->track[j].start_m - f->origin_m);
    }
}

real hstpf__track_acc(const hstpf_t *f, uint16_t *hint, real s)
{
    uint16_t j = *hint;
    const uint16_t n = f->cfg.n_track;
    while (j + 1u < n && s >= f->track_rel[j + 1u]) {
        ++j;
    }
    while (j > 0u && s < f->track_rel[j]) {
        --j;
    }
    *hint = j;
    return s < f->track_rel[0] ? (real)0 : f->track_acc[j];
}

int32_t hstpf_track_resistance(const hstpf_t *f, double pos_m, double *g_out)
{
    uint16_t j;
    double g = 0.0;
    if (f == NULL || g_out == NULL) {
        return HSTPF_E_NULL;
    }
    if (f->magic != HSTPF_MAGIC) {
        return HSTPF_E_INIT;
    }
    for (j = 0; j < f->cfg.n_track && pos_m >= f->track[j].start_m; ++j) {
        g = hstpf__seg_resistance(&f->track[j]);
    }
    *g_out = g;
    return HSTPF_OK;
}
