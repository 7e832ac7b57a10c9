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
import sys
import time
from collections import defaultdict
from typing import Dict, List, Optional, Sequence, Tuple

import can
import numpy as np

from . import cli
from .logio import write_log

KINDS = ("drop", "corrupt", "truncate", "duplicate", "delay", "reorder", "unknown")


def _window(spec: str) -> Tuple[float, float]:
    a, _, b = spec.partition(":")
    w = (float(a), float(b))
    if w[1] <= w[0]:
        raise argparse.ArgumentTypeError(f"window {spec!r}: END must be after START")
    return w


def _std_id(spec: str) -> int:
    try:
        i = int(spec, 0)
    except ValueError:
        i = -1
    if not 0 <= i <= 0x7FF:
        raise argparse.ArgumentTypeError(f"{spec!r}: want an 11-bit ID, 0..0x7FF")
    return i


def _copy(m: can.Message, t: Optional[float] = None, data: Optional[bytes] = None) -> can.Message:
    n = copy.copy(m)
    n.timestamp = m.timestamp if t is None else t
    if data is not None:
        n.data = bytearray(data)
        n.dlc = len(data)
    n.is_rx = False
    return n


def _after(msgs: Sequence[can.Message], i: int, t: float) -> float:
    """Where a frame of time t, frame i's or later, goes: after the frames
    that follow frame i up to t (not past a step back of the clock), so
    that the times never go back."""
    j = i + 1
    while j < len(msgs) and msgs[i].timestamp <= msgs[j].timestamp <= t:
        j += 1
    return j - 0.5


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
    """Returns (faulted messages, report dict). The log's order is kept (a
    clock step in it stays one); a delayed, duplicated or unknown frame
    goes after the frames that follow its own up to its time. Window times are seconds from the first frame of the log."""
    rng = np.random.default_rng(seed)
    out: List[Tuple[float, float, can.Message]] = []  # (place: the log index, or between two; time; msg)
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
    for i, m in enumerate(msgs):
        r = m.timestamp - t_start
        key = f"0x{m.arbitration_id:03X}"
        eligible = cli.id_selected(m, ids) and not m.is_error_frame
        u = rng.random()  # drawn for every frame: faults do not shift later draws
        bit = int(rng.integers(0, 64))
        if not eligible:
            out.append((float(i), m.timestamp, m))
            continue
        if any(a <= r < b for a, b in sil):
            counts["silence"][key] += 1
            continue
        if i in skip:
            out.append((float(i), m.timestamp, m))
            continue
        kind = next((k for k in KINDS if any(a <= r < b for a, b in windows.get(k, ()))), None)
        if kind is None:
            acc = 0.0
            for k in KINDS:
                acc += rates.get(k, 0.0)
                if u < acc:
                    kind = k
                    break
        if kind in ("corrupt", "truncate") and (m.is_remote_frame or not m.data):
            kind = None  # no payload to flip a bit in or to cut
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
        place = float(i)
        if kind == "delay":
            m = _copy(m, t=m.timestamp + delay_s)
            place = _after(msgs, i, m.timestamp)
        out.append((place, m.timestamp, m))
        if kind == "duplicate":
            out.append((_after(msgs, i, m.timestamp + 0.001), m.timestamp + 0.001, _copy(m, t=m.timestamp + 0.001)))
        elif kind == "unknown":
            x = can.Message(timestamp=m.timestamp + 0.0005, arbitration_id=unknown_id, data=bytes(8),
                            is_extended_id=False, is_rx=False, channel=m.channel)
            out.append((_after(msgs, i, x.timestamp), x.timestamp, x))
    # by place; frames put at one place by their times; stable otherwise
    out.sort(key=lambda e: (e[0], e[1] if e[0] != int(e[0]) else 0.0))
    report = {
        "frames_in": len(msgs),
        "frames_out": len(out),
        "seed": seed,
        "injected": {k: dict(v) for k, v in counts.items()},
        "totals": {k: sum(v.values()) for k, v in counts.items()},
        "silence_windows": [[round(a, 6), round(b, 6)] for a, b in sorted(sil)],
    }
    return [e[2] for e in out], report


class SendError(Exception):
    """The bus failed while sending; `sent` frames went out before."""

    def __init__(self, sent: int, cause: BaseException):
        super().__init__(str(cause))
        self.sent = sent
        self.cause = cause


