"""hstpf-score on a scripted "estimator" whose errors are known."""
import json

import numpy as np
import pytest

from hstpf_tools import score, simulate
from hstpf_tools.frames import FrameCodec
from hstpf_tools.logio import message, read_log, write_log

CRH3 = (0.79, 0.0064, 0.000115)
SS8 = (1.02, 0.0035, 0.000426)


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    d = tmp_path_factory.mktemp("score")
    log = d / "run.log"
    assert simulate.main(["-o", str(log), "--duration", "400", "--seed", "2"]) == 0
    rows = np.genfromtxt(d / "run_truth.csv", delimiter=",", names=True, dtype=None, encoding=None)
    return d, log, rows


def outputs(codec, t, truth_s, truth_v):
    """Output frames an estimator might send at simulation time t: position
    1 m ahead, speed 0.1 m/s fast; undecided (leader SS8) before 150 s,
    then CRH3 declared with exact coefficients."""
    out = [("EstState", {"EstValid": 1, "EstPosition": truth_s + 1.0, "EstSpeed": truth_v + 0.1})]
    if abs(t - round(t)) < 1e-6:  # 1 Hz frames
        if t < 150:
            out.append(("EstType", {"TypeStatus": 0, "DeclaredType": 255, "DeclaredWeight": 0, "LeaderType": 6, "LeaderWeight": 0.5}))
            th = [(a + b) / 2 for a, b in zip(CRH3, SS8)]
        else:
            out.append(("EstType", {"TypeStatus": 1, "DeclaredType": 2, "DeclaredWeight": 0.97, "LeaderType": 2, "LeaderWeight": 0.97}))
            th = CRH3
        out.append(("EstTheta", {"ThetaValid": 1, "C0": th[0], "C1": th[1], "C2": th[2]}))
        out.append(("HealthRx", {"BadCrc": 4, "CounterRepeat": 1}))
        out.append(("HealthSys", {"StaleEvents": 2, "Degeneracy": 0}))
    return [(codec.encode(n, v)) for n, v in out]


def check_metrics(res):
    assert res["position_rms_m"] == pytest.approx(1.0, abs=0.006)  # 1 cm resolution
    assert res["speed_rms_mps"] == pytest.approx(0.1, abs=0.006)
    assert res["declared_type"] == "CRH3" and res["declared_correct"] is True
    assert res["decision_time_s"] == pytest.approx(150.0)
    assert res["final_status"] == "declared" and res["final_leader"] == "CRH3"
    assert np.max(np.abs(res["theta_rel_err"])) < 2e-4  # signal resolution
    assert res["w_rms_rel_err"] < 2e-4
    assert np.max(res["theta_max_abs_rel_err_after_decision"]) < 2e-4
    assert res["health"]["BadCrc"] == 4 and res["health"]["StaleEvents"] == 2


def test_time_aligned_offline_log(sim, tmp_path, capsys):
    d, log, rows = sim
    codec = FrameCodec()
    msgs = []
    for k in range(0, len(rows) - 1):
        for sub in range(10):  # every position frame time, 0.1 s
            t = k + sub / 10
            s = np.interp(t, rows["time_s"], rows["position_m"])
            v = np.interp(t, rows["time_s"], rows["speed_mps"])
            msgs += [message(t, fid, data) for fid, data in outputs(codec, t, s, v)]
    rec = tmp_path / "est.log"
    write_log(str(rec), msgs)
    js, plots = tmp_path / "m.json", tmp_path / "plots"
    assert score.main([str(rec), "--truth", str(d / "run_truth.csv"), "--json", str(js), "--plots", str(plots)]) == 0
    res = json.loads(js.read_text())
    assert res["align"] == "time"
    check_metrics(res)
    assert sorted(p.name for p in plots.iterdir()) == ["resistance.png", "states.png", "theta.png", "weights.png"]
    assert all(p.stat().st_size > 10000 for p in plots.iterdir())
    assert "declared_type" in capsys.readouterr().out


