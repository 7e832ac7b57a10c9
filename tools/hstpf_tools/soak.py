"""hstpf-soak: a simulated day through `hstpfd --log`, checked step by step (docs/soak.md).

Three parts, each usable alone:
  make   the day as a candump log: a timetable of station stops (holding brake
         reported), GNSS outages (PosValid = 0), receive-clock steps (+-30 s and
         one large forward jump: the log's stamps step, the fix times do not)
         and bus faults (hstpf-replay's injector: bad CRC, repeated and jumping
         counters, dropped frames, wrong lengths, unknown IDs, silences);
         deterministic by seed. Writes LOG, <stem>_truth.csv (hstpf-simulate's
         format), <stem>_plan.json (what was injected where) and
         <stem>_frames.npz (every position frame: time, value, validity).
  run    hstpfd --log LOG --out steps.jsonl --summary summary.json, sampling
         VmRSS and the process's CPU time every --sample-s seconds together
         with the step number reached (the last line of steps.jsonl).
  check  the step stream against the truth and the plan (see check()).
"""
import argparse
import bisect
import contextlib
import csv
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from . import cli, model, replay
from .frames import FrameCodec
from .logio import input_frames, log_writer
from .simulate import write_truth

ROOT = Path(__file__).resolve().parents[2]
HOUR = 3600.0

# ---- the day -------------------------------------------------------------------------------

LAYOVER_S = 900.0  # dwell at the terminal between two rounds of the 4 h timetable
CLOCK_STEP_S = 30.0  # the small receive-clock steps, forward and back
LARGE_JUMP_S = 3 * 86400.0  # one forward jump of the receive clock (far beyond max_gap_s)
OUTAGES_PER_H, OUTAGE_S = 3.0, (5.0, 120.0)
SILENCES_PER_H, SILENCE_S = 1.0, 2.0
MARGIN_S = 60.0  # clock steps keep this far from outages and silences (their detection needs fixes)
#: bus faults per input frame (IDs 0x100, 0x101), hstpf-replay's kinds
FAULT_RATES = {"drop": 0.002, "corrupt": 0.001, "truncate": 0.0005, "duplicate": 0.001,
               "delay": 0.0005, "reorder": 0.0005, "unknown": 0.0002}
UNKNOWN_ID = 0x1F0  # inside hstpfd's block filter (0x100-0x1FF): seen and counted
CHUNK_S = 3600.0  # frames are made, faulted and written an hour at a time


def timetable() -> list:
    """hstpf-mc's 4 h "day" timetable (model.PROFILES["day"]) as rounds that
    repeat: its 12 legs, then a layover, for as long as the run lasts."""
    day = model.PROFILES["day"]
    legs = day[1:-2]  # without the first dwell and the final run to the end
    assert legs[-1][0] == "stop"
    one = legs[:-1] + [("stop", LAYOVER_S)]
    return [day[0]] + one * 8  # 8 rounds: more than 24 h


def _spread(rng, t_end: float, n: int, length: Tuple[float, float], avoid: Sequence[Tuple[float, float]],
            gap: float) -> List[Tuple[float, float]]:
    """n windows [a, b) in [gap, t_end - gap), lengths uniform in `length`,
    not closer than `gap` to each other or to a window of `avoid`."""
    out: List[Tuple[float, float]] = []
    for _ in range(200 * max(n, 1)):
        if len(out) >= n:
            break
        ln = float(rng.uniform(*length)) if length[1] > length[0] else length[0]
        if t_end - gap - ln <= gap:
            break  # a run too short for this window
        a = float(rng.uniform(gap, t_end - gap - ln))
        b = a + ln
        if all(b + gap <= c or a >= d + gap for c, d in list(out) + list(avoid)):
            out.append((round(a, 1), round(b, 1)))
    return sorted(out)


