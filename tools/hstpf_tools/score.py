"""hstpf-score: the estimator's output frames against the simulation's truth.

An EstState frame followed by an EstQuality frame with EstTimeValid is
dated by EstQuality.EstTime, the estimate's own time on the position
sender's fix clock (inputs alignment: through the latest input's FixTime),
whatever the bus or estimator latency. Other frame times are mapped to
simulation time in one of two ways:
  inputs  the recorded log also holds the Position frames that were on the
          bus; each one is found by content in the simulated input log
          (--input-log), whose frame times are t0 + simulation time (--t0;
          by default 0 when the input log starts within the truth's span,
          as hstpf-simulate writes it, whole or cut, else its first
          timestamp). A payload the input log holds more than once (a
          position frame without a fix, PosValid 0, repeats with the E2E
          counter every 15 frames) is matched in order: the occurrence
          nearest the time the frame is due at, from the frame matched
          before it (the next input frame, or later by the bus time since
          times the replay's rate when frames were lost). An output frame
          gets the time of the latest input position seen before it. Exact
          at any replay speed and with faults (corrupted or injected frames
          simply do not match).
  time    simulation time = (timestamp - t0) x speed (--t0, --speed): for a
          log whose timestamps are already simulation times (an offline
          run that stamps outputs with input times), or a plain replay.
"""
import argparse
import csv
import io
import json
import re
import sys
from pathlib import Path
from typing import Dict, List, Optional, Tuple

import numpy as np

from . import cli, e2e, runconfig
from .frames import (BAND_SPEEDS_KMH, EST_BAND, EST_QUALITY, EST_STATE, EST_THETA, EST_TYPE, FIT_NAMES,
                     FIX_TIME_WRAP_MS, HEALTH_RX, HEALTH_SYS, HEALTH_TIME, POSITION, STATUS_NAMES, TYPE_CUSTOM,
                     TYPE_NONE, FrameCodec, is_hstpf_frame, type_name)
from .model import Theta

V_GRID_KMH = np.arange(0.0, 351.0, 1.0)
OUTPUT_SENDER = "HSTPF"  # the DBC node of the estimator: its frames are the outputs
Z95 = 1.959963984540054  # two-sided 95 % of a normal distribution: W at one speed
# the whole curve W(v) at once: hstpf.h's HSTPF_BAND_Z_CURVE (sqrt of the chi-square
# 95 % quantile, 3 degrees of freedom; tests/python/test_band.py checks they agree)
Z_CURVE = 2.7955


def read_truth(path: str) -> Dict[str, np.ndarray]:
    rows = list(csv.DictReader(io.StringIO(cli.read_text(path))))
    if not rows:
        raise ValueError(f"{path}: no rows")
    cols = ("time_s", "position_m", "speed_mps", "type", "c0", "c1", "c2")
    for n, r in enumerate(rows, start=2):  # line 1 is the header
        gone = [k for k in cols if r.get(k) in (None, "")]  # a file cut short ends in a partial row
        if gone:
            raise ValueError(f"line {n} has no {gone[0]}")
    out = {k: np.array([float(r[k]) for r in rows]) for k in ("time_s", "position_m", "speed_mps", "c0", "c1", "c2")}
    r0 = rows[-1]
    out["theta"] = Theta(r0["type"], float(r0["c0"]), float(r0["c1"]), float(r0["c2"]))
    out["identity"] = {k: r0[k] for k in ("type", "seed", "noise", "profile") if r0.get(k)}
    return out


def truth_theta_at(truth: Dict[str, np.ndarray], t: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The truth's c0, c1, c2 in force at each time t (the row at or before
    it): a consist coupled on the way changes them, and the plots compared
    every estimate with the last row's (a review)."""
    tt = truth["time_s"]
    at = np.clip(np.searchsorted(tt, np.asarray(t, dtype=float), side="right") - 1, 0, len(tt) - 1)
    return truth["c0"][at], truth["c1"][at], truth["c2"][at]


def w_rms_rel(est: Theta, true: Theta) -> float:
    """RMS relative error of W(V) over 0..350 km/h in 1 km/h steps."""
    v = V_GRID_KMH / 3.6
    wt, we = true.resistance(v), est.resistance(v)
    return float(np.sqrt(np.mean(((we - wt) / wt) ** 2)))


