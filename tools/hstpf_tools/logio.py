"""candump logs through python-can's readers and writers."""
import gzip
import io
import math
import sys
from pathlib import Path
from typing import Iterable, List

import can

from .frames import FIX_TIME_WRAP_MS, FrameCodec


def message(t: float, frame_id: int, data: bytes, channel: str = "vcan0") -> can.Message:
    # a plain float: python-can's CSV writer stores repr(timestamp), and a
    # numpy float's repr ("np.float64(...)") could not be read back
    return can.Message(timestamp=float(t), arbitration_id=frame_id, data=data, is_extended_id=False,
                       channel=channel, is_rx=False)


class CandumpLogWriter(can.CanutilsLogWriter):
    """python-can's candump -L writer, with each message's stamp as given.
    can.CanutilsLogWriter (4.6) writes a stamp earlier than the first
    message's as the first's (its docstring says the previous message's; it
    never updates last_timestamp): a log with a backward clock step could
    not be written, and hstpf-replay and hstpfd take a log in its order,
    backward steps included. A message without a stamp still gets the
    previous one (python-can's rule)."""

    def on_message_received(self, msg: can.Message) -> None:
        if msg.timestamp is not None:
            self.last_timestamp = msg.timestamp  # the floor python-can clamps to: this stamp itself
        super().on_message_received(msg)


def log_writer(path: str, channel: str = "vcan0"):
    """A python-can writer for path, its suffix picking the format as
    can.Logger does; candump -L (.log, .log.gz, and '-': text on stdout)
    through CandumpLogWriter, every stamp as given."""
    if str(path) == "-":
        from .cli import stdout

        return CandumpLogWriter(stdout(), channel=channel)
    name = str(path).lower()
    if name.endswith(".log"):
        return CandumpLogWriter(path, channel=channel)
    if name.endswith(".log.gz"):  # as can.Logger compresses a text format
        return CandumpLogWriter(gzip.open(path, "wt"), channel=channel)
    return can.Logger(path)


def write_log(path: str, msgs: Iterable[can.Message], channel: str = "vcan0") -> int:
    """Writes messages with log_writer(). Returns the count."""
    n = 0
    with log_writer(path, channel) as log:
        for m in msgs:
            log.on_message_received(m)
            n += 1
    return n


# the text formats read line by line when a line is bad: python-can's reader, header lines
_LINE_READERS = {".log": (can.CanutilsLogReader, 0), ".csv": (can.CSVReader, 1)}


def _read_lines(text: str, path: str, reader, header: int) -> List[can.Message]:
    """Each line of a text log through python-can's reader; a line it
    cannot read (a recording cut off mid-line, a comment) is left out with
    a warning that names it, as hstpfd counts it in bad_lines. ValueError
    when no line can be read."""
    lines = text.splitlines()
    out: List[can.Message] = []
    bad = []
    for n, line in enumerate(lines[header:], start=header + 1):
        if not line.strip():
            continue
        try:
            with reader(io.StringIO("\n".join(lines[:header] + [line]) + "\n")) as r:
                out.extend(r)
        except Exception as exc:  # python-can's readers raise many kinds on bad text
            bad.append(f"line {n} {line[:40]!r}: {exc}")
    if bad and not out:
        raise ValueError(f"not one line python-can can read; {bad[0]}")
    if bad:
        print(f"warning: {path}: {len(bad)} line(s) python-can cannot read were left out; the first: {bad[0]}",
              file=sys.stderr)
    return out


def read_log(path: str) -> List[can.Message]:
    """Every message of a log python-can reads (by suffix); '-' is candump
    -L text on stdin. In a candump or CSV text a line that cannot be read is
    left out with a warning."""
    suffix = ".log" if str(path) == "-" else Path(path).suffix.lower()
    if suffix not in _LINE_READERS:
        with can.LogReader(path) as r:
            return list(r)
    if str(path) == "-":
        from .cli import stdin

        text = stdin().read()
    else:
        with open(path, newline="") as f:
            text = f.read()
    reader, header = _LINE_READERS[suffix]
    try:
        with reader(io.StringIO(text)) as r:
            return list(r)
    except Exception:  # read again line by line, to leave out only what is bad
        return _read_lines(text, str(path), reader, header)


def fix_time_ms(t_s: float, wrap_ms: int = FIX_TIME_WRAP_MS) -> int:
    """Position.FixTime of a fix measured at t_s on the sender's clock:
    milliseconds modulo the wrap (8192 ms, docs/can.md)."""
    return int(math.floor(t_s * 1000.0 + 0.5)) % wrap_ms


def input_frames(codec: FrameCodec, t0: float, times, positions, forces_kn, channel: str = "vcan0",
                 pos_valid=None, trac_valid=None, fix_times=None, fix_time: bool = True) -> List[can.Message]:
    """Position and traction frames at the given times, E2E protected.
    At each time the position frame comes first: the traction frame at t
    carries the effort applied from t on, so a receiver that steps on the
    position at t still holds the previous interval's effort.
    Each valid position carries its fix time (Position.FixTime): fix_times[i]
    (s, the sender's clock; None for that row: no fix time), else t0 +
    times[i]; fix_time=False sends none (FixTimeValid 0, an older sender)."""
    out = []
    for i, (t, y, f) in enumerate(zip(times, positions, forces_kn)):
        pv = 1 if pos_valid is None else int(pos_valid[i])
        tv = 1 if trac_valid is None else int(trac_valid[i])
        tf = (fix_times[i] if fix_times is not None else t0 + t) if fix_time else None
        sig = {"PosValid": pv, "PosQuality": 0, "Position": y if pv else 0.0}
        if pv and tf is not None:
            sig.update(FixTimeValid=1, FixTime=fix_time_ms(tf))
        fid, d = codec.encode("Position", sig)
        out.append(message(t0 + t, fid, d, channel))
        fid, d = codec.encode("Traction", {"TractValid": tv, "TractForce": f if tv else 0.0})
        out.append(message(t0 + t, fid, d, channel))
    return out


def consist_frames(codec: FrameCodec, t0: float, duration_s: float, change_t=None, channel: str = "vcan0",
                   period_s: float = 1.0) -> List[can.Message]:
    """The train control's Consist frame every period_s over [0, duration_s],
    E2E protected: topology counter 1, then 2 from change_t (None: no
    change)."""
    out = []
    k = 0
    while k * period_s <= duration_s + 1e-9:
        t = k * period_s
        topo = 2 if change_t is not None and t >= change_t else 1
        fid, d = codec.encode("Consist", {"TopoValid": 1, "TopoCounter": topo})
        out.append(message(t0 + t, fid, d, channel))
        k += 1
    return out
