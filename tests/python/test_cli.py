"""CLI hygiene of every console script (tools/pyproject.toml [project.scripts]):
--version, one-line errors with the documented exit codes, '-' for stdin and
stdout, '--json -' alone on stdout, SIGINT/SIGTERM, progress lines."""
import importlib
import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path

import can
import pytest

import hstpf_tools
from hstpf_tools import cli, record, replay, score, simulate
from hstpf_tools.frames import FrameCodec
from hstpf_tools.logio import message, read_log, write_log

ROOT = Path(__file__).resolve().parents[2]
MISSING = "/nonexistent-hstpf/none.log"


def scripts():
    """{console script name: callable} from pyproject.toml itself."""
    text = (ROOT / "tools" / "pyproject.toml").read_text()
    block = text.split("[project.scripts]", 1)[1].split("\n[", 1)[0]
    out = {}
    for name, target in re.findall(r'^([\w-]+)\s*=\s*"([\w.:]+)"', block, re.M):
        mod, fn = target.split(":")
        out[name] = getattr(importlib.import_module(mod), fn)
    return out


SCRIPTS = scripts()


def test_every_console_script_is_covered():
    # a new script must get its rows in the tables below
    assert set(SCRIPTS) == {"hstpf-simulate", "hstpf-encode", "hstpf-replay", "hstpf-record", "hstpf-score",
                            "hstpf-soak"}


@pytest.fixture
def no_can_config(monkeypatch, tmp_path):
    for k in ("CAN_INTERFACE", "CAN_CHANNEL", "CAN_BITRATE", "CAN_CONFIG"):
        monkeypatch.delenv(k, raising=False)
    monkeypatch.setenv("HOME", str(tmp_path))


def one_line(err: str, prog: str, *words: str) -> None:
    assert err.endswith("\n") and err.count("\n") == 1, repr(err)
    assert err.startswith(prog + ": "), err
    for w in words:
        assert w in err, (w, err)


@pytest.mark.parametrize("name", sorted(SCRIPTS))
def test_version(name, capsys):
    assert SCRIPTS[name](["--version"]) == 0
    out = capsys.readouterr()
    assert out.out == f"{name} {hstpf_tools.__version__} (python-can {can.__version__})\n" and out.err == ""


