"""hstpf-replay: a candump log onto a CAN interface, with fault injection.

Faults are drawn per frame from the tool's own numpy Generator (--seed), so
the same log, options and seed give the same faults. A frame gets at most
one fault. What each does and what an E2E receiver (max_delta 3, 100 ms
cycle) sees:
  drop       frame not sent                  counter gap (frames lost)
  corrupt    one random bit flipped          bad CRC
  truncate   sent with one byte less         wrong length
  duplicate  sent twice, 1 ms apart          repeated counter
  delay      sent --delay-s later            counter jump (one, if the delay
                                             is under max_delta cycles)
  reorder    payload swapped with the next   counter jump (one)
             frame of the same ID
  unknown    an extra frame with --unknown-id after this one: unknown ID
  silence    no frame of the selected IDs in a window: stale (one per ID)
"""
import argparse
import copy
import json
import sys
import time
from collections import defaultdict
from typing import Dict, List, Optional, Sequence, Tuple

import can
import numpy as np

from .logio import read_log, write_log

KINDS = ("drop", "corrupt", "truncate", "duplicate", "delay", "reorder", "unknown")


def _window(spec: str) -> Tuple[float, float]:
    a, _, b = spec.partition(":")
    w = (float(a), float(b))
    if w[1] <= w[0]:
        raise argparse.ArgumentTypeError(f"window {spec!r}: END must be after START")
    return w


def _ids(spec: str):
    return {int(x, 0) for x in spec.split(",") if x.strip()}


def _copy(m: can.Message, t: Optional[float] = None, data: Optional[bytes] = None) -> can.Message:
    n = copy.copy(m)
    n.timestamp = m.timestamp if t is None else t
    if data is not None:
        n.data = bytearray(data)
        n.dlc = len(data)
    n.is_rx = False
    return n


