"""hstpf-simulate: a run of the model as a candump log plus a truth CSV."""
import argparse
import csv
import io
import sys
from pathlib import Path

import numpy as np

from . import cli, model
from .frames import FrameCodec, TABLE1
from .logio import consist_frames, input_frames


def build_parser() -> argparse.ArgumentParser:
    p = cli.Parser(
        prog="hstpf-simulate",
        description="Simulate the train model and write E2E-protected position and traction frames "
        "(candump log) and the ground truth (CSV). Model step T on a grid; frames every "
        "--frame-period: position interpolated linearly between grid points plus fresh noise e, "
        "traction held over each step. Each position frame carries its fix time (Position.FixTime): "
        "--t0 + the frame's simulation time, ms modulo 8192. Prints a JSON report.",
        epilog="Exit codes: 0 done, 2 usage, 3 an input file (--track, --dbc) cannot be read, 6 an output "
        "cannot be written (docs/tools.md).",
    )
    g = p.add_mutually_exclusive_group()
    g.add_argument("--type", help="Table 1 type (default CRH3): " + ", ".join(r[0] for r in TABLE1))
    g.add_argument("--coeffs", help="custom c0,c1,c2 (N/kN, per km/h, per (km/h)^2)")
    p.add_argument("--profile", default="paper", choices=sorted(model.PROFILES), help="speed profile (default paper)")
    p.add_argument("--track", help="track CSV: start_m,gradient_permille,curve_radius_m")
    p.add_argument("--noise", default="case1", choices=sorted(model.NOISE_CASES), help="noise preset (default case1)")
    p.add_argument("--ws", help="override w_s (m per step): none | normal:mean=M,var=V | normal:sd=S | gamma:shape=K,scale=S[,loc=L]")
    p.add_argument("--wv", help="override w_v (m/s per step), same syntax")
    p.add_argument("--e", dest="e_noise", help="override e (m per position frame), same syntax")
    p.add_argument("--traction-noise-sd", type=float, default=0.0, help="Gaussian noise on the reported traction, N/kN sd per frame (0)")
    p.add_argument("--duration", type=float, default=1800.0, help="run length, s (1800)")
    p.add_argument("--dt", type=float, default=1.0, help="model step T, s (1)")
    p.add_argument("--frame-period", type=float, default=0.1, help="position/traction frame period, s (0.1, the DBC cycle)")
    p.add_argument("--restart-at", type=float, metavar="T",
                   help="from simulation time T on, positions (frames and truth) count from where the train "
                   "is at T: the positioning unit starts a new run from 0, as at a terminus (a time in a dwell) "
                   "or where a line's kilometrage changes")
    p.add_argument("--couple-at", metavar="T:TYPE",
                   help="the consist is coupled or split at the first stop from simulation time T: from there the "
                   "train runs with TYPE's resistance (a Table 1 name, or c0,c1,c2), and the log carries the train "
                   "control's Consist frame once a second, its topology counter 1, then 2 from the change")
    p.add_argument("--couple-silent", action="store_true",
                   help="with --couple-at: no Consist frames (the estimator must find the change from the data)")
    p.add_argument("--seed", type=int, default=1, help="seed of the simulation's own numpy Generator (1)")
    p.add_argument("--mass-t", type=float, default=500.0, help="train mass for the total force in the traction frame, t (500)")
    p.add_argument("--gamma", type=float, default=0.06, help="rotating-mass factor (0.06)")
    p.add_argument("--t0", type=float, default=0.0, help="log timestamp of simulation time 0, s (0)")
    p.add_argument("--channel", default="vcan0", help="channel name written in the log (vcan0)")
    p.add_argument("--no-fix-time", action="store_true",
                   help="position frames without their fix time (an older sender: the receiver dates them on receipt)")
    p.add_argument("--dbc", help="DBC file (default port/dbc/hstpf.dbc)")
    p.add_argument("-o", "--out", default="run.log", help="candump log to write (run.log); '-': stdout")
    p.add_argument("--truth", help="truth CSV (default: <out stem>_truth.csv; needed with -o -); '-': stdout")
    cli.add_json_argument(p, default=" (default: stdout, or stderr when -o or --truth is '-')")
    return p


def noise_from_args(a):
    ws, wv, e = model.NOISE_CASES[a.noise]
    if a.ws:
        ws = model.Noise.parse(a.ws)
    if a.wv:
        wv = model.Noise.parse(a.wv)
    if a.e_noise:
        e = model.Noise.parse(a.e_noise)
    return ws, wv, e


