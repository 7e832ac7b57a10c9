/* hstpfd: the configuration's final cross-checks (hstpfd_config_finish). */
#include "config_internal.h"

int hstpfd_config_finish(hstpfd_config_t *c, char *err, size_t err_size)
{
    hstpf_config_t fc;
    hstpfd_sched_t s;
    int32_t rc;
    if ((c->iface[0] != '\0') == (c->log[0] != '\0')) {
        hstpfd__fail(err, err_size, "give exactly one source: --iface IFACE or --log FILE");
        return -1;
    }
    if (c->sched.step_period_s > 0.0 && c->sched.step_period_s < 1e-6) { /* time is counted in whole us */
        hstpfd__fail(err, err_size, "step_period_s: %g is neither 0 nor at least 1e-6 s", c->sched.step_period_s);
        return -1;
    }
    c->sched.mass_t = c->mass_t;
    c->sched.first_dt_s = c->dt_nominal_s;
    if (hstpfd_sched_init(&s, &c->sched, NULL, NULL) != 0) {
        hstpfd__fail(err, err_size, "scheduling values out of range");
        return -1;
    }
    hstpfd_config_filter(c, &fc);
    {
        const char *field = NULL;
        rc = hstpf_config_check(&fc, &field); /* hstpf_init's check; the core owns the workspace */
        if (rc != HSTPF_OK) {
            /* the library's field names are the keys' (hstpf.h's ranges are the ones that hold) */
            hstpfd__fail(err, err_size, "the estimator rejects %s: %s (%ld)", field != NULL ? field : "the configuration",
                         hstpf_strerror(rc), (long)rc);
            return -1;
        }
    }
    return 0;
}