class InputLog:
    """The position frames of the simulated input log: their simulation
    times (log time - t0) in log order, and where each payload occurs."""

    def __init__(self, msgs, pos_id: int, t0: float):
        pos = [m for m in msgs if m.arbitration_id == pos_id and is_hstpf_frame(m)]
        self.times = np.array([m.timestamp - t0 for m in pos], dtype=float)
        occ: Dict[bytes, List[int]] = {}
        for j, m in enumerate(pos):
            occ.setdefault(bytes(m.data), []).append(j)
        self.occ = {k: np.array(v) for k, v in occ.items()}

    def match(self, rec_msgs, pos_id: int, speed: Optional[float] = None) -> Dict[int, float]:
        """Simulation time of each recorded position frame found in the input
        log, by its index in rec_msgs. A payload that occurs once is that
        frame. One that occurs more than once (PosValid 0 frames repeat byte
        for byte every 15 frames, the E2E counter's cycle) is the occurrence
        nearest the time it is due at, reckoned from the frame matched just
        before it (before the first unique one: just after it): the next
        input frame in the log, or, when more bus time has gone by, that
        time by the replay's rate (speed, else measured on the unique
        frames), so frames the daemon or the bus dropped are skipped. In
        order and without losses the k-th echo of a payload is its k-th
        occurrence; a duplicate (the same frame again) is the same one."""
        cand = [(i, m.timestamp, self.occ[bytes(m.data)]) for i, m in enumerate(rec_msgs)
                if m.arbitration_id == pos_id and is_hstpf_frame(m) and bytes(m.data) in self.occ]
        if not cand:
            return {}
        times = self.times
        rate = speed
        uniq = np.array([(ts, times[o[0]]) for _, ts, o in cand if len(o) == 1]).reshape(-1, 2)
        if rate is None and len(uniq) > 10:
            d_ts, d_sim = np.diff(uniq[:, 0]), np.diff(uniq[:, 1])
            ok = (d_ts > 0) & (d_sim > 0)
            if ok.sum() > 10:
                rate = float(np.median(d_sim[ok] / d_ts[ok]))
        got: List[int] = [0] * len(cand)

        def pick(k: int, ref: Optional[int], step: int) -> int:
            _, ts, o = cand[k]
            if len(o) == 1 or ref is None:
                return int(o[0])
            jr, ts_r = got[ref], cand[ref][1]
            due = times[jr + step] if 0 <= jr + step < len(times) else times[jr]
            if rate is not None:  # more bus time than one frame's since the reference: frames were lost
                by_rate = times[jr] + rate * (ts - ts_r)
                due = max(due, by_rate) if step > 0 else min(due, by_rate)
            return int(o[np.argmin(np.abs(times[o] - due))])

        first = next((k for k, c in enumerate(cand) if len(c[2]) == 1), 0)
        for k in range(first, len(cand)):
            got[k] = pick(k, k - 1 if k > first else None, 1)
        for k in range(first - 1, -1, -1):
            got[k] = pick(k, k + 1, -1)
        return {cand[k][0]: float(times[got[k]]) for k in range(len(cand))}


# the input log's positions this far (median) from the truth's: its t0 is wrong
INPUT_OFFSET_WARN_M = 100.0


def input_offset_m(msgs, codec: FrameCodec, t0: float, truth) -> Optional[float]:
    """Median |Position - truth position| over the input log's valid
    position frames within the truth's span, each at log time - t0; None
    without one. Metres of measurement noise when t0 is right."""
    pos_id = codec.message(POSITION).frame_id
    msg = codec.message(POSITION)
    tt = truth["time_s"]
    t, y = [], []
    for m in msgs:
        if m.arbitration_id != pos_id or not is_hstpf_frame(m) or not tt[0] <= m.timestamp - t0 <= tt[-1]:
            continue
        try:
            sig = msg.decode(bytes(m.data), decode_choices=False)
        except Exception:  # a frame cantools cannot decode (wrong length): not a position
            continue
        if sig.get("PosValid", 0) >= 0.5:
            t.append(m.timestamp - t0)
            y.append(float(sig["Position"]))
    if not t:
        return None
    return float(np.median(np.abs(np.array(y) - np.interp(np.array(t), tt, truth["position_m"]))))


