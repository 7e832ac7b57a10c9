"""hstpf-record: capture frames from a CAN interface into a log (python-can)."""
import argparse
import json
import sys
import time
from typing import Optional

import can


def record(bus: can.BusABC, out: str, duration: Optional[float] = None, quiet: Optional[float] = None,
           first_timeout: float = 60.0, max_frames: Optional[int] = None, ids=None) -> dict:
    """Writes received frames (error frames too) to `out` until `duration`
    has passed, `max_frames` were written, or, once the first frame came,
    nothing came for `quiet` seconds; gives up when no frame came within
    `first_timeout`. Returns counts."""
    n = errors = 0
    t_start = time.monotonic()
    t_last = None
    reason = "duration"
    with can.Logger(out) as log:
        while True:
            now = time.monotonic()
            if duration is not None and now - t_start >= duration:
                reason = "duration"
                break
            if t_last is None and now - t_start >= first_timeout:
                reason = "no_frames"
                break
            if t_last is not None and quiet is not None and now - t_last >= quiet:
                reason = "quiet"
                break
            msg = bus.recv(timeout=0.05)
            if msg is None:
                continue
            if ids is not None and not msg.is_error_frame and msg.arbitration_id not in ids:
                continue
            t_last = time.monotonic()
            log.on_message_received(msg)
            n += 1
            errors += int(msg.is_error_frame)
            if max_frames is not None and n >= max_frames:
                reason = "max_frames"
                break
    return {"log": out, "frames": n, "error_frames": errors, "stopped": reason,
            "wall_s": round(time.monotonic() - t_start, 3)}


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="hstpf-record",
                                description="Record frames from a CAN interface to a log (candump .log, or any "
                                            "format python-can writes by suffix).")
    p.add_argument("-c", "--channel", "--iface", dest="channel", default="vcan0", help="channel (vcan0)")
    p.add_argument("--interface", default="socketcan", help="python-can interface (socketcan)")
    p.add_argument("-o", "--out", default="recorded.log", help="output log (recorded.log)")
    p.add_argument("--duration", type=float, help="stop after this many seconds")
    p.add_argument("--quiet", type=float, help="stop after this long without a frame (once one came)")
    p.add_argument("--first-timeout", type=float, default=60.0, help="give up if no frame comes in this time, s (60)")
    p.add_argument("--max-frames", type=int, help="stop after this many frames")
    p.add_argument("--ids", help="only these IDs, e.g. 0x200,0x210 (error frames are always kept)")
    return p


def main(argv=None, bus: Optional[can.BusABC] = None) -> int:
    a = build_parser().parse_args(argv)
    if a.duration is None and a.quiet is None and a.max_frames is None:
        print("hstpf-record: give --duration, --quiet or --max-frames", file=sys.stderr)
        return 2
    ids = {int(x, 0) for x in a.ids.split(",")} if a.ids else None
    own = bus is None
    if own:
        bus = can.Bus(interface=a.interface, channel=a.channel, receive_own_messages=False)
    try:
        res = record(bus, a.out, a.duration, a.quiet, a.first_timeout, a.max_frames, ids)
    finally:
        if own:
            bus.shutdown()
    print(json.dumps(res))
    return 0 if res["stopped"] != "no_frames" else 1


if __name__ == "__main__":
    sys.exit(main())
