/* hstpfd: the configuration keys: name, type, place, range and help of each
 * (docs/daemon.md lists them). */
#include "config_internal.h"
#include "hstpf_frames.h"

#define OFF(m) offsetof(hstpfd_config_t, m)

const hstpfd__key_t hstpfd__keys[] = {
    {"iface", K_NAME, OFF(iface), 0, 0, 0, "CAN interface to run on, e.g. can0 (live)"},
    {"log", K_PATH, OFF(log), 0, 0, 0, "candump log file to replay instead (offline)"},
    {"models", K_MODELS, 0, 0, 0, 0,
     "model set: Table 1 names and/or name:c0:c1:c2, comma-separated; all = the 17 rows"},
    {"engine", K_ENGINE, 0, 0, 0, 0,
     "per-model estimator: auto (Kalman if all three noises are Gaussian, else grid) | particle | kalman | grid"},
    {"particles", K_U16, OFF(particles), 2, HSTPF_MAX_PARTICLES, 0, "particles per model"},
    {"seed", K_U64, OFF(seed), 0, 0, 0, "random seed of the filter"},
    {"gamma_rot", K_DBL, OFF(gamma_rot), 0, 1, 0, "rotating-mass factor gamma"},
    {"noise", K_PRESET, 0, 0, 0, 0, "noise preset for all three channels: case1 | case2 (the paper's)"},
    {"noise_s", K_NOISE, OFF(noise_s), 0, 0, 0,
     "position process noise w_s, m per step: gaussian:mean:sd | gamma:shape:scale:loc"},
    {"noise_v", K_NOISE, OFF(noise_v), 0, 0, 0, "speed process noise w_v, m/s per step"},
    {"noise_e", K_NOISE, OFF(noise_e), 0, 0, 0, "position measurement noise e, m"},
    {"dt_nominal_s", K_DBL, OFF(dt_nominal_s), 1e-6, HSTPF_DT_MAX_S, 0,
     "step the noise is given for (also the first step's length), s"},
    {"init_speed_mps", K_DBL, OFF(init_speed_mps), -HSTPF_SPEED_MAX, HSTPF_SPEED_MAX, 0,
     "prior speed mean at the first fix, m/s"},
    {"init_speed_sd", K_DBL, OFF(init_speed_sd), 0, HSTPF_SPEED_MAX, 0, "prior speed sd, m/s"},
    {"roughening_k", K_DBL, OFF(roughening_k), 0, 10, 0,
     "particle engine: roughening after resampling, sd = k x spread / sqrt(M)"},
    {"e_blur_sd", K_DBL, OFF(e_blur_sd), 0, 100, 0,
     "particle engine: measurement density blurred by N(0, sd), m (0 = exact; for one-sided noise)"},
    {"grid_speed_lattice", K_BOOL, OFF(grid_speed_lattice), 0, 0, 0,
     "grid engine: 1 = each model's speed cells carried by its own dynamics, 0 = remapped every step"},
    {"grid_rows", K_U16, OFF(grid_rows), 0, HSTPF_MAX_MODELS, 0,
     "grid engine, Gaussian process noise: rows stepped on the grid, those with the largest weights (0 = every row)"},
    {"refine", K_U16, OFF(refine), 0, 2, 0,
     "continuous-theta hypothesis: 0 = rows only, 1 = on (grid: a Kalman yardstick, or its own grid under non-Gaussian process noise), 2 = on its own grid under any noise"},
    {"declare_threshold", K_DBL, OFF(declare_threshold), 0.5, 1, HSTPFD_LO_OPEN | HSTPFD_HI_OPEN,
     "model weight above which a type may be declared"},
    {"declare_hold_s", K_DBL, OFF(declare_hold_s), 0, 1e6, 0, "how long it must stay above, s"},
    {"gate_m", K_DBL, OFF(gate_m), 0, HSTPF_POS_MAX_M, 0, "outlier gate on the position, m (0 = none)"},
    {"accel_unknown_sd", K_DBL, OFF(accel_unknown_sd), 0, 10, HSTPFD_LO_OPEN,
     "while the traction is stale: the train's acceleration taken as 0 with this sd, m/s^2"},
    {"traction_check", K_BOOL, OFF(traction_check), 0, 0, 0,
     "1 = take the traction as unknown while it explains the fixes worse than none (HealthRx.TractImplausible)"},
    {"fix_step", K_BOOL, OFF(fix_step), 0, 0, 0,
     "1 = a step in the positions' reference (a GNSS bias, a balise correction) moves the position, not the speed"},
    {"consist_change_p", K_DBL, OFF(consist_change_p), 0, 0.5, 0,
     "probability that the consist changed during a standstill of 3 min or more (the Consist frame says it for sure)"},
    {"mass_t", K_DBL, OFF(mass_t), 0, 1e5, HSTPFD_LO_OPEN, "train mass, t (traction kN -> N/kN)"},
    {"step_period_s", K_DBL, OFF(sched.step_period_s), 0, HSTPF_DT_MAX_S, 0,
     "0: a step per valid position frame; else step at most this often (decimate)"},
    /* 1 ms to 14 cycles of the input frames (100 ms, the DBC): the E2E
     * checker's timeout in whole ms, and a counter that wraps round (15
     * values) within the timeout would read as in sequence (docs/can.md) */
    {"position_timeout_s", K_DBL, OFF(sched.pos_timeout_s), 0.001, HSTPF_FRAME_POSITION_CYCLE_MS * 14 / 1000.0, 0,
     "no valid position for longer: position stale (at most 14 cycles of the Position frame)"},
    {"traction_timeout_s", K_DBL, OFF(sched.trac_timeout_s), 0.001, HSTPF_FRAME_TRACTION_CYCLE_MS * 14 / 1000.0, 0,
     "no valid traction for longer: traction stale, last value held (at most 14 cycles)"},
    {"stale_policy", K_STALE, 0, 0, 0, 0, "position stale: predict (predict-only steps) | wait"},
    {"predict_period_s", K_DBL, OFF(sched.predict_period_s), 1e-6, HSTPF_DT_MAX_S, 0,
     "length of the predict-only steps while position is stale, s"},
    {"max_gap_s", K_DBL, OFF(sched.max_gap_s), 1e-6, 1e7, 0,
     "a gap between positions longer than this (predicted across or not) restarts the estimator, s"},
    {"traction_mode", K_TRACTION, 0, 0, 0, 0, "traction of a step: mean (time-weighted over the step) | latest"},
    {"e2e_max_delta", K_U32, OFF(e2e_max_delta), 1, 13, 0,
     "largest accepted alive-counter increment (1 = no frame may be lost)"},
    {"time_scale", K_DBL, OFF(time_scale), 0, 1e4, HSTPFD_LO_OPEN,
     "frame time = first stamp + (stamp - first stamp) x time_scale (a log replayed k x faster: k)"},
    {"tick_s", K_DBL, OFF(tick_s), 0, 60, HSTPFD_LO_OPEN, "idle tick: with no frame for this long, time advances by it, s"},
    {"rx_filter", K_RXFILTER, 0, 0, 0, 0,
     "kernel receive filter: inputs (the two input IDs) | block (0x100-0x1FF) | all"},
    {"send", K_BOOL, OFF(send), 0, 0, 0, "with iface: send the estimate frames (0 = listen only)"},
    {"reopen_s", K_DBL, OFF(reopen_s), 0, 3600, HSTPFD_LO_OPEN, "retry period to reopen a lost interface, s (wall clock)"},
    {"out", K_PATH, OFF(out), 0, 0, 0, "per-step stream file (- = stdout, empty = none)"},
    {"out_format", K_FORMAT, 0, 0, 0, 0, "per-step stream format: jsonl | csv"},
    {"summary", K_PATH, OFF(summary), 0, 0, 0, "also write the final JSON summary line to this file"},
    {"frames_out", K_PATH, OFF(frames_out), 0, 0, 0,
     "write the estimate frames as a candump log (with --log: what would be sent)"},
    {"frames_out_inputs", K_BOOL, OFF(frames_out_inputs), 0, 0, 0,
     "1: frames_out also gets every received frame (a whole-bus recording)"},
};

const size_t hstpfd__n_keys = sizeof hstpfd__keys / sizeof hstpfd__keys[0];

unsigned hstpfd_config_n_keys(void)
{
    return (unsigned)hstpfd__n_keys;
}

const char *hstpfd_config_key_name(unsigned i)
{
    return i < hstpfd__n_keys ? hstpfd__keys[i].name : NULL;
}

const char *hstpfd_config_key_help(unsigned i)
{
    return i < hstpfd__n_keys ? hstpfd__keys[i].help : NULL;
}