def send_all(bus: can.BusABC, msgs: Sequence[can.Message], speed: float = 1.0, fast: bool = False,
             stop: Optional[cli.Stop] = None, progress: Optional[cli.Progress] = None,
             behind: Optional[dict] = None, skip: float = 60.0, skipped: Optional[list] = None) -> int:
    """Sends each message at its log time scaled by 1/speed from the first
    (fast: back to back), as python-can's MessageSync with gap 0: a pause
    of more than `skip` log seconds between two frames is cut to `skip`
    (MessageSync's and can.player's default 60; one line stamped 1e6 s
    ahead made the replay sleep 11.6 days), each such pause appended to
    `skipped` as (log time, its length). It waits
    in slices of at most 50 ms so that a stop (SIGINT/SIGTERM) ends it at
    once. The deadlines are absolute (from the start), so a stall does not
    shift what follows: the frames it held back go out at once, in order,
    and the schedule is met again as soon as the sender catches up.
    Retries when the interface queue is full. `behind` (if given) gets how
    late the frames went out against their deadlines, wall seconds:
    max, p99 and the count more than 0.1 s late. Returns the count sent;
    SendError when the bus fails."""
    if not msgs:
        return 0
    t0 = msgs[0].timestamp
    w0 = time.perf_counter()
    n = 0
    late: List[float] = []
    cut, prev = 0.0, t0
    for m in msgs:
        if m.timestamp - prev > skip:
            cut += m.timestamp - prev - skip
            if skipped is not None:
                skipped.append((round(prev - t0, 6), round(m.timestamp - prev, 6)))
        prev = max(prev, m.timestamp)
        if not fast:
            due = w0 + (m.timestamp - t0 - cut) / speed
            while not stop:
                left = due - time.perf_counter()
                if left <= 0:
                    break
                time.sleep(min(left, 0.05))
            late.append(max(0.0, time.perf_counter() - due))
        if stop:
            break
        for attempt in range(200):
            try:
                bus.send(m, timeout=0.1)
                break
            except can.CanOperationError as exc:
                if attempt == 199:
                    raise SendError(n, exc) from exc
                time.sleep(0.001)  # ENOBUFS: the tx queue drains in microseconds on vcan
            except can.CanError as exc:
                raise SendError(n, exc) from exc
        n += 1
        if progress is not None:
            progress.update(n, m.timestamp - t0)
    if progress is not None:
        progress.done(n, msgs[n - 1].timestamp - t0 if n else 0.0)
    if behind is not None and late:
        a = np.array(late)
        behind.update({"max": round(float(a.max()), 3), "p99": round(float(np.percentile(a, 99)), 3),
                       "over_0.1": int((a > 0.1).sum())})
    return n