def plan_events(hours: float, seed: int) -> dict:
    """Clock steps, GNSS outages and bus silences of a day, by seed."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x50AC]))
    t_end = hours * HOUR
    n_small = max(1, int(round(hours / 4.0)))
    kinds = [CLOCK_STEP_S] * n_small + [-CLOCK_STEP_S] * n_small + [LARGE_JUMP_S]
    at = _spread(rng, t_end, len(kinds), (0.0, 0.0), [], max(60.0, t_end / (4 * len(kinds))))
    order = rng.permutation(len(kinds))
    steps = [{"t_sim": a, "delta_s": kinds[int(i)]} for (a, _), i in zip(at, order)]
    near = [(s["t_sim"] - MARGIN_S, s["t_sim"] + 10.0 + MARGIN_S) for s in steps]
    outages = _spread(rng, t_end, int(round(OUTAGES_PER_H * hours)), OUTAGE_S, near, 30.0)
    silences = _spread(rng, t_end, int(round(SILENCES_PER_H * hours)), (SILENCE_S, SILENCE_S),
                       near + outages, 30.0)
    return {"clock_steps": steps, "outages": [list(w) for w in outages], "silences": [list(w) for w in silences]}


def _in_windows(t: np.ndarray, windows) -> np.ndarray:
    m = np.zeros(len(t), dtype=bool)
    for a, b in windows:
        m |= (t >= a) & (t < b)
    return m


def make(out: str, hours: float, seed: int, dbc: Optional[str] = None, theta_name: str = "CRH3") -> dict:
    """Writes the day's log, truth, plan and position frames; returns the plan."""
    out_p = Path(out)
    out_p.parent.mkdir(parents=True, exist_ok=True)
    stem = out_p.with_name(out_p.stem)
    theta = model.theta_for(theta_name)
    noise = model.NOISE_CASES["case1"]
    ss = np.random.SeedSequence(seed)
    rng_proc, rng_meas = (np.random.default_rng(s) for s in ss.spawn(2))
    run = model.simulate(theta, timetable(), hours * HOUR, 1.0, noise, rng_proc)
    tf, y, u = model.sample_frames(run, 0.1, noise[2], rng_meas)
    plan = plan_events(hours, seed)
    pos_valid = ~_in_windows(tf, plan["outages"])
    steps = sorted((s["t_sim"], s["delta_s"]) for s in plan["clock_steps"])
    step_t = [a for a, _ in steps]
    step_cum = np.cumsum([0.0] + [d for _, d in steps])
    codec = FrameCodec(dbc)
    force = model.force_kn(u, 500.0)
    injected: Dict[str, Dict[str, int]] = {}
    n_written = 0
    pending: list = []
    n_chunks = int(math.ceil(len(tf) * 0.1 / CHUNK_S))
    with log_writer(str(out_p)) as log:
        for c in range(n_chunks + 1):
            msgs = []
            if c < n_chunks:
                lo, hi = np.searchsorted(tf, [c * CHUNK_S - 1e-9, (c + 1) * CHUNK_S - 1e-9])
                msgs = input_frames(codec, 0.0, tf[lo:hi], y[lo:hi], force[lo:hi], pos_valid=pos_valid[lo:hi])
            if msgs:
                t0 = msgs[0].timestamp
                sil = [(a - t0, b - t0) for a, b in plan["silences"] if a < t0 + CHUNK_S and b > t0]
                msgs, rep = replay.inject(msgs, FAULT_RATES, {}, seed=seed * 1000 + c, ids={0x100, 0x101},
                                          silence=sil, unknown_id=UNKNOWN_ID)
                for kind, per_id in rep["injected"].items():
                    for key, n in per_id.items():
                        injected.setdefault(kind, {}).setdefault(key, 0)
                        injected[kind][key] += n
            # a frame delayed past the chunk's end waits for the next chunk: the log stays in order
            merged = sorted(pending + msgs, key=lambda m: m.timestamp)
            limit = (c + 1) * CHUNK_S if c < n_chunks else math.inf
            cut = bisect.bisect_left([m.timestamp for m in merged], limit - 1e-9)
            pending = merged[cut:]
            for m in merged[:cut]:
                # the receive clock steps; the fix times (sender's clock) do not
                m.timestamp += float(step_cum[bisect.bisect_right(step_t, m.timestamp)])
                log.on_message_received(m)
                n_written += 1
    write_truth(str(stem) + "_truth.csv", run, 500.0, (seed, "case1", "soak"))
    np.savez_compressed(str(stem) + "_frames.npz", t=tf, y=y, valid=pos_valid)
    plan.update({
        "log": str(out_p), "hours": hours, "seed": seed, "type": theta.name, "noise": "case1",
        "frames": n_written, "model_steps": len(run.t) - 1, "fault_rates": FAULT_RATES,
        "unknown_id": f"0x{UNKNOWN_ID:03X}", "injected": injected,
        "injected_totals": {k: sum(v.values()) for k, v in injected.items()},
        "pos_invalid_frames": int((~pos_valid).sum()),
        "stops": int(sum(1 for a, b in zip(run.phase, run.phase[1:]) if b == "stop" and a != "stop")),
    })
    cli.write_text(str(stem) + "_plan.json", json.dumps(plan, indent=1) + "\n")
    return plan


