"""hstpf-mc's --json: "-" is stdout (the table then goes to stderr), a path
is a file (the table stays on stdout)."""
import json
import os
import subprocess
from pathlib import Path

import pytest


@pytest.fixture(scope="module")
def mc() -> str:
    build = os.environ.get("HSTPF_BUILD_DIR")
    exe = Path(build) / "tools" / "montecarlo" / "hstpf-mc" if build else None
    if exe is None or not exe.is_file():
        pytest.skip("hstpf-mc is built by CMake: set HSTPF_BUILD_DIR")
    return str(exe)


ARGS = ["--scenario", "paper1", "--seeds", "2", "--duration", "120", "--threads", "1"]


def test_json_dash_is_stdout(mc, tmp_path):
    r = subprocess.run([mc, *ARGS, "--json", "-"], cwd=tmp_path, capture_output=True, text=True, check=True)
    d = json.loads(r.stdout)
    assert d["scenario"] == "paper1" and d["seeds"] == 2
    assert [run["seed"] for run in d["results"][0]["runs"]] == [1, 2]
    assert "truth" in r.stderr and "success" in r.stderr  # the table
    assert not (tmp_path / "-").exists()


def test_json_file_keeps_the_table_on_stdout(mc, tmp_path):
    out = tmp_path / "r.json"
    r = subprocess.run([mc, *ARGS, "--json", str(out)], capture_output=True, text=True, check=True)
    assert "truth" in r.stdout
    assert json.loads(out.read_text())["results"][0]["truth"] == "CRH3"


OFF = ["--scenario", "off15", "--truth", "CRH3", "--seeds", "3", "--duration", "600", "--threads", "1"]


def test_oracle_measures_without_touching_the_filter(mc, tmp_path):
    """--oracle runs a second bank beside the filter: the filter's figures
    are the same with it, and each run's oracle fields are within range."""
    plain = subprocess.run([mc, *OFF], capture_output=True, text=True, check=True).stdout.splitlines()
    out = tmp_path / "o.json"
    r = subprocess.run([mc, *OFF, "--oracle", "--json", str(out)], capture_output=True, text=True, check=True)
    lines = r.stdout.splitlines()
    assert lines[:-2] == plain  # two lines more, nothing else changed
    assert lines[-2].startswith("oracle (the truth's own theta")
    assert lines[-1].startswith("oracle, the nearest row against 8 trains 10% from it")
    runs = json.loads(out.read_text())["results"][0]["runs"]
    assert len(runs) == 3
    for run in runs:
        assert run["oracle_sep"] == -1 or 0 <= run["oracle_sep"] <= 601
        if not run["false_decl"]:
            assert run["oracle_llr_decl"] is None and run["oracle_llr_near_decl"] is None


def test_oracle_on_the_table(mc, tmp_path):
    """On the table the oracle scores trains 10 % from the truth's row; the
    table is the same with it, two lines more."""
    args = ["--scenario", "paper1", "--seeds", "2", "--duration", "300", "--threads", "1"]
    plain = subprocess.run([mc, *args], capture_output=True, text=True, check=True).stdout.splitlines()
    r = subprocess.run([mc, *args, "--oracle", "--json", str(tmp_path / "o.json")], capture_output=True,
                       text=True, check=True)
    lines = r.stdout.splitlines()
    assert lines[:-2] == plain
    assert lines[-2].startswith("oracle (8 trains 10% from the truth's row") and "2 runs;" in lines[-2]
    assert lines[-1].startswith("oracle, paired with the declaration")
    for run in json.loads((tmp_path / "o.json").read_text())["results"][0]["runs"]:
        assert run["oracle_sep"] == -1 or 0 <= run["oracle_sep"] <= 301