def write_truth(path, run: model.Run, mass_t: float, identity=("", "", "")) -> None:
    """The truth CSV; identity = (seed, noise, profile), repeated per row so
    that a reader of any row (hstpf-score's plot titles) knows the run."""
    th = run.theta
    f = io.StringIO()  # one write at the end: '-' (stdout) or a file, errors as exit 6
    w = csv.writer(f)
    w.writerow(["time_s", "position_m", "speed_mps", "traction_nkn", "force_kn", "track_nkn", "phase", "c0", "c1", "c2",
                "type", "seed", "noise", "profile"])
    for k in range(len(run.t)):
        if run.change_t is not None and run.t[k] >= run.change_t:
            th = run.change_theta  # the consist changed (--couple-at)
        w.writerow([
            f"{run.t[k]:.6f}", f"{run.s[k]:.6f}", f"{run.v[k]:.6f}", f"{run.u[k]:.6f}",
            f"{model.force_kn(run.u[k], mass_t):.6f}", f"{run.g[k]:.6f}", run.phase[k],
            repr(th.c0), repr(th.c1), repr(th.c2), th.name, *identity,
        ])
    cli.write_text(str(path), f.getvalue())


def _main(argv) -> int:
    a = build_parser().parse_args(argv)
    try:
        theta = (model.theta_for(None, [float(x) for x in a.coeffs.split(",")]) if a.coeffs
                 else model.theta_for(a.type or "CRH3"))
        ws, wv, e = noise_from_args(a)
        if a.frame_period <= 0 or a.mass_t <= 0 or a.dt <= 0 or a.duration <= 0:
            raise ValueError("--frame-period, --mass-t, --dt and --duration must be > 0")
        if a.restart_at is not None and not 0 < a.restart_at <= a.duration:
            raise ValueError("--restart-at must lie in (0, --duration]")
        change = None
        if a.couple_at:
            t_s, _, kind = a.couple_at.partition(":")
            t_c = float(t_s)
            if not kind or not 0 <= t_c <= a.duration:
                raise ValueError("--couple-at wants T:TYPE with T in [0, --duration]")
            change = (t_c, model.theta_for(None, [float(x) for x in kind.split(",")]) if "," in kind
                      else model.theta_for(kind))
        elif a.couple_silent:
            raise ValueError("--couple-silent needs --couple-at")
    except (KeyError, ValueError) as exc:
        raise cli.CliError(cli.EXIT_USAGE, str(exc).strip("'\"")) from exc
    if a.out == "-" and not a.truth:
        raise cli.CliError(cli.EXIT_USAGE, "with -o -, give --truth FILE")
    cli.check_stdout_once(out=a.out, truth=a.truth, json=a.json)
    track = None
    if a.track:
        try:
            track = model.Track.from_csv(a.track)
        except (OSError, KeyError, ValueError) as exc:
            raise cli.input_error(a.track, exc) from exc
    try:
        codec = FrameCodec(a.dbc)
    except Exception as exc:  # missing or unreadable DBC
        raise cli.input_error(a.dbc or "the DBC", exc) from exc
    # Separate streams: the trajectory does not change with the frame rate.
    ss = np.random.SeedSequence(a.seed)
    rng_proc, rng_meas = (np.random.default_rng(s) for s in ss.spawn(2))
    run = model.simulate(theta, a.profile, a.duration, a.dt, (ws, wv, e), rng_proc, track, a.gamma, change)
    tf, y, u = model.sample_frames(run, a.frame_period, e, rng_meas, a.traction_noise_sd)
    if a.restart_at is not None:  # a new run from 0 where the train is at T: the reference moves, not the train
        s_at = float(np.interp(a.restart_at, run.t, run.s))
        y = np.where(tf >= a.restart_at, y - s_at, y)
        run.s = np.where(run.t >= a.restart_at, run.s - s_at, run.s)
    msgs = input_frames(codec, a.t0, tf, y, model.force_kn(u, a.mass_t), a.channel, fix_time=not a.no_fix_time)
    if change is not None and not a.couple_silent:
        msgs = sorted(msgs + consist_frames(codec, a.t0, a.duration, run.change_t, a.channel),
                      key=lambda m: m.timestamp)  # stable: at a shared time the inputs stay first
    n = cli.save_log(a.out, msgs, a.channel)
    truth = a.truth or str(Path(a.out).with_name(Path(a.out).stem + "_truth.csv"))
    noise = a.noise + "".join(f" {k}={v}" for k, v in (("ws", a.ws), ("wv", a.wv), ("e", a.e_noise)) if v)
    write_truth(truth, run, a.mass_t, (a.seed, noise, a.profile))
    cli.emit_report({
        "log": a.out, "truth": truth, "frames": n, "steps": len(run.t) - 1, "type": theta.name,
        "theta": [theta.c0, theta.c1, theta.c2], "profile": a.profile, "noise": noise, "seed": a.seed,
        "final_position_m": round(float(run.s[-1]), 3), "final_speed_mps": round(float(run.v[-1]), 3),
        **({"couple_t": run.change_t, "couple_type": run.change_theta.name if run.change_theta else None,
            "couple_theta": ([run.change_theta.c0, run.change_theta.c1, run.change_theta.c2]
                             if run.change_theta else None)} if change is not None else {}),
    }, a.json, stdout_taken="-" in (a.out, truth))
    return cli.EXIT_OK


def main(argv=None) -> int:
    return cli.run("hstpf-simulate", _main, argv)


if __name__ == "__main__":
    sys.exit(main())
