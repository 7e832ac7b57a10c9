"""hstpfd on a log whose positioning unit starts a new run from 0 at a
station (hstpf-simulate --restart-at): the estimate is invalid while the
library checks the new reference, then valid at it, with the weights kept.
Before the probation (lib/src/lock.c) it stayed invalid until the train had
run the whole distance again."""
import csv
import json
import os
import subprocess
from pathlib import Path

import pytest

from hstpf_tools import simulate


def test_restart_at_a_station(root, tmp_path):
    exe = Path(os.environ.get("HSTPF_BUILD_DIR", str(root / "build"))) / "port" / "hstpfd"
    if not exe.is_file():
        pytest.skip("hstpfd not built (set HSTPF_BUILD_DIR)")
    log = tmp_path / "run.log"
    # the line's first station: at rest from about 447 s, departing at 567 s
    assert simulate.main(["--profile", "line", "--duration", "900", "--seed", "4", "--restart-at", "480",
                          "-o", str(log), "--json", str(tmp_path / "sim.json")]) == 0
    subprocess.run([str(exe), "--log", str(log), "--models", "all", "--noise", "case1", "--out",
                    str(tmp_path / "steps.jsonl"), "--summary", str(tmp_path / "summary.json")],
                   check=True, capture_output=True)
    with open(tmp_path / "run_truth.csv", newline="") as f:
        truth = {round(float(r["time_s"])): float(r["position_m"]) for r in csv.DictReader(f)}
    steps = [json.loads(ln) for ln in (tmp_path / "steps.jsonl").read_text().splitlines()]
    before = [s for s in steps if 300 <= s["t"] < 480]
    assert all(s["valid"] for s in before)
    # 5 gated fixes, the acquisition pair, HSTPF_REF_PROBATION_S (30 s) at rest: valid again by 520 s
    after = [s for s in steps if s["t"] >= 480]
    invalid = [s["t"] for s in after if not s["valid"]]
    assert invalid and invalid[0] == 480.0 and max(invalid) <= 520.0
    late = [s for s in after if s["t"] > 520]
    assert all(s["valid"] and abs(s["pos"] - truth[round(s["t"])]) < 10.0 for s in late)
    assert abs(late[0]["pos"]) < 10.0  # the new reference: the train stands at its 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["valid"] and summary["backward"] >= 1 and summary["acquisitions"] == 2
