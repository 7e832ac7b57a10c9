"""The tools on what a HIL bench's logs really hold: 29-bit, remote and CAN FD
frames beside ours, clock steps, files cut off mid-line, an output silence,
wall-clock stamps, a zero coefficient, a spreadsheet's CSV."""
import json

import can
import numpy as np
import pytest

from hstpf_tools import cli, encode, replay, score, simulate
from hstpf_tools.frames import FrameCodec
from hstpf_tools.logio import message, read_log, write_log
from hstpf_tools.replay import inject


def strict_json(text: str):
    def refuse(c):
        raise ValueError(f"not JSON: {c}")

    return json.loads(text, parse_constant=refuse)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """120 s simulated, and a scripted estimator's frames at 1 Hz: the
    position 1 m ahead of the truth, CRH3 declared from 60 s."""
    d = tmp_path_factory.mktemp("bench")
    assert simulate.main(["-o", str(d / "run.log"), "--duration", "120", "--seed", "3"]) == 0
    rows = np.genfromtxt(d / "run_truth.csv", delimiter=",", names=True, dtype=None, encoding=None)
    c = FrameCodec()
    msgs = []
    for t in range(0, 120):
        s = float(np.interp(t, rows["time_s"], rows["position_m"]))
        v = float(np.interp(t, rows["time_s"], rows["speed_mps"]))
        for name, sig in (("EstState", {"EstValid": 1, "EstPosition": s + 1.0, "EstSpeed": v}),
                          ("EstType", {"TypeStatus": int(t >= 60), "DeclaredType": 2 if t >= 60 else 255,
                                       "LeaderType": 2, "LeaderWeight": 0.99})):
            fid, data = c.encode(name, sig)
            msgs.append(message(float(t), fid, data))
    write_log(str(d / "est.log"), msgs)
    return d, msgs


def score_json(tmp_path, log, truth, *extra):
    js = tmp_path / "m.json"
    code = score.main([str(log), "--truth", str(truth), "--json", str(js), *extra])
    return code, (strict_json(js.read_text()) if js.exists() else None)


def test_29bit_remote_and_fd_frames_are_not_ours(run, tmp_path, capsys):
    """hstpfd takes a 29-bit frame with one of our ID numbers as someone
    else's, and a remote or FD one as a format error (port/src/frames.c);
    so must the score: before, a 29-bit frame with a valid E2E payload
    after each EstState moved the position RMS from 1 m to hundreds."""
    d, msgs = run
    code, base = score_json(tmp_path, d / "est.log", d / "run_truth.csv")
    assert code == 0 and base["position_rms_m"] == pytest.approx(1.0, abs=0.01)
    c = FrameCodec()
    state_id = c.message("EstState").frame_id
    mixed, n_ext = [], 0
    for m in msgs:
        mixed.append(m)
        if m.arbitration_id == state_id:
            _, data = c.encode("EstState", {"EstValid": 1, "EstPosition": 0.0, "EstSpeed": 0.0})
            mixed.append(can.Message(timestamp=m.timestamp + 0.001, arbitration_id=state_id, data=data,
                                     is_extended_id=True))
            mixed.append(can.Message(timestamp=m.timestamp + 0.002, arbitration_id=state_id, is_remote_frame=True,
                                     dlc=8, is_extended_id=False))
            mixed.append(can.Message(timestamp=m.timestamp + 0.003, arbitration_id=state_id, data=data + bytes(4),
                                     is_fd=True, is_extended_id=False))
            n_ext += 1
    log = tmp_path / "mixed.asc"  # a format that keeps the 29-bit, remote and FD flags
    write_log(str(log), mixed)
    code, res = score_json(tmp_path, log, d / "run_truth.csv")
    assert code == 0
    assert res["position_rms_m"] == pytest.approx(base["position_rms_m"], abs=1e-9)
    assert res["state_frames"] == base["state_frames"]
    assert res["ignored_29bit_frames"] == n_ext
    assert res["output_e2e"]["EstState"] == {**base["output_e2e"]["EstState"], "format": 2 * n_ext}


def test_an_output_silence_is_not_a_counter_jump(run, tmp_path):
    """The outputs' receivers time out as the DBC says (5 s): a 10 s silence
    of the estimator (a restart, a link outage) restarts them. With no
    timeout the first frame after it was a counter jump, and rejected."""
    d, msgs = run
    log = tmp_path / "gap.log"
    write_log(str(log), [m for m in msgs if not 60.0 <= m.timestamp < 70.0])
    code, res = score_json(tmp_path, log, d / "run_truth.csv")
    assert code == 0
    for name, counts in res["output_e2e"].items():
        assert set(counts) <= {"ok", "ok_initial"}, (name, counts)
    assert res["state_frames"] == 110