def collect(rec_msgs, codec: FrameCodec, align: str, inputs: Optional[InputLog], t0: float,
            speed: Optional[float]):
    """Decoded output series with simulation times. speed: the replay's
    speed-up (None: 1 for time alignment; measured from the inputs for
    inputs alignment)."""
    series: Dict[str, List] = {EST_STATE: [], EST_QUALITY: [], EST_TYPE: [], EST_THETA: [], EST_BAND: [],
                               HEALTH_RX: [], HEALTH_SYS: [], HEALTH_TIME: []}
    t_sim: Optional[float] = None
    t_in: Optional[float] = None  # bus time of the latest matched input
    e2e_results: Dict[str, Dict[str, int]] = {}
    rec_msgs = list(rec_msgs)
    pos_id = codec.message(POSITION).frame_id
    # An output frame long after the latest input (the inputs ended, or a
    # silence) holds a prediction, not the estimate at that input's time:
    # with inputs alignment it cannot be timed, so it is not scored.
    foreign = 0  # 29-bit frames: never ours, whatever their ID (as hstpfd)
    match = inputs.match(rec_msgs, pos_id, speed) if inputs is not None else {}
    matched = sorted(match)  # indices in rec_msgs
    in_ts = [rec_msgs[i].timestamp for i in matched]
    gaps = np.diff(in_ts) if len(in_ts) > 1 else np.array([np.inf])
    max_age = 3.0 * float(np.median(gaps)) if len(gaps) else np.inf
    # For dating by EstTime when nothing else does: simulation seconds per
    # bus second (the replay's speed-up), the median over consecutive inputs
    # (stalls and their bursts do not move it). hstpfd runs its predictions
    # on the receive time less the latest fix's latency, so a prediction
    # lies near the latest input's time plus the bus time since it, at that rate.
    in_sim = np.array([match[i] for i in matched])
    rate = speed if speed is not None else 1.0
    if speed is None and len(in_ts) > 10:
        d_ts, d_sim = np.diff(np.array(in_ts)), np.diff(in_sim)
        ok = (d_ts > 0) & (d_sim > 0)
        if ok.sum() > 10:
            rate = float(np.median(d_sim[ok] / d_ts[ok]))
    pos_msg = codec.message(POSITION)
    fix_in: Optional[int] = None  # FixTime of the latest matched input
    fix_sim: Dict[int, float] = {}  # FixTime -> simulation time of the latest matched input with it
    prev_est: Optional[Tuple[float, int, float]] = None  # the latest dated estimate: sim time, EstTime, bus time
    pending = None  # an EstState waiting for the EstQuality frame that dates it
    n_dated = 0

    def keep(name, t, ts, sig):
        if t is None:
            return
        if align == "inputs" and name in (EST_STATE, EST_QUALITY) and t_in is not None and ts - t_in > max_age:
            return
        series[name].append((t, sig))

    for idx, m in enumerate(rec_msgs):
        if not is_hstpf_frame(m):  # a remote or CAN FD frame with one of our IDs: hstpfd's format error
            foreign += int(m.is_extended_id and not m.is_error_frame)
            name = None if m.is_extended_id or m.is_error_frame else codec.message_name(m.arbitration_id)
            if name is not None and OUTPUT_SENDER in (codec.message(name).senders or ()):
                e2e_results.setdefault(name, {}).setdefault("format", 0)
                e2e_results[name]["format"] += 1
            continue
        if m.arbitration_id == pos_id:
            t = match.get(idx)
            if t is not None:
                try:
                    p = pos_msg.decode(bytes(m.data), decode_choices=False)
                except Exception:  # a truncated frame (hstpfd refuses it): no step, nothing to align to
                    continue
                t_sim = t
                t_in = m.timestamp
                fix_in = int(p["FixTime"]) if p.get("FixTimeValid", 0) >= 0.5 else None
                if fix_in is not None:
                    fix_sim[fix_in] = t
            continue
        name, sig, res = codec.decode(m.arbitration_id, bytes(m.data), now=m.timestamp)
        if name not in series:
            if name is None or OUTPUT_SENDER not in (codec.message(name).senders or ()):
                continue  # inputs and unknown IDs
            series[name] = []  # an estimator frame this tool has no name for (e.g. the sd of the state)
        e2e_results.setdefault(name, {}).setdefault(res, 0)
        e2e_results[name][res] += 1
        if sig is None:
            continue
        t = t_sim if align == "inputs" else (m.timestamp - t0) * (speed if speed is not None else 1.0)
        if name == EST_QUALITY and align == "inputs" and sig.get("EstTimeValid", 0) >= 0.5 \
                and (fix_in is not None or prev_est is not None) and t_sim is not None:
            # the estimate's own time, on the fix clock. A step on a fix has
            # that fix's FixTime: the latest recorded input with it dates the
            # estimate exactly. A predict-only step lies after the estimate
            # before it (steps never go back) by less than a wrap when the
            # two are close on the bus (also when the latest inputs carry no
            # fix time: PosValid 0, a tunnel). Otherwise (the first estimate,
            # or one after a long silence of the outputs): from the latest
            # input's time and the bus time since, below, when that input
            # has a fix time.
            est_ms = int(sig["EstTime"])
            t_est = fix_sim.get(est_ms)
            if t_est is not None and t_sim - t_est > FIX_TIME_WRAP_MS / 2000.0:
                t_est = None  # that input is more than half a wrap old: another fix's time
            if t_est is None and prev_est is not None and (m.timestamp - prev_est[2]) * rate < FIX_TIME_WRAP_MS / 2000.0:
                t_est = prev_est[0] + ((est_ms - prev_est[1]) % FIX_TIME_WRAP_MS) / 1000.0
            if t_est is None and fix_in is not None:
                # hstpfd never predicts past the latest input plus the bus
                # time since it (a late publication only makes the estimate
                # older than that): the latest time with that EstTime not
                # after it, with 0.5 s for the rate's error
                expect_ms = rate * (m.timestamp - t_in) * 1000.0  # how far past the latest input
                d = -((expect_ms + 500.0 - (est_ms - fix_in)) % FIX_TIME_WRAP_MS)  # in (-wrap, 0]
                t_est = t_sim + (expect_ms + 500.0 + d) / 1000.0
            if t_est is not None:
                prev_est = (t_est, est_ms, m.timestamp)
                if pending is not None:
                    series[EST_STATE].append((t_est, pending[2]))
                    n_dated += 1
                    pending = None
                series[name].append((t_est, sig))
                continue
        if pending is not None:
            keep(EST_STATE, *pending)
            pending = None
        if name == EST_STATE:
            pending = (t, m.timestamp, sig)
            continue
        keep(name, t, m.timestamp, sig)
    if pending is not None:
        keep(EST_STATE, *pending)
    series["dated_by_est_time"] = n_dated
    series["ignored_29bit_frames"] = foreign
    return series, e2e_results