def test_input_aligned_replay_with_faults(sim, tmp_path):
    """A recorded bus log: inputs replayed 20x faster at wall-clock times,
    some position frames lost or corrupted, outputs right after each
    position frame. Scoring by input content recovers simulation time."""
    d, log, rows = sim
    codec = FrameCodec()
    rng = np.random.default_rng(0)
    msgs = []
    t_wall = 1.7e9
    for i, m in enumerate(read_log(str(log))):
        t_sim = m.timestamp
        t_wall = 1.7e9 + t_sim / 20 + rng.uniform(0, 0.002)
        data = bytes(m.data)
        if m.arbitration_id == 0x100 and i % 37 == 0:
            continue  # lost
        if m.arbitration_id == 0x100 and i % 41 == 0:
            data = bytes([data[0] ^ 0xFF]) + data[1:]  # corrupted: matches nothing
        msgs.append(message(t_wall, m.arbitration_id, data))
        if m.arbitration_id == 0x100 and i % 37 and i % 41:
            s = np.interp(t_sim, rows["time_s"], rows["position_m"])
            v = np.interp(t_sim, rows["time_s"], rows["speed_mps"])
            msgs += [message(t_wall + 0.0005, fid, dd) for fid, dd in outputs(codec, t_sim, s, v)]
    rec = tmp_path / "bus.log"
    write_log(str(rec), msgs)
    js = tmp_path / "m.json"
    assert score.main([str(rec), "--truth", str(d / "run_truth.csv"), "--input-log", str(log), "--json", str(js)]) == 0
    res = json.loads(js.read_text())
    assert res["align"] == "inputs"
    check_metrics(res)
    # time alignment with the right speed is close, but not exact
    assert score.main([str(rec), "--truth", str(d / "run_truth.csv"), "--align", "time", "--t0", "1.7e9",
                       "--speed", "20", "--json", str(js)]) == 0
    assert json.loads(js.read_text())["position_rms_m"] < 5.0


def test_input_log_with_truncated_positions(sim, tmp_path):
    """Position frames cut to 7 bytes in the input log (hstpf-replay
    --truncate-window; hstpfd refuses them) and recorded beside the outputs:
    the score skips them; it crashed with cantools' DecodeError (a review)."""
    d, log, rows = sim
    codec = FrameCodec()
    inp, rec_msgs = [], []
    for i, m in enumerate(read_log(str(log))):
        data = bytes(m.data)
        cut = m.arbitration_id == 0x100 and i % 53 == 0
        if cut:
            data = data[:7]
        inp.append(message(m.timestamp, m.arbitration_id, data))
        rec_msgs.append(message(1.7e9 + m.timestamp, m.arbitration_id, data))
        if m.arbitration_id == 0x100 and not cut:
            s = np.interp(m.timestamp, rows["time_s"], rows["position_m"])
            v = np.interp(m.timestamp, rows["time_s"], rows["speed_mps"])
            rec_msgs += [message(1.7e9 + m.timestamp + 0.0005, fid, dd) for fid, dd in outputs(codec, m.timestamp, s, v)]
    il, rec, js = tmp_path / "in.log", tmp_path / "bus.log", tmp_path / "m.json"
    write_log(str(il), inp)
    write_log(str(rec), rec_msgs)
    assert score.main([str(rec), "--truth", str(d / "run_truth.csv"), "--input-log", str(il), "--json", str(js)]) == 0
    res = json.loads(js.read_text())
    assert res["align"] == "inputs"
    check_metrics(res)


def test_truth_theta_at_a_coupling(tmp_path):
    """The theta plot compares each estimate with the truth's coefficients
    at its time: CRH3 until 900 s, SS8 coupled from then on."""
    p = tmp_path / "truth.csv"
    lines = ["time_s,position_m,speed_mps,type,c0,c1,c2"]
    for k in range(0, 1801, 300):
        th, name = (CRH3, "CRH3") if k < 900 else (SS8, "SS8")
        lines.append(f"{k},{k * 50.0},50.0,{name},{th[0]},{th[1]},{th[2]}")
    p.write_text("\n".join(lines) + "\n")
    truth = score.read_truth(str(p))
    c0, c1, c2 = score.truth_theta_at(truth, np.array([-5.0, 0.0, 600.0, 899.9, 900.0, 1500.0, 1900.0]))
    assert list(c0) == [CRH3[0]] * 4 + [SS8[0]] * 3
    assert list(c2) == [CRH3[2]] * 4 + [SS8[2]] * 3
    assert truth["theta"].c1 == SS8[1]  # the summary's truth: the last row


