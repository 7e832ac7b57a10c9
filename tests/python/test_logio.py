"""hstpf_tools.logio's candump writer: python-can's format, each stamp as
given (a backward clock step is a log hstpfd and hstpf-replay take in log
order)."""
import io

import can
import pytest

from hstpf_tools import logio
from hstpf_tools.logio import message, read_log, write_log

STAMPS = [100.0, 100.1, 99.5, 40.25, 100.2, 1e9]  # back 0.6 s, back 1 minute, then on


def _msgs(stamps):
    return [message(t, 0x100 + i, bytes([i, 0xA5])) for i, t in enumerate(stamps)]


def test_python_can_writer_clamps():
    """Why logio has its own writer: python-can's CanutilsLogWriter (4.6)
    writes a stamp before the first message's as the first's. If this
    fails, python-can writes stamps as given and logio can use it as is."""
    f = io.StringIO()
    w = can.CanutilsLogWriter(f, channel="vcan0")
    for m in _msgs(STAMPS):
        w.on_message_received(m)
    stamps = [float(line.split()[0].strip("()")) for line in f.getvalue().splitlines()]
    assert stamps == [100.0, 100.1, 100.0, 100.0, 100.2, 1e9]


@pytest.mark.parametrize("suffix", [".log", ".log.gz"])
def test_backward_stamps_written_as_given(tmp_path, suffix):
    path = str(tmp_path / f"back{suffix}")
    assert write_log(path, _msgs(STAMPS)) == len(STAMPS)
    back = read_log(path)
    assert [m.timestamp for m in back] == STAMPS
    assert [(m.arbitration_id, bytes(m.data)) for m in back] == [(0x100 + i, bytes([i, 0xA5])) for i in range(6)]


def test_same_text_as_python_can_otherwise(tmp_path):
    """In time order the file is python-can's, line for line (candump -L:
    '(stamp) channel ID#DATA T')."""
    msgs = _msgs(sorted(STAMPS)) + [can.Message(timestamp=2e9, arbitration_id=0x1ABCDE, is_extended_id=True,
                                                data=b"\x01", channel="vcan1", is_rx=True)]
    ref = io.StringIO()
    w = can.CanutilsLogWriter(ref, channel="vcan0")
    for m in msgs:
        w.on_message_received(m)
    write_log(str(tmp_path / "a.log"), msgs)
    assert (tmp_path / "a.log").read_text() == ref.getvalue()
    assert ref.getvalue().splitlines()[1] == "(99.500000) vcan0 101#01A5 T"


def test_stdout_written_as_given(capsys):
    write_log("-", _msgs(STAMPS))
    assert [float(line.split()[0].strip("()")) for line in capsys.readouterr().out.splitlines()] == STAMPS
