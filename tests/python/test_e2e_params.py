"""One source of truth for the E2E parameters: the DBC's attributes
HstpfE2EProfile, HstpfE2EMaxDeltaCounter, HstpfE2ETimeoutMs (and
HstpfE2EDataId). The DBC text is read here with its own small parser (not
cantools), and every copy must agree with it: the generated C table and
macros, the C codec at run time, the Python codec's receivers and hstpfd's
defaults. A test also shows that the generators follow an edited DBC."""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from hstpf_tools import e2e
from hstpf_tools.frames import FrameCodec


def dbc_params(text: str):
    """{frame name: (data ID, max delta, timeout ms)}, defaults, profile."""
    names = {int(i): n for i, n in re.findall(r"^BO_ (\d+) (\w+):", text, re.M)}
    dflt = dict(re.findall(r'^BA_DEF_DEF_ +"(HstpfE2E\w+)" +"?(\w+)"?;', text, re.M))
    prof = re.search(r'^BA_ +"HstpfE2EProfile" +"(\w+)";', text, re.M)
    per = {}
    for attr, fid, val in re.findall(r'^BA_ +"(HstpfE2E\w+)" +BO_ +(\d+) +(\d+);', text, re.M):
        per.setdefault(names[int(fid)], {})[attr] = int(val)
    frames = {}
    for n in names.values():
        a = per.get(n, {})
        frames[n] = (a["HstpfE2EDataId"],
                     a.get("HstpfE2EMaxDeltaCounter", int(dflt["HstpfE2EMaxDeltaCounter"])),
                     a.get("HstpfE2ETimeoutMs", int(dflt["HstpfE2ETimeoutMs"])))
    defaults = (int(dflt["HstpfE2EMaxDeltaCounter"]), int(dflt["HstpfE2ETimeoutMs"]))
    return frames, defaults, (prof.group(1) if prof else dflt["HstpfE2EProfile"])


@pytest.fixture(scope="module")
def dbc(root):
    return dbc_params((root / "port" / "dbc" / "hstpf.dbc").read_text())


def test_dbc_has_the_parameters(dbc):
    frames, defaults, profile = dbc
    assert profile == "P01" and defaults == (3, 500)
    assert frames["Position"][1:] == (3, 500) and frames["Traction"][1:] == (3, 500)
    assert len({v[0] for v in frames.values()}) == len(frames)  # a data ID each, all different


def test_generated_c_table(dbc, root):
    frames, defaults, profile = dbc
    h = (root / "port" / "codec" / "generated" / "hstpf_frames.h").read_text()
    c = (root / "port" / "codec" / "generated" / "hstpf_frames.c").read_text()
    assert f'#define HSTPF_E2E_PROFILE "{profile}"' in h
    assert f"#define HSTPF_E2E_DEFAULT_MAX_DELTA {defaults[0]}u" in h
    assert f"#define HSTPF_E2E_DEFAULT_TIMEOUT_MS {defaults[1]}u" in h
    for name, (did, md, to) in frames.items():
        assert re.search(rf'0x{did:04X}u, 8u, \d+u, {md}u, {to}u, "{name}"', c), name


def test_c_codec_at_run_time(dbc, codec_dump):
    frames, defaults, profile = dbc
    out = json.loads(subprocess.run([codec_dump, "e2e"], capture_output=True, text=True, check=True).stdout)
    assert out["profile"] == profile
    assert (out["default"]["max_delta"], out["default"]["timeout_ms"]) == defaults
    assert {n: (v["data_id"], v["max_delta"], v["timeout_ms"]) for n, v in out["frames"].items()} == frames


def test_python_codec(dbc):
    frames, defaults, profile = dbc
    assert e2e.PROFILE == profile
    r = e2e.Receiver(0x1101)
    assert (r.max_delta, r.timeout_s) == (defaults[0], defaults[1] / 1000.0)
    c = FrameCodec()
    for name, (did, md, to) in frames.items():
        fid, data = c.encode(name, {})
        c.decode(fid, data, now=0.0)
        rx = c.receivers[fid]
        assert (rx.data_id, rx.max_delta, rx.timeout_s) == (did, md, to / 1000.0), name


def test_daemon_defaults(dbc, root):
    build = os.environ.get("HSTPF_BUILD_DIR", str(root / "build"))
    exe = Path(build) / "port" / "hstpfd"
    if not exe.is_file():
        pytest.skip("hstpfd not built (set HSTPF_BUILD_DIR)")
    frames = dbc[0]
    cfg = subprocess.run([str(exe), "--print-config"], capture_output=True, text=True, check=True).stdout
    val = dict(re.findall(r"^(\w+) = (\S+)", cfg, re.M))
    assert int(val["e2e_max_delta"]) == frames["Position"][1] == frames["Traction"][1]
    assert float(val["position_timeout_s"]) * 1000 == frames["Position"][2]
    assert float(val["traction_timeout_s"]) * 1000 == frames["Traction"][2]


def test_generators_follow_the_dbc(root, tmp_path):
    """Edit the attributes: the C generator and the Python codec take the
    new values; an unknown profile is refused."""
    text = (root / "port" / "dbc" / "hstpf.dbc").read_text()
    edited = text.replace('BA_ "HstpfE2EMaxDeltaCounter" BO_ 257 3;', 'BA_ "HstpfE2EMaxDeltaCounter" BO_ 257 5;')
    edited = edited.replace('BA_ "HstpfE2ETimeoutMs" BO_ 256 500;', 'BA_ "HstpfE2ETimeoutMs" BO_ 256 700;')
    assert edited != text
    dbc = tmp_path / "e.dbc"
    dbc.write_text(edited)
    gen = root / "port" / "codec" / "gen_frames.py"
    subprocess.run([sys.executable, str(gen), str(dbc), str(tmp_path)], check=True)
    c = (tmp_path / "hstpf_frames.c").read_text()
    assert '0x1101u, 8u, 100u, 3u, 700u, "Position"' in c and '0x1102u, 8u, 100u, 5u, 500u, "Traction"' in c
    py = FrameCodec(str(dbc))
    fid, data = py.encode("Traction", {})
    py.decode(fid, data)
    assert py.receivers[fid].max_delta == 5
    bad = tmp_path / "p.dbc"
    bad.write_text(text.replace('BA_ "HstpfE2EProfile" "P01";', 'BA_ "HstpfE2EProfile" "P02";'))
    r = subprocess.run([sys.executable, str(gen), str(bad), str(tmp_path)], capture_output=True, text=True)
    assert r.returncode != 0 and "HstpfE2EProfile" in r.stderr
    with pytest.raises(ValueError, match="HstpfE2EProfile"):
        FrameCodec(str(bad))