def declaration_log(path, n, t_declare, declared, weight, theta, theta_valid_before=None):
    """An estimator's EstType and EstTheta at 1 Hz for n s: undecided (255)
    until t_declare, then `declared` (a Table 1 index, or 254 for a custom
    row), theta published throughout (valid before theta_valid_before only,
    if given)."""
    codec = FrameCodec()
    msgs = []
    for k in range(0, n):
        fid, data = codec.encode("EstType", {"TypeStatus": 1 if k >= t_declare else 0,
                                             "DeclaredType": declared if k >= t_declare else 255,
                                             "DeclaredWeight": weight, "LeaderType": declared, "LeaderWeight": weight})
        msgs.append(message(float(k), fid, data))
        valid = 1 if theta_valid_before is None or k < theta_valid_before else 0
        fid, data = codec.encode("EstTheta", {"ThetaValid": valid, "C0": theta[0], "C1": theta[1], "C2": theta[2]})
        msgs.append(message(float(k), fid, data))
    write_log(str(path), msgs)


def test_wrong_declaration_is_reported(sim, tmp_path):
    d, log, rows = sim
    rec = tmp_path / "wrong.log"
    declaration_log(rec, 300, 100, 6, 0.95, SS8)
    js = tmp_path / "m.json"
    assert score.main([str(rec), "--truth", str(d / "run_truth.csv"), "--json", str(js)]) == 0
    res = json.loads(js.read_text())
    assert res["declared_type"] == "SS8" and res["declared_correct"] is False and res["decision_time_s"] == 100.0
    assert res["theta_rel_err"][2] == pytest.approx(0.000426 / 0.000115 - 1, rel=1e-3)
    # W(V) relative error by hand at 0..350 km/h
    V = np.arange(0, 351.0)
    wt = CRH3[0] + CRH3[1] * V + CRH3[2] * V**2
    we = SS8[0] + SS8[1] * V + SS8[2] * V**2
    assert res["w_rms_rel_err"] == pytest.approx(np.sqrt(np.mean(((we - wt) / wt) ** 2)), rel=1e-3)


def test_quality_frames_coverage(sim, tmp_path):
    """EstQuality (position and speed sd, sent with each EstState): the
    score's 95 % coverage is the share of steps whose error lies within
    1.96 sd. The scripted errors are 1 m and 0.1 m/s; the position sd is
    0.5 m (1.96 x 0.5 < 1: not covered) on even seconds and 1 m (covered)
    on odd ones, the speed sd 0.1 m/s (always covered)."""
    d, log, rows = sim
    codec = FrameCodec()
    msgs = []
    for k in range(0, len(rows) - 1):
        s, v = float(rows["position_m"][k]), float(rows["speed_mps"][k])
        for fid, data in outputs(codec, float(k), s, v):
            msgs.append(message(float(k), fid, data))
        fid, data = codec.encode("EstQuality", {"QualValid": 1, "PositionSd": 0.5 if k % 2 == 0 else 1.0,
                                                "SpeedSd": 0.1, "Acquisitions": 1})
        msgs.append(message(float(k), fid, data))
        fid, data = codec.encode("HealthTime", {"ClockStepsFwd": 1, "Reacquisitions": 2})
        msgs.append(message(float(k), fid, data))
    rec = tmp_path / "q.log"
    write_log(str(rec), msgs)
    js = tmp_path / "q.json"
    assert score.main([str(rec), "--truth", str(d / "run_truth.csv"), "--json", str(js)]) == 0
    res = json.loads(js.read_text())
    assert res["quality_frames"] == res["state_frames"] == len(rows) - 1
    assert res["position_95_coverage"] == pytest.approx(0.5, abs=1.0 / len(rows) + 1e-9)
    assert res["speed_95_coverage"] == 1.0
    assert res["position_sd_median_m"] == pytest.approx(0.75)
    assert res["health"]["ClockStepsFwd"] == 1 and res["health"]["Reacquisitions"] == 2
    # on a live bus each EstQuality is stamped a little after its EstState: still paired
    for m in msgs:
        if m.arbitration_id == codec.db.get_message_by_name("EstQuality").frame_id:
            m.timestamp += 0.00015
    write_log(str(rec), sorted(msgs, key=lambda m: m.timestamp))
    assert score.main([str(rec), "--truth", str(d / "run_truth.csv"), "--json", str(js)]) == 0
    live = json.loads(js.read_text())
    assert live["quality_frames"] == res["quality_frames"]
    assert live["position_95_coverage"] == res["position_95_coverage"]


