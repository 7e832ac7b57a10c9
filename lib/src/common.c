#include "hstpf/common.h"

const char *hstpf_strerror(int32_t err)
{
    switch (err) {
    case HSTPF_OK: return "ok";
    case HSTPF_E_NULL: return "required pointer is NULL";
    case HSTPF_E_INIT: return "instance not initialised";
    case HSTPF_E_SIZE: return "count out of range, or workspace too small or misaligned";
    case HSTPF_E_NONFINITE: return "input is NaN or infinite";
    case HSTPF_E_DT: return "step length out of range";
    case HSTPF_E_RANGE: return "value outside physical range";
    case HSTPF_E_ABI: return "sizeof(hstpf_t) mismatch between caller and library";
    case HSTPF_E_DIST: return "invalid noise distribution";
    case HSTPF_E_CONFIG: return "invalid configuration option";
    case HSTPF_E_OUTLIER: return "measurement beyond the gate";
    default: return "unknown error";
    }
}