# ---- the run -------------------------------------------------------------------------------

_K = re.compile(rb'"k":(\d+)')


def _last_k(path: str) -> int:
    """Step number of the last complete line of the (growing) step stream."""
    try:
        with open(path, "rb") as f:
            f.seek(0, os.SEEK_END)
            n = f.tell()
            f.seek(max(0, n - 16384))
            tail = f.read()
    except OSError:
        return 0
    lines = tail.split(b"\n")[:-1]  # the part after the last newline is not written yet
    for ln in reversed(lines):
        m = _K.search(ln)
        if m:
            return int(m.group(1))
    return 0


def _proc_sample(pid: int) -> Optional[Tuple[float, int]]:
    """(CPU seconds, VmRSS kB) of a live process, None once it is gone.
    CPU from /proc/PID/schedstat (ns), else utime + stime of /proc/PID/stat."""
    try:
        rss = 0
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    rss = int(line.split()[1])
                    break
        try:
            with open(f"/proc/{pid}/schedstat") as f:
                cpu = int(f.read().split()[0]) / 1e9
        except (OSError, ValueError, IndexError):
            with open(f"/proc/{pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            cpu = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
        return cpu, rss
    except (OSError, ValueError, IndexError):
        return None


def find_hstpfd(path: Optional[str]) -> str:
    cands = [path] if path else [
        str(Path(os.environ["HSTPF_BUILD_DIR"]) / "port" / "hstpfd") if os.environ.get("HSTPF_BUILD_DIR") else None,
        str(ROOT / "build" / "port" / "hstpfd"), shutil.which("hstpfd")]
    for c in cands:
        if c and os.path.isfile(c) and os.access(c, os.X_OK):
            return c
    raise cli.CliError(cli.EXIT_INPUT, f"cannot run {path or 'hstpfd'}: No such file or directory "
                       "(build it, or give --hstpfd / HSTPF_BUILD_DIR)")


def run(hstpfd: str, log: str, outdir: str, args: Sequence[str], sample_s: float) -> dict:
    """Runs hstpfd on the log, sampling it; returns the run's record."""
    steps = str(Path(outdir) / "steps.jsonl")
    summary = str(Path(outdir) / "summary.json")
    cmd = [hstpfd, *args, "--log", log, "--out", steps, "--summary", summary]
    for old in (steps, summary):  # a stream left from an earlier run would be sampled as this one's progress
        with contextlib.suppress(FileNotFoundError):
            os.unlink(old)
    samples = []
    w0 = time.perf_counter()
    with open(os.devnull, "w") as null, open(Path(outdir) / "hstpfd.stderr", "w") as err:
        p = subprocess.Popen(cmd, stdout=null, stderr=err)
        try:
            while True:
                s = _proc_sample(p.pid)
                k = _last_k(steps)
                if s is not None and p.poll() is None:
                    samples.append((round(time.perf_counter() - w0, 4), s[0], s[1], k))
                try:
                    p.wait(timeout=sample_s)
                    break
                except subprocess.TimeoutExpired:
                    continue
        finally:
            if p.poll() is None:
                p.kill()
                p.wait()
    wall = time.perf_counter() - w0
    with open(Path(outdir) / "samples.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["wall_s", "cpu_s", "rss_kb", "k"])
        w.writerows(samples)
    return {"cmd": cmd, "exit": p.returncode, "wall_s": round(wall, 3), "samples": samples,
            "stderr": (Path(outdir) / "hstpfd.stderr").read_text()[-2000:]}


# ---- the checks ----------------------------------------------------------------------------

SIGMA_E = math.sqrt(5.0)  # case1 measurement noise sd, m
Q_V, Q_S = 0.05, 0.02  # case1 process noise variances per 1 s step (speed m^2/s^2, position m^2)
SIGMA_V0 = 0.5  # speed error (sd) assumed at the last fix, m/s


def error_bound(tau: float, k_sd: float) -> float:
    """Largest position error accepted for a valid estimate tau s after its
    last fix: k_sd standard deviations of the case1 model's own error from a
    fix alone (no filtering credit): the measurement sd, a speed error of
    SIGMA_V0 and the integrated process noise,
    sqrt(sigma_e^2 + (sigma_v0 tau)^2 + q_v tau^3 / 3 + q_s tau)."""
    return k_sd * math.sqrt(SIGMA_E ** 2 + (SIGMA_V0 * tau) ** 2 + Q_V * tau ** 3 / 3.0 + Q_S * tau)


def speed_bound(tau: float, k_sd: float) -> float:
    """The same for the speed: a speed from two fixes 1 s apart (sd
    sqrt(2) sigma_e per s) plus the speed noise's random walk since the fix,
    sqrt(2 sigma_e^2 + q_v (tau + 1))."""
    return k_sd * math.sqrt(2.0 * SIGMA_E ** 2 + Q_V * (tau + 1.0))


def _strict_json(line: str):
    def bad(c):
        raise ValueError(f"non-finite {c}")
    return json.loads(line, parse_constant=bad)


NUM_FIELDS = ("t", "dt", "u", "pos", "speed")
NULLABLE = ("y", "pos_sd", "speed_sd")
POS_MAX_M, SPEED_MAX = 1.0e8, 200.0  # HSTPF_POS_MAX_M, HSTPF_SPEED_MAX (lib/include/hstpf/hstpf.h)


def _finite(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def per_block(samples, k_at_block: List[int]) -> List[dict]:
    """CPU seconds per step and max RSS per block of simulated time, from the
    samples (wall, cpu, rss, k) interpolated at the blocks' first steps."""
    if len(samples) < 2:
        return []
    ks = np.array([s[3] for s in samples], dtype=float)
    cpu = np.array([s[1] for s in samples])
    out = []
    for b in range(len(k_at_block) - 1):
        # only what the samples cover: the run may end, or start, between two samples
        k0, k1 = max(k_at_block[b], int(ks[0])), min(k_at_block[b + 1], int(ks[-1]))
        if k1 - k0 < 0.5 * (k_at_block[b + 1] - k_at_block[b]) or k1 <= k0:
            continue
        c0, c1 = np.interp([k0, k1], ks, cpu)
        rs = [s[2] for s in samples if k0 <= s[3] < k1]
        out.append({"block": b, "steps": k1 - k0, "cpu_us_per_step": round((c1 - c0) / (k1 - k0) * 1e6, 2),
                    "rss_max_kb": max(rs) if rs else None, "samples": len(rs)})
    return out


def check(steps_path: str, summary_path: str, stem: str, run_rec: Optional[dict], block_s: float,
          warmup_s: float, k_sd: float, rss_tol_kb: int, cpu_tol: float) -> dict:
    """Every check of docs/soak.md; returns the figures and the failures."""
    plan = json.loads(Path(stem + "_plan.json").read_text())
    fr = np.load(stem + "_frames.npz")
    tf, yf, vf = fr["t"], fr["y"], fr["valid"]
    truth_t, truth_s, truth_v = [], [], []
    with open(stem + "_truth.csv", newline="") as f:
        for r in csv.DictReader(f):
            truth_t.append(float(r["time_s"]))
            truth_s.append(float(r["position_m"]))
            truth_v.append(float(r["speed_mps"]))
    truth_t, truth_s, truth_v = map(np.array, (truth_t, truth_s, truth_v))
    clock = sorted((s["t_sim"], s["delta_s"]) for s in plan["clock_steps"])
    clock_t, clock_d = [c[0] for c in clock], [c[1] for c in clock]
    lead: List[float] = []  # errors of the valid steps between a small forward clock step and its detection
    fails: List[str] = []

    n_fail: Dict[str, int] = {}

    def fail(msg, what="output"):
        """One failed check; the first 50 are kept, prefixed by the check's name."""
        n_fail[what] = n_fail.get(what, 0) + 1
        if len(fails) < 50:
            fails.append(f"{what}: {msg}")

    n = n_valid = n_scored = n_unscored = n_pred = n_nonfinite = 0
    worst = {"ratio": 0.0}
    err_fix, err_pred, err_v, sd_ratios = [], [], [], []
    p = 0  # frames before this index are matched already
    last = None  # (daemon t, sim t) of the last step with a fix
    block_k: Dict[int, int] = {}
    with open(steps_path) as f:
        for ln, line in enumerate(f, 1):
            n += 1
            try:
                s = _strict_json(line)
            except ValueError as exc:
                n_nonfinite += 1
                fail(f"line {ln}: not finite JSON ({exc})", "nonfinite")
                continue
            # no non-finite value anywhere: numbers are finite, null only where documented
            for key in NUM_FIELDS:
                if not _finite(s.get(key)):
                    n_nonfinite += 1
                    fail(f"line {ln}: {key} = {s.get(key)!r}", "nonfinite")
            for key in NULLABLE:
                if s.get(key) is not None and not _finite(s[key]):
                    fail(f"line {ln}: {key} = {s[key]!r}", "nonfinite")
            for key in ("theta", "q", "ess"):
                if not all(_finite(x) for x in s.get(key) or [None]):
                    n_nonfinite += 1
                    fail(f"line {ln}: {key} = {s.get(key)!r}", "nonfinite")
            # the declaration invariant
            if (s.get("status") in ("declared", "changed")) != (s.get("declared") is not None):
                fail(f"line {ln}: status {s.get('status')!r} with declared {s.get('declared')!r}", "declaration")
            # its time on the simulation's clock: a fix by its value, else from the last fix
            sim = None
            if s.get("y") is not None:
                y = s["y"]
                lo, width = p, 64
                while lo < len(yf):
                    hi = min(len(yf), lo + width)
                    hit = np.nonzero((np.abs(yf[lo:hi] - y) <= 0.0051) & vf[lo:hi])[0]
                    if len(hit):
                        p = lo + int(hit[0]) + 1
                        sim = float(tf[p - 1])
                        break
                    lo, width = hi, width * 4
                if sim is None:
                    fail(f"line {ln}: fix y = {y} is in no position frame after t = {tf[min(p, len(tf) - 1)]}",
                         "alignment")
                    continue
                last = (s["t"], sim)
                tau = 0.0
            elif last is not None:
                n_pred += 1
                tau = s["t"] - last[0]
                cand = last[1] + tau
                # a receive-clock step since the last fix: the stamp no longer tells the time
                i0, i1 = bisect.bisect_right(clock_t, last[1]), bisect.bisect_right(clock_t, cand)
                if i0 == i1:
                    sim = cand
                elif i1 == i0 + 1 and 0 < clock_d[i0] < 600.0 and s.get("valid") and _finite(s.get("pos")):
                    # a forward step too short to be told from a silence until 10 s of fix
                    # time show it: the daemon predicts across it; such a step goes out on
                    # the first frame after the step (or, later, when the stamps pass it)
                    pub = max(clock_t[i0], cand - clock_d[i0])
                    lead.append(abs(s["pos"] - float(np.interp(pub, truth_t, truth_s))))
            if sim is not None:
                b = int(sim // block_s)
                block_k.setdefault(b, s["k"])
            if not s.get("valid"):
                continue
            n_valid += 1
            pos, v = s.get("pos"), s.get("speed")
            if not (_finite(pos) and _finite(v) and abs(pos) <= POS_MAX_M and -SPEED_MAX <= v <= SPEED_MAX):
                fail(f"line {ln}: valid with pos {pos!r}, speed {v!r}", "range")
                continue
            if sim is None or sim > truth_t[-1]:
                n_unscored += 1
                continue
            n_scored += 1
            e = pos - float(np.interp(sim, truth_t, truth_s))
            (err_fix if s.get("y") is not None else err_pred).append(e)
            ev = v - float(np.interp(sim, truth_t, truth_v))
            err_v.append(ev)
            bound = error_bound(tau, k_sd)
            if abs(e) / bound > worst["ratio"]:
                worst = {"ratio": round(abs(e) / bound, 4), "line": ln, "k": s["k"], "t_sim": round(sim, 3),
                         "error_m": round(e, 3), "bound_m": round(bound, 3), "since_fix_s": round(tau, 3)}
            if abs(e) > bound:
                fail(f"line {ln} (k {s['k']}, sim t {sim:.1f} s, {tau:.0f} s after a fix): position error "
                     f"{e:.2f} m beyond {bound:.2f} m", "position_error")
            if abs(ev) > speed_bound(tau, k_sd):
                fail(f"line {ln} (k {s['k']}, sim t {sim:.1f} s, restart {s.get('restart')}): speed {v:.2f} m/s, "
                     f"error {ev:.2f} beyond {speed_bound(tau, k_sd):.2f} m/s", "speed_error")
            if _finite(s.get("pos_sd")) and s["pos_sd"] > 0:  # consistency of the published sd (reported)
                sd_ratios.append((abs(e) / s["pos_sd"], bool(s.get("standstill")), s["pos_sd"]))
    try:
        summary = _strict_json(Path(summary_path).read_text())
    except ValueError as exc:
        fail(f"summary is not finite JSON ({exc})", "nonfinite")
        summary = {}

    # counts against the plan
    inj = plan["injected_totals"]
    # hstpfd counts a forward step only beyond max_gap_s (30 s in the
    # configs used here); a shorter one acts as a silence (docs/daemon.md)
    n_fwd = sum(1 for s in plan["clock_steps"] if s["delta_s"] > 30.0)
    n_back = sum(1 for s in plan["clock_steps"] if s["delta_s"] < 0)
    fa, sch = summary.get("faults", {}), summary.get("scheduler", {})
    expect = {
        ("faults", "bad_crc"): inj.get("corrupt", 0),
        ("faults", "wrong_length"): inj.get("truncate", 0),
        ("faults", "unknown_id"): inj.get("unknown", 0),
        ("faults", "clock_steps_forward"): n_fwd,
        ("faults", "clock_steps_back"): n_back,
    }
    for (grp, key), want in expect.items():
        got = summary.get(grp, {}).get(key)
        if got != want:
            fail(f"summary {grp}.{key} = {got}, injected {want}", "counts")
    if summary.get("end") != "eof":
        fail(f"summary end = {summary.get('end')!r}", "counts")
    if summary.get("steps") != n:
        fail(f"summary steps = {summary.get('steps')}, step stream has {n} lines", "counts")

    # resources: blocks of simulated time
    figures: dict = {}
    if run_rec is not None:
        if run_rec["exit"] != 0:
            fail(f"hstpfd exit {run_rec['exit']}: {run_rec['stderr'].strip()[-300:]}", "exit")
        nb = int(math.ceil(plan["hours"] * HOUR / block_s))
        ks = [block_k.get(b) for b in range(nb)] + [n + 1]
        for b in range(nb - 1, -1, -1):  # a block without a step of its own starts where the next does
            if ks[b] is None:
                ks[b] = ks[b + 1]
        ks[0] = min(ks[0] + int(warmup_s), ks[1] - 1)  # the first block after warm-up (steps ~1 s apart)
        blocks = per_block(run_rec["samples"], ks)
        samples = run_rec["samples"]
        first = [s[2] for s in samples if ks[0] <= s[3] < ks[1]]
        lastb = [s[2] for s in samples if ks[-2] <= s[3]]
        figures = {"blocks": blocks, "rss_first_kb": max(first) if first else None,
                   "rss_last_kb": max(lastb) if lastb else None, "samples": len(samples)}
        if not first or not lastb:
            fail(f"too few samples: {len(first)} in the first block after warm-up, {len(lastb)} in the last", "rss")
        elif max(lastb) > max(first) + rss_tol_kb:
            fail(f"last block max {max(lastb)} kB against {max(first)} kB in the first (+{rss_tol_kb} allowed)",
                 "rss")
        if len(blocks) >= 2:
            # medians of the first and last quarter (at most 6 blocks): on a shared machine a
            # quarter's median moves by +-20 % from run to run (docs/soak.md); a cost that
            # grows with the run's length grows far more than that over a day
            m = max(1, min(6, len(blocks) // 4))
            c_first = round(float(np.median([b["cpu_us_per_step"] for b in blocks[:m]])), 2)
            c_last = round(float(np.median([b["cpu_us_per_step"] for b in blocks[-m:]])), 2)
            figures["cpu_us_per_step_first"], figures["cpu_us_per_step_last"] = c_first, c_last
            cs = np.array([b["cpu_us_per_step"] for b in blocks])
            slope = np.polyfit(np.arange(len(cs)), cs, 1)[0] if len(cs) > 2 else 0.0
            figures["cpu_trend_over_run"] = round(float(slope * (len(cs) - 1) / cs.mean()), 4)
            if c_last > c_first * (1.0 + cpu_tol):
                fail(f"{c_last} us per step in the last {m} block(s) against {c_first} us in the first "
                     f"(+{cpu_tol:.0%} allowed)",
                     "step_time")
        else:
            fail(f"{len(blocks)} block(s) sampled, need 2 (lower --sample-s)", "step_time")
        figures["wall_s"] = run_rec["wall_s"]
        cpu_total = samples[-1][1] if samples else None
        figures["cpu_s"] = round(cpu_total, 3) if cpu_total is not None else None

    def stats(xs):
        a = np.abs(np.array(xs))
        return ({"n": len(xs), "rms": round(float(np.sqrt(np.mean(a ** 2))), 3), "max": round(float(a.max()), 3)}
                if len(xs) else {"n": 0})

    report = {
        "steps": n, "valid": n_valid, "valid_fraction": round(n_valid / n, 5) if n else 0.0,
        "predict_steps": n_pred, "scored": n_scored, "unscored_valid": n_unscored, "nonfinite": n_nonfinite,
        "before_step_found_m": stats(lead),
        "position_error_fix_m": stats(err_fix), "position_error_predict_m": stats(err_pred),
        "speed_error_mps": stats(err_v), "worst": worst, "k_sd": k_sd,
        "clock_steps": {"injected_forward": n_fwd, "injected_back": n_back,
                        "counted_forward": fa.get("clock_steps_forward"), "counted_back": fa.get("clock_steps_back"),
                        },
        "faults": {"injected": inj, "pos_invalid_frames": plan["pos_invalid_frames"],
                   "counted": {k: v for k, v in fa.items() if v}},
        "reacquire": sch.get("reacquire"), "restarts": sch.get("restarts"),
        "acquisitions": summary.get("acquisitions"), "nonfinite_resets": summary.get("nonfinite_resets"),
        "declared": summary.get("declared"), "status": summary.get("status"),
        "step_errors": summary.get("step_errors"),
    }
    report.update(figures)
    if sd_ratios:  # is the published position_sd_m honest? (reported, not a check)
        a = np.array(sd_ratios)
        report["sd_consistency"] = {}
        for name, sel in (("moving", a[:, 1] == 0), ("standstill", a[:, 1] == 1)):
            r, sd = a[sel, 0], a[sel, 2]
            report["sd_consistency"][name] = {
                "n": int(sel.sum()), "beyond_3sd": int((r > 3).sum()), "beyond_6sd": int((r > 6).sum()),
                "max_error_over_sd": round(float(r.max()), 2) if len(r) else None,
                "sd_min_m": round(float(sd.min()), 4) if len(r) else None}
    report["failed_checks"] = n_fail
    report["failures"] = fails
    report["pass"] = not fails
    return report


# ---- command line --------------------------------------------------------------------------

DEFAULT_ARGS = ["--config", str(ROOT / "port" / "config" / "case1.ini"), "--models", "all", "--engine", "particle"]


def build_parser() -> argparse.ArgumentParser:
    p = cli.Parser(
        prog="hstpf-soak",
        description="A simulated day through hstpfd --log: make the log (stops, GNSS outages, receive-clock steps, "
        "bus faults; deterministic by seed), run hstpfd sampling its RSS and CPU time, check every step "
        "(finite, in range, position error within a bound, declaration invariant) and that RSS and per-step "
        "time stay flat. Prints a JSON report; exit 1 when a check fails.",
        epilog="Exit codes: 0 every check passed (or --make-only), 1 a check failed, 2 usage, 3 an input (--log, its "
        "_plan.json/_truth.csv/_frames.npz, hstpfd) cannot be read, 6 an output cannot be written. "
        "Arguments after '--' go to hstpfd (default: " + " ".join(DEFAULT_ARGS[2:]) + " --config "
        "port/config/case1.ini).",
    )
    p.add_argument("--hours", type=float, default=24.0, help="simulated hours (24)")
    p.add_argument("--seed", type=int, default=1, help="seed of the day: trajectory, noise, events, faults (1)")
    p.add_argument("--dir", default="soak", help="folder for every file (soak)")
    p.add_argument("--log", help="use this log (made by hstpf-soak: its _plan.json, _truth.csv, _frames.npz beside "
                   "it) instead of making one")
    p.add_argument("--make-only", action="store_true", help="only make the log")
    p.add_argument("--hstpfd", help="the daemon (default: $HSTPF_BUILD_DIR/port/hstpfd, build/port/hstpfd, PATH)")
    p.add_argument("--sample-s", type=float, default=0.1, help="sampling period of RSS and CPU time, s (0.1)")
    p.add_argument("--block-s", type=float, default=3600.0,
                   help="blocks of simulated time compared for flatness, s (3600)")
    p.add_argument("--warmup-s", type=float, default=600.0,
                   help="simulated time left out of the first block (RSS and CPU), s (600)")
    p.add_argument("--k-sd", type=float, default=6.0, help="position error bound in standard deviations (6)")
    p.add_argument("--rss-tol-kb", type=int, default=256, help="RSS growth allowed, last block against first (256)")
    p.add_argument("--cpu-tol", type=float, default=0.5, help="per-step CPU growth allowed, fraction (0.5)")
    p.add_argument("--dbc", help="DBC file (default port/dbc/hstpf.dbc)")
    cli.add_json_argument(p)
    p.add_argument("hstpfd_args", nargs=argparse.REMAINDER, help="-- then hstpfd's options")
    return p


def _main(argv) -> int:
    a = build_parser().parse_args(argv)
    extra = a.hstpfd_args[1:] if a.hstpfd_args[:1] == ["--"] else a.hstpfd_args
    if a.hours <= 0 or a.sample_s <= 0 or a.block_s <= 0:
        raise cli.CliError(cli.EXIT_USAGE, "--hours, --sample-s and --block-s must be > 0")
    report: dict = {}
    if a.log:
        stem = str(Path(a.log).with_name(Path(a.log).stem))
        for suffix in ("", "_plan.json", "_truth.csv", "_frames.npz"):
            path = a.log if suffix == "" else stem + suffix
            try:
                with open(path, "rb"):
                    pass
            except OSError as exc:
                raise cli.input_error(path, exc) from exc
        log = a.log
    else:
        log = str(Path(a.dir) / "soak.log")
        stem = str(Path(a.dir) / "soak")
        t = time.perf_counter()
        try:
            plan = make(log, a.hours, a.seed, a.dbc)
        except OSError as exc:
            raise cli.output_error(log, exc) from exc
        report["make"] = {"log": log, "frames": plan["frames"], "wall_s": round(time.perf_counter() - t, 1)}
    if a.make_only:
        cli.emit_report(report, a.json)
        return cli.EXIT_OK
    exe = find_hstpfd(a.hstpfd)
    Path(a.dir).mkdir(parents=True, exist_ok=True)
    rec = run(exe, log, a.dir, extra or DEFAULT_ARGS, a.sample_s)
    report["cmd"] = " ".join(rec["cmd"])
    if not Path(a.dir, "steps.jsonl").exists() or not Path(a.dir, "summary.json").exists():
        raise cli.CliError(1, f"hstpfd exit {rec['exit']} without output: {rec['stderr'].strip()[-300:]}")
    report.update(check(str(Path(a.dir) / "steps.jsonl"), str(Path(a.dir) / "summary.json"), stem, rec,
                        a.block_s, a.warmup_s, a.k_sd, a.rss_tol_kb, a.cpu_tol))
    cli.write_text(str(Path(a.dir) / "report.json"), json.dumps(report, indent=1) + "\n")
    cli.emit_report(report, a.json)
    return cli.EXIT_OK if report["pass"] else 1


def main(argv=None) -> int:
    return cli.run("hstpf-soak", _main, argv)


if __name__ == "__main__":
    sys.exit(main())
