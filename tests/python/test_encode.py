"""hstpf-encode: a user's CSV to frames and back."""
import json

import pytest

from hstpf_tools import encode
from hstpf_tools.frames import FrameCodec
from hstpf_tools.logio import read_log


def decode(path):
    c = FrameCodec()
    out = []
    for m in read_log(str(path)):
        name, sig, res = c.decode(m.arbitration_id, bytes(m.data), now=m.timestamp)
        out.append((m.timestamp, name, sig, res))
    return out


def test_round_trip_force_kn(tmp_path, capsys):
    csv = tmp_path / "train.csv"
    csv.write_text("time_s,position_m,force_kn\n0.0,0.0,120.5\n0.1,0.25,119.99\n0.2,,118.0\n0.3,0.9871,nan\n0.5,-1.5,-300.25\n")
    out = tmp_path / "enc.log"
    assert encode.main([str(csv), "-o", str(out), "--t0", "1000"]) == 0
    assert json.loads(capsys.readouterr().out)["frames"] == 10
    d = decode(out)
    assert [x[1] for x in d] == ["Position", "Traction"] * 5
    assert all(x[3] in ("ok", "ok_initial") for x in d)  # counters in sequence, CRC good
    pos = [(t, s["PosValid"], s["Position"]) for t, n, s, _ in d if n == "Position"]
    trac = [(t, s["TractValid"], s["TractForce"]) for t, n, s, _ in d if n == "Traction"]
    assert [p[0] for p in pos] == pytest.approx([1000.0, 1000.1, 1000.2, 1000.3, 1000.5])
    assert [p[1] for p in pos] == [1, 1, 0, 1, 1]  # an empty cell clears the valid bit
    assert [p[2] for p in pos] == pytest.approx([0.0, 0.25, 0.0, 0.99, -1.5], abs=0.0051)  # 1 cm
    # fix times: --t0 + time_s in ms modulo 8192 (1000.1 s = 1000100 ms = 122 x 8192 + 676), none when invalid
    fixes = [(s["FixTimeValid"], s["FixTime"]) for t, n, s, _ in d if n == "Position"]
    assert fixes == [(1, 1000000 % 8192), (1, 676), (0, 0), (1, 1000300 % 8192), (1, 1000500 % 8192)]
    assert [p[1] for p in trac] == [1, 1, 1, 0, 1]  # nan too
    assert [p[2] for p in trac] == pytest.approx([120.5, 119.99, 118.0, 0.0, -300.25], abs=0.0051)


def test_unit_force_needs_mass(tmp_path):
    csv = tmp_path / "u.csv"
    csv.write_text("time_s,position_m,traction_nkn\n0,0,20\n1,1,-10\n")
    assert encode.main([str(csv), "-o", str(tmp_path / "x.log")]) == 2
    assert encode.main([str(csv), "-o", str(tmp_path / "x.log"), "--mass-t", "400"]) == 0
    forces = [s["TractForce"] for _, n, s, _ in decode(tmp_path / "x.log") if n == "Traction"]
    assert forces == pytest.approx([20 * 400 * 9.81 / 1000, -10 * 400 * 9.81 / 1000], abs=0.0051)


def test_rows_slower_than_the_timeout_warned(tmp_path, capsys):
    """One frame per row: rows 1 s apart exceed the frames' 0.5 s E2E
    timeout (the DBC's), so hstpfd takes each frame as stale; the encoder
    says so (stderr, and the report's rows_beyond_timeout), and not for
    rows 0.1 s apart."""
    csv = tmp_path / "slow.csv"
    csv.write_text("time_s,position_m,force_kn\n" + "".join(f"{k},{10.0 * k},5\n" for k in range(6)))
    assert encode.main([str(csv), "-o", str(tmp_path / "s.log")]) == 0
    cap = capsys.readouterr()
    assert json.loads(cap.out)["rows_beyond_timeout"] == 5 and "E2E timeout (0.5 s" in cap.err
    csv.write_text("time_s,position_m,force_kn\n" + "".join(f"{k / 10},{k},5\n" for k in range(6)))
    assert encode.main([str(csv), "-o", str(tmp_path / "s.log")]) == 0
    cap = capsys.readouterr()
    assert "rows_beyond_timeout" not in json.loads(cap.out) and cap.err == ""


def test_bad_input(tmp_path):
    csv = tmp_path / "b.csv"
    csv.write_text("time_s,position_m,force_kn\n1,0,0\n0.5,0,0\n")
    assert encode.main([str(csv), "-o", str(tmp_path / "x.log")]) == 3  # time going back: input not valid
    csv.write_text("t,pos,f\n1,0,0\n")
    assert encode.main([str(csv), "-o", str(tmp_path / "x.log")]) == 3


def test_fix_time_column_and_none(tmp_path):
    """fix_time_s gives the measurement's own time (rows may be sent late);
    an empty cell or --no-fix-time sends the position without one."""
    csv = tmp_path / "f.csv"
    csv.write_text("time_s,position_m,force_kn,fix_time_s\n0.0,0,1,-0.05\n0.1,1,1,8.142\n0.2,2,1,\n")
    assert encode.main([str(csv), "-o", str(tmp_path / "f.log")]) == 0
    fixes = [(s["FixTimeValid"], s["FixTime"]) for _, n, s, _ in decode(tmp_path / "f.log") if n == "Position"]
    # -50 ms is 8142 modulo 8192, as is 8142 ms: the wrap is taken modulo, never clamped
    assert fixes == [(1, 8142), (1, 8142), (0, 0)]
    assert encode.main([str(csv), "-o", str(tmp_path / "n.log"), "--no-fix-time"]) == 0
    assert all(s["FixTimeValid"] == 0 for _, n, s, _ in decode(tmp_path / "n.log") if n == "Position")
