/* hstpfd: the summary, one JSON line at the end of a run. */
#include "core_internal.h"

#include <math.h>

static void kv(FILE *fp, const char *k, unsigned long v, int first)
{
    fprintf(fp, "%s\"%s\":%lu", first ? "" : ",", k, v);
}

/* The E2E receiver's counts of one input, as the members of an object. */
static void e2e_kv(FILE *fp, const hstpf_e2e_counts_t *x)
{
    kv(fp, "ok", (unsigned long)x->ok, 1);
    kv(fp, "lost", (unsigned long)x->lost, 0);
    kv(fp, "bad_crc", (unsigned long)x->bad_crc, 0);
    kv(fp, "wrong_length", (unsigned long)x->wrong_length, 0);
    kv(fp, "repeated", (unsigned long)x->repeated, 0);
    kv(fp, "counter_jump", (unsigned long)x->jump, 0);
    kv(fp, "stale", (unsigned long)x->stale, 0);
}

void hstpfd_core_summary(const hstpfd_core_t *c, FILE *fp, const char *source_kind, const char *source,
                         const char *end)
{
    const hstpf_estimate_t *e = &c->est;
    const hstpfd_config_t *cfg = c->cfg;
    const hstpf_e2e_counts_t *p = hstpf_e2e_rx_counts(&c->rx.pos);
    const hstpf_e2e_counts_t *t = hstpf_e2e_rx_counts(&c->rx.trac);
    const hstpf_e2e_counts_t *k = hstpf_e2e_rx_counts(&c->rx.topo);
    const hstpfd_sched_counts_t *s = &c->sched.n;
    uint16_t l;
    unsigned i;
    int first;

    fprintf(fp, "{\"summary\":\"hstpfd\",\"version\":\"%d.%d.%d\",\"source\":", HSTPF_VERSION_MAJOR,
            HSTPF_VERSION_MINOR, HSTPF_VERSION_PATCH);
    hstpfd__json_str(fp, source_kind);
    fputs(",\"name\":", fp);
    hstpfd__json_str(fp, source);
    fputs(",\"end\":", fp);
    hstpfd__json_str(fp, end);
    fputs(",\"t_first\":", fp);
    if (c->have_time) {
        hstpfd__json_time(fp, c->t_first);
        fputs(",\"t_last\":", fp);
        hstpfd__json_time(fp, c->t_now);
        fputs(",\"duration_s\":", fp);
        hstpfd__json_num(fp, (double)(c->t_now - c->t_first) / 1e6);
    } else {
        fputs("null,\"t_last\":null,\"duration_s\":0", fp);
    }
    fputs(",\"first_fix_t\":", fp);
    if (c->had_fix) {
        hstpfd__json_time(fp, c->t_first_fix);
    } else {
        fputs("null", fp);
    }
    fprintf(fp, ",\"steps\":%lu,\"predict_steps\":%lu,\"steps_ok\":%lu", (unsigned long)s->steps,
            (unsigned long)s->predict_steps, (unsigned long)c->n.step_ok);
    fputs(",\"declared\":", fp);
    if (e->declared >= 0) {
        hstpfd__json_str(fp, cfg->models[e->declared].name);
    } else {
        fputs("null", fp);
    }
    fprintf(fp, ",\"status\":\"%s\",\"fit\":\"%s\",\"off_what\":%u,\"decision_time_s\":",
            hstpfd__status_name(e->status), hstpfd__fit_name(e->fit), (unsigned)e->off_what);
    if (e->declared >= 0 && c->have_decision && c->had_fix) {
        hstpfd__json_num(fp, (double)(c->decision_t - c->t_first_fix) / 1e6);
        fputs(",\"decision_t\":", fp);
        hstpfd__json_time(fp, c->decision_t);
    } else {
        fputs("null,\"decision_t\":null", fp);
    }
    fputs(",\"lib_decision_time_s\":", fp);
    if (e->declared >= 0) {
        hstpfd__json_num(fp, e->decision_time_s);
    } else {
        fputs("null", fp);
    }
    fputs(",\"leader\":", fp);
    if (c->have_fix && e->best >= 0 && e->best < (int)cfg->n_models) {
        hstpfd__json_str(fp, cfg->models[e->best].name);
    } else {
        fputs("null", fp);
    }
    fputs(",\"theta\":[", fp);
    for (i = 0; i < 3; ++i) {
        fputs(i ? "," : "", fp);
        hstpfd__out_num(fp, 0, (double)e->theta[i], 9);
    }
    fprintf(fp, "],\"valid\":%s,\"position_m\":", hstpfd__est_valid(c) ? "true" : "false");
    hstpfd__json_num(fp, e->position_m);
    fputs(",\"speed_mps\":", fp);
    hstpfd__json_num(fp, (double)e->speed_mps);
    fputs(",\"position_sd_m\":", fp);
    hstpfd__json_num(fp, LIB_HAS_SD ? e->position_sd_m : HUGE_VAL);
    fputs(",\"speed_sd_mps\":", fp);
    hstpfd__json_num(fp, LIB_HAS_SD ? (double)e->speed_sd_mps : HUGE_VAL);
    fprintf(fp, ",\"standstill\":%u,\"acquisitions\":%lu,\"nonfinite_resets\":%lu,\"backward\":%lu",
            (unsigned)e->standstill, (unsigned long)e->acquisitions, (unsigned long)e->nonfinite_resets,
            (unsigned long)e->backward);
    fputs(",\"weights\":{", fp);
    for (l = 0; l < e->n_models; ++l) {
        if (l) {
            fputc(',', fp);
        }
        hstpfd__json_str(fp, cfg->models[l].name);
        fputc(':', fp);
        hstpfd__out_num(fp, 0, (double)e->model[l].q, 9);
    }
    fputs("},\"faults\":{", fp);
    kv(fp, "bad_crc", (unsigned long)(p->bad_crc + t->bad_crc + k->bad_crc), 1);
    kv(fp, "wrong_length", (unsigned long)(p->wrong_length + t->wrong_length + k->wrong_length), 0);
    kv(fp, "repeated", (unsigned long)(p->repeated + t->repeated + k->repeated), 0);
    kv(fp, "counter_jump", (unsigned long)(p->jump + t->jump + k->jump), 0);
    kv(fp, "lost", (unsigned long)(p->lost + t->lost + k->lost), 0);
    kv(fp, "stale_events", (unsigned long)(p->stale + t->stale), 0);
    kv(fp, "position_stale", (unsigned long)s->pos_stale, 0);
    kv(fp, "traction_stale", (unsigned long)s->trac_stale, 0);
    kv(fp, "traction_implausible", (unsigned long)c->n.trac_implausible, 0);
    kv(fp, "position_invalid", (unsigned long)c->n.pos_invalid, 0);
    kv(fp, "position_range", (unsigned long)c->n.pos_range, 0);
    kv(fp, "traction_invalid", (unsigned long)c->n.trac_invalid, 0);
    kv(fp, "traction_range", (unsigned long)c->n.trac_range, 0);
    kv(fp, "unknown_id", (unsigned long)c->n.unknown, 0);
    kv(fp, "bad_format", (unsigned long)c->n.format, 0);
    kv(fp, "error_frames", (unsigned long)c->n.error, 0);
    kv(fp, "late_position", (unsigned long)s->late, 0);
    kv(fp, "time_backwards", (unsigned long)s->time_backwards, 0);
    kv(fp, "clock_steps_forward", (unsigned long)s->clock_fwd, 0);
    kv(fp, "clock_steps_back", (unsigned long)s->clock_back, 0);
    kv(fp, "bad_lines", (unsigned long)c->n.bad_lines, 0);
    fputs("},\"e2e\":{\"position\":{", fp);
    e2e_kv(fp, p);
    fputs("},\"traction\":{", fp);
    e2e_kv(fp, t);
    fputs("},\"consist\":{", fp);
    e2e_kv(fp, k);
    fputs("}},\"error_classes\":{", fp);
    for (i = 0; i < HSTPFD_ERR_N_CLASSES; ++i) {
        kv(fp, hstpfd__class_names[i], (unsigned long)c->n.err_class[i], i == 0);
    }
    fputs("},\"step_errors\":{", fp);
    first = 1;
    for (i = 0; i < 11; ++i) {
        if (c->n.step_err[i] != 0) {
            kv(fp, hstpfd__err_names[i], (unsigned long)c->n.step_err[i], first);
            first = 0;
        }
    }
    fputs("},\"frames\":{", fp);
    kv(fp, "total", (unsigned long)c->n.frames, 1);
    kv(fp, "position", (unsigned long)c->n.position, 0);
    kv(fp, "traction", (unsigned long)c->n.traction, 0);
    kv(fp, "consist", (unsigned long)c->n.consist, 0);
    kv(fp, "own_outputs", (unsigned long)c->n.output, 0);
    kv(fp, "ticks", (unsigned long)c->n.ticks, 0);
    fputs("},\"scheduler\":{", fp);
    kv(fp, "decimated", (unsigned long)s->decimated, 1);
    kv(fp, "split", (unsigned long)s->split, 0);
    kv(fp, "fix_dated", (unsigned long)s->fix_dated, 0);
    kv(fp, "fix_clock_steps", (unsigned long)s->fix_clock_steps, 0);
    kv(fp, "reacquire", (unsigned long)c->n.reacquire, 0);
    kv(fp, "restarts", (unsigned long)s->restarts, 0);
    kv(fp, "degeneracy", (unsigned long)c->n.degeneracy, 0);
    kv(fp, "consist_changes", (unsigned long)c->n.consist_changes, 0);
    fputs("},\"io\":{", fp);
    kv(fp, "tx_frames", (unsigned long)c->n.tx_frames, 1);
    kv(fp, "tx_errors", (unsigned long)c->n.tx_errors, 0);
    kv(fp, "tx_offline", (unsigned long)c->n.tx_offline, 0);
    kv(fp, "reopens", (unsigned long)c->n.reopens, 0);
    kv(fp, "read_errors", (unsigned long)c->n.read_errors, 0);
    fputs("}}\n", fp);
}