def inject(
    msgs: Sequence[can.Message],
    rates: Dict[str, float],
    windows: Dict[str, List[Tuple[float, float]]],
    seed: int = 1,
    ids: Optional[set] = None,
    silence: Sequence[Tuple[float, float]] = (),
    silence_rate: float = 0.0,
    silence_len: float = 2.0,
    delay_s: float = 0.25,
    unknown_id: int = 0x7F0,
):
    """Returns (faulted messages sorted by time, report dict). Window times
    are seconds from the first frame of the log."""
    rng = np.random.default_rng(seed)
    out: List[Tuple[float, int, can.Message]] = []  # (time, order, msg)
    if not msgs:
        return [], {"frames_in": 0, "frames_out": 0, "injected": {}, "seed": seed}
    t_start = msgs[0].timestamp
    t_end = msgs[-1].timestamp - t_start
    sil = list(silence)
    if silence_rate > 0:
        t = rng.exponential(1.0 / silence_rate)
        while t < t_end:
            sil.append((t, t + silence_len))
            t += silence_len + rng.exponential(1.0 / silence_rate)
    counts: Dict[str, Dict[str, int]] = defaultdict(lambda: defaultdict(int))
    pending_swap: Dict[int, int] = {}  # arbitration id -> index of the frame waiting for its swap
    msgs = [_copy(m) for m in msgs]
    skip = set()
    order = 0
    for i, m in enumerate(msgs):
        r = m.timestamp - t_start
        key = f"0x{m.arbitration_id:03X}"
        eligible = (ids is None or m.arbitration_id in ids) and not m.is_error_frame
        u = rng.random()  # drawn for every frame: faults do not shift later draws
        bit = int(rng.integers(0, 64))
        if not eligible:
            out.append((m.timestamp, order, m))
            order += 1
            continue
        if any(a <= r < b for a, b in sil):
            counts["silence"][key] += 1
            continue
        if i in skip:
            out.append((m.timestamp, order, m))
            order += 1
            continue
        kind = next((k for k in KINDS if any(a <= r < b for a, b in windows.get(k, ()))), None)
        if kind is None:
            acc = 0.0
            for k in KINDS:
                acc += rates.get(k, 0.0)
                if u < acc:
                    kind = k
                    break
        if kind == "reorder":
            j = next((j for j in range(i + 1, len(msgs)) if msgs[j].arbitration_id == m.arbitration_id), None)
            if j is None:
                kind = None
            else:
                msgs[i].data, msgs[j].data = msgs[j].data, msgs[i].data
                skip.add(j)
        if kind is not None:
            counts[kind][key] += 1
        if kind == "drop":
            continue
        if kind == "corrupt":
            d = bytearray(m.data)
            d[(bit // 8) % len(d)] ^= 1 << (bit % 8)
            m = _copy(m, data=bytes(d))
        elif kind == "truncate":
            m = _copy(m, data=bytes(m.data[:-1]))
        elif kind == "delay":
            m = _copy(m, t=m.timestamp + delay_s)
        out.append((m.timestamp, order, m))
        order += 1
        if kind == "duplicate":
            out.append((m.timestamp + 0.001, order, _copy(m, t=m.timestamp + 0.001)))
            order += 1
        elif kind == "unknown":
            x = can.Message(timestamp=m.timestamp + 0.0005, arbitration_id=unknown_id, data=bytes(8),
                            is_extended_id=False, is_rx=False)
            out.append((x.timestamp, order, x))
            order += 1
    out.sort(key=lambda e: (e[0], e[1]))
    report = {
        "frames_in": len(msgs),
        "frames_out": len(out),
        "seed": seed,
        "injected": {k: dict(v) for k, v in counts.items()},
        "totals": {k: sum(v.values()) for k, v in counts.items()},
        "silence_windows": [[round(a, 6), round(b, 6)] for a, b in sorted(sil)],
    }
    return [e[2] for e in out], report


def send_all(bus: can.BusABC, msgs: Sequence[can.Message], speed: float = 1.0, fast: bool = False) -> int:
    """Sends with python-can's MessageSync timing, timestamps scaled by
    1/speed (fast: no timing, back to back). Retries when the interface
    queue is full."""
    if not msgs:
        return 0
    t0 = msgs[0].timestamp
    scaled = [_copy(m, t=t0 + (m.timestamp - t0) / speed) for m in msgs]
    sync = can.MessageSync(scaled, timestamps=not fast, gap=0.0, skip=0)
    n = 0
    for m in sync:
        for attempt in range(200):
            try:
                bus.send(m, timeout=0.1)
                break
            except can.CanOperationError:
                if attempt == 199:
                    raise
                time.sleep(0.001)  # ENOBUFS: the tx queue drains in microseconds on vcan
        n += 1
    return n


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="hstpf-replay",
        description="Replay a candump log onto a CAN interface (python-can) at real time or sped up, "
        "with reproducible fault injection. Prints a JSON report of what was injected.",
        epilog=__doc__.split("\n", 2)[2],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("log", help="candump log (or any format python-can reads)")
    p.add_argument("-c", "--channel", "--iface", dest="channel", help="interface channel, e.g. vcan0")
    p.add_argument("--interface", default="socketcan", help="python-can interface (socketcan; virtual in tests)")
    p.add_argument("--speed", type=float, default=1.0, help="speed-up factor (1 = real time)")
    p.add_argument("--fast", action="store_true", help="no timing: send back to back")
    p.add_argument("-o", "--out", help="also write the faulted stream to this log")
    p.add_argument("--seed", type=int, default=1, help="fault RNG seed (1)")
    p.add_argument("--ids", type=_ids, help="IDs subject to faults, e.g. 0x100,0x101 (default all)")
    for k in KINDS:
        p.add_argument(f"--{k}", type=float, default=0.0, metavar="P", help=f"{k}: probability per frame")
        p.add_argument(f"--{k}-window", type=_window, action="append", default=[], metavar="START:END",
                       help=f"{k} every selected frame in [START, END) s from the log start (repeatable)")
    p.add_argument("--silence-window", type=_window, action="append", default=[], metavar="START:END",
                   help="send nothing of the selected IDs in [START, END) (repeatable)")
    p.add_argument("--silence-rate", type=float, default=0.0, help="random silences: starts per second")
    p.add_argument("--silence-len", type=float, default=2.0, help="length of a random silence, s (2)")
    p.add_argument("--delay-s", type=float, default=0.25, help="delay of a delayed frame, s (0.25)")
    p.add_argument("--unknown-id", type=lambda s: int(s, 0), default=0x7F0, help="ID of injected unknown frames (0x7F0)")
    p.add_argument("--report", help="also write the JSON report to this file")
    return p


def main(argv=None, bus: Optional[can.BusABC] = None) -> int:
    a = build_parser().parse_args(argv)
    if a.channel is None and a.out is None and bus is None:
        print("hstpf-replay: give --channel and/or --out", file=sys.stderr)
        return 2
    if a.speed <= 0:
        print("hstpf-replay: --speed must be > 0", file=sys.stderr)
        return 2
    rates = {k: getattr(a, k) for k in KINDS}
    if any(r < 0 for r in rates.values()) or sum(rates.values()) > 1:
        print("hstpf-replay: fault probabilities must be >= 0 and sum to at most 1", file=sys.stderr)
        return 2
    windows = {k: getattr(a, f"{k}_window") for k in KINDS}
    msgs, report = inject(read_log(a.log), rates, windows, a.seed, a.ids, a.silence_window, a.silence_rate,
                          a.silence_len, a.delay_s, a.unknown_id)
    if a.out:
        write_log(a.out, msgs)
    if bus is not None or a.channel is not None:
        own = bus is None
        if own:
            bus = can.Bus(interface=a.interface, channel=a.channel)
        try:
            t = time.perf_counter()
            report["sent"] = send_all(bus, msgs, a.speed, a.fast)
            report["wall_s"] = round(time.perf_counter() - t, 3)
        finally:
            if own:
                bus.shutdown()
    text = json.dumps(report, sort_keys=True)
    print(text)
    if a.report:
        with open(a.report, "w") as f:
            f.write(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
