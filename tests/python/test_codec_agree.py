"""The C codec (cantools-generated pack/unpack + hstpf_e2e.c) and the
Python side (cantools + hstpf_tools.e2e) agree byte for byte."""
import json
import subprocess

import cantools
import pytest

from hstpf_tools import e2e
from hstpf_tools.frames import FrameCodec, data_id, load_db
from hstpf_tools.logio import read_log, write_log
from hstpf_tools.replay import inject


def _run(exe, *args, stdin=None):
    r = subprocess.run([exe, *args], input=stdin, capture_output=True, text=True, check=True)
    return [json.loads(line) for line in r.stdout.splitlines() if line.strip()]


@pytest.fixture(scope="module")
def c_frames(codec_dump):
    return _run(codec_dump)


def test_c_encoding_equals_cantools(c_frames):
    db = load_db()
    counters = {}
    assert len(c_frames) >= 40
    for fr in c_frames:
        msg = db.get_message_by_name(fr["msg"])
        assert fr["id"] == msg.frame_id
        k = counters.get(fr["msg"], 0)
        counters[fr["msg"]] = k + 1
        # cantools packs the same physical values, then Python's E2E protects
        packed = msg.encode({**fr["in"], "E2eCrc": 0, "E2eCounter": 0}, scaling=True, strict=True)
        want = e2e.protect(data_id(msg), packed, k % 15)
        assert bytes.fromhex(fr["bytes"]) == want, fr


def test_cantools_decodes_c_bytes(c_frames):
    db = load_db()
    for fr in c_frames:
        msg = db.get_message_by_name(fr["msg"])
        dec = msg.decode(bytes.fromhex(fr["bytes"]), decode_choices=False)
        assert set(dec) == set(fr["out"])
        for k, v in fr["out"].items():
            assert dec[k] == pytest.approx(v, rel=1e-12, abs=1e-12), (fr["msg"], k)
        # and the decoded values are the inputs within half a resolution step
        for k, v in fr["in"].items():
            assert dec[k] == pytest.approx(v, abs=msg.get_signal_by_name(k).scale / 2 + 1e-9), (fr["msg"], k)
        e = bytes.fromhex(fr["bytes"])
        assert dec["E2eCrc"] == e2e.frame_crc(data_id(msg), e)


def test_c_decodes_python_frames(codec_dump, tmp_path):
    """The other way round: frames made by FrameCodec (cantools + Python
    E2E), read by the C codec from a candump log."""
    codec = FrameCodec()
    values = [
        ("Position", {"PosValid": 1, "PosQuality": 2, "Position": -1.234}),
        ("Traction", {"TractValid": 1, "TractForce": -4321.09}),
        ("Consist", {"TopoValid": 1, "TopoCounter": 4294967295}),
        ("EstState", {"EstValid": 1, "EstPosition": 123456.78, "EstSpeed": 88.88}),
        ("EstType", {"TypeStatus": 1, "FitStatus": 1, "DeclaredType": 2, "DeclaredWeight": 0.9876, "LeaderType": 2,
                     "LeaderWeight": 0.9876}),
        ("EstBand", {"BandValid": 1, "BandFault": 0, "WSd0": 0.25, "WSd1": 0.35, "WSd2": 1.2, "WSd3": 2.6, "WSd4": 4.3,
                     "OffWhat": 2}),
        ("EstTheta", {"ThetaValid": 1, "C0": 0.79, "C1": 0.0064, "C2": 0.000115}),
        ("HealthRx", {"PosStale": 1, "TractImplausible": 1, "BadCrc": 12, "CounterRepeat": 3, "CounterJump": 4095, "WrongLength": 7}),
        ("HealthSys", {"StaleEvents": 2, "UnknownId": 5, "ErrorFrames": 1, "Degeneracy": 9}),
        ("EstQuality", {"QualValid": 1, "Standstill": 1, "EstTimeValid": 1, "PositionSd": 3.21, "SpeedSd": 0.17,
                        "EstTime": 4321}),
        ("HealthTime", {"ClockStepsFwd": 1, "ClockStepsBack": 2, "LatePositions": 3, "Reacquisitions": 4,
                        "Acquisitions": 5}),
    ]
    from hstpf_tools.logio import message
    msgs = []
    for i in range(3):
        for name, v in values:
            fid, d = codec.encode(name, v)
            msgs.append(message(i * 0.1, fid, d))
    log = tmp_path / "py.log"
    write_log(str(log), msgs)
    out = _run(codec_dump, "decode", stdin=log.read_text())
    frames, counts = out[:-1], out[-1]["counts"]
    assert len(frames) == len(msgs)
    for fr, m in zip(frames, msgs):
        name, dec, res = FrameCodec().decode(m.arbitration_id, bytes(m.data), check=False)
        assert fr["msg"] == name
        assert fr["e2e"] in ("ok", "ok_initial")
        for k, v in fr["out"].items():
            assert dec[k] == pytest.approx(v, rel=1e-12, abs=1e-12), (name, k)
    assert all(c["ok"] == 3 and c["bad_crc"] == 0 for c in counts.values())


def test_c_and_python_receivers_count_alike(codec_dump, tmp_path, root):
    """A log with every kind of fault: the C and the Python receivers end
    with the same counts for every frame ID."""
    codec = FrameCodec()
    from hstpf_tools.logio import message
    msgs = []
    for k in range(3000):  # 300 s of position + traction at 10 Hz
        for name, v in (("Position", {"PosValid": 1, "Position": 27.7 * k * 0.1}), ("Traction", {"TractValid": 1, "TractForce": 50.0})):
            fid, d = codec.encode(name, v)
            msgs.append(message(k * 0.1, fid, d))
    faulted, rep = inject(msgs, {"drop": 0.02, "corrupt": 0.02, "truncate": 0.01, "duplicate": 0.02, "delay": 0.01,
                                 "reorder": 0.01, "unknown": 0.01}, {}, seed=7, silence=[(100.0, 101.5)])
    log = tmp_path / "faulted.log"
    write_log(str(log), faulted)
    c_counts = _run(codec_dump, "decode", stdin=log.read_text())[-1]["counts"]
    py = FrameCodec()
    for m in read_log(str(log)):
        py.decode(m.arbitration_id, bytes(m.data), now=m.timestamp)
    for fid, rx in py.receivers.items():
        assert c_counts[f"0x{fid:03X}"] == rx.counts
    assert rep["totals"]["corrupt"] > 50 and c_counts["0x100"]["stale"] == 1
