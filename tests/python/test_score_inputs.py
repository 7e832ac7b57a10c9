"""hstpf-score's inputs alignment: recorded position frames found in the
simulated input log when the same payload occurs there more than once (a
tunnel: PosValid 0 frames repeat byte for byte with the E2E counter's
15-frame cycle), and when the input log does not start at simulation time 0
(the log cut where a daemon restarted, or simulated with --t0)."""
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from hstpf_tools import score, simulate
from hstpf_tools.frames import E2E_SIGNALS, FrameCodec
from hstpf_tools.logio import message, read_log, write_log

TUNNEL = (200.0, 380.0)  # simulation seconds without a fix: 3 minutes


def _hstpfd(root):
    exe = Path(os.environ.get("HSTPF_BUILD_DIR", str(root / "build"))) / "port" / "hstpfd"
    if not exe.is_file():
        pytest.skip("hstpfd not built (set HSTPF_BUILD_DIR)")
    return str(exe)


def _truth(path):
    return np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding=None)


def with_tunnel(msgs, t_from, t_to):
    """The log with its position frames in [t_from, t_to) sent without a
    fix (PosValid 0, no position, no fix time), as a positioning unit in a
    tunnel sends them; every position frame protected again in order, so
    the E2E counter runs on as the sender's would."""
    dec, enc = FrameCodec(), FrameCodec()
    out = []
    for m in msgs:
        if m.arbitration_id != 0x100:
            out.append(m)
            continue
        _, sig, _ = dec.decode(0x100, bytes(m.data), check=False)
        sig = {k: v for k, v in sig.items() if k not in E2E_SIGNALS}
        if t_from <= m.timestamp < t_to:
            sig.update(PosValid=0, Position=0.0, FixTimeValid=0, FixTime=0)
        fid, data = enc.encode("Position", sig)
        out.append(message(m.timestamp, fid, data))
    return out


@pytest.fixture(scope="module")
def tunnel_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("tunnel")
    assert simulate.main(["-o", str(d / "sim.log"), "--truth", str(d / "run_truth.csv"), "--duration", "600",
                          "--seed", "3", "--json", str(d / "sim.json")]) == 0
    msgs = with_tunnel(read_log(str(d / "sim.log")), *TUNNEL)
    write_log(str(d / "run.log"), msgs)
    pos = [bytes(m.data) for m in msgs if m.arbitration_id == 0x100]
    # the case: payloads repeat in the input log (180 s x 10 frames / 15 payloads)
    assert len(pos) - len(set(pos)) > 1700
    return d, _truth(d / "run_truth.csv")


def _scripted_outputs(codec, t_sim, rows):
    """An estimator 1 m ahead and 0.1 m/s fast of the truth at t_sim."""
    s = np.interp(t_sim, rows["time_s"], rows["position_m"])
    v = np.interp(t_sim, rows["time_s"], rows["speed_mps"])
    return [codec.encode("EstState", {"EstValid": 1, "EstPosition": s + 1.0, "EstSpeed": v + 0.1})]


def _score(rec, d, tmp_path, *extra, log="run.log"):
    js = tmp_path / "m.json"
    assert score.main([str(rec), "--truth", str(d / "run_truth.csv"), "--input-log", str(d / log), "--json",
                       str(js), *extra]) == 0
    return json.loads(js.read_text())


def test_tunnel_frames_matched_in_order(tunnel_run, tmp_path):
    """The input log replayed 20 x faster at wall-clock times, with an
    output after each position frame. Through the tunnel, some position
    frames lost (each 7th), some sent twice (each 11th), and a 3 s silence
    of every frame: each repeated payload is still the frame it was (not
    its first occurrence in the log), so the scripted 1 m / 0.1 m/s errors
    come back."""
    d, rows = tunnel_run
    codec = FrameCodec()
    msgs = []
    for i, m in enumerate(read_log(str(d / "run.log"))):
        t_sim = m.timestamp
        t_wall = 1.7e9 + t_sim / 20
        pos = m.arbitration_id == 0x100
        if 300.0 <= t_sim < 303.0 or (pos and TUNNEL[0] <= t_sim < TUNNEL[1] and i % 7 == 0):
            continue
        msgs.append(message(t_wall, m.arbitration_id, bytes(m.data)))
        if pos and i % 11 == 0:
            msgs.append(message(t_wall + 0.001, m.arbitration_id, bytes(m.data)))
        if pos:
            msgs += [message(t_wall + 0.002, fid, data) for fid, data in _scripted_outputs(codec, t_sim, rows)]
    rec = tmp_path / "bus.log"
    write_log(str(rec), msgs)
    res = _score(rec, d, tmp_path)
    assert res["align"] == "inputs"
    assert res["state_frames"] > 5000
    assert res["position_rms_m"] == pytest.approx(1.0, abs=0.01)  # the first occurrence: hundreds of m
    assert res["speed_rms_mps"] == pytest.approx(0.1, abs=0.01)


def _daemon(root, d, log, tag):
    out = d / f"{tag}_bus.log"
    steps = d / f"{tag}_steps.jsonl"
    subprocess.run([_hstpfd(root), "--config", str(root / "port" / "config" / "case1.ini"), "--log", str(log),
                    "--out", str(steps), "--frames-out", str(out), "--frames-out-inputs", "1"],
                   check=True, capture_output=True)
    return out, [json.loads(x) for x in steps.read_text().splitlines() if x.strip()]