def input_clock_steps(msgs, codec: FrameCodec) -> List[float]:
    """Log times at which the input log's clock steps: consecutive valid
    position frames whose log times differ from their fix times' difference
    (Position.FixTime, within half its wrap) by more than a second. Frames
    are dated log time - t0, so the truth is misread after such a step."""
    pos_id = codec.message(POSITION).frame_id
    msg = codec.message(POSITION)
    out: List[float] = []
    prev = None
    for m in msgs:
        if m.arbitration_id != pos_id or not is_hstpf_frame(m):
            continue
        try:
            sig = msg.decode(bytes(m.data), decode_choices=False)
        except Exception:  # a frame cantools cannot decode (wrong length): not a position
            continue
        if sig.get("PosValid", 0) < 0.5 or sig.get("FixTimeValid", 0) < 0.5:
            prev = None  # a gap in the fix clock: the next pair starts afresh
            continue
        if prev is not None:
            d = (int(sig["FixTime"]) - prev[1]) % FIX_TIME_WRAP_MS
            d = d - FIX_TIME_WRAP_MS if d > FIX_TIME_WRAP_MS // 2 else d
            if abs((m.timestamp - prev[0]) - d / 1000.0) > 1.0:
                out.append(float(m.timestamp))
        prev = (m.timestamp, int(sig["FixTime"]))
    return out


