"""candump logs through python-can's readers and writers."""
import math
from typing import Iterable, List

import can

from .frames import FIX_TIME_WRAP_MS, FrameCodec


def message(t: float, frame_id: int, data: bytes, channel: str = "vcan0") -> can.Message:
    # a plain float: python-can's CSV writer stores repr(timestamp), and a
    # numpy float's repr ("np.float64(...)") could not be read back
    return can.Message(timestamp=float(t), arbitration_id=frame_id, data=data, is_extended_id=False,
                       channel=channel, is_rx=False)


def log_writer(path: str, channel: str = "vcan0"):
    """can.Logger for path (its suffix picks the format: .log is candump -L);
    '-' is candump -L text on stdout."""
    if str(path) == "-":
        from .cli import stdout

        return can.CanutilsLogWriter(stdout(), channel=channel)
    kw = {"channel": channel} if str(path).endswith(".log") else {}
    return can.Logger(path, **kw)


def write_log(path: str, msgs: Iterable[can.Message], channel: str = "vcan0") -> int:
    """Writes messages with log_writer(). Returns the count."""
    n = 0
    with log_writer(path, channel) as log:
        for m in msgs:
            log.on_message_received(m)
            n += 1
    return n


def read_log(path: str) -> List[can.Message]:
    """Every message of a log python-can reads (by suffix); '-' is candump
    -L text on stdin."""
    if str(path) == "-":
        from .cli import stdin

        with can.CanutilsLogReader(stdin()) as r:
            return list(r)
    with can.LogReader(path) as r:
        return list(r)


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