def test_a_file_cut_off_mid_line(run, tmp_path, capsys):
    """A recording stopped mid-write ends in half a line: the frames before
    it are scored, with a warning naming the line (hstpfd counts it in
    bad_lines); the whole file was refused before. The same for python-can's CSV."""
    d, msgs = run
    for suffix in (".log", ".csv"):
        full = tmp_path / f"full{suffix}"
        write_log(str(full), msgs)
        text = full.read_text()
        cut = tmp_path / f"cut{suffix}"
        last = text.rstrip("\n").rsplit("\n", 1)[1]
        cut.write_text(text[: len(text) - len(last) - 1 + 5])  # the last line keeps 5 characters
        code, res = score_json(tmp_path, cut, d / "run_truth.csv")
        err = capsys.readouterr().err
        assert code == 0, err
        assert "line" in err and str(cut) in err and "left out" in err
        assert res["frames"]["EstType"] + res["frames"]["EstState"] == len(msgs) - 1
    truth = tmp_path / "truth_cut.csv"
    text = (d / "run_truth.csv").read_text()
    truth.write_text(text[: len(text) // 2])  # cut inside a row
    assert score.main([str(d / "est.log"), "--truth", str(truth)]) == cli.EXIT_INPUT
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not a truth CSV" in err and "line" in err


def test_wall_clock_stamps_need_t0(run, tmp_path, capsys):
    """A live recording is stamped in epoch seconds: without --t0 nothing
    falls in the truth's span, which is said (exit 5) instead of scoring
    nothing and exiting 0."""
    d, msgs = run
    t0 = 1.7e9
    log = tmp_path / "epoch.log"
    write_log(str(log), [message(m.timestamp + t0, m.arbitration_id, bytes(m.data)) for m in msgs])
    assert score.main([str(log), "--truth", str(d / "run_truth.csv")]) == cli.EXIT_NO_TRAFFIC
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--t0" in err
    code, res = score_json(tmp_path, log, d / "run_truth.csv", "--t0", str(t0))
    assert code == 0 and res["position_rms_m"] == pytest.approx(1.0, abs=0.01)


def test_zero_true_coefficient_is_null_in_json(run, tmp_path):
    """A truth with c0 = 0 (the library accepts it) has an infinite relative
    error of c0: null in the JSON, which had 'Infinity' (not JSON)."""
    d, msgs = run
    c = FrameCodec()
    fid, data = c.encode("EstTheta", {"ThetaValid": 1, "C0": 0.79, "C1": 0.0064, "C2": 0.000115})
    log = tmp_path / "theta.log"
    write_log(str(log), msgs + [message(119.5, fid, data)])
    lines = (d / "run_truth.csv").read_text().splitlines()
    head = lines[0].split(",")
    k = head.index("c0")
    rows = [",".join("0" if i == k else x for i, x in enumerate(r.split(","))) for r in lines[1:]]
    truth = tmp_path / "zero_truth.csv"
    truth.write_text("\n".join([lines[0]] + rows) + "\n")
    code, res = score_json(tmp_path, log, truth)
    assert code == 0
    assert res["theta_rel_err"][0] is None and res["theta_rel_err"][1] == pytest.approx(0.0, abs=1e-3)
    assert res["w_rms_rel_err"] is None
    assert cli.dumps({"a": float("nan"), "b": [1.0, float("-inf")]}) == '{"a":null,"b":[1.0,null]}'


def stepped_log():
    """Two IDs at 10 Hz for 10 s, then the clock steps back 5 s and runs on."""
    msgs = []
    for k in range(200):
        t = 0.1 * k if k < 100 else 5.0 + 0.1 * (k - 100)
        msgs.append(message(t, 0x100, bytes([k % 256] * 8)))
        msgs.append(message(t, 0x101, bytes([k % 256] * 8)))
    return msgs


def test_replay_keeps_a_clock_step(tmp_path):
    """The log's order is kept: a step back of its clock stays one, where
    sorting by time interleaved the two stretches."""
    msgs = stepped_log()
    out, rep = inject(msgs, {}, {})
    assert [(m.timestamp, bytes(m.data)) for m in out] == [(m.timestamp, bytes(m.data)) for m in msgs]
    # a frame delayed 0.25 s goes after the frames that follow it within
    # 0.25 s, in its own stretch: 9.9 s is in both (k = 99 and k = 149)
    out, rep = inject(msgs, {}, {"delay": [(9.9, 9.95)]}, ids={0x100}, delay_s=0.25)
    assert rep["totals"] == {"delay": 2}
    seq = [(m.arbitration_id, m.data[0], round(m.timestamp, 2)) for m in out]
    i = seq.index((0x100, 99, 10.15))
    assert seq[i - 1:i + 2] == [(0x101, 99, 9.9), (0x100, 99, 10.15), (0x100, 100, 5.0)]
    i = seq.index((0x100, 149, 10.15))
    assert seq[i - 2:i + 2] == [(0x100, 151, 10.1), (0x101, 151, 10.1), (0x100, 149, 10.15), (0x100, 152, 10.2)]
    assert len(out) == len(msgs)
    o = tmp_path / "o.log"
    assert replay.main([str(write(tmp_path, msgs)), "--no-bus", "-o", str(o)]) == 0
    assert [m.timestamp for m in read_log(str(o))] == pytest.approx([m.timestamp for m in msgs])


def write(tmp_path, msgs, name="in.log"):
    p = tmp_path / name
    write_log(str(p), msgs)
    return p


def test_no_payload_no_corruption(tmp_path, capsys):
    """A remote frame or an empty one has no bit to flip or byte to cut: it
    goes out as it was (a remote frame crashed --corrupt with a
    ZeroDivisionError, and --truncate turned R8 into R0)."""
    msgs = [message(0.0, 0x100, bytes(8)), can.Message(timestamp=0.01, arbitration_id=0x123, is_remote_frame=True,
                                                       dlc=8, is_extended_id=False),
            message(0.02, 0x124, b"")]
    for kind in ("corrupt", "truncate"):
        out, rep = inject(msgs, {kind: 1.0}, {})
        assert rep["totals"] == {kind: 1}
        assert out[1].is_remote_frame and out[1].dlc == 8 and len(out[2].data) == 0
        assert replay.main([str(write(tmp_path, msgs)), "--no-bus", "-o", str(tmp_path / "o.log"), f"--{kind}",
                            "1"]) == 0
        capsys.readouterr()


@pytest.mark.parametrize("bad", ["-5", "0x800", "x"])
def test_unknown_id_must_be_11_bit(tmp_path, capsys, bad):
    assert replay.main([str(write(tmp_path, stepped_log())), "--no-bus", "-o", str(tmp_path / "o.log"),
                        "--unknown", "0.01", "--unknown-id", bad]) == cli.EXIT_USAGE
    assert "11-bit" in capsys.readouterr().err


def test_ids_tell_11_from_29_bit():
    """--ids 0x100 selects the 11-bit frame 0x100, not a 29-bit one of the
    same number; an ID above 0x7FF selects 29-bit frames."""
    std = message(0.0, 0x100, bytes(8))
    ext = can.Message(timestamp=0.0, arbitration_id=0x100, data=bytes(8), is_extended_id=True)
    big = can.Message(timestamp=0.0, arbitration_id=0x18FF0010, data=bytes(8), is_extended_id=True)
    assert cli.id_selected(std, {0x100}) and not cli.id_selected(ext, {0x100})
    assert cli.id_selected(big, {0x18FF0010}) and cli.id_selected(ext, None)
    out, rep = inject([std, ext, big], {"drop": 1.0}, {}, ids={0x100})
    assert rep["totals"] == {"drop": 1}
    assert [(m.arbitration_id, m.is_extended_id) for m in out] == [(0x100, True), (0x18FF0010, True)]
    assert cli.parse_ids("0x200, 0x18FF0010") == {0x200, 0x18FF0010}
    for bad in ("", "0x2000_0000", "-1", "zz"):
        with pytest.raises(Exception):
            cli.parse_ids(bad)


def test_a_spreadsheet_csv_with_a_bom(tmp_path):
    """Excel's "CSV UTF-8" begins with a byte-order mark: the first column
    is still time_s."""
    p = tmp_path / "bom.csv"
    p.write_bytes(b"\xef\xbb\xbftime_s,position_m,force_kn\r\n0,0,10\r\n0.1,0.5,10\r\n")
    assert encode.main([str(p), "-o", str(tmp_path / "x.log"), "--json", str(tmp_path / "r.json")]) == 0
    assert len(read_log(str(tmp_path / "x.log"))) == 4


def test_inserted_frames_keep_time_order():
    """Two IDs share each timestamp (as hstpf-simulate writes them): a
    duplicate 1 ms later and an unknown frame 0.5 ms later go after the
    frames of their own frame's time, not before them (times went back, and
    hstpfd counted time_backwards)."""
    msgs = [message(0.1 * (k // 2), 0x100 + k % 2, bytes(8)) for k in range(200)]
    for kind in ("duplicate", "unknown"):
        out, rep = inject(msgs, {}, {kind: [(1.0, 1.15)]}, ids={0x100})
        assert rep["totals"] == {kind: 2}
        t = [m.timestamp for m in out]
        assert all(b >= a for a, b in zip(t, t[1:])), kind
        assert len(out) == len(msgs) + 2