@pytest.mark.parametrize("dated", [True, False])
def test_est_time_dates_late_outputs(sim, tmp_path, dated):
    """The estimator's outputs reach the bus 7 input frames (0.7 s) after the
    position they were computed from (a busy estimator). Inputs alignment
    alone times them by the latest input and scores the lag as error; with
    EstQuality.EstTime (the step's fix time) they are dated right and the
    scripted 1 m / 0.1 m/s errors come back."""
    d, log, rows = sim
    codec = FrameCodec()
    msgs, queue = [], []
    fix_of = {}
    for m in read_log(str(log)):
        msgs.append(message(m.timestamp, m.arbitration_id, bytes(m.data)))
        if m.arbitration_id != 0x100:
            continue
        _, sig, _ = FrameCodec().decode(0x100, bytes(m.data), check=False)
        t = m.timestamp
        if abs(t - round(t)) < 1e-6:  # one step per second, on this fix
            queue.append((t, sig["FixTime"]))
        if len(queue) and t - queue[0][0] >= 0.7 - 1e-9:
            ts, fix = queue.pop(0)
            s = np.interp(ts, rows["time_s"], rows["position_m"])
            v = np.interp(ts, rows["time_s"], rows["speed_mps"])
            fid, data = codec.encode("EstState", {"EstValid": 1, "EstPosition": s + 1.0, "EstSpeed": v + 0.1})
            msgs.append(message(t + 0.0001, fid, data))
            fid, data = codec.encode("EstQuality", {"QualValid": 1, "EstTimeValid": int(dated), "EstTime": fix,
                                                    "PositionSd": 1.0, "SpeedSd": 0.1})
            msgs.append(message(t + 0.0002, fid, data))
            fix_of[ts] = fix
    rec = tmp_path / "late.log"
    write_log(str(rec), msgs)
    js = tmp_path / "late.json"
    assert score.main([str(rec), "--truth", str(d / "run_truth.csv"), "--input-log", str(log), "--json", str(js)]) == 0
    res = json.loads(js.read_text())
    if dated:
        assert res["state_frames_dated"] >= res["state_frames"] > 300
        assert res["position_rms_m"] == pytest.approx(1.0, abs=0.006)
        assert res["speed_rms_mps"] == pytest.approx(0.1, abs=0.006)
    else:
        assert res["state_frames_dated"] == 0
        assert res["position_rms_m"] > 5.0  # 0.7 s of travel at up to ~60 m/s


def test_est_time_after_the_latest_input(sim, tmp_path):
    """A predict-only step can end after the latest position seen (the
    positions are late): EstTime then lies ahead of that input's FixTime and
    is dated ahead of it, not a wrap (8.192 s) earlier."""
    d, log, rows = sim
    codec = FrameCodec()
    msgs = []
    for m in read_log(str(log)):
        msgs.append(message(m.timestamp, m.arbitration_id, bytes(m.data)))
        if m.arbitration_id != 0x100 or abs(m.timestamp - round(m.timestamp)) > 1e-6:
            continue
        _, sig, _ = FrameCodec().decode(0x100, bytes(m.data), check=False)
        ts = m.timestamp + 0.5  # predicted half a second past this fix
        s = np.interp(ts, rows["time_s"], rows["position_m"])
        v = np.interp(ts, rows["time_s"], rows["speed_mps"])
        fid, data = codec.encode("EstState", {"EstValid": 1, "EstPosition": s + 1.0, "EstSpeed": v + 0.1})
        msgs.append(message(m.timestamp + 0.0001, fid, data))
        fid, data = codec.encode("EstQuality", {"QualValid": 1, "EstTimeValid": 1, "EstTime": (sig["FixTime"] + 500) % 8192})
        msgs.append(message(m.timestamp + 0.0002, fid, data))
    rec = tmp_path / "ahead.log"
    write_log(str(rec), msgs)
    js = tmp_path / "ahead.json"
    assert score.main([str(rec), "--truth", str(d / "run_truth.csv"), "--input-log", str(log), "--json", str(js)]) == 0
    res = json.loads(js.read_text())
    assert res["state_frames_dated"] >= res["state_frames"] > 300  # the last one, at 400.5 s, is past the truth
    assert res["position_rms_m"] == pytest.approx(1.0, abs=0.006)


