"""What every hstpf command-line tool shares (docs/tools.md, "Conventions").

Exit codes, the same in every tool:
  0    done
  2    usage: a bad option or option value
  3    an input file cannot be opened or read, or its contents are not valid
  4    the CAN bus cannot be opened (none configured, unknown interface,
       channel absent, driver error) or fails while in use
  5    no traffic: the bus opened but no frame came (hstpf-record), or the
       log holds none of the frames the tool needs (hstpf-score)
  6    an output file cannot be written
  128 + signal number (130 SIGINT, 143 SIGTERM): interrupted before the run
       was complete; the bus and the files are closed and the report printed
Errors are one line on stderr: "<tool>: <what>".
"""
import argparse
import contextlib
import io
import json
import math
import os
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any, Callable, Optional

from . import __version__

EXIT_OK = 0
EXIT_USAGE = 2
EXIT_INPUT = 3
EXIT_BUS = 4
EXIT_NO_TRAFFIC = 5
EXIT_OUTPUT = 6

EXIT_CODES = {
    EXIT_OK: "done",
    EXIT_USAGE: "usage: a bad option or option value",
    EXIT_INPUT: "an input file cannot be opened or read, or is not valid",
    EXIT_BUS: "the CAN bus cannot be opened, or failed while in use",
    EXIT_NO_TRAFFIC: "no traffic: no frame came, or none of the frames needed",
    EXIT_OUTPUT: "an output file cannot be written",
}


class CliError(Exception):
    """A user error: `message` goes to stderr as one line, `code` is the exit status."""

    def __init__(self, code: int, message: str):
        super().__init__(message)
        self.code = code
        self.message = message


def version_string(prog: str) -> str:
    try:
        import can

        extra = f" (python-can {can.__version__})"
    except ImportError:  # pragma: no cover - python-can is a dependency
        extra = ""
    return f"{prog} {__version__}{extra}"


class _Version(argparse.Action):
    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        parser.stdout().write(version_string(parser.prog) + "\n")
        parser.exit()


class Parser(argparse.ArgumentParser):
    """argparse with --version, one-line usage errors (exit 2) and --help on stdout.

    While parsing, stdout is redirected to stderr: python-can's --timing
    action prints, and stdout is kept for data and JSON."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._out = None
        self.add_argument("--version", action=_Version, help="print the version and exit")

    def stdout(self):
        return self._out if self._out is not None else sys.stdout

    def parse_args(self, args=None, namespace=None):
        self._out = sys.stdout
        try:
            with contextlib.redirect_stdout(sys.stderr):
                return super().parse_args(args, namespace)
        finally:
            self._out = None

    def print_help(self, file=None):
        super().print_help(file if file is not None else self.stdout())

    def error(self, message):
        raise CliError(EXIT_USAGE, f"{message} (see {self.prog} --help)")


def run(prog: str, body: Callable[..., int], *args, **kwargs) -> int:
    """Calls body and turns user errors into one line on stderr and an exit code."""
    try:
        return body(*args, **kwargs)
    except CliError as exc:
        print(f"{prog}: {exc.message}", file=sys.stderr)
        return exc.code
    except SystemExit as exc:  # --help, --version
        return exc.code if isinstance(exc.code, int) else 0
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 128 + signal.SIGINT
    except BrokenPipeError:  # stdout closed early (| head): nothing left to say
        try:  # and nothing to flush at exit either
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        except (OSError, ValueError, AttributeError, io.UnsupportedOperation):
            pass
        return 0


# ---- files ------------------------------------------------------------------


class _KeepOpen(io.TextIOBase):
    """stdin/stdout for python-can's readers and writers, which close their file."""

    def __init__(self, f):
        self._f = f

    def __getattr__(self, name):
        return getattr(self._f, name)

    def __iter__(self):
        return iter(self._f)

    def read(self, *a):
        return self._f.read(*a)

    def readline(self, *a):
        return self._f.readline(*a)

    def write(self, s):
        return self._f.write(s)

    def flush(self):
        self._f.flush()

    def tell(self):
        return 0

    def close(self):
        self._f.flush()


def stdin():
    return _KeepOpen(sys.stdin)


def stdout():
    return _KeepOpen(sys.stdout)


def input_error(path: str, exc: BaseException) -> CliError:
    why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc) or type(exc).__name__
    return CliError(EXIT_INPUT, f"cannot read {path}: {why}")


def output_error(path: str, exc: BaseException) -> BaseException:
    """CliError(6) naming the file; a closed stdout pipe (| head) stays
    BrokenPipeError, which run() ends quietly."""
    if isinstance(exc, BrokenPipeError):
        return exc
    why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc) or type(exc).__name__
    return CliError(EXIT_OUTPUT, f"cannot write {path}: {why}")


