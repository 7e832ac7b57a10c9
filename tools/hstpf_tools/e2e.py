"""E2E protection of hstpf frames, AUTOSAR Profile 1 style.

The same scheme as port/codec/hstpf_e2e.[ch] (docs/can.md): byte 0 is a
CRC-8 (SAE J1850 polynomial 0x1D, initial value 0x00, no final XOR) over
the data ID's low byte, its high byte and frame bytes 1..7; the low nibble
of byte 1 is an alive counter 0..14. Receiver rules as in hstpf_e2e.h.
"""
from dataclasses import dataclass, field
from typing import Dict, Optional

COUNTER_MAX = 14
COUNTER_CYCLE = COUNTER_MAX + 1

OK = "ok"
OK_INITIAL = "ok_initial"
OK_LOST = "ok_lost"
WRONG_LENGTH = "wrong_length"
BAD_CRC = "bad_crc"
REPEATED = "repeated"
COUNTER_JUMP = "counter_jump"
STALE = "stale"
NO_DATA = "no_data"
ACCEPTED = (OK, OK_INITIAL, OK_LOST)


def _table():
    t = []
    for b in range(256):
        r = b
        for _ in range(8):
            r = ((r << 1) ^ 0x1D) & 0xFF if r & 0x80 else (r << 1) & 0xFF
        t.append(r)
    return bytes(t)


_T = _table()


def crc8(data: bytes, crc: int = 0x00) -> int:
    """CRC-8 SAE J1850 register update, no initial/final XOR applied."""
    for b in data:
        crc = _T[crc ^ b]
    return crc


def frame_crc(data_id: int, frame: bytes) -> int:
    """Profile 1 CRC of a frame: data ID low, data ID high, frame[1:]."""
    return crc8(bytes(frame[1:]), crc8(bytes((data_id & 0xFF, (data_id >> 8) & 0xFF))))


def protect(data_id: int, frame: bytes, counter: int) -> bytes:
    """Returns frame with `counter` in byte 1's low nibble and the CRC in byte 0."""
    f = bytearray(frame)
    f[1] = (f[1] & 0xF0) | (counter % COUNTER_CYCLE)
    f[0] = frame_crc(data_id, f)
    return bytes(f)


class Sender:
    """Per-frame sender state: the first frame carries counter 0."""

    def __init__(self, data_id: int):
        self.data_id = data_id
        self.counter = 0

    def protect(self, frame: bytes) -> bytes:
        out = protect(self.data_id, frame, self.counter)
        self.counter = (self.counter + 1) % COUNTER_CYCLE
        return out


PROFILE = "P01"  # the profile implemented here and in hstpf_e2e.c (DBC attribute HstpfE2EProfile)


@dataclass
class Receiver:
    """Receiver of one stream; mirrors hstpf_e2e_rx_t (times in seconds).
    max_delta and timeout_s default to the DBC's defaults (BA_DEF_DEF_ of
    HstpfE2EMaxDeltaCounter and HstpfE2ETimeoutMs), as
    hstpf_e2e_rx_config_default() in C; FrameCodec passes each frame's own."""

    data_id: int
    length: int = 8
    max_delta: Optional[int] = None
    timeout_s: Optional[float] = None
    counts: Dict[str, int] = field(
        default_factory=lambda: {k: 0 for k in ("ok", "lost", "wrong_length", "bad_crc", "repeated", "jump", "stale")}
    )
    _last_counter: Optional[int] = None
    _last_ok: Optional[float] = None
    stale: bool = False

    def __post_init__(self):
        if self.max_delta is None or self.timeout_s is None:
            from .frames import e2e_defaults  # late: frames imports this module

            md, to = e2e_defaults()
            self.max_delta = md if self.max_delta is None else self.max_delta
            self.timeout_s = to if self.timeout_s is None else self.timeout_s

    def _update_stale(self, now: float) -> None:
        if self._last_ok is not None and not self.stale and now - self._last_ok > self.timeout_s:
            self.stale = True
            self.counts["stale"] += 1

    def _accept(self, counter: int, now: float, result: str) -> str:
        self._last_counter, self._last_ok, self.stale = counter, now, False
        self.counts["ok"] += 1
        return result

    def check(self, frame: bytes, now: float) -> str:
        self._update_stale(now)
        if len(frame) != self.length:
            self.counts["wrong_length"] += 1
            return WRONG_LENGTH
        if frame[0] != frame_crc(self.data_id, frame):
            self.counts["bad_crc"] += 1
            return BAD_CRC
        counter = frame[1] & 0x0F
        if counter > COUNTER_MAX:
            self.counts["jump"] += 1
            return COUNTER_JUMP
        if self._last_counter is None or self.stale:
            return self._accept(counter, now, OK_INITIAL)
        delta = (counter - self._last_counter) % COUNTER_CYCLE
        if delta == 0:
            self.counts["repeated"] += 1
            return REPEATED
        if delta > self.max_delta:
            self.counts["jump"] += 1
            self._last_counter = counter  # resync
            return COUNTER_JUMP
        if delta == 1:
            return self._accept(counter, now, OK)
        self.counts["lost"] += delta - 1
        return self._accept(counter, now, OK_LOST)

    def poll(self, now: float) -> str:
        if self._last_ok is None:
            self._last_ok = now
            return NO_DATA
        self._update_stale(now)
        if self.stale:
            return STALE
        return OK if self._last_counter is not None else NO_DATA
