"""hstpf-encode: a user's CSV of time, position, traction -> candump log."""
import argparse
import csv
import io
import math
import sys

from . import cli, model
from .frames import POSITION, TRACTION, FrameCodec, e2e_params
from .logio import input_frames


def build_parser() -> argparse.ArgumentParser:
    p = cli.Parser(
        prog="hstpf-encode",
        description="Encode a CSV of recorded train data into E2E-protected Position and Traction frames "
        "(candump log). Columns (header required): time_s, position_m, and force_kn (total effort, kN) "
        "or traction_nkn (unit force, N/kN; needs --mass-t). An empty or non-numeric position or "
        "traction cell sends that frame with its valid bit cleared. One position and one traction "
        "frame per row, at the row's time, position first. Prints a JSON report.",
        epilog="Exit codes: 0 done, 2 usage, 3 the CSV (or --dbc) cannot be read or is not valid, 6 the log "
        "cannot be written (docs/tools.md).",
    )
    p.add_argument("csv", help="input CSV; '-': stdin")
    p.add_argument("-o", "--out", default="encoded.log", help="candump log to write (encoded.log); '-': stdout")
    p.add_argument("--mass-t", type=float, help="train mass, t: converts traction_nkn to the frame's kN")
    p.add_argument("--t0", type=float, default=0.0, help="added to time_s for the log timestamps (0)")
    p.add_argument("--channel", default="vcan0")
    p.add_argument("--no-fix-time", action="store_true", help="send positions without a fix time (an older sender)")
    p.add_argument("--dbc", help="DBC file (default port/dbc/hstpf.dbc)")
    cli.add_json_argument(p, default=" (default: stdout, or stderr when -o is '-')")
    return p


def _num(cell):
    try:
        x = float(cell)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def _main(argv) -> int:
    a = build_parser().parse_args(argv)
    cli.check_stdout_once(out=a.out, json=a.json)

    def bad(what: str) -> cli.CliError:
        return cli.CliError(cli.EXIT_INPUT, f"{a.csv}: {what}")

    try:
        rows = list(csv.DictReader(io.StringIO(cli.read_text(a.csv))))
    except csv.Error as exc:
        raise bad(str(exc)) from exc
    if not rows:
        raise bad("no rows")
    cols = rows[0].keys()
    if "time_s" not in cols or "position_m" not in cols:
        raise bad("need columns time_s and position_m")
    if "force_kn" in cols:
        conv = lambda x: x  # noqa: E731
        col = "force_kn"
    elif "traction_nkn" in cols:
        if not a.mass_t or a.mass_t <= 0:
            raise cli.CliError(cli.EXIT_USAGE, "traction_nkn needs --mass-t > 0")
        conv = lambda x: model.force_kn(x, a.mass_t)  # noqa: E731
        col = "traction_nkn"
    else:
        raise bad("need a force_kn or traction_nkn column")
    times, pos, force, pv, tv, fix = [], [], [], [], [], []
    last_t = -math.inf
    for i, r in enumerate(rows, start=2):
        t = _num(r["time_s"])
        if t is None or t < last_t:
            raise bad(f"line {i}: time_s missing or going back")
        last_t = t
        y, u = _num(r["position_m"]), _num(r[col])
        times.append(t)
        pos.append(y if y is not None else 0.0)
        force.append(conv(u) if u is not None else 0.0)
        pv.append(y is not None)
        tv.append(u is not None)
        fix.append(_num(r["fix_time_s"]) if "fix_time_s" in cols else a.t0 + t)
    try:
        codec = FrameCodec(a.dbc)
    except Exception as exc:  # missing or unreadable DBC
        raise cli.input_error(a.dbc or "the DBC", exc) from exc
    msgs = input_frames(codec, a.t0, times, pos, force, a.channel, pv, tv, fix, not a.no_fix_time)
    n = cli.save_log(a.out, msgs, a.channel)
    report = {"log": a.out, "rows": len(rows), "frames": n}
    # one frame per row: rows further apart than the receiver's E2E timeout (the DBC's, hstpfd's
    # default) arrive stale, and the estimator then never has a traction (a review: 1 Hz rows, 0.5 s)
    timeout = min(e2e_params(codec.message(name), codec.db)[1] for name in (POSITION, TRACTION))
    gaps = [b - t for t, b in zip(times, times[1:])]
    slow = sum(g > timeout for g in gaps)
    if slow:
        report["rows_beyond_timeout"] = slow
        print(f"hstpf-encode: {slow} of {len(gaps)} row intervals exceed the frames' E2E timeout "
              f"({timeout:g} s, the DBC's HstpfE2ETimeoutMs): hstpfd with its default timeouts takes those "
              f"frames as stale (resample the CSV, or raise position_timeout_s / traction_timeout_s)",
              file=sys.stderr)
    cli.emit_report(report, a.json, stdout_taken=a.out == "-")
    return cli.EXIT_OK


def main(argv=None) -> int:
    return cli.run("hstpf-encode", _main, argv)


if __name__ == "__main__":
    sys.exit(main())