def read_text(path: str) -> str:
    """The text of a file, '-' for stdin; CliError(3) if it cannot be read."""
    if path == "-":
        text = sys.stdin.read()
    else:
        try:
            with open(path, newline="", encoding="utf-8") as f:
                text = f.read()
        except (OSError, UnicodeDecodeError) as exc:
            raise input_error(path, exc) from exc
    return text[1:] if text.startswith("\ufeff") else text  # a spreadsheet's "CSV UTF-8" begins with a BOM


def write_text(path: str, text: str) -> None:
    """Writes text to a file, '-' for stdout; CliError(6) if it cannot."""
    if path == "-":
        sys.stdout.write(text)
        sys.stdout.flush()
        return
    try:
        with open(path, "w", newline="") as f:
            f.write(text)
    except OSError as exc:
        raise output_error(path, exc) from exc


# ---- reports ----------------------------------------------------------------


def add_json_argument(p: argparse.ArgumentParser, *aliases: str, what: str = "the JSON report",
                      default: str = "") -> None:
    p.add_argument("--json", *aliases, dest="json", metavar="FILE",
                   help=f"write {what} to FILE; '-': stdout, one compact JSON line and nothing else{default}")


def _finite(obj: Any) -> Any:
    """obj with every non-finite float as None: JSON has no inf or nan."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    return obj


def dumps(obj: Any) -> str:
    """Compact, sorted JSON; a non-finite number (e.g. the relative error
    against a zero coefficient) is null."""
    return json.dumps(_finite(obj), separators=(",", ":"), sort_keys=True, allow_nan=False)


def emit_report(report: dict, json_path: Optional[str], stdout_taken: bool = False) -> None:
    """The report as one compact JSON line: to json_path ('-' stdout), by
    default on stdout, or on stderr when stdout carries data."""
    text = dumps(report) + "\n"
    if json_path is None:
        (sys.stderr if stdout_taken else sys.stdout).write(text)
        (sys.stderr if stdout_taken else sys.stdout).flush()
    else:
        write_text(json_path, text)


def parse_ids(spec: str) -> set:
    """An --ids list, e.g. 0x100,0x101: an ID up to 0x7FF selects 11-bit
    frames, a larger one 29-bit frames (as candump writes them)."""
    try:
        ids = {int(x, 0) for x in spec.split(",") if x.strip()}
    except ValueError:
        raise argparse.ArgumentTypeError(f"bad ID list {spec!r}: want e.g. 0x200,0x210") from None
    bad = [i for i in ids if not 0 <= i <= 0x1FFFFFFF]
    if bad or not ids:
        raise argparse.ArgumentTypeError(f"bad ID list {spec!r}: want IDs in 0..0x1FFFFFFF, e.g. 0x200,0x210")
    return ids


def id_selected(msg, ids: Optional[set]) -> bool:
    """msg is one of parse_ids()'s frames (ids None: every frame): the same
    ID, 11-bit or 29-bit as the ID's size says."""
    return ids is None or (msg.arbitration_id in ids and bool(msg.is_extended_id) == (msg.arbitration_id > 0x7FF))


def check_stdout_once(**uses: Optional[str]) -> None:
    """Usage error when more than one output is '-'."""
    dash = [k for k, v in uses.items() if v == "-"]
    if len(dash) > 1:
        raise CliError(EXIT_USAGE, f"only one of {', '.join('--' + d.replace('_', '-') for d in dash)} can be '-'")


# ---- the CAN bus --------------------------------------------------------------

BUS_HELP = ("The bus comes from python-can: the options below, else its environment "
            "(CAN_INTERFACE, CAN_CHANNEL, CAN_BITRATE, CAN_CONFIG) and config file "
            "(~/can.conf, ~/.canrc, /etc/can.conf). There is no built-in default interface.")

BUS_KEYS = ("channel", "interface", "bitrate", "fd", "data_bitrate", "can_filters", "timing", "bus_kwargs")


def add_bus_arguments(p: argparse.ArgumentParser) -> None:
    """python-can's own bus options (-i, -c, -b, --fd, --data-bitrate, --timing, --bus-kwargs)."""
    import can.cli

    can.cli.add_bus_arguments(p, group_title="bus (python-can)")


def bus_given(ns: argparse.Namespace) -> bool:
    """Whether any bus option was given on the command line."""
    return any(k in ns for k in BUS_KEYS)


def _describe(ns: argparse.Namespace) -> str:
    import can.util

    cfg = {k: getattr(ns, k) for k in ("interface", "channel") if k in ns}
    # the sources load_config reads, without its check of the interface name
    for src in (can.util.load_environment_config(), can.util.load_file_config()):
        for k in ("interface", "channel"):
            if src.get(k) is not None:  # an unset source must not hide the next one's value
                cfg.setdefault(k, src.get(k))
    return f"interface {cfg.get('interface')!s}, channel {cfg.get('channel')!s}"


