"""The soak test of issue 11, shortened: 1.5 simulated hours through hstpfd --log
(docs/soak.md has the full 24 h run). The log is checked independently of
the tool that made it, and the checker is shown to catch what it looks for."""
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

from hstpf_tools import soak
from hstpf_tools.frames import FrameCodec
from hstpf_tools.logio import read_log

ROOT = Path(__file__).resolve().parents[2]
HOURS = 1.5


def hstpfd_path():
    exe = Path(os.environ.get("HSTPF_BUILD_DIR", str(ROOT / "build"))) / "port" / "hstpfd"
    if not exe.is_file():
        pytest.skip(f"hstpfd not built at {exe} (set HSTPF_BUILD_DIR)")
    return str(exe)


@pytest.fixture(scope="module")
def day(tmp_path_factory):
    d = tmp_path_factory.mktemp("soak")
    code = soak.main(["--hours", str(HOURS), "--seed", "3", "--dir", str(d), "--hstpfd", hstpfd_path(),
                      "--block-s", "1800", "--warmup-s", "300", "--sample-s", "0.01", "--cpu-tol", "0.5",
                      "--json", str(d / "r.json")])
    rep = json.loads((d / "r.json").read_text())
    plan = json.loads((d / "soak_plan.json").read_text())
    return d, code, rep, plan


def lock_api(d) -> bool:
    """The daemon publishes the library's lock (pos_sd filled): HSTPFD_LIB_LOCK_API 1."""
    with open(d / "steps.jsonl") as f:
        return any(json.loads(line)["pos_sd"] is not None for line in f)


def test_log_holds_the_planned_day(day):
    """Read back with python-can and the DBC, not with the generator's own arrays."""
    d, _, _, plan = day
    msgs = read_log(str(d / "soak.log"))
    assert len(msgs) == plan["frames"]
    ts = np.array([m.timestamp for m in msgs])
    steps = np.diff(ts)
    # receive-clock steps: the stamps go back by ~30 s once, jump ahead by days once, +30 s once
    assert int((steps < -1.0).sum()) == sum(1 for s in plan["clock_steps"] if s["delta_s"] < 0) == 1
    assert int((steps > 600.0).sum()) == 1 and steps.max() > 2 * 86400
    assert sum(1 for s in plan["clock_steps"] if 0 < s["delta_s"] < 600) == 1
    c = FrameCodec()
    invalid = short = 0
    for m in msgs:
        if m.arbitration_id != 0x100:
            continue
        if len(m.data) != 8:
            short += 1
            continue
        name, sig, res = c.decode(m.arbitration_id, bytes(m.data), check=False)
        invalid += sig["PosValid"] == 0
    # GNSS outages: PosValid = 0 frames, less those a bus fault took
    assert 0.95 * plan["pos_invalid_frames"] <= invalid <= plan["pos_invalid_frames"] + 5
    assert plan["pos_invalid_frames"] >= 10 * 3 * HOURS  # 3 outages an hour of at least 5 s at 10 Hz
    assert short == plan["injected"]["truncate"].get("0x100", 0)
    assert plan["stops"] >= 3  # station stops with the holding brake
    assert plan["injected_totals"]["corrupt"] > 0 and plan["injected_totals"]["duplicate"] > 0


def test_same_seed_same_log(tmp_path):
    a = soak.make(str(tmp_path / "a" / "soak.log"), 0.1, 7)
    b = soak.make(str(tmp_path / "b" / "soak.log"), 0.1, 7)
    assert (tmp_path / "a" / "soak.log").read_bytes() == (tmp_path / "b" / "soak.log").read_bytes()
    assert a["injected"] == b["injected"]
    soak.make(str(tmp_path / "c" / "soak.log"), 0.1, 8)
    assert (tmp_path / "c" / "soak.log").read_bytes() != (tmp_path / "a" / "soak.log").read_bytes()


def test_soak_checks_pass(day):
    """Finite, in range, position within the bound, declaration invariant, the
    injected faults and clock steps counted, RSS and per-step time flat."""
    d, code, rep, plan = day
    other = {k: n for k, n in rep["failed_checks"].items() if k != "speed_error"}
    assert not other, rep["failures"]
    assert rep["nonfinite"] == 0 and rep["steps"] > HOURS * 3600 * 0.95
    assert rep["scored"] > 0.95 * rep["valid"] and rep["valid_fraction"] > 0.95
    assert rep["clock_steps"]["counted_forward"] == 2 and rep["clock_steps"]["counted_back"] == 1
    assert rep["faults"]["counted"]["bad_crc"] == plan["injected_totals"]["corrupt"]
    assert rep["rss_last_kb"] <= rep["rss_first_kb"] + 256
    assert rep["position_error_fix_m"]["rms"] < 3.0  # tracking, well inside the 6 sd bound (13.4 m)


