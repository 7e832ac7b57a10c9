"""hstpf-replay: fault injection counts as an E2E receiver sees them,
reproducibility, and timing on python-can's virtual bus; hstpf-record."""
import json
import threading
import time

import can
import numpy as np
import pytest

from hstpf_tools import record, replay
from hstpf_tools.frames import FrameCodec
from hstpf_tools.logio import message, read_log, write_log
from hstpf_tools.replay import inject


@pytest.fixture(scope="module")
def clean_msgs():
    """120 s of position + traction frames at 10 Hz."""
    c = FrameCodec()
    out = []
    for k in range(1200):
        for name, v in (("Position", {"PosValid": 1, "Position": 50.0 * k * 0.1}), ("Traction", {"TractValid": 1, "TractForce": 80.0})):
            fid, d = c.encode(name, v)
            out.append(message(500.0 + k * 0.1, fid, d))
    return out


def receive(msgs):
    c = FrameCodec()
    unknown = 0
    for m in msgs:
        name, _, res = c.decode(m.arbitration_id, bytes(m.data), now=m.timestamp)
        unknown += res == "unknown_id"
    return {f"0x{k:03X}": rx.counts for k, rx in c.receivers.items()}, unknown


def test_clean_replay_has_no_faults(clean_msgs):
    out, rep = inject(clean_msgs, {}, {})
    assert len(out) == len(clean_msgs) and rep["injected"] == {}
    counts, _ = receive(out)
    assert counts["0x100"] == {"ok": 1200, "lost": 0, "wrong_length": 0, "bad_crc": 0, "repeated": 0, "jump": 0, "stale": 0}


@pytest.mark.parametrize("kind,field", [("corrupt", "bad_crc"), ("truncate", "wrong_length"),
                                        ("duplicate", "repeated"), ("drop", "lost"),
                                        ("delay", "jump"), ("reorder", "jump")])
def test_each_fault_is_seen_as_documented(clean_msgs, kind, field):
    out, rep = inject(clean_msgs, {kind: 0.02}, {}, seed=3)
    counts, _ = receive(out)
    for fid in ("0x100", "0x101"):
        n = rep["injected"][kind][fid]
        assert n > 5
        assert counts[fid][field] == n, (kind, fid, counts[fid])
        others = {k: v for k, v in counts[fid].items() if k not in (field, "ok", "lost")}
        assert all(v == 0 for v in others.values()), others
    if kind == "delay":  # a frame 2.5 cycles late: one jump, and the gaps it leaves
        assert counts["0x100"]["lost"] == 3 * rep["injected"]["delay"]["0x100"]


def test_windows_silence_and_unknown(clean_msgs):
    out, rep = inject(clean_msgs, {"unknown": 0.01}, {"corrupt": [(10.0, 12.0)]}, seed=9,
                      silence=[(30.0, 32.0), (60.0, 60.7)], ids={0x100})
    counts, unknown = receive(out)
    assert rep["injected"]["corrupt"] == {"0x100": 20}  # 10.0 .. 11.9 s
    assert counts["0x100"]["bad_crc"] == 20 and counts["0x101"]["bad_crc"] == 0
    assert rep["injected"]["silence"] == {"0x100": 27}  # 20 + 7 frames
    # both silences last > 0.5 s, and so do the 2 s of rejected frames: 3 stale episodes
    assert counts["0x100"]["stale"] == 3 and counts["0x101"]["stale"] == 0
    assert unknown == rep["totals"]["unknown"] > 0
    assert all(m.arbitration_id in (0x100, 0x101, 0x7F0) for m in out)


def test_random_silences_and_reproducibility(clean_msgs):
    a, ra = inject(clean_msgs, {"drop": 0.01, "corrupt": 0.01}, {}, seed=5, silence_rate=0.02, silence_len=1.5)
    b, rb = inject(clean_msgs, {"drop": 0.01, "corrupt": 0.01}, {}, seed=5, silence_rate=0.02, silence_len=1.5)
    c, rc = inject(clean_msgs, {"drop": 0.01, "corrupt": 0.01}, {}, seed=6, silence_rate=0.02, silence_len=1.5)
    assert ra == rb and [bytes(m.data) for m in a] == [bytes(m.data) for m in b]
    assert ra != rc
    counts, _ = receive(a)
    assert counts["0x100"]["stale"] == len(ra["silence_windows"]) > 0