def fix_time_stats(rec_msgs, dbc: Optional[str] = None) -> dict:
    """The recorded position frames' fix times (Position.FixTime) against
    their receive stamps: how many carry one, the rate of the receive clock
    per fix-clock second (1 / replay speed) and the receive jitter, in ms of
    the fix clock (the error a receiver that dates fixes on receipt makes).
    Only E2E-accepted frames count."""
    codec = FrameCodec(dbc)
    pos_id = codec.message(POSITION).frame_id
    rx, fix = [], []
    for m in rec_msgs:
        if m.arbitration_id != pos_id or not is_hstpf_frame(m):
            continue
        _, sig, _ = codec.decode(m.arbitration_id, bytes(m.data), now=m.timestamp)
        if sig is not None and sig.get("FixTimeValid", 0) >= 0.5 and sig["PosValid"] >= 0.5:
            rx.append(m.timestamp)
            fix.append(int(sig["FixTime"]))
    out: dict = {"fix_time_frames": len(fix)}
    if len(fix) < 3:
        return out
    d = np.diff(np.array(fix, dtype=np.int64)) % FIX_TIME_WRAP_MS
    d = np.where(d > FIX_TIME_WRAP_MS // 2, d - FIX_TIME_WRAP_MS, d)  # consecutive fixes: within half a wrap
    fix_u = np.concatenate(([0], np.cumsum(d))).astype(float)  # ms
    b, a = np.polyfit(fix_u, np.array(rx), 1)
    if not b > 0:
        return out
    lat = (np.array(rx) - (a + b * fix_u)) / b  # ms of the fix clock
    lat -= np.min(lat)  # latency above the least one seen
    out["rx_s_per_fix_s"] = round(float(b * 1000.0), 9)
    out["rx_latency_ms"] = {k: round(float(v), 3) for k, v in
                            (("p50", np.percentile(lat, 50)), ("p99", np.percentile(lat, 99)), ("max", np.max(lat)))}
    return out


# an EstQuality this long after an EstState belongs to it (both go out together; the
# state period is 1 s by default)
QUALITY_PAIR_S = 0.05
# EstTheta's resolution (the DBC's factors of C0, C1, C2)
THETA_LSB = (0.001, 1e-6, 2e-8)


def custom_is_truth(series, t_from: float, t_type: float, th_true: Theta) -> Optional[bool]:
    """Every custom row goes out as DeclaredType 254, without its name; a
    declared row publishes its own theta, so the declared custom row is the
    truth's when the last valid EstTheta of the final declaration (from
    t_from to the last EstType, t_type) is the truth's theta to the frame's
    resolution. None (unknown) without one: a theta beyond the frame's
    range goes out invalid (saturated), and one from before the
    declaration is a blend."""
    thf = [s for t, s in series[EST_THETA]
           if s["ThetaValid"] >= 0.5 and t_from - QUALITY_PAIR_S <= t <= t_type + QUALITY_PAIR_S]
    if not thf:
        return None
    s = thf[-1]
    return all(abs(s[k] - v) <= lsb for k, v, lsb in zip(("C0", "C1", "C2"), (th_true.c0, th_true.c1, th_true.c2),
                                                           THETA_LSB))

def metrics(series, truth) -> dict:
    th_true: Theta = truth["theta"]
    tt = truth["time_s"]
    res: dict = {"true_type": th_true.name, "true_theta": [th_true.c0, th_true.c1, th_true.c2]}
    st = [(t, s) for t, s in series[EST_STATE] if s["EstValid"] >= 0.5 and tt[0] <= t <= tt[-1]]
    if st:
        t = np.array([x[0] for x in st])
        pos = np.array([x[1]["EstPosition"] for x in st])
        spd = np.array([x[1]["EstSpeed"] for x in st])
        ep = pos - np.interp(t, tt, truth["position_m"])
        ev = spd - np.interp(t, tt, truth["speed_mps"])
        res.update(position_rms_m=float(np.sqrt(np.mean(ep**2))), speed_rms_mps=float(np.sqrt(np.mean(ev**2))),
                   state_frames=len(st))
        # EstQuality goes out with each EstState: the 95 % intervals' coverage.
        # Each is paired with the state just before it (offline the same
        # stamp; on a live bus a little later, which an exact match missed)
        pair: dict = {}
        for tq, q in series[EST_QUALITY]:
            i = int(np.searchsorted(t, tq, side="right")) - 1
            if q["QualValid"] >= 0.5 and i >= 0 and tq - t[i] <= QUALITY_PAIR_S and i not in pair:
                pair[i] = q
        both = sorted(pair.items())
        if both:
            idx = np.array([i for i, _ in both])
            psd = np.array([q["PositionSd"] for _, q in both])
            vsd = np.array([q["SpeedSd"] for _, q in both])
            res["quality_frames"] = len(both)
            res["position_95_coverage"] = float(np.mean(np.abs(ep[idx]) <= 1.96 * psd))
            res["speed_95_coverage"] = float(np.mean(np.abs(ev[idx]) <= 1.96 * vsd))
            res["position_sd_median_m"] = float(np.median(psd))
    ty = series[EST_TYPE]
    declared, decision = None, None
    if ty:
        last = int(ty[-1][1]["DeclaredType"])
        res["final_status"] = STATUS_NAMES[min(int(ty[-1][1]["TypeStatus"]), len(STATUS_NAMES) - 1)]
        res["final_leader"] = type_name(int(ty[-1][1]["LeaderType"]))
        res["final_leader_weight"] = float(ty[-1][1]["LeaderWeight"])
        if "FitStatus" in ty[-1][1]:
            res["final_fit"] = FIT_NAMES[min(int(ty[-1][1]["FitStatus"]), len(FIT_NAMES) - 1)]
        if last != TYPE_NONE:
            declared = type_name(last)
            decision = ty[-1][0]
            for t, s in reversed(ty):  # start of the final, unbroken declaration
                if int(s["DeclaredType"]) != last:
                    break
                decision = t
    res["declared_type"] = declared
    res["declared_correct"] = declared == th_true.name
    if declared is not None and last == TYPE_CUSTOM:
        res["declared_correct"] = custom_is_truth(series, decision, ty[-1][0], th_true)
    res["decision_time_s"] = decision
    thf = [(t, s) for t, s in series[EST_THETA] if s["ThetaValid"] >= 0.5]
    if thf:
        t_last, s_last = thf[-1]
        est = Theta("estimate", s_last["C0"], s_last["C1"], s_last["C2"])
        true = np.array([th_true.c0, th_true.c1, th_true.c2])
        e = np.array([est.c0, est.c1, est.c2])
        res["final_theta"] = e.tolist()
        with np.errstate(divide="ignore", invalid="ignore"):  # a zero true coefficient: inf (null in the JSON)
            res["theta_rel_err"] = ((e - true) / true).tolist()
            res["w_rms_rel_err"] = w_rms_rel(est, th_true)
        band = band_at(series, t_last)
        if band is not None:
            # the final band around the final W(v): the share of 0..350 km/h where it holds the truth
            v = V_GRID_KMH / 3.6
            sd = band_sd(band, V_GRID_KMH)
            err = np.abs(est.resistance(v) - th_true.resistance(v))
            res["w_band_coverage"] = float(np.mean(err <= Z95 * sd))
            # the curve's band: does it hold the true curve at every speed
            res["w_curve_band_covers"] = bool(np.all(err <= Z_CURVE * sd))
        if decision is not None:
            after = np.array([[s["C0"], s["C1"], s["C2"]] for t, s in thf if t >= decision])
            if len(after):
                with np.errstate(divide="ignore", invalid="ignore"):
                    res["theta_max_abs_rel_err_after_decision"] = np.max(np.abs((after - true) / true),
                                                                         axis=0).tolist()
    for name in (HEALTH_RX, HEALTH_SYS, HEALTH_TIME):
        if series[name]:
            s = series[name][-1][1]
            res.setdefault("health", {}).update({k: int(v) for k, v in s.items() if not k.startswith("E2e")})
    return res


def sd_series(series, pattern: str) -> Optional[Tuple[np.ndarray, np.ndarray]]:
    """(times, sd) of the first output signal whose name matches `pattern`
    (case-insensitive), in whichever estimator frame carries it; None when
    no frame does or it never holds a positive sd (not yet published)."""
    rx = re.compile(pattern, re.I)
    for rows in series.values():
        if not rows:
            continue
        sig = next((k for k in rows[0][1] if rx.fullmatch(k)), None)
        if sig is None:
            continue
        t = np.array([r[0] for r in rows])
        sd = np.array([float(r[1][sig]) for r in rows])
        ok = np.isfinite(sd) & (sd > 0)
        if ok.any():
            return t[ok], sd[ok]
    return None


def band_at(series, t: float) -> Optional[Dict[str, float]]:
    """The valid EstBand of the same step as the EstTheta at time t (the
    daemon sends the two together), or None: a band is never paired with
    another step's W(v)."""
    near = [(abs(tb - t), s) for tb, s in series.get(EST_BAND, []) if s["BandValid"] >= 0.5 and abs(tb - t) < 0.05]
    return min(near, key=lambda x: x[0])[1] if near else None


def band_sd(band: Dict[str, float], v_kmh) -> np.ndarray:
    """The sd of W(v) at speeds v_kmh from one EstBand frame's WSd0..WSd4.
    sd(V)^2 = h' Cov h with h = (1, V, V^2) is a polynomial of degree 4 in V,
    so its values at the five BAND_SPEEDS_KMH give it exactly everywhere."""
    sd2 = np.array([float(band[f"WSd{k}"]) ** 2 for k in range(len(BAND_SPEEDS_KMH))])
    poly = np.polynomial.Polynomial.fit(np.array(BAND_SPEEDS_KMH), sd2, len(BAND_SPEEDS_KMH) - 1)
    return np.sqrt(np.maximum(poly(np.asarray(v_kmh, dtype=float)), 0.0))


SD_SIGNALS = {  # signal-name patterns of the published standard deviations
    "position": r"(est)?pos(ition)?_?sd(_?m)?", "speed": r"(est)?(speed|spd)_?sd(_?mps)?",
    "c0": r"(est)?c0_?sd", "c1": r"(est)?c1_?sd", "c2": r"(est)?c2_?sd",
}


def run_title(truth) -> str:
    """The run's identity for plot titles: true type, seed, noise (profile)."""
    i = truth.get("identity", {})
    parts = [f"truth {i.get('type', truth['theta'].name)}"]
    parts += [f"{k} {i[k]}" for k in ("seed", "noise", "profile") if k in i]
    return ", ".join(parts)


def _mark_decision(ax, decision: Optional[float], declared: Optional[str], label: bool = True) -> None:
    if decision is not None:
        ax.axvline(decision, color="tab:red", ls=":", lw=1.2,
                   label=f"declared {declared} at {decision:.0f} s" if label else None)


def plots(series, truth, outdir: Path, rule: Optional[dict] = None, decision: Optional[float] = None,
          declared: Optional[str] = None) -> List[str]:
    """PNGs of the run: states (with 95 % bands when the estimator publishes
    sd), model weights with the declaration threshold of `rule`
    (runconfig.declaration), Davis coefficients and W(v). The decision time
    is marked on every time axis; titles name the run."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    outdir.mkdir(parents=True, exist_ok=True)
    files = []
    th_true: Theta = truth["theta"]
    tt = truth["time_s"]
    who = run_title(truth)
    rule = rule or {}
    st = [(t, s) for t, s in series[EST_STATE] if s["EstValid"] >= 0.5]
    if st:
        t = np.array([x[0] for x in st])
        fig, ax = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
        ax[0].plot(t, np.array([x[1]["EstPosition"] for x in st]) - np.interp(t, tt, truth["position_m"]), lw=0.8,
                   label="estimate - truth")
        ax[1].plot(tt, truth["speed_mps"] * 3.6, label="true", lw=1.2)
        v_est = np.array([x[1]["EstSpeed"] for x in st]) * 3.6
        ax[1].plot(t, v_est, label="estimate", lw=0.8)
        for a, key, centre, scale in ((ax[0], "position", np.zeros_like(t), 1.0), (ax[1], "speed", v_est, 3.6)):
            sd = sd_series(series, SD_SIGNALS[key])
            if sd is not None:
                band = Z95 * scale * np.interp(t, *sd)
                a.fill_between(t, centre - band, centre + band, color="tab:blue", alpha=0.2, lw=0,
                               label="95 % band of the estimate")
        for a in ax:
            _mark_decision(a, decision, declared)
            a.legend(fontsize=8)
        ax[0].set_ylabel("position error (m)")
        ax[1].set_ylabel("speed (km/h)")
        ax[1].set_xlabel("time (s)")
        fig.suptitle(f"State estimate vs truth ({who})")
        files.append(_save(fig, outdir / "states.png"))
    if series[EST_TYPE]:
        t = np.array([x[0] for x in series[EST_TYPE]])
        fig, ax = plt.subplots(figsize=(9, 4))
        lead = np.array([int(x[1]["LeaderType"]) for x in series[EST_TYPE]])
        lw = np.array([x[1]["LeaderWeight"] for x in series[EST_TYPE]])
        for idx in sorted(set(lead.tolist())):
            sel = lead == idx
            ax.plot(t[sel], lw[sel], ".", ms=3, label=f"leader {type_name(idx)}")
        if rule.get("threshold") is not None:
            hold = f", held {rule['hold_s']:g} s" if rule.get("hold_s") is not None else ""
            ax.axhline(rule["threshold"], color="grey", ls="--", lw=0.8,
                       label=f"declaration: q > {rule['threshold']:g}{hold} ({rule.get('source', '?')})")
        _mark_decision(ax, decision, declared)
        ax.set_ylim(0, 1.05)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("model weight q")
        ax.set_title(f"Leading model weight ({who})")
        ax.legend(fontsize=8)
        files.append(_save(fig, outdir / "weights.png"))
    thf = [(t, s) for t, s in series[EST_THETA] if s["ThetaValid"] >= 0.5]
    if thf:
        t = np.array([x[0] for x in thf])
        fig, ax = plt.subplots(figsize=(9, 4))
        true_at = truth_theta_at(truth, t)
        for i, k in enumerate(("C0", "C1", "C2")):
            c = true_at[i]
            ax.plot(t, 100 * (np.array([x[1][k] for x in thf]) - c) / c, label=k.lower())
        ax.axhspan(-5, 5, color="green", alpha=0.1, label="+-5 %")
        _mark_decision(ax, decision, declared)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("relative error (%)")
        ax.set_title(f"Estimated Davis coefficients ({who})")
        ax.legend(fontsize=8)
        files.append(_save(fig, outdir / "theta.png"))
        s = thf[-1][1]
        est = Theta("estimate", s["C0"], s["C1"], s["C2"])
        fig, ax = plt.subplots(figsize=(7, 4))
        vk = V_GRID_KMH
        ax.plot(vk, th_true.resistance(vk / 3.6), label=f"true ({th_true.name})")
        w_est = est.resistance(vk / 3.6)
        ax.plot(vk, w_est, "--", label="estimate (final)")
        sds = [sd_series(series, SD_SIGNALS[c]) for c in ("c0", "c1", "c2")]
        last_band = band_at(series, thf[-1][0])
        if last_band is not None:
            sd = band_sd(last_band, vk)
            band = Z95 * sd
            ax.fill_between(vk, w_est - band, w_est + band, color="tab:orange", alpha=0.2, lw=0,
                            label="95 % at each speed (EstBand)")
            band = Z_CURVE * sd
            ax.fill_between(vk, w_est - band, w_est + band, color="tab:orange", alpha=0.1, lw=0,
                            label="95 % for the whole curve")
        elif all(x is not None for x in sds):
            # final sd of each coefficient; their covariances are not published, so this band treats
            # them as independent: var W = sum_k (V^k sd_k)^2
            band = Z95 * np.sqrt(sum((vk ** k * x[1][-1]) ** 2 for k, x in enumerate(sds)))
            ax.fill_between(vk, w_est - band, w_est + band, color="tab:orange", alpha=0.2, lw=0,
                            label="95 % band (coefficients independent)")
        ax.set_xlabel("speed (km/h)")
        ax.set_ylabel("W (N/kN)")
        ax.set_title(f"Running resistance ({who})")
        ax.legend(fontsize=8)
        files.append(_save(fig, outdir / "resistance.png"))
    return files


def _save(fig, path: Path) -> str:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    import matplotlib.pyplot as plt

    plt.close(fig)
    return str(path)


def build_parser() -> argparse.ArgumentParser:
    p = cli.Parser(prog="hstpf-score", description="Score recorded estimator frames against the truth.",
                   epilog=__doc__.split("\n", 2)[2] + "\nExit codes: 0 done, 2 usage, 3 an input cannot be read "
                   "or is not valid, 5 no estimator frame in the log, 6 an output cannot be written (docs/tools.md).",
                   formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("log", help="recorded log with the estimator's frames; '-': candump text on stdin")
    p.add_argument("--truth", required=True, help="truth CSV from hstpf-simulate")
    p.add_argument("--input-log", help="the simulated input log (for --align inputs)")
    p.add_argument("--align", choices=("auto", "inputs", "time"), default="auto",
                   help="auto: inputs when --input-log is given, else time")
    p.add_argument("--t0", type=float, default=None,
                   help="log timestamp of simulation time 0: in the input log (inputs alignment; default 0 when "
                        "the input log starts within the truth's span, else its first timestamp), in the recorded "
                        "log (time alignment; default 0)")
    p.add_argument("--speed", type=float, default=None,
                   help="replay speed-up (time alignment: 1; inputs alignment: measured from the inputs, used "
                        "only to date an estimate after a silence of the outputs)")
    cli.add_json_argument(p, what="the metrics as JSON", default=" (the table then goes to stderr)")
    p.add_argument("--plots", help="write PNG plots into this directory")
    p.add_argument("--config", help="the hstpfd config file of the run: its declare_threshold and declare_hold_s "
                   "are drawn on the weights plot (default: the library's defaults)")
    p.add_argument("--dbc", help="DBC file (default port/dbc/hstpf.dbc)")
    return p


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return str(v)


def _main(argv) -> int:
    a = build_parser().parse_args(argv)
    align = a.align if a.align != "auto" else ("inputs" if a.input_log else "time")
    if align == "inputs" and not a.input_log:
        raise cli.CliError(cli.EXIT_USAGE, "--align inputs needs --input-log")
    if a.speed is not None and a.speed <= 0:
        raise cli.CliError(cli.EXIT_USAGE, "--speed must be > 0")
    if [a.log, a.input_log, a.truth].count("-") > 1:
        raise cli.CliError(cli.EXIT_USAGE, "only one input can be '-'")
    try:
        codec = FrameCodec(a.dbc)  # each frame's receiver as the DBC has it: a restart after a silence is no jump
    except Exception as exc:  # missing or unreadable DBC
        raise cli.input_error(a.dbc or "the DBC", exc) from exc
    try:
        truth = read_truth(a.truth)
    except (KeyError, ValueError, IndexError) as exc:
        raise cli.CliError(cli.EXIT_INPUT, f"{a.truth}: not a truth CSV of hstpf-simulate ({exc})") from exc
    tt = truth["time_s"]
    inputs: Optional[InputLog] = None
    t0 = 0.0 if a.t0 is None else a.t0
    if align == "inputs":
        inp = cli.load_log(a.input_log)
        if a.t0 is None and inp and not tt[0] - 1.0 <= inp[0].timestamp <= tt[-1]:
            t0 = inp[0].timestamp  # simulated with --t0 (hstpf-simulate's default is 0): from its start
        inputs = InputLog(inp, codec.message(POSITION).frame_id, t0)
        steps = input_clock_steps(inp, codec)
        if steps:
            print(f"warning: {a.input_log}: its clock steps {len(steps)} time(s) (first at log time "
                  f"{steps[0]:.6g}): frames are dated log time - t0, so the estimates after a step are scored "
                  "against the wrong truth time; score the parts between steps separately", file=sys.stderr)
        off = input_offset_m(inp, codec, t0, truth)
        if off is not None and off > INPUT_OFFSET_WARN_M:
            print(f"warning: {a.input_log}: its positions lie {off:.0f} m (median) from the truth's at simulation "
                  f"time = log time - {t0:.6g}: pass --t0 (the input log's time of simulation time 0)",
                  file=sys.stderr)
    rec = cli.load_log(a.log)
    series, e2e_res = collect(rec, codec, align, inputs, t0, a.speed)
    times = [t for k, v in series.items() if isinstance(v, list) for t, _ in v]
    if times and not any(tt[0] - 1.0 <= t <= tt[-1] + 1.0 for t in times):
        raise cli.CliError(cli.EXIT_NO_TRAFFIC, f"no estimator frame of {a.log} falls within the truth's "
                           f"{tt[0]:g}-{tt[-1]:g} s (they lie at {min(times):.6g}-{max(times):.6g} s): "
                           "pass --t0 (the log time of simulation time 0) or --input-log")
    res = metrics(series, truth)
    res["inputs"] = fix_time_stats(rec, a.dbc)
    res["align"] = align
    if align == "inputs":
        res["input_t0"] = t0
        res["input_clock_steps"] = len(steps)
    res["output_e2e"] = e2e_res
    res["state_frames_dated"] = series.pop("dated_by_est_time")
    res["ignored_29bit_frames"] = series.pop("ignored_29bit_frames")
    res["frames"] = {k: len(v) for k, v in series.items()}
    if a.plots:
        try:
            rule = runconfig.declaration(a.config)
            res["plots"] = plots(series, truth, Path(a.plots), rule, res.get("decision_time_s"),
                                 res.get("declared_type"))
        except OSError as exc:
            raise cli.output_error(a.plots, exc) from exc
    table = sys.stderr if a.json == "-" else sys.stdout  # '--json -': nothing but JSON on stdout
    for k, v in res.items():
        if k not in ("output_e2e", "health", "frames", "inputs"):
            print(f"{k:38s} {_fmt(v)}", file=table)
    if "health" in res:
        print("health".ljust(38), " ".join(f"{k}={v}" for k, v in res["health"].items()), file=table)
    if "inputs" in res:
        print("inputs".ljust(38), json.dumps(res["inputs"]), file=table)
    bad = {n: {r: c for r, c in d.items() if r not in e2e.ACCEPTED} for n, d in e2e_res.items()}
    print("output_e2e_rejected".ljust(38), json.dumps({n: d for n, d in bad.items() if d}), file=table)
    if a.json:
        cli.emit_report(res, a.json)
    if not any(res["frames"].values()):
        print(f"hstpf-score: no estimator frame in {a.log}" + (" could be timed by its inputs"
              if align == "inputs" and e2e_res else ""), file=sys.stderr)
        return cli.EXIT_NO_TRAFFIC
    return cli.EXIT_OK


def main(argv=None) -> int:
    return cli.run("hstpf-score", _main, argv)


if __name__ == "__main__":
    sys.exit(main())