def _steps_rms(steps, rows, t0=0.0):
    """RMS errors of the daemon's own valid steps (its step stream, dated
    by their log time - t0) against the truth: what the score must find
    from the frames on the bus."""
    st = [s for s in steps if s["valid"] and rows["time_s"][0] <= s["t"] - t0 <= rows["time_s"][-1]]
    t = np.array([s["t"] for s in st]) - t0
    ep = np.array([s["pos"] for s in st]) - np.interp(t, rows["time_s"], rows["position_m"])
    ev = np.array([s["speed"] for s in st]) - np.interp(t, rows["time_s"], rows["speed_mps"])
    return len(st), float(np.sqrt(np.mean(ep ** 2))), float(np.sqrt(np.mean(ev ** 2)))


def test_tunnel_scored_as_the_daemon_stepped(root, tunnel_run, tmp_path):
    """hstpfd through a 3-minute tunnel, its frames and echoed inputs
    scored: the RMS errors are those of its own step stream (the tester's
    tunnel logs read 20 x too high when the tunnel's repeated position
    frames were dated by their first occurrence)."""
    d, rows = tunnel_run
    bus, steps = _daemon(root, d, d / "run.log", "tunnel")
    n, pos_rms, spd_rms = _steps_rms(steps, rows)
    in_tunnel = [s for s in steps if TUNNEL[0] + 5 <= s["t"] < TUNNEL[1]]
    assert in_tunnel and all(s["y"] is None for s in in_tunnel)  # predict-only: the daemon saw the tunnel
    res = _score(bus, d, tmp_path)
    assert res["state_frames"] == n
    assert res["position_rms_m"] == pytest.approx(pos_rms, rel=1e-3, abs=1e-3)
    assert res["speed_rms_mps"] == pytest.approx(spd_rms, rel=1e-3, abs=1e-3)


CUT = 250.0  # simulation time where the input log starts: a daemon restarted there


@pytest.fixture(scope="module")
def cut_run(tmp_path_factory):
    """A 600 s run simulated at log times t0 + simulation time (t0 0 and
    1.7e9), and each input log cut at simulation time 250 s; the truth is
    the whole run's."""
    d = tmp_path_factory.mktemp("cut")
    for t0 in (0.0, 1.7e9):
        tag = f"t0_{t0:.0f}"
        assert simulate.main(["-o", str(d / f"{tag}.log"), "--truth", str(d / "run_truth.csv"), "--duration",
                              "600", "--seed", "4", "--t0", repr(t0), "--json", str(d / "sim.json")]) == 0
        msgs = read_log(str(d / f"{tag}.log"))
        write_log(str(d / f"{tag}_cut.log"), [m for m in msgs if m.timestamp - t0 >= CUT])
    return d, _truth(d / "run_truth.csv")


def _offline_outputs(log, rows, t0):
    """The input log with a scripted output after each position frame."""
    codec = FrameCodec()
    msgs = []
    for m in read_log(str(log)):
        msgs.append(m)
        if m.arbitration_id == 0x100:
            msgs += [message(m.timestamp, fid, data) for fid, data in _scripted_outputs(codec, m.timestamp - t0, rows)]
    return msgs


@pytest.mark.parametrize("t0, args", [(0.0, ()), (0.0, ("--t0", "0")), (1.7e9, ("--t0", "1.7e9")),
                                      (1.7e9, ())])
def test_input_log_cut_mid_run(cut_run, tmp_path, capfd, t0, args):
    """An input log that starts at simulation time 250 s: its frames are
    dated log time - t0 (--t0; by default 0 for a log that starts within the
    truth's span, as hstpf-simulate writes it), not from its first frame
    (28-33 km RMS in the tester's runs). A log simulated with --t0 and cut
    needs --t0: without it, it is taken from its first frame, and a warning
    says its positions do not follow the truth."""
    d, rows = cut_run
    tag = f"t0_{t0:.0f}"
    rec = tmp_path / "bus.log"
    write_log(str(rec), _offline_outputs(d / f"{tag}_cut.log", rows, t0))
    res = _score(rec, d, tmp_path, *args, log=f"{tag}_cut.log")
    err = capfd.readouterr().err
    if t0 and not args:
        assert res["input_t0"] == pytest.approx(t0 + CUT)
        assert res["position_rms_m"] > 1000.0
        assert "warning" in err and "--t0" in err
        return
    assert res["input_t0"] == t0
    assert "warning" not in err
    assert res["state_frames"] == pytest.approx((600 - CUT) * 10, abs=1)
    assert res["position_rms_m"] == pytest.approx(1.0, abs=0.01)
    assert res["speed_rms_mps"] == pytest.approx(0.1, abs=0.01)


def test_uncut_log_with_t0_needs_no_option(cut_run, tmp_path, capfd):
    """A whole log simulated with --t0 starts at simulation time 0: its
    first frame dates it without --t0, as before."""
    d, rows = cut_run
    rec = tmp_path / "bus.log"
    write_log(str(rec), _offline_outputs(d / "t0_1700000000.log", rows, 1.7e9))
    res = _score(rec, d, tmp_path, log="t0_1700000000.log")
    assert "warning" not in capfd.readouterr().err
    assert res["input_t0"] == 1.7e9
    assert res["position_rms_m"] == pytest.approx(1.0, abs=0.01)


def test_daemon_restarted_mid_run_scored(root, cut_run, tmp_path):
    """hstpfd started on the log cut at 250 s (the tester's restart case):
    the score finds the RMS errors of its own step stream."""
    d, rows = cut_run
    bus, steps = _daemon(root, d, d / "t0_0_cut.log", "cut")
    n, pos_rms, spd_rms = _steps_rms(steps, rows)
    assert n > 300
    res = _score(bus, d, tmp_path, log="t0_0_cut.log")
    assert res["state_frames"] == n
    assert res["position_rms_m"] == pytest.approx(pos_rms, rel=1e-3, abs=1e-3)
    assert res["speed_rms_mps"] == pytest.approx(spd_rms, rel=1e-3, abs=1e-3)
