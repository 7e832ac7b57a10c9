"""The hstpf frames, from the one DBC (port/dbc/hstpf.dbc), with E2E.

FrameCodec.encode() clamps physical values to the DBC ranges (as the C
codec's hstpf_frames_*_raw() do), packs with cantools and protects with the
per-frame sender; FrameCodec.decode() checks E2E and unpacks.
"""
import os
from functools import lru_cache
from pathlib import Path
from typing import Dict, Optional, Tuple

import cantools

from . import e2e
from .table1 import TABLE1  # Table 1 from lib/src/train_types.c; its index is DeclaredType/LeaderType

TYPE_CUSTOM = 254
TYPE_NONE = 255

POSITION, TRACTION = "Position", "Traction"
EST_STATE, EST_QUALITY, EST_TYPE, EST_THETA = "EstState", "EstQuality", "EstType", "EstTheta"
EST_BAND = "EstBand"
#: the speeds of EstBand's WSd0..WSd4, km/h (the DBC's comment of frame 530; port/src/frames.h)
BAND_SPEEDS_KMH = (0.0, 87.5, 175.0, 262.5, 350.0)
#: FitStatus values (hstpf_fit_t)
FIT_NAMES = ("unknown", "table", "none", "reserved")  # as hstpfd's stream and summary write them
HEALTH_RX, HEALTH_SYS, HEALTH_TIME = "HealthRx", "HealthSys", "HealthTime"
#: TypeStatus values (hstpf_status_t)
STATUS_NAMES = ("undecided", "declared", "changed", "withdrawn")
E2E_SIGNALS = ("E2eCrc", "E2eCounter")


def is_hstpf_frame(msg) -> bool:
    """msg can be one of hstpf's frames: a classic data frame with an 11-bit
    ID. hstpfd takes nothing else (port/src/frames.c): a 29-bit, remote,
    CAN FD or error frame with the same ID number is someone else's."""
    return not (msg.is_extended_id or msg.is_remote_frame or getattr(msg, "is_fd", False) or msg.is_error_frame)


def type_index(name: str) -> int:
    """Table 1 index of a type name: exact, case-insensitive, or one part of
    a slash-separated row ("SS4" -> "SS1/SS3/SS4"). KeyError if none."""
    names = [r[0] for r in TABLE1]
    if name in names:
        return names.index(name)
    low = [n.lower() for n in names]
    if name.lower() in low:
        return low.index(name.lower())
    for i, n in enumerate(low):
        if name.lower() in n.split("/"):
            return i
    raise KeyError(f"unknown train type {name!r}; Table 1 has: {', '.join(names)}")


def type_name(index: int) -> str:
    if 0 <= index < len(TABLE1):
        return TABLE1[index][0]
    return {TYPE_CUSTOM: "custom", TYPE_NONE: "none"}.get(index, f"#{index}")


def dbc_path(path: Optional[str] = None) -> Path:
    """The DBC: `path`, else $HSTPF_DBC, else port/dbc/hstpf.dbc of the
    source tree this package lives in (an editable install)."""
    for p in (path, os.environ.get("HSTPF_DBC")):
        if p:
            return Path(p)
    p = Path(__file__).resolve().parents[2] / "port" / "dbc" / "hstpf.dbc"
    if not p.exists():
        raise FileNotFoundError(f"hstpf.dbc not found at {p}: pass --dbc or set HSTPF_DBC")
    return p


@lru_cache(maxsize=8)
def _load(path: str):
    return cantools.database.load_file(path)


def load_db(path: Optional[str] = None):
    return _load(str(dbc_path(path)))


def _fix_time_wrap() -> int:
    try:
        sig = load_db().get_message_by_name("Position").get_signal_by_name("FixTime")
    except FileNotFoundError:  # no source tree: the DBC's value (docs/can.md)
        return 8192
    return 1 << sig.length


#: Position.FixTime wraps at this many ms (from the DBC's signal width).
FIX_TIME_WRAP_MS = _fix_time_wrap()


def data_id(msg) -> int:
    return int(msg.dbc.attributes["HstpfE2EDataId"].value)