def test_est_time_during_a_stall(sim, tmp_path):
    """The inputs stall for 6 s (more than half the 8.192 s wrap) while the
    estimator predicts on: its estimates end up to 6 s past the latest
    input seen and are dated there (from how long after it they came), not
    a wrap earlier."""
    d, log, rows = sim
    codec = FrameCodec()
    msgs = []
    fix0 = None
    for m in read_log(str(log)):
        t = m.timestamp
        if 200.0 < t < 206.0:
            continue  # the stalled inputs never reach the bus
        msgs.append(message(t, m.arbitration_id, bytes(m.data)))
        if m.arbitration_id == 0x100 and fix0 is None:
            fix0 = FrameCodec().decode(0x100, bytes(m.data), check=False)[1]["FixTime"] - round(t * 1000) % 8192
    for k in range(1, 6):  # predictions at 201..205 s
        ts = 200.0 + k
        s = np.interp(ts, rows["time_s"], rows["position_m"])
        v = np.interp(ts, rows["time_s"], rows["speed_mps"])
        fid, data = codec.encode("EstState", {"EstValid": 1, "EstPosition": s + 1.0, "EstSpeed": v + 0.1})
        msgs.append(message(ts + 0.0001, fid, data))
        fid, data = codec.encode("EstQuality", {"QualValid": 1, "EstTimeValid": 1,
                                                "EstTime": (round(ts * 1000) + fix0) % 8192})
        msgs.append(message(ts + 0.0002, fid, data))
    msgs.sort(key=lambda m: m.timestamp)
    rec = tmp_path / "stall.log"
    write_log(str(rec), msgs)
    js = tmp_path / "stall.json"
    assert score.main([str(rec), "--truth", str(d / "run_truth.csv"), "--input-log", str(log), "--json", str(js)]) == 0
    res = json.loads(js.read_text())
    assert res["state_frames_dated"] == res["state_frames"] == 5
    assert res["position_rms_m"] == pytest.approx(1.0, abs=0.006)


def test_est_time_behind_lagging_inputs(sim, tmp_path):
    """From 200 s on every input reaches the bus 6 s late (a replayer that
    fell behind and keeps pace without catching up), and the estimator steps
    on each fix as it arrives. The bus clock then puts each estimate 6 s past
    its fix, more than half the 8.192 s wrap: the recorded fix with the
    estimate's EstTime dates it exactly (where the bus clock alone was a wrap
    off: about 700 m at 90 m/s)."""
    d, log, rows = sim
    codec = FrameCodec()
    msgs = []
    for m in read_log(str(log)):
        late = 6.0 if m.timestamp >= 200.0 else 0.0
        msgs.append(message(m.timestamp + late, m.arbitration_id, bytes(m.data)))
        if m.arbitration_id != 0x100 or abs(m.timestamp - round(m.timestamp)) > 1e-6:
            continue
        _, sig, _ = FrameCodec().decode(0x100, bytes(m.data), check=False)
        s = np.interp(m.timestamp, rows["time_s"], rows["position_m"])
        v = np.interp(m.timestamp, rows["time_s"], rows["speed_mps"])
        fid, data = codec.encode("EstState", {"EstValid": 1, "EstPosition": s + 1.0, "EstSpeed": v + 0.1})
        msgs.append(message(m.timestamp + late + 0.0001, fid, data))
        fid, data = codec.encode("EstQuality", {"QualValid": 1, "EstTimeValid": 1, "EstTime": sig["FixTime"]})
        msgs.append(message(m.timestamp + late + 0.0002, fid, data))
    rec = tmp_path / "lagging.log"
    write_log(str(rec), msgs)
    js = tmp_path / "lagging.json"
    assert score.main([str(rec), "--truth", str(d / "run_truth.csv"), "--input-log", str(log), "--json", str(js)]) == 0
    res = json.loads(js.read_text())
    assert res["state_frames_dated"] >= res["state_frames"] > 300
    assert res["position_rms_m"] == pytest.approx(1.0, abs=0.006)
    assert res["speed_rms_mps"] == pytest.approx(0.1, abs=0.006)


