"""The committed C codec cannot drift from the DBC: regenerate and diff."""
import filecmp
import os
import subprocess
import sys
from pathlib import Path


def test_regen_matches_committed(root, tmp_path):
    env = dict(os.environ, PYTHON=sys.executable)  # the interpreter that has cantools
    subprocess.run(["sh", str(root / "port" / "codec" / "regen.sh"), str(tmp_path)], check=True, env=env)
    committed = root / "port" / "codec" / "generated"
    names = sorted(p.name for p in committed.iterdir())
    assert names == sorted(p.name for p in Path(tmp_path).iterdir())
    assert names == ["hstpf_can.c", "hstpf_can.h", "hstpf_frames.c", "hstpf_frames.h"]
    for n in names:
        assert filecmp.cmp(committed / n, tmp_path / n, shallow=False), (
            f"port/codec/generated/{n} differs from what port/codec/regen.sh makes of port/dbc/hstpf.dbc: run regen.sh")


def test_generator_rejects_a_frame_without_e2e_layout(root, tmp_path):
    dbc = (root / "port" / "dbc" / "hstpf.dbc").read_text()
    bad = tmp_path / "bad.dbc"
    bad.write_text(dbc.replace("SG_ E2eCounter : 8|4@1+", "SG_ E2eCounter : 12|4@1+", 1)
                   .replace("SG_ PosValid : 12|1@1+", "SG_ PosValid : 8|1@1+", 1))
    r = subprocess.run([sys.executable, str(root / "port" / "codec" / "gen_frames.py"), str(bad), str(tmp_path)],
                       capture_output=True, text=True)
    assert r.returncode != 0 and "E2eCounter" in (r.stderr + r.stdout)
