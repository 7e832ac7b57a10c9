"""hstpf-record: capture frames from a CAN bus into a log (python-can)."""
import argparse
import sys
import time
from typing import Optional

import can

from . import cli
from .logio import log_writer


def record(bus: can.BusABC, out: str, duration: Optional[float] = None, quiet: Optional[float] = None,
           first_timeout: float = 60.0, max_frames: Optional[int] = None, ids=None,
           stop: Optional[cli.Stop] = None, progress: Optional[cli.Progress] = None) -> dict:
    """Writes received frames (error frames too) to `out` ('-': stdout)
    until `duration` has passed, `max_frames` were written, once the first
    frame came nothing came for `quiet` seconds, or `stop` is set
    (SIGINT/SIGTERM); gives up when no frame came within `first_timeout`.
    The log is closed in every case. Returns counts and the reason
    ("stopped"); "error" when the bus failed."""
    n = errors = 0
    t_start = time.monotonic()
    t_last = None
    ts_first = ts_last = None
    reason = "duration"
    error = None
    with log_writer(out) as log:
        while True:
            now = time.monotonic()
            if stop:
                reason = stop.name
                break
            if duration is not None and now - t_start >= duration:
                reason = "duration"
                break
            if t_last is None and first_timeout is not None and now - t_start >= first_timeout:
                reason = "no_frames"
                break
            if t_last is not None and quiet is not None and now - t_last >= quiet:
                reason = "quiet"
                break
            try:
                msg = bus.recv(timeout=0.05)
            except can.CanError as exc:
                reason, error = "error", str(exc)
                break
            if msg is None:
                continue
            if not msg.is_error_frame and not cli.id_selected(msg, ids):
                continue
            t_last = time.monotonic()
            ts_first = msg.timestamp if ts_first is None else ts_first
            ts_last = msg.timestamp
            log.on_message_received(msg)
            n += 1
            errors += int(msg.is_error_frame)
            if progress is not None:
                progress.update(n, ts_last - ts_first)
            if max_frames is not None and n >= max_frames:
                reason = "max_frames"
                break
    if progress is not None:
        progress.done(n, (ts_last - ts_first) if n else 0.0)
    res = {"log": out, "frames": n, "error_frames": errors, "stopped": reason,
           "log_s": round(ts_last - ts_first, 6) if n else 0.0, "wall_s": round(time.monotonic() - t_start, 3)}
    if error is not None:
        res["error"] = error
    return res


def _seconds(spec: str) -> float:
    x = float(spec)
    if not x > 0:
        raise argparse.ArgumentTypeError(f"{spec}: want a time > 0 s")
    return x


def build_parser() -> argparse.ArgumentParser:
    p = cli.Parser(
        prog="hstpf-record",
        description="Record frames from a CAN bus to a log (candump .log, or any format python-can writes "
        "by suffix) until a stop condition, or SIGINT/SIGTERM, then print a JSON report. " + cli.BUS_HELP,
        epilog="Exit codes: 0 frames recorded, 2 usage, 4 the bus cannot be opened or failed, 5 no frame came, "
        "6 the log cannot be written (docs/tools.md).")
    cli.add_bus_arguments(p)
    p.add_argument("-o", "--out", default="recorded.log",
                   help="output log (recorded.log); '-': candump text on stdout (the report then goes to stderr)")
    p.add_argument("--duration", type=_seconds, help="stop after this many seconds")
    p.add_argument("--quiet", type=_seconds, help="stop after this long without a frame (once one came)")
    p.add_argument("--first-timeout", type=_seconds, default=60.0,
                   help="give up if no frame comes in this time, s (60)")
    p.add_argument("--max-frames", type=int, help="stop after this many frames")
    p.add_argument("--ids", type=cli.parse_ids,
                   help="only these IDs, e.g. 0x200,0x210; above 0x7FF: 29-bit IDs (error frames are always kept)")
    cli.add_json_argument(p, default=" (default: stdout, or stderr when -o is '-')")
    cli.add_progress_argument(p)
    return p


def _main(argv, bus: Optional[can.BusABC]) -> int:
    a = build_parser().parse_args(argv)
    if a.max_frames is not None and a.max_frames < 1:
        raise cli.CliError(cli.EXIT_USAGE, "--max-frames must be >= 1")
    cli.check_stdout_once(out=a.out, json=a.json)
    own = bus is None
    if own:
        bus = cli.open_bus(a)  # before the log: an unopenable bus leaves no empty file
    try:
        with cli.Stop() as stop:
            progress = cli.Progress("hstpf-record", a.progress)
            try:
                res = record(bus, a.out, a.duration, a.quiet, a.first_timeout, a.max_frames, a.ids, stop, progress)
            except cli.LOG_WRITE_ERRORS as exc:
                raise cli.output_error(a.out, exc) from exc
    finally:
        if own:
            bus.shutdown()
    cli.emit_report(res, a.json, stdout_taken=a.out == "-")
    if "error" in res:
        print(f"hstpf-record: the bus failed after {res['frames']} frames: {res['error']}", file=sys.stderr)
        return cli.EXIT_BUS
    if res["frames"] == 0:
        print("hstpf-record: no frame came" + (f" within {a.first_timeout:g} s" if res["stopped"] == "no_frames"
                                                else f" (stopped: {res['stopped']})"), file=sys.stderr)
        return cli.EXIT_NO_TRAFFIC
    return cli.EXIT_OK


def main(argv=None, bus: Optional[can.BusABC] = None) -> int:
    """Console entry point; `bus` (tests): an open bus to use instead of the configured one."""
    return cli.run("hstpf-record", _main, argv, bus)


if __name__ == "__main__":
    sys.exit(main())