@pytest.mark.parametrize("name", sorted(SCRIPTS))
def test_version_of_installed_script(name):
    exe = Path(sys.executable).parent / name
    if not exe.exists():
        pytest.skip(f"{name} not installed next to {sys.executable}")
    p = subprocess.run([str(exe), "--version"], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0 and p.stdout.startswith(f"{name} {hstpf_tools.__version__}")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A 60 s simulated run, a CSV for hstpf-encode, and a scripted estimator log."""
    d = tmp_path_factory.mktemp("cli")
    assert simulate.main(["-o", str(d / "run.log"), "--duration", "60", "--json", str(d / "sim.json")]) == 0
    (d / "in.csv").write_text("time_s,position_m,force_kn\n0,0,10\n0.1,0.5,10\n0.2,1.0,10\n")
    c = FrameCodec()
    msgs = []
    for k in range(61):
        fid, data = c.encode("EstState", {"EstValid": 1, "EstPosition": 0.0, "EstSpeed": 0.0})
        msgs.append(message(float(k), fid, data))
    write_log(str(d / "est.log"), msgs)
    return d


def args_missing_input(name, d):
    return {
        "hstpf-simulate": ["-o", str(d / "x.log"), "--track", MISSING],
        "hstpf-encode": [MISSING, "-o", str(d / "x.log")],
        "hstpf-replay": [MISSING, "--no-bus", "-o", str(d / "x.log")],
        "hstpf-record": ["-i", "virtual", "-c", "hstpf-cli-rec", "--duration", "0.05", "-o", MISSING],
        "hstpf-score": [MISSING, "--truth", str(d / "run_truth.csv")],
        "hstpf-soak": ["--log", MISSING, "--dir", str(d / "soak")],
    }[name]


@pytest.mark.parametrize("name", sorted(SCRIPTS))
def test_missing_file_is_one_line_exit_3(name, files, capsys):
    code = SCRIPTS[name](args_missing_input(name, files))
    err = capsys.readouterr().err
    # hstpf-record reads no file: its one file is the log it writes (exit 6)
    assert code == (cli.EXIT_OUTPUT if name == "hstpf-record" else cli.EXIT_INPUT)
    one_line(err, name, MISSING, "No such file or directory")


def test_bad_input_contents_is_exit_3(files, tmp_path, capsys):
    bad = tmp_path / "bad.log"
    bad.write_text("this is not a candump log\n")
    assert replay.main([str(bad), "--no-bus", "-o", str(tmp_path / "o.log")]) == cli.EXIT_INPUT
    one_line(capsys.readouterr().err, "hstpf-replay", str(bad))
    truth = tmp_path / "t.csv"
    truth.write_text("a,b\n1,2\n")
    assert score.main([str(files / "est.log"), "--truth", str(truth)]) == cli.EXIT_INPUT
    one_line(capsys.readouterr().err, "hstpf-score", str(truth), "not a truth CSV")
    empty = tmp_path / "empty.log"  # no frame at all: replay sent nothing and exited 0 (a review)
    empty.write_text("")
    assert replay.main([str(empty), "--no-bus", "-o", str(tmp_path / "o.log")]) == cli.EXIT_INPUT
    one_line(capsys.readouterr().err, "hstpf-replay", str(empty), "no frame")
    assert score.main([str(empty), "--truth", str(files / "run_truth.csv")]) == cli.EXIT_INPUT
    one_line(capsys.readouterr().err, "hstpf-score", str(empty), "no frame")


@pytest.mark.parametrize("name", ["hstpf-replay", "hstpf-record"])
@pytest.mark.parametrize("how", ["option", "environment"])
def test_unopenable_bus_is_one_line_exit_4(name, how, files, no_can_config, monkeypatch, capsys):
    """An interface that cannot open (socketcan on an absent channel, or a name
    python-can does not know) is exit 4, not 'no traffic'."""
    if how == "option":
        bus = ["-i", "socketcan", "-c", "hstpf-nosuch0"]
    else:
        monkeypatch.setenv("CAN_INTERFACE", "hstpf-nosuch-interface")
        bus = []
    args = [str(files / "run.log"), "--fast"] if name == "hstpf-replay" else ["-o", "-", "--duration", "1"]
    assert SCRIPTS[name](args + bus) == cli.EXIT_BUS
    one_line(capsys.readouterr().err, name, "cannot open the CAN bus",
             "hstpf-nosuch0" if how == "option" else "hstpf-nosuch-interface")


def test_unknown_interface_option_is_a_usage_error(files, capsys):
    # python-can's -i takes only the interface names it knows: argparse refuses the rest
    assert replay.main([str(files / "run.log"), "-i", "hstpf-nosuch"]) == cli.EXIT_USAGE
    one_line(capsys.readouterr().err, "hstpf-replay", "invalid choice", "--help")


@pytest.mark.parametrize("name", sorted(SCRIPTS))
def test_usage_error_is_one_line_exit_2(name, capsys):
    assert SCRIPTS[name](["--no-such-option"]) == cli.EXIT_USAGE
    one_line(capsys.readouterr().err, name, "--help")  # the missing positional or the unknown option


def json_args(name, d):
    return {
        "hstpf-simulate": ["-o", str(d / "j.log"), "--duration", "5"],
        "hstpf-encode": [str(d / "in.csv"), "-o", str(d / "e.log")],
        "hstpf-replay": [str(d / "run.log"), "--no-bus", "-o", str(d / "f.log"), "--drop", "0.1"],
        "hstpf-record": ["-i", "virtual", "-c", "hstpf-cli-" + uuid.uuid4().hex, "-o", str(d / "r.log"),
                         "--first-timeout", "0.1"],
        "hstpf-score": [str(d / "est.log"), "--truth", str(d / "run_truth.csv"), "--plots", str(d / "plots")],
        "hstpf-soak": ["--make-only", "--hours", "0.01", "--dir", str(d / "soak")],
    }[name]


@pytest.mark.parametrize("name", sorted(SCRIPTS))
def test_json_dash_is_alone_on_stdout(name, files, capsys):
    code = SCRIPTS[name](json_args(name, files) + ["--json", "-"])
    out = capsys.readouterr().out
    assert code == (cli.EXIT_NO_TRAFFIC if name == "hstpf-record" else 0)
    assert out.endswith("\n") and out.count("\n") == 1, out  # one compact line
    doc = json.loads(out)
    assert isinstance(doc, dict) and doc
    assert ": " not in out and ", " not in out.replace('", "', "")  # compact separators


def test_stdout_cannot_hold_two_streams(files, capsys):
    assert replay.main([str(files / "run.log"), "--no-bus", "-o", "-", "--json", "-"]) == cli.EXIT_USAGE
    one_line(capsys.readouterr().err, "hstpf-replay", "-o", "--json")


def run_tool(name, args, **kw):
    code = f"import sys; from hstpf_tools.cli import *; import {SCRIPTS[name].__module__} as m; sys.exit(m.main())"
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=120, **kw)


def test_dash_pipes_encode_replay_score(files, tmp_path):
    """CSV on stdin -> encode -> log on stdout -> replay from stdin -> faulted log on stdout."""
    p = run_tool("hstpf-encode", ["-", "-o", "-"], input=(files / "in.csv").read_text())
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stderr)["frames"] == 6  # the report moves to stderr
    lines = p.stdout.splitlines()
    assert len(lines) == 6 and all(re.match(r"^\(\d+\.\d+\) vcan0 10[01]#[0-9A-F]{16}", x) for x in lines)
    q = run_tool("hstpf-replay", ["-", "--no-bus", "-o", "-", "--drop-window", "0:0.15", "--ids", "0x100"],
                 input=p.stdout)
    assert q.returncode == 0, q.stderr
    assert json.loads(q.stderr)["injected"] == {"drop": {"0x100": 2}}
    assert len(q.stdout.splitlines()) == 4
    (tmp_path / "f.log").write_text(q.stdout)
    assert [m.arbitration_id for m in read_log(str(tmp_path / "f.log"))] == [0x101, 0x101, 0x100, 0x101]


def test_simulate_to_stdout(tmp_path):
    p = run_tool("hstpf-simulate", ["-o", "-", "--truth", str(tmp_path / "t.csv"), "--duration", "2"])
    assert p.returncode == 0, p.stderr
    assert len(p.stdout.splitlines()) == json.loads(p.stderr)["frames"] == 42
    assert run_tool("hstpf-simulate", ["-o", "-"]).returncode == cli.EXIT_USAGE  # the truth needs a file


def long_log(tmp_path, seconds=60.0):
    c = FrameCodec()
    msgs = []
    for k in range(int(seconds * 10)):
        fid, d = c.encode("Position", {"PosValid": 1, "Position": float(k)})
        msgs.append(message(0.1 * k, fid, d))
    write_log(str(tmp_path / "long.log"), msgs)
    return tmp_path / "long.log", len(msgs)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_signal_ends_replay_with_report(sig, tmp_path):
    """60 s of log at real time, signalled after about 1 s: the report is still
    printed (sent < total), the faulted log was written whole, exit 128 + n."""
    src, n = long_log(tmp_path)
    env = dict(os.environ, CAN_INTERFACE="virtual", CAN_CHANNEL="hstpf-sig")
    code = "import sys; from hstpf_tools import replay; sys.exit(replay.main())"
    p = subprocess.Popen([sys.executable, "-c", code, str(src), "-o", str(tmp_path / "f.log"), "--bus",
                          "--progress"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    first = p.stderr.readline()  # the first progress line: sending, handlers installed
    assert first.startswith("hstpf-replay: "), first
    p.send_signal(sig)
    out, err = p.communicate(timeout=30)
    err = first + err
    assert p.returncode == 128 + sig, err
    rep = json.loads(out)
    assert rep["interrupted"] == signal.Signals(sig).name
    assert 0 < rep["sent"] < n and rep["wall_s"] < 30
    assert len(read_log(str(tmp_path / "f.log"))) == n
    assert f"hstpf-replay: interrupted by {signal.Signals(sig).name} after {rep['sent']} of {n} frames" in err
    assert re.search(r"hstpf-replay: \d+/600 frames, log [\d.]+/59.9 s, \d+ frames/s", err)  # --progress


def test_signal_ends_record_without_frames(tmp_path):
    env = dict(os.environ, CAN_INTERFACE="virtual", CAN_CHANNEL="hstpf-sig-rec")
    code = "import sys; from hstpf_tools import record; sys.exit(record.main())"
    p = subprocess.Popen([sys.executable, "-c", code, "-o", str(tmp_path / "r.log")], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=env)
    t = time.monotonic()
    while not (tmp_path / "r.log").exists():  # created after the handlers are installed
        assert time.monotonic() - t < 60 and p.poll() is None
        time.sleep(0.05)
    p.send_signal(signal.SIGTERM)
    out, err = p.communicate(timeout=30)
    assert p.returncode == cli.EXIT_NO_TRAFFIC, err
    assert json.loads(out)["stopped"] == "SIGTERM"
    assert (tmp_path / "r.log").read_text() == ""
    one_line(err, "hstpf-record", "no frame came", "SIGTERM")


def test_signal_ends_record_and_keeps_the_frames(tmp_path, capsys):
    """In this process (the virtual bus is per process): frames arrive, then
    SIGTERM; the log holds every frame, the report is printed, exit 0."""
    ch = "hstpf-" + uuid.uuid4().hex[:8]
    c = FrameCodec()
    sent = []

    def feed():
        import can.interfaces.virtual as v
        while not v.channels.get(ch):
            time.sleep(0.01)
        tx = can.Bus(interface="virtual", channel=ch)
        for k in range(25):
            fid, d = c.encode("Position", {"PosValid": 1, "Position": float(k)})
            tx.send(message(0.0, fid, d))
            sent.append(d)
            time.sleep(0.005)
        tx.shutdown()
        time.sleep(0.3)
        os.kill(os.getpid(), signal.SIGTERM)

    th = threading.Thread(target=feed)
    th.start()
    code = record.main(["-i", "virtual", "-c", ch, "-o", str(tmp_path / "r.log"), "--progress"])
    th.join(10)
    out = capsys.readouterr()
    assert code == 0
    res = json.loads(out.out)
    assert res["stopped"] == "SIGTERM" and res["frames"] == 25
    assert [bytes(m.data) for m in read_log(str(tmp_path / "r.log"))] == sent
    assert re.search(r"hstpf-record: 25 frames, log [\d.]+ s, \d+ frames/s", out.err)
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # handlers restored


def test_no_progress_unless_asked_or_a_terminal(files, capsys):
    # stderr is not a terminal under pytest: no line by default
    assert replay.main([str(files / "run.log"), "-i", "virtual", "-c", "hstpf-p", "--fast", "--json",
                        str(files / "p.json")]) == 0
    assert capsys.readouterr().err == ""
    assert replay.main([str(files / "run.log"), "-i", "virtual", "-c", "hstpf-p", "--fast", "--progress", "--json",
                        str(files / "p.json")]) == 0
    assert re.fullmatch(r"hstpf-replay: 1202/1202 frames, log 60\.0/60\.0 s, \d+ frames/s, [\d.]+ log-s/s, \d+ s\n",
                        capsys.readouterr().err)


def test_score_without_estimator_frames_is_no_traffic(files, capsys):
    assert score.main([str(files / "run.log"), "--truth", str(files / "run_truth.csv"), "--json", "-"]) == \
        cli.EXIT_NO_TRAFFIC
    out = capsys.readouterr()
    assert json.loads(out.out)["frames"]["EstState"] == 0
    assert out.err.splitlines()[-1] == f"hstpf-score: no estimator frame in {files / 'run.log'}"


def test_closed_stdout_pipe_ends_quietly(tmp_path):
    """`hstpf-replay LOG --no-bus -o - | head -1`: no traceback, no error, exit 0.
    The log (about 400 kB) is larger than a pipe's buffer, so the pipe breaks."""
    src, n = long_log(tmp_path, 1000.0)
    assert src.stat().st_size > 4 * 65536
    code = "import sys; from hstpf_tools import replay; sys.exit(replay.main())"
    p = subprocess.Popen([sys.executable, "-c", code, str(src), "--no-bus", "-o", "-"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    first = p.stdout.readline()
    p.stdout.close()
    err = p.stderr.read()
    assert p.wait(60) == 0 and first.startswith(b"(0.000000) vcan0 100#")  # (no report: stdout is gone)
    assert err == b""


def test_log_suffix_python_can_cannot_write_is_exit_6(files, capsys):
    assert replay.main([str(files / "run.log"), "--no-bus", "-o", str(files / "x.nosuchformat")]) == cli.EXIT_OUTPUT
    one_line(capsys.readouterr().err, "hstpf-replay", "x.nosuchformat", "unknown log format")
    assert record.main(["-i", "virtual", "-c", "hstpf-sfx", "--duration", "0.05", "-o",
                        str(files / "r.nosuchformat")]) == cli.EXIT_OUTPUT
    one_line(capsys.readouterr().err, "hstpf-record", "r.nosuchformat")


def test_exit_codes_are_documented():
    """docs/tools.md's exit-code table has exactly the codes of hstpf_tools.cli."""
    text = (ROOT / "docs" / "tools.md").read_text()
    table = text.split("| Exit | Meaning |", 1)[1].split("\n\n", 1)[0]
    documented = set()
    for cell in re.findall(r"^\| ([\d, ]+) \|", table, re.M):
        documented |= {int(x) for x in cell.split(",")}
    assert documented == set(cli.EXIT_CODES) | {128 + signal.SIGINT, 128 + signal.SIGTERM}
