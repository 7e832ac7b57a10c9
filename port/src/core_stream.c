/* hstpfd: the per-step stream (--out): one JSON line or CSV row a step. */
#include "core_internal.h"

#include <math.h>

void hstpfd__stream_header(FILE *out, const hstpfd_config_t *cfg)
{
    static const char *const pre[2] = {"q_", "ess_"};
    uint16_t l;
    int w;
    fputs("t,k,dt,u,y,err,valid,pos,speed,pos_sd,speed_sd,standstill,acquisitions,c0,c1,c2,best,declared,status,"
          "pos_stale,trac_stale,restart,trac_implausible",
          out);
    for (w = 0; w < 2; ++w) {
        for (l = 0; l < cfg->n_models; ++l) {
            char col[HSTPFD_NAME_MAX + 8];
            (void)snprintf(col, sizeof col, "%s%s", pre[w], cfg->models[l].name);
            fputc(',', out);
            hstpfd__csv_str(out, col);
        }
    }
    fputs(",fit,off_what,q_offtable,cov_c0c0,cov_c0c1,cov_c0c2,cov_c1c1,cov_c1c2,cov_c2c2\n", out);
}

/* The separator before a field: "," in CSV, ,"key": in JSON. */
static void out_key(FILE *fp, int csv, const char *key)
{
    if (csv) {
        fputc(',', fp);
    } else {
        fprintf(fp, ",\"%s\":", key);
    }
}

void hstpfd__write_step(hstpfd_core_t *c, const hstpfd_step_t *st, int32_t rc)
{
    const hstpf_estimate_t *e = &c->est;
    const hstpfd_config_t *cfg = c->cfg;
    FILE *fp = c->out;
    const int csv = cfg->out_format == HSTPFD_OUT_CSV;
    const int valid = hstpfd__est_valid(c);
    uint16_t l;
    const char *best = c->have_fix && e->best >= 0 && e->best < (int)cfg->n_models ? cfg->models[e->best].name : NULL;
    const char *decl = e->declared >= 0 && e->declared < (int)cfg->n_models ? cfg->models[e->declared].name : NULL;
    if (fp == NULL) {
        return;
    }
    if (csv) {
        hstpfd__json_time(fp, st->t_us);
        fprintf(fp, ",%lu", (unsigned long)c->sched.n.steps);
    } else {
        fputs("{\"t\":", fp);
        hstpfd__json_time(fp, st->t_us);
        fprintf(fp, ",\"k\":%lu", (unsigned long)c->sched.n.steps);
    }
    out_key(fp, csv, "dt");
    hstpfd__out_num(fp, csv, st->in.dt_s, 9);
    out_key(fp, csv, "u");
    hstpfd__out_num(fp, csv, st->in.traction, 9);
    out_key(fp, csv, "y");
    /* positions to 1 mm up to 1e8 m (the signal has 1 cm): 11 digits */
    hstpfd__out_num(fp, csv, st->in.has_position ? st->in.position_m : HUGE_VAL, 11);
    out_key(fp, csv, "err");
    if (rc != HSTPF_OK) {
        if (csv) {
            fputs(hstpfd_err_name(rc), fp);
        } else {
            hstpfd__json_str(fp, hstpfd_err_name(rc));
        }
    } else if (!csv) {
        fputs("null", fp);
    }
    if (csv) {
        fprintf(fp, ",%d", valid ? 1 : 0);
    } else {
        fprintf(fp, ",\"valid\":%s", valid ? "true" : "false");
    }
    out_key(fp, csv, "pos");
    hstpfd__out_num(fp, csv, e->position_m, 11);
    out_key(fp, csv, "speed");
    hstpfd__out_num(fp, csv, (double)e->speed_mps, 9);
    out_key(fp, csv, "pos_sd"); /* null until the library provides it */
    hstpfd__out_num(fp, csv, LIB_HAS_SD ? e->position_sd_m : HUGE_VAL, 6);
    out_key(fp, csv, "speed_sd");
    hstpfd__out_num(fp, csv, LIB_HAS_SD ? (double)e->speed_sd_mps : HUGE_VAL, 6);
    out_key(fp, csv, "standstill");
    fprintf(fp, "%u", (unsigned)e->standstill);
    out_key(fp, csv, "acquisitions");
    fprintf(fp, "%lu", (unsigned long)e->acquisitions);
    if (csv) {
        for (l = 0; l < 3; ++l) {
            fputc(',', fp);
            hstpfd__out_num(fp, 1, (double)e->theta[l], 9);
        }
        fputc(',', fp);
        hstpfd__csv_str(fp, best != NULL ? best : "");
        fputc(',', fp);
        hstpfd__csv_str(fp, decl != NULL ? decl : "");
        fprintf(fp, ",%s,%u,%u,%u,%u", hstpfd__status_name(e->status), (unsigned)st->pos_stale,
                (unsigned)st->trac_stale, (unsigned)st->restart, (unsigned)e->traction_fault);
        for (l = 0; l < e->n_models; ++l) {
            fputc(',', fp);
            hstpfd__out_num(fp, 1, (double)e->model[l].q, 9);
        }
        for (l = 0; l < e->n_models; ++l) {
            fputc(',', fp);
            hstpfd__out_num(fp, 1, (double)e->model[l].ess, 6);
        }
        fprintf(fp, ",%s,%u,", hstpfd__fit_name(e->fit), (unsigned)e->off_what);
        hstpfd__out_num(fp, 1, (double)e->q_offtable, 6);
        for (l = 0; l < 6; ++l) {
            fputc(',', fp);
            hstpfd__out_num(fp, 1, (double)e->theta_cov[l], 6);
        }
        fputc('\n', fp);
        return;
    }
    fputs(",\"theta\":[", fp);
    for (l = 0; l < 3; ++l) {
        fputs(l ? "," : "", fp);
        hstpfd__out_num(fp, 0, (double)e->theta[l], 9);
    }
    fputs("],\"theta_cov\":[", fp);
    for (l = 0; l < 6; ++l) {
        fputs(l ? "," : "", fp);
        hstpfd__out_num(fp, 0, (double)e->theta_cov[l], 6);
    }
    fprintf(fp, "],\"fit\":\"%s\",\"off_what\":%u,\"q_offtable\":", hstpfd__fit_name(e->fit), (unsigned)e->off_what);
    hstpfd__out_num(fp, 0, (double)e->q_offtable, 6);
    fputs(",\"q\":[", fp);
    for (l = 0; l < e->n_models; ++l) {
        fputs(l ? "," : "", fp);
        hstpfd__out_num(fp, 0, (double)e->model[l].q, 9);
    }
    fputs("],\"ess\":[", fp);
    for (l = 0; l < e->n_models; ++l) {
        fputs(l ? "," : "", fp);
        hstpfd__out_num(fp, 0, (double)e->model[l].ess, 6);
    }
    fputs("],\"best\":", fp);
    if (best != NULL) {
        hstpfd__json_str(fp, best);
    } else {
        fputs("null", fp);
    }
    fputs(",\"declared\":", fp);
    if (decl != NULL) {
        hstpfd__json_str(fp, decl);
    } else {
        fputs("null", fp);
    }
    fprintf(fp, ",\"status\":\"%s\",\"pos_stale\":%u,\"trac_stale\":%u,\"restart\":%u,\"trac_implausible\":%u}\n",
            hstpfd__status_name(e->status), (unsigned)st->pos_stale, (unsigned)st->trac_stale, (unsigned)st->restart,
            (unsigned)e->traction_fault);
}
