"""hstpf-simulate against hand-computed trajectories and the stated noise."""
import csv
import math

import numpy as np
import pytest

from hstpf_tools import model, simulate
from hstpf_tools.frames import FrameCodec
from hstpf_tools.logio import read_log

XI = 9.81 / 1.06 / 1000.0  # (m/s^2) per (N/kN), gamma 0.06
A0 = (350.0 / 3.6) / 396.0  # the paper: 0 to 350 km/h in 396 s


def W_crh3(v):
    V = 3.6 * v
    return 0.79 + 0.0064 * V + 0.000115 * V * V


def read_truth(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def decode_log(path):
    """{name: [(t, signals)]} via a fresh codec (E2E checked)."""
    c = FrameCodec()
    out = {}
    for m in read_log(str(path)):
        name, sig, res = c.decode(m.arbitration_id, bytes(m.data), now=m.timestamp)
        assert res in ("ok", "ok_initial"), res
        out.setdefault(name, []).append((m.timestamp, sig))
    return out


def run_cli(tmp_path, *args):
    log = tmp_path / "run.log"
    assert simulate.main(["-o", str(log), *args]) == 0
    return log, tmp_path / "run_truth.csv"


def test_noise_free_paper_profile_by_hand(tmp_path):
    log, truth = run_cli(tmp_path, "--noise", "none", "--duration", "600", "--type", "CRH3")
    rows = read_truth(truth)
    assert len(rows) == 601
    for k in (0, 1, 2, 10, 200, 395, 396, 397, 450, 600):
        r = rows[k]
        # Euler steps at constant acceleration A0, then cruise at 350 km/h
        kk = min(k, 396)
        v = kk * A0
        s = A0 * kk * (kk - 1) / 2 + (k - kk) * 396 * A0
        assert float(r["time_s"]) == k
        assert float(r["speed_mps"]) == pytest.approx(v, abs=1e-6)
        assert float(r["position_m"]) == pytest.approx(s, abs=1e-5)
        # traction that makes the train follow the profile (no track)
        a = A0 if k < 396 else 0.0
        assert float(r["traction_nkn"]) == pytest.approx(a / XI + W_crh3(v), abs=1e-5)
        assert float(r["force_kn"]) == pytest.approx(float(r["traction_nkn"]) * 500 * 9.81 / 1000, abs=1e-5)
        assert (r["type"], float(r["c0"]), float(r["c1"]), float(r["c2"])) == ("CRH3", 0.79, 0.0064, 0.000115)
    assert float(rows[396]["speed_mps"]) == pytest.approx(350 / 3.6)

    frames = decode_log(log)
    pos, trac = frames["Position"], frames["Traction"]
    assert len(pos) == len(trac) == 6001  # every 0.1 s from 0 to 600 s
    # the position frame between grid points interpolates linearly (1 cm resolution)
    for n in (0, 5, 15, 1234, 3961, 6000):
        t = n * 0.1
        k = min(int(math.floor(t + 1e-9)), 599)
        s0, s1 = (float(rows[k]["position_m"]), float(rows[k + 1]["position_m"]))
        assert pos[n][0] == pytest.approx(t)
        assert pos[n][1]["Position"] == pytest.approx(s0 + (t - k) * (s1 - s0), abs=0.0051)
        # and carries its own time: simulation time in ms modulo 8192
        assert (pos[n][1]["FixTimeValid"], pos[n][1]["FixTime"]) == (1, round(t * 1000) % 8192)
        assert pos[n][1]["PosValid"] == 1
        # traction held over the step, in kN at 0.01 kN resolution
        kk = min(k, 396)
        u = (A0 if k < 396 else 0.0) / XI + W_crh3(kk * A0)
        assert trac[n][1]["TractForce"] == pytest.approx(u * 500 * 9.81 / 1000, abs=0.0051)
    # position first, then traction, at the same timestamp
    msgs = read_log(str(log))
    assert [m.arbitration_id for m in msgs[:4]] == [0x100, 0x101, 0x100, 0x101]
    assert msgs[0].timestamp == msgs[1].timestamp


def test_track_profile_adds_grade_and_curve(tmp_path):
    track = tmp_path / "track.csv"
    track.write_text("start_m,gradient_permille,curve_radius_m\n0,0,0\n1000,10,0\n3000,-2,2000\n")
    log, truth = run_cli(tmp_path, "--noise", "none", "--duration", "300", "--track", str(track))
    rows = read_truth(truth)
    seen = set()
    for r in rows[:-1]:
        s, v = float(r["position_m"]), float(r["speed_mps"])
        g = 0.0 if s < 1000 else (10.0 if s < 3000 else -2.0 + 600 / 2000)
        seen.add(g)
        assert float(r["track_nkn"]) == pytest.approx(g)
        assert float(r["traction_nkn"]) == pytest.approx(A0 / XI + W_crh3(v) + g, abs=1e-5)
        assert v == pytest.approx(float(r["time_s"]) * A0, abs=1e-6)  # the profile still holds
    assert seen == {0.0, 10.0, -1.7}


def test_resistance_cannot_reverse_the_train(monkeypatch):
    # accelerate to 1 m/s, then coast against c0 = 50 N/kN (c1 = c2 = 0)
    monkeypatch.setitem(model.PROFILES, "test", [("accel", 3.6, 1.0), ("coast", 1e9)])
    run = model.simulate(model.Theta("x", 50.0, 0.0, 0.0), "test", 8.0, 1.0, model.NOISE_CASES["none"])
    d = 50.0 * XI
    assert run.v.tolist() == pytest.approx([0.0, 1.0, 1.0 - d, 1.0 - 2 * d, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert run.u[2:].tolist() == [0.0] * 7  # coasting


@pytest.mark.parametrize("profile", ["coast-brake", "stops"])
def test_profiles_noise_free_stay_physical(profile):
    run = model.simulate(model.theta_for("CRH3"), profile, 5000.0, 1.0, model.NOISE_CASES["none"])
    phases = set(run.phase)
    assert {"accel", "cruise", "brake", "stop"} <= phases
    assert run.v.min() >= 0.0
    assert np.all(np.diff(run.s) >= -1e-9)  # never backwards
    stop = np.array([p == "stop" for p in run.phase])
    assert np.all(run.v[1:][stop[:-1]] == 0.0)  # standing still after a stop step
    assert run.v.max() * 3.6 <= (300.0 if profile == "coast-brake" else 250.0) + 1e-6
    if profile == "coast-brake":
        assert "coast" in phases and np.all(run.u[np.array([p == "coast" for p in run.phase])] == 0.0)


def _recover_process_noise(rows, theta=W_crh3):
    s = np.array([float(r["position_m"]) for r in rows])
    v = np.array([float(r["speed_mps"]) for r in rows])
    u = np.array([float(r["traction_nkn"]) for r in rows])
    v_det = v[:-1] + XI * (u[:-1] - theta(v[:-1]))
    v_det = np.where((v[:-1] >= 0) & (v_det < 0), 0.0, v_det)
    return s[1:] - s[:-1] - v[:-1], v[1:] - v_det


def _recover_noise(log, truth):
    """w_s, w_v of every step (from the truth) and e of every position frame
    (the frame's position less the truth interpolated at its time)."""
    rows = read_truth(truth)
    ws, wv = _recover_process_noise(rows)
    t = np.array([float(r["time_s"]) for r in rows])
    s = np.array([float(r["position_m"]) for r in rows])
    frames = decode_log(log)["Position"]
    e = np.array([sig["Position"] for _, sig in frames]) - np.interp([tt for tt, _ in frames], t, s)
    return ws, wv, e


def test_case1_noise_has_the_stated_variance(tmp_path):
    """w_s ~ N(0, 0.02), w_v ~ N(0, 0.05), e ~ N(0, 5). Tolerance: 5 standard
    errors of the sample mean (sd/sqrt n) and of the sample variance
    (var sqrt(2/(n-1)), Gaussian)."""
    log, truth = run_cli(tmp_path, "--noise", "case1", "--duration", "7200", "--frame-period", "0.2", "--seed", "11")
    ws, wv, e = _recover_noise(log, truth)
    for x, var in ((ws, 0.02), (wv, 0.05), (e, 5.0)):
        n = len(x)
        assert abs(x.mean()) < 5 * math.sqrt(var / n)
        assert abs(x.var(ddof=1) - var) < 5 * var * math.sqrt(2 / (n - 1))
    assert len(e) == 36001


def test_case2_noise_is_gamma(tmp_path):
    """w_s ~ Gamma(0.02, 0.1), w_v ~ Gamma(0.1, 0.05), e ~ Gamma(0.5, 0.2):
    support >= 0; means within 5 standard errors (sd = sqrt(k) theta)."""
    log, truth = run_cli(tmp_path, "--noise", "case2", "--duration", "7200", "--frame-period", "0.2", "--seed", "5")
    ws, wv, e = _recover_noise(log, truth)
    for x, k, th, tol0 in ((ws, 0.02, 0.1, 2e-6), (wv, 0.1, 0.05, 2e-6), (e, 0.5, 0.2, 5.1e-3)):
        assert x.min() >= -tol0  # CSV (1e-6) and frame (1 cm) rounding only
        assert abs(x.mean() - k * th) < 5 * math.sqrt(k) * th / math.sqrt(len(x))
    assert abs(e.var() - 0.5 * 0.04) < 0.1 * 0.02  # excess kurtosis 12: sd of the sample variance ~2 %


def test_seeded_and_reproducible(tmp_path):
    a, b, c = tmp_path / "a", tmp_path / "b", tmp_path / "c"
    for d in (a, b, c):
        d.mkdir()
    run_cli(a, "--duration", "60", "--seed", "3")
    run_cli(b, "--duration", "60", "--seed", "3")
    run_cli(c, "--duration", "60", "--seed", "4")
    assert (a / "run.log").read_bytes() == (b / "run.log").read_bytes()
    assert (a / "run.log").read_bytes() != (c / "run.log").read_bytes()
    # the trajectory does not depend on the frame rate (own streams)
    d = tmp_path / "d"
    d.mkdir()
    run_cli(d, "--duration", "60", "--seed", "3", "--frame-period", "0.5")
    assert (a / "run_truth.csv").read_bytes() == (d / "run_truth.csv").read_bytes()


def test_custom_coefficients_and_noise_specs(tmp_path):
    log, truth = run_cli(tmp_path, "--coeffs", "1.0,0.01,0.0002", "--duration", "30", "--ws", "none", "--wv", "none",
                         "--e", "normal:mean=0,sd=0", "--profile", "stops")
    rows = read_truth(truth)
    assert rows[0]["type"] == "custom" and float(rows[0]["c1"]) == 0.01
    assert model.Noise.parse("gamma:shape=0.5,scale=0.2,loc=-1").mean == pytest.approx(-0.9)
    assert model.Noise.parse("normal:var=4").b == 2.0
    with pytest.raises(ValueError):
        model.Noise.parse("gamma:shape=0,scale=1")
    assert simulate.main(["-o", str(tmp_path / "x.log"), "--type", "NoSuchTrain"]) == 2
    assert model.theta_for("SS4").name == "SS1/SS3/SS4"


def test_restart_moves_the_reference_not_the_train(tmp_path):
    """--restart-at T: from T the frames and the truth count from where the
    train was at T; the same seed without it gives the same train."""
    args = ["--profile", "line", "--duration", "700", "--seed", "4", "--noise", "case1"]
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    log_a, truth_a = run_cli(tmp_path / "a", *args)
    log_b, truth_b = run_cli(tmp_path / "b", *args, "--restart-at", "480")
    ta, tb = read_truth(truth_a), read_truth(truth_b)
    s_at = float(ta[480]["position_m"])
    assert s_at > 10000.0 and float(ta[480]["speed_mps"]) == 0.0  # standing at the first station
    for ra, rb in zip(ta, tb):
        shift = s_at if float(ra["time_s"]) >= 480.0 else 0.0
        assert float(rb["position_m"]) == pytest.approx(float(ra["position_m"]) - shift, abs=1e-5)
        assert rb["speed_mps"] == ra["speed_mps"]
    pa, pb = decode_log(log_a)["Position"], decode_log(log_b)["Position"]
    assert len(pa) == len(pb)
    for (t, sa), (_, sb) in zip(pa, pb):
        shift = s_at if t >= 480.0 - 1e-9 else 0.0
        assert sb["Position"] == pytest.approx(sa["Position"] - shift, abs=0.011)  # the signal's 0.01 m
    assert simulate.main(["-o", str(tmp_path / "c.log"), "--restart-at", "x"]) == 2
    assert simulate.main(["-o", str(tmp_path / "c.log"), "--duration", "10", "--restart-at", "20"]) == 2