def test_soak_speed_within_bound(day):
    """A valid speed is within 6 sd of the truth. On the daemon without the
    library's lock API the step that restarts after a clock step publishes
    speed 0 as valid while the train runs (docs/soak.md): expected to fail
    until HSTPFD_LIB_LOCK_API is 1."""
    d, code, rep, _ = day
    if rep["failed_checks"].get("speed_error") and not lock_api(d):
        assert all("restart 1" in f for f in rep["failures"] if f.startswith("speed_error"))
        pytest.xfail("restart steps valid with speed 0 until the daemon uses the library's lock (HSTPFD_LIB_LOCK_API)")
    assert "speed_error" not in rep["failed_checks"], rep["failures"]
    assert code == 0 and rep["pass"]


def test_checker_catches_bad_steps(day, tmp_path):
    """The same run with its step stream spoilt: each fault is caught by its check."""
    d, _, _, _ = day
    lines = (d / "steps.jsonl").read_text().splitlines()
    valid_fix = [i for i, x in enumerate(lines) if '"valid":true' in x and '"y":null' not in x and i > 100]
    i, j, k = valid_fix[10], valid_fix[20], valid_fix[30]
    a = json.loads(lines[i])
    a["pos"] += 100.0  # 100 m off, marked valid
    lines[i] = json.dumps(a)
    lines[j] = lines[j].replace('"speed":', '"speed":NaN,"x":', 1)
    b = json.loads(lines[k])
    b["status"], b["declared"] = "declared", None
    lines[k] = json.dumps(b)
    (tmp_path / "steps.jsonl").write_text("\n".join(lines) + "\n")
    rep = soak.check(str(tmp_path / "steps.jsonl"), str(d / "summary.json"), str(d / "soak"), None, 1800.0, 300.0,
                     6.0, 256, 0.25)
    assert rep["failed_checks"].get("position_error") == 1
    assert rep["failed_checks"].get("nonfinite") == 1
    assert rep["failed_checks"].get("declaration") == 1
    assert not rep["pass"]


def test_error_bound_is_the_model_prediction_error():
    # at a fix: 6 measurement sd; after tau s the speed error and the speed noise's walk add up
    assert soak.error_bound(0.0, 6.0) == pytest.approx(6 * math.sqrt(5.0))
    tau = 60.0
    want = 6 * math.sqrt(5.0 + (0.5 * tau) ** 2 + 0.05 * tau ** 3 / 3 + 0.02 * tau)
    assert soak.error_bound(tau, 6.0) == pytest.approx(want)
    assert soak.speed_bound(0.0, 6.0) == pytest.approx(6 * math.sqrt(10.05))


def test_checker_catches_growth(day):
    """Made-up samples of the same run: per-step CPU time growing with the
    step number and RSS growing by 1 MB are both caught; flat ones are not."""
    d, _, rep, _ = day
    n = rep["steps"]
    ks = np.linspace(1, n, 400)

    def rec(cpu, rss):
        return {"exit": 0, "wall_s": 1.0, "stderr": "",
                "samples": [(i * 0.01, float(c), int(r), int(k)) for i, (k, c, r) in enumerate(zip(ks, cpu, rss))]}

    args = (str(d / "steps.jsonl"), str(d / "summary.json"), str(d / "soak"))
    flat = soak.check(*args, rec(50e-6 * ks, np.full(len(ks), 2400)), 1800.0, 300.0, 6.0, 256, 0.25)
    assert "step_time" not in flat["failed_checks"] and "rss" not in flat["failed_checks"]
    assert flat["cpu_us_per_step_first"] == pytest.approx(50.0, rel=0.02)
    # 50 us per step at the start, 100 us at the end: the per-step time doubles
    grow = soak.check(*args, rec(50e-6 * (ks + ks ** 2 / (2 * n)), 2400 + 1024 * ks / n), 1800.0, 300.0, 6.0,
                      256, 0.25)
    assert grow["failed_checks"].get("step_time") == 1 and grow["failed_checks"].get("rss") == 1
    assert grow["cpu_us_per_step_last"] > 1.5 * grow["cpu_us_per_step_first"]


def test_rerun_on_the_same_log_and_folder(day):
    """--log runs hstpfd again on a made day; the step stream left by the first
    run is not taken for the second run's progress (samples start from 0)."""
    d, _, rep, _ = day
    code = soak.main(["--log", str(d / "soak.log"), "--dir", str(d), "--hstpfd", hstpfd_path(), "--block-s", "1800",
                      "--warmup-s", "300", "--sample-s", "0.01", "--cpu-tol", "0.5", "--json", str(d / "r2.json")])
    rep2 = json.loads((d / "r2.json").read_text())
    ks = [int(line.split(",")[3]) for line in (d / "samples.csv").read_text().splitlines()[1:]]
    assert ks == sorted(ks) and ks[0] < 1000
    assert all(b["cpu_us_per_step"] > 0 for b in rep2["blocks"])
    # the same log gives the same steps: the daemon is deterministic
    assert rep2["steps"] == rep["steps"] and rep2["position_error_fix_m"] == rep["position_error_fix_m"]
    assert code in (0, 1) and rep2["failed_checks"].keys() <= {"speed_error"}