def build_parser() -> argparse.ArgumentParser:
    p = cli.Parser(
        prog="hstpf-replay",
        description="Replay a candump log onto a CAN bus (python-can) at real time or sped up, "
        "with reproducible fault injection. Prints a JSON report of what was injected. " + cli.BUS_HELP,
        epilog=__doc__.split("\n", 2)[2] + "\nExit codes: see docs/tools.md (2 usage, 3 input, 4 bus, 6 output, "
        "130/143 interrupted).",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("log", help="candump log (or any format python-can reads); '-': candump text on stdin")
    cli.add_bus_arguments(p)
    p.add_argument("--bus", action=argparse.BooleanOptionalAction, default=None,
                   help="send on the bus (default: yes, unless -o is given without any bus option)")
    p.add_argument("--speed", type=float, default=1.0, help="speed-up factor (1 = real time)")
    p.add_argument("--fast", action="store_true", help="no timing: send back to back")
    p.add_argument("--skip", type=float, default=60.0, metavar="S",
                   help="cut pauses in the log longer than S seconds to S (60, as python-can's player; "
                        "inf keeps every pause)")
    p.add_argument("--error-frames", action="store_true",
                   help="also send the log's error frames (not sent by default, as python-can's player)")
    p.add_argument("-o", "--out", help="also write the faulted stream to this log ('-': candump text on stdout)")
    p.add_argument("--seed", type=int, default=1, help="fault RNG seed (1)")
    p.add_argument("--ids", type=cli.parse_ids,
                   help="IDs subject to faults, e.g. 0x100,0x101 (default all); above 0x7FF: 29-bit IDs")
    for k in KINDS:
        p.add_argument(f"--{k}", type=float, default=0.0, metavar="P", help=f"{k}: probability per frame")
        p.add_argument(f"--{k}-window", type=_window, action="append", default=[], metavar="START:END",
                       help=f"{k} every selected frame in [START, END) s from the log start (repeatable)")
    p.add_argument("--silence-window", type=_window, action="append", default=[], metavar="START:END",
                   help="send nothing of the selected IDs in [START, END) (repeatable)")
    p.add_argument("--silence-rate", type=float, default=0.0, help="random silences: starts per second")
    p.add_argument("--silence-len", type=float, default=2.0, help="length of a random silence, s (2)")
    p.add_argument("--delay-s", type=float, default=0.25, help="delay of a delayed frame, s (0.25)")
    p.add_argument("--unknown-id", type=_std_id, default=0x7F0, help="11-bit ID of injected unknown frames (0x7F0)")
    cli.add_json_argument(p, "--report", default=" (default: stdout, or stderr when -o is '-')")
    cli.add_progress_argument(p)
    return p


def _main(argv, bus: Optional[can.BusABC]) -> int:
    a = build_parser().parse_args(argv)
    if a.speed <= 0:
        raise cli.CliError(cli.EXIT_USAGE, "--speed must be > 0")
    if not a.skip > 0:
        raise cli.CliError(cli.EXIT_USAGE, "--skip must be > 0")
    rates = {k: getattr(a, k) for k in KINDS}
    if any(r < 0 for r in rates.values()) or sum(rates.values()) > 1:
        raise cli.CliError(cli.EXIT_USAGE, "fault probabilities must be >= 0 and sum to at most 1")
    cli.check_stdout_once(out=a.out, json=a.json)
    use_bus = bus is not None or (a.bus if a.bus is not None else (cli.bus_given(a) or a.out is None))
    if not use_bus and a.out is None:
        raise cli.CliError(cli.EXIT_USAGE, "--no-bus needs -o")
    windows = {k: getattr(a, f"{k}_window") for k in KINDS}
    msgs, report = inject(cli.load_log(a.log), rates, windows, a.seed, a.ids, a.silence_window, a.silence_rate,
                          a.silence_len, a.delay_s, a.unknown_id)
    if a.out:
        try:
            write_log(a.out, msgs)
        except cli.LOG_WRITE_ERRORS as exc:
            raise cli.output_error(a.out, exc) from exc
    code, failure = cli.EXIT_OK, None
    if use_bus:
        own = bus is None
        if own:
            bus = cli.open_bus(a)
        if not a.error_frames:  # as python-can's player: a log's error frames are not sent
            sent_msgs = [m for m in msgs if not m.is_error_frame]
            if len(sent_msgs) != len(msgs):
                report["error_frames_skipped"] = len(msgs) - len(sent_msgs)
            msgs = sent_msgs
        span = msgs[-1].timestamp - msgs[0].timestamp if msgs else 0.0
        progress = cli.Progress("hstpf-replay", a.progress, len(msgs), span)
        t = time.perf_counter()
        try:
            with cli.Stop() as stop:
                try:
                    behind: dict = {}
                    skipped: list = []
                    report["sent"] = send_all(bus, msgs, a.speed, a.fast, stop, progress, behind, a.skip, skipped)
                    if behind:
                        report["behind_s"] = behind
                    if skipped:
                        report["pauses_cut"] = [{"at_s": t, "log_s": g} for t, g in skipped]
                        print(f"hstpf-replay: {len(skipped)} pause(s) in the log longer than {a.skip:g} s cut to it "
                              f"(the first at log time {skipped[0][0]:g} s, {skipped[0][1]:g} s long; "
                              f"--skip inf keeps them)", file=sys.stderr)
                except SendError as exc:
                    report["sent"] = exc.sent
                    failure = f"the bus failed after {exc.sent} frames: {exc.cause}"
                    report["error"] = failure
                    code = cli.EXIT_BUS
        finally:
            report["wall_s"] = round(time.perf_counter() - t, 3)
            if own:
                bus.shutdown()
        if stop:
            report["interrupted"] = stop.name
            code = code or 128 + stop.signum
    cli.emit_report(report, a.json, stdout_taken=a.out == "-")
    if failure:
        print(f"hstpf-replay: {failure}", file=sys.stderr)
    elif code:
        print(f"hstpf-replay: interrupted by {report['interrupted']} after {report['sent']} of "
              f"{len(msgs)} frames", file=sys.stderr)
    return code


def main(argv=None, bus: Optional[can.BusABC] = None) -> int:
    """Console entry point; `bus` (tests): an open bus to use instead of the configured one."""
    return cli.run("hstpf-replay", _main, argv, bus)


if __name__ == "__main__":
    sys.exit(main())