def test_cli_to_log_and_report(clean_msgs, tmp_path, capsys):
    src, out, rep = tmp_path / "in.log", tmp_path / "out.log", tmp_path / "rep.json"
    write_log(str(src), clean_msgs)
    assert replay.main([str(src), "-o", str(out), "--duplicate-window", "5:6", "--ids", "0x101", "--report", str(rep)]) == 0
    assert capsys.readouterr().out == ""  # the report went to --report (--json) only
    printed = json.loads(rep.read_text())
    assert printed["injected"] == {"duplicate": {"0x101": 10}}
    assert len(read_log(str(out))) == len(clean_msgs) + 10
    assert replay.main([str(src), "--no-bus"]) == 2  # neither a bus nor an output
    assert replay.main([str(src), "-o", str(out), "--drop", "0.7", "--corrupt", "0.7"]) == 2


def test_replay_and_record_on_virtual_bus(clean_msgs, tmp_path, capsys):
    """3 s of log at 10x: about 0.3 s on the bus, all frames recorded in order."""
    src, rec = tmp_path / "in.log", tmp_path / "rec.log"
    msgs = [m for m in clean_msgs if m.timestamp < 503.0 - 1e-9]
    write_log(str(src), msgs)
    rx_bus = can.Bus(interface="virtual", channel="hstpf-test", receive_own_messages=False)
    result = {}
    th = threading.Thread(target=lambda: result.update(record.record(rx_bus, str(rec), quiet=0.5, first_timeout=10)))
    th.start()
    try:
        t = time.perf_counter()
        assert replay.main([str(src), "--interface", "virtual", "--channel", "hstpf-test", "--speed", "10",
                            "--corrupt-window", "1:1.5", "--ids", "0x100"]) == 0
        wall = time.perf_counter() - t
        th.join(10)
    finally:
        rx_bus.shutdown()
    rep = json.loads(capsys.readouterr().out)
    assert rep["sent"] == len(msgs) == 60 and rep["injected"]["corrupt"] == {"0x100": 5}
    assert 0.25 <= wall < 2.0
    assert result["stopped"] == "quiet" and result["frames"] == 60
    got = read_log(str(rec))
    assert [bytes(m.data) for m in got if m.arbitration_id == 0x101] == [bytes(m.data) for m in msgs if m.arbitration_id == 0x101]
    assert 0.2 <= got[-1].timestamp - got[0].timestamp < 1.5
    counts, _ = receive(got)
    assert counts["0x100"]["bad_crc"] == 5 and counts["0x101"]["bad_crc"] == 0


def test_record_cli_gives_up_without_frames(tmp_path, capsys):
    t = time.monotonic()
    assert record.main(["--interface", "virtual", "--channel", "hstpf-empty", "-o", str(tmp_path / "r.log"),
                        "--quiet", "0.1", "--first-timeout", "0.2"]) == 5  # no traffic
    assert 0.2 <= time.monotonic() - t < 5
    out = capsys.readouterr()
    assert json.loads(out.out)["stopped"] == "no_frames"
    assert out.err == "hstpf-record: no frame came within 0.2 s\n"
    assert (tmp_path / "r.log").read_text() == ""  # created and closed
    assert record.main(["--interface", "virtual", "-o", str(tmp_path / "r.log"), "--max-frames", "0"]) == 2


class _StallingBus:
    """A bus whose send stalls once, for `stall` s before frame `at`; records
    when each frame went out."""

    def __init__(self, at: int, stall: float):
        self.at, self.stall, self.sent = at, stall, []

    def send(self, msg, timeout=None):
        if len(self.sent) == self.at:
            time.sleep(self.stall)
        self.sent.append((time.perf_counter(), msg))


def test_send_all_catches_up_on_absolute_deadlines(clean_msgs):
    """The sender stalls 0.3 s at frame 20 of 6 s of log at 10x (0.6 s on
    the bus): the frames held back go out at once and in order, and the
    frames due after that keep their deadlines (absolute, from the start;
    a sender that waited the log's gaps after each frame would send every
    one of them 0.3 s late), and `behind` says how late the held-back
    frames went."""
    msgs = [m for m in clean_msgs if m.timestamp < 506.0 - 1e-9]
    bus = _StallingBus(20, 0.3)
    behind: dict = {}
    assert replay.send_all(bus, msgs, speed=10.0, behind=behind) == len(msgs) == 120
    assert [m for _, m in bus.sent] == msgs  # all, in order
    w0 = bus.sent[0][0]
    late = np.array([w - w0 - (m.timestamp - 500.0) / 10.0 for w, m in bus.sent])
    due = np.array([(m.timestamp - 500.0) / 10.0 for _, m in bus.sent])
    assert late[(due > 0.1) & (due < 0.35)].min() > 0.05  # held back by the stall (ends at 0.4 s)
    assert np.median(late[due > 0.5]) < 0.1  # on schedule again
    assert behind["over_0.1"] >= 10 and 0.2 <= behind["max"] < 0.6