def open_bus(ns: argparse.Namespace, **kwargs):
    """can.cli.create_bus_from_namespace, its failure as CliError(4)."""
    import can
    import can.cli

    try:
        return can.cli.create_bus_from_namespace(ns, **kwargs)
    except argparse.ArgumentError as exc:
        cause = exc.__cause__ or exc
        if isinstance(cause, can.CanInterfaceNotImplementedError) and "None" in str(cause):
            raise CliError(EXIT_BUS, "cannot open the CAN bus: no interface configured (give -i/--interface, "
                                     "or set CAN_INTERFACE or a python-can config file)") from exc
        why = cause.strerror if isinstance(cause, OSError) and cause.strerror else str(cause)
        raise CliError(EXIT_BUS, f"cannot open the CAN bus ({_describe(ns)}): {why}") from exc


# ---- signals and progress -------------------------------------------------------


class Stop:
    """SIGINT and SIGTERM set `signum` instead of killing the tool, so that its
    loop can end, close the bus and the log and print the report. Handlers
    are installed only in the main thread and restored on exit."""

    def __init__(self):
        self.signum: Optional[int] = None
        self._old = {}

    @property
    def name(self) -> Optional[str]:
        return signal.Signals(self.signum).name if self.signum else None

    def _handle(self, signum, frame):
        self.signum = signum

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for s in (signal.SIGINT, signal.SIGTERM):
                self._old[s] = signal.signal(s, self._handle)
        return self

    def __exit__(self, *exc):
        for s, h in self._old.items():
            signal.signal(s, h)
        self._old = {}
        return False

    def __bool__(self):
        return self.signum is not None


def add_progress_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="a progress line on stderr (frames, log time, rate); default: when stderr is a terminal")


class Progress:
    """One progress line on stderr: rewritten in place on a terminal, one line
    every `every` s otherwise (when asked for with --progress)."""

    def __init__(self, prog: str, enabled: Optional[bool], total: Optional[int] = None,
                 span_s: Optional[float] = None, every: Optional[float] = None):
        self.tty = bool(getattr(sys.stderr, "isatty", lambda: False)())
        self.on = self.tty if enabled is None else enabled
        self.prog, self.total, self.span = prog, total, span_s
        self.every = every if every is not None else (0.25 if self.tty else 2.0)
        self.t0 = time.monotonic()
        self.t_last = self.t0
        self.shown = False

    def line(self, frames: int, log_s: float) -> str:
        wall = max(time.monotonic() - self.t0, 1e-9)
        n = f"{frames}" + (f"/{self.total}" if self.total else "")
        t = f"{log_s:.1f}" + (f"/{self.span:.1f}" if self.span else "")
        return (f"{self.prog}: {n} frames, log {t} s, {frames / wall:.0f} frames/s, "
                f"{log_s / wall:.1f} log-s/s, {wall:.0f} s")

    def update(self, frames: int, log_s: float, force: bool = False) -> None:
        if not self.on:
            return
        now = time.monotonic()
        if not force and now - self.t_last < self.every:
            return
        self.t_last = now
        text = self.line(frames, log_s)
        if self.tty:
            sys.stderr.write("\r" + text + "\033[K")
        else:
            sys.stderr.write(text + "\n")
        sys.stderr.flush()
        self.shown = True

    def done(self, frames: int, log_s: float) -> None:
        """The final line (also after a short run)."""
        if self.on:
            self.update(frames, log_s, force=True)
            if self.tty:
                sys.stderr.write("\n")
                sys.stderr.flush()


def load_log(path: str):
    """read_log(path) with its failure as CliError(3), and a log with no
    frame at all (an empty file: replay sent nothing and exited 0)."""
    from .logio import read_log

    try:
        msgs = read_log(path)
    except Exception as exc:  # python-can's readers raise many kinds on bad text
        raise input_error(path, exc) from exc
    if not msgs:
        raise input_error(path, ValueError("no frame in it"))
    return msgs


# What writing a log through python-can raises for a bad output path: OSError;
# ValueError, a suffix it cannot write; NotImplementedError, one whose
# optional package is missing (.mf4 without asammdf)
LOG_WRITE_ERRORS = (OSError, ValueError, NotImplementedError)

def save_log(path: str, msgs, channel: str) -> int:
    """write_log(path, msgs, channel) into a folder made if missing ('-':
    stdout), with its failure as CliError(6). Returns the frame count."""
    from .logio import write_log

    try:
        if path != "-":
            Path(path).parent.mkdir(parents=True, exist_ok=True)
        return write_log(path, msgs, channel)
    except LOG_WRITE_ERRORS as exc:
        raise output_error(path, exc) from exc