def _attr(db, msg, name):
    """A message (or, msg None, network) attribute, else its BA_DEF_DEF_ default."""
    a = (msg.dbc.attributes if msg is not None else db.dbc.attributes).get(name)
    return a.value if a is not None else db.dbc.attribute_definitions[name].default_value


def e2e_params(msg, db=None) -> Tuple[int, float]:
    """(max delta counter, timeout s) of a frame's E2E receiver, from the DBC
    (HstpfE2EMaxDeltaCounter, HstpfE2ETimeoutMs), as the C table has them."""
    db = db or load_db()
    return int(_attr(db, msg, "HstpfE2EMaxDeltaCounter")), int(_attr(db, msg, "HstpfE2ETimeoutMs")) / 1000.0


def e2e_defaults(dbc: Optional[str] = None) -> Tuple[int, float]:
    """The DBC's default receiver parameters (max delta, timeout s)."""
    return e2e_params(None, load_db(dbc))


def check_profile(db) -> None:
    p = _attr(db, None, "HstpfE2EProfile")
    if p != e2e.PROFILE:
        raise ValueError(f"DBC HstpfE2EProfile {p!r}: only {e2e.PROFILE} is implemented")


class FrameCodec:
    """Encoder/decoder of all hstpf frames with per-frame E2E state."""

    def __init__(self, dbc: Optional[str] = None, max_delta: Optional[int] = None, timeout_s: Optional[float] = None):
        """max_delta, timeout_s: every receiver's, else each frame's from the DBC."""
        self.db = load_db(dbc)
        check_profile(self.db)
        self.senders: Dict[int, e2e.Sender] = {}
        self.receivers: Dict[int, e2e.Receiver] = {}
        self.max_delta, self.timeout_s = max_delta, timeout_s

    def message(self, name_or_id):
        if isinstance(name_or_id, str):
            return self.db.get_message_by_name(name_or_id)
        return self.db.get_message_by_frame_id(name_or_id)

    def message_name(self, frame_id: int) -> Optional[str]:
        """The name of the frame with this ID, None if the DBC has none."""
        try:
            return self.message(frame_id).name
        except KeyError:
            return None

    def clamp(self, msg, values: Dict[str, float]) -> Dict[str, float]:
        """All signals of msg (missing ones 0), clamped to the DBC ranges."""
        out = {}
        for s in msg.signals:
            v = float(values.get(s.name, 0))
            if v != v:  # NaN, as the C codec
                v = 0.0
            if s.minimum is not None:
                v = max(v, s.minimum)
            if s.maximum is not None:
                v = min(v, s.maximum)
            out[s.name] = v
        return out

    def pack(self, name: str, values: Dict[str, float]) -> bytes:
        """Packed frame without E2E (CRC and counter as given, else 0)."""
        msg = self.message(name)
        return bytes(msg.encode(self.clamp(msg, values), scaling=True, strict=True))

    def encode(self, name: str, values: Dict[str, float]) -> Tuple[int, bytes]:
        """(arbitration ID, protected payload); advances the frame's counter."""
        msg = self.message(name)
        payload = self.pack(name, {k: v for k, v in values.items() if k not in E2E_SIGNALS})
        snd = self.senders.setdefault(msg.frame_id, e2e.Sender(data_id(msg)))
        return msg.frame_id, snd.protect(payload)

    def decode(self, frame_id: int, data: bytes, now: float = 0.0, check: bool = True):
        """(name, signals, e2e result) or (None, None, "unknown_id").
        Signals are None when the E2E check rejected the frame."""
        try:
            msg = self.message(frame_id)
        except KeyError:
            return None, None, "unknown_id"
        result = e2e.OK
        if check:
            rx = self.receivers.get(frame_id)
            if rx is None:
                md, to = e2e_params(msg, self.db)
                md = md if self.max_delta is None else self.max_delta
                to = to if self.timeout_s is None else self.timeout_s
                rx = self.receivers[frame_id] = e2e.Receiver(data_id(msg), msg.length, md, to)
            result = rx.check(bytes(data), now)
            if result not in e2e.ACCEPTED:
                return msg.name, None, result
        elif len(data) != msg.length:
            return msg.name, None, e2e.WRONG_LENGTH
        return msg.name, msg.decode(bytes(data), decode_choices=False, scaling=True), result