def test_send_all_cuts_long_pauses(clean_msgs):
    """A frame stamped 1e6 s after the rest (a garbage line) went out after
    11.6 days; as python-can's MessageSync (skip=60) a pause longer than
    `skip` is cut to it: at 1000x the frame after a 1e6 s pause goes out
    about 60 / 1000 s after the one before, and the pause is reported."""
    msgs = [m for m in clean_msgs if m.timestamp < 501.0 - 1e-9]
    late = can.Message(timestamp=msgs[-1].timestamp + 1e6, arbitration_id=0x7F0, data=bytes(2))
    bus = _StallingBus(-1, 0.0)
    skipped: list = []
    t = time.perf_counter()
    assert replay.send_all(bus, msgs + [late], speed=1000.0, skipped=skipped) == len(msgs) + 1
    assert time.perf_counter() - t < 5.0
    assert 0.055 < bus.sent[-1][0] - bus.sent[-2][0] < 0.5
    assert len(skipped) == 1 and skipped[0][1] == pytest.approx(1e6)
    bus = _StallingBus(-1, 0.0)  # a pause within skip is kept
    assert replay.send_all(bus, msgs + [late], speed=1e6, skip=float("inf")) == len(msgs) + 1
    assert bus.sent[-1][0] - bus.sent[-2][0] > 0.9


def test_error_frames_not_sent_unless_asked(clean_msgs, tmp_path, capsys):
    """As python-can's player: a log's error frames stay off the bus unless
    --error-frames (hstpf-record keeps them in its logs)."""
    src = tmp_path / "err.log"
    msgs = [m for m in clean_msgs if m.timestamp < 500.5 - 1e-9]
    err = can.Message(timestamp=500.15, arbitration_id=0x20000080, is_extended_id=True, is_error_frame=True,
                      data=bytes(8), channel="vcan0")
    write_log(str(src), sorted(msgs + [err], key=lambda m: m.timestamp))
    for flag, expect_err in (([], 0), (["--error-frames"], 1)):
        rx_bus = can.Bus(interface="virtual", channel="hstpf-err", receive_own_messages=False)
        try:
            assert replay.main([str(src), "--interface", "virtual", "--channel", "hstpf-err", "--fast"] + flag) == 0
            got = []
            while (m := rx_bus.recv(0.2)) is not None:
                got.append(m)
        finally:
            rx_bus.shutdown()
        rep = json.loads(capsys.readouterr().out)
        assert sum(m.is_error_frame for m in got) == expect_err
        assert len(got) == len(msgs) + expect_err
        assert rep.get("error_frames_skipped", 0) == 1 - expect_err


def test_unknown_frames_keep_the_channel(clean_msgs):
    msgs = [message(m.timestamp, m.arbitration_id, bytes(m.data), channel="can1") for m in clean_msgs[:200]]
    out, rep = inject(msgs, {"unknown": 0.2}, {}, seed=3)
    assert rep["totals"]["unknown"] > 0
    assert {m.channel for m in out} == {"can1"}


def test_csv_and_unsupported_suffix(clean_msgs, tmp_path, capsys):
    """A .csv written from numpy times reads back (its repr was np.float64(...));
    a suffix whose package is missing is one line and exit 6, not a traceback."""
    src = tmp_path / "in.csv"
    write_log(str(src), [message(np.float64(m.timestamp), m.arbitration_id, bytes(m.data)) for m in clean_msgs[:20]])
    back = read_log(str(src))
    assert [m.timestamp for m in back] == pytest.approx([m.timestamp for m in clean_msgs[:20]])
    try:
        import asammdf  # noqa: F401
    except ImportError:
        assert replay.main([str(src), "--no-bus", "-o", str(tmp_path / "x.mf4")]) == 6
        assert "x.mf4" in capsys.readouterr().err