def test_est_time_after_an_output_silence(sim, tmp_path):
    """Inputs 6 s late from 200 s on (a backlog), the estimator silent from
    200 to 215 s (held off the CPU), and each estimate a prediction 50 ms past
    the fix it followed (no fix has its EstTime). After the silence the
    estimate before it is too far back to count from: it is dated from the
    latest input and the bus time since (hstpfd never predicts past that),
    not from the bus clock alone, which runs 6 s ahead of the inputs and put
    it a wrap away."""
    d, log, rows = sim
    codec = FrameCodec()
    msgs = []
    for m in read_log(str(log)):
        late = 6.0 if m.timestamp >= 200.0 else 0.0
        msgs.append(message(m.timestamp + late, m.arbitration_id, bytes(m.data)))
        if m.arbitration_id != 0x100 or abs(m.timestamp - round(m.timestamp)) > 1e-6 or 200.0 <= m.timestamp < 215.0:
            continue
        _, sig, _ = FrameCodec().decode(0x100, bytes(m.data), check=False)
        ts = m.timestamp + 0.05
        s = np.interp(ts, rows["time_s"], rows["position_m"])
        v = np.interp(ts, rows["time_s"], rows["speed_mps"])
        fid, data = codec.encode("EstState", {"EstValid": 1, "EstPosition": s + 1.0, "EstSpeed": v + 0.1})
        msgs.append(message(m.timestamp + late + 0.005, fid, data))
        fid, data = codec.encode("EstQuality", {"QualValid": 1, "EstTimeValid": 1, "EstTime": (sig["FixTime"] + 50) % 8192})
        msgs.append(message(m.timestamp + late + 0.0051, fid, data))
    msgs.sort(key=lambda m: m.timestamp)
    rec = tmp_path / "silent.log"
    write_log(str(rec), msgs)
    js = tmp_path / "silent.json"
    assert score.main([str(rec), "--truth", str(d / "run_truth.csv"), "--input-log", str(log), "--json", str(js)]) == 0
    res = json.loads(js.read_text())
    assert res["state_frames_dated"] >= res["state_frames"] > 300
    assert res["position_rms_m"] == pytest.approx(1.0, abs=0.006)


@pytest.mark.parametrize("declared, correct", [((1.10, 0.0090, 0.000150), True), ((1.12, 0.0090, 0.000150), False)])
def test_custom_declared_row_judged_by_its_theta(tmp_path, declared, correct):
    """Custom rows all go out as DeclaredType 254 without a name: the declared
    one is the truth's when its published theta is the truth's (to the
    frames' resolution), not merely because both are "custom"."""
    log = tmp_path / "c.log"
    assert simulate.main(["-o", str(log), "--duration", "60", "--seed", "1", "--coeffs", "1.10,0.0090,0.000150"]) == 0
    rec = tmp_path / "rec.log"
    declaration_log(rec, 60, 30, 254, 0.99, declared)
    js = tmp_path / "m.json"
    assert score.main([str(rec), "--truth", str(tmp_path / "c_truth.csv"), "--json", str(js)]) == 0
    res = json.loads(js.read_text())
    assert res["declared_type"] == "custom" and res["declared_correct"] is correct


def test_custom_declared_row_without_its_theta(tmp_path):
    """A declared custom row whose theta never went out valid within the
    declaration (beyond the frame's range: saturated) is not judged at all."""
    log = tmp_path / "c.log"
    assert simulate.main(["-o", str(log), "--duration", "60", "--seed", "1", "--coeffs", "1.10,0.0090,0.000150"]) == 0
    rec = tmp_path / "rec.log"
    declaration_log(rec, 60, 30, 254, 0.99, (1.10, 0.0090, 0.000150), theta_valid_before=30)
    js = tmp_path / "m.json"
    assert score.main([str(rec), "--truth", str(tmp_path / "c_truth.csv"), "--json", str(js)]) == 0
    assert json.loads(js.read_text())["declared_correct"] is None


def test_input_log_clock_step_warned(sim, tmp_path, capsys):
    """An input log whose clock steps 20 s forward half-way (a receiver's
    clock step recorded in the log): the frames are dated log time - t0, so
    the score warns and counts it; a clean log counts none."""
    d, log, rows = sim
    msgs = read_log(str(log))
    for m in msgs:
        if m.timestamp >= 200.0:
            m.timestamp += 20.0
    stepped = tmp_path / "stepped.log"
    write_log(str(stepped), msgs)
    codec = FrameCodec()
    assert len(score.input_clock_steps(read_log(str(stepped)), codec)) == 1
    assert score.input_clock_steps(read_log(str(log)), codec) == []
