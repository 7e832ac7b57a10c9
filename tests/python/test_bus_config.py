"""hstpf-replay and hstpf-record take their bus from python-can's own CLI
helpers and configuration: command line, environment (CAN_INTERFACE,
CAN_CHANNEL, CAN_BITRATE, CAN_CONFIG) or config file, with no default of
their own. Runs on python-can's virtual interface, in this process."""
import json
import threading
import time
import uuid

import can
import can.interfaces.virtual
import pytest

from hstpf_tools import cli, record, replay
from hstpf_tools.frames import FrameCodec
from hstpf_tools.logio import message, read_log, write_log

ENV = ("CAN_INTERFACE", "CAN_CHANNEL", "CAN_BITRATE", "CAN_CONFIG")


@pytest.fixture
def clean_env(monkeypatch, tmp_path):
    """No python-can configuration at all: no variables, no config file
    (HOME is an empty folder; /etc/can.conf is checked absent)."""
    for k in ENV:
        monkeypatch.delenv(k, raising=False)
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    if can.util.load_file_config():
        pytest.skip("a system-wide python-can config file is present")
    return home


@pytest.fixture
def log_file(tmp_path):
    """2 s of position + traction frames at 10 Hz (40 frames)."""
    c = FrameCodec()
    msgs = []
    for k in range(20):
        for name, v in (("Position", {"PosValid": 1, "Position": 10.0 * k}),
                        ("Traction", {"TractValid": 1, "TractForce": 50.0})):
            fid, d = c.encode(name, v)
            msgs.append(message(100.0 + 0.1 * k, fid, d))
    path = tmp_path / "in.log"
    write_log(str(path), msgs)
    return path, msgs


def channel_name() -> str:
    return "hstpf-" + uuid.uuid4().hex[:8]


def wait_for_listener(channel: str, n: int = 1, timeout: float = 10.0) -> None:
    """Until n buses are connected to the virtual channel (a frame sent
    before the receiver connects is not delivered)."""
    t = time.monotonic()
    while len(can.interfaces.virtual.channels.get(channel, ())) < n:
        assert time.monotonic() - t < timeout, "the recorder never opened the bus"
        time.sleep(0.01)


def test_replay_and_record_configured_only_by_environment(clean_env, monkeypatch, log_file, tmp_path):
    """The bar of issue 12: both tools run unchanged on python-can's virtual
    interface when only CAN_INTERFACE / CAN_CHANNEL / CAN_BITRATE say which bus."""
    src, msgs = log_file
    ch = channel_name()
    monkeypatch.setenv("CAN_INTERFACE", "virtual")
    monkeypatch.setenv("CAN_CHANNEL", ch)
    monkeypatch.setenv("CAN_BITRATE", "500000")
    rec, rec_json, rep_json = tmp_path / "rec.log", tmp_path / "rec.json", tmp_path / "rep.json"
    codes = {}
    th = threading.Thread(target=lambda: codes.update(rec=record.main(
        ["-o", str(rec), "--quiet", "0.5", "--first-timeout", "20", "--json", str(rec_json)])))
    th.start()
    wait_for_listener(ch)
    codes["rep"] = replay.main([str(src), "--speed", "10", "--json", str(rep_json)])
    th.join(30)
    assert not th.is_alive()
    assert codes == {"rec": 0, "rep": 0}
    rep, res = json.loads(rep_json.read_text()), json.loads(rec_json.read_text())
    assert rep["sent"] == len(msgs) == 40
    assert res["frames"] == 40 and res["stopped"] == "quiet"
    got = read_log(str(rec))
    assert [(m.arbitration_id, bytes(m.data)) for m in got] == [(m.arbitration_id, bytes(m.data)) for m in msgs]
    assert ch not in can.interfaces.virtual.channels or not can.interfaces.virtual.channels[ch]  # both closed


def test_can_config_variable_and_config_file_are_honoured(clean_env, monkeypatch, log_file, tmp_path):
    src, msgs = log_file
    for how in ("CAN_CONFIG", "file"):
        ch = channel_name()
        if how == "CAN_CONFIG":
            monkeypatch.setenv("CAN_CONFIG", json.dumps({"interface": "virtual", "channel": ch}))
        else:
            monkeypatch.delenv("CAN_CONFIG")
            (clean_env / ".canrc").write_text(f"[default]\ninterface = virtual\nchannel = {ch}\n")
        rx = can.Bus(interface="virtual", channel=ch)
        try:
            assert replay.main([str(src), "--fast", "--json", str(tmp_path / "r.json")]) == 0, how
            got = [rx.recv(1.0) for _ in msgs]
        finally:
            rx.shutdown()
        assert all(m is not None for m in got), how
        assert [bytes(m.data) for m in got] == [bytes(m.data) for m in msgs], how


def test_command_line_overrides_environment(clean_env, monkeypatch, log_file, tmp_path):
    src, msgs = log_file
    ch_env, ch_cli = channel_name(), channel_name()
    monkeypatch.setenv("CAN_INTERFACE", "virtual")
    monkeypatch.setenv("CAN_CHANNEL", ch_env)
    rx_env, rx_cli = can.Bus(interface="virtual", channel=ch_env), can.Bus(interface="virtual", channel=ch_cli)
    try:
        assert replay.main([str(src), "--fast", "-c", ch_cli, "--json", str(tmp_path / "r.json")]) == 0
        assert rx_env.recv(0.2) is None
        assert rx_cli.recv(1.0) is not None
    finally:
        rx_env.shutdown()
        rx_cli.shutdown()


def test_no_built_in_default_interface(clean_env, log_file, capsys):
    """Without any configuration neither tool falls back to socketcan: exit 4
    (cannot open the bus) with a one-line hint."""
    src, _ = log_file
    assert replay.main([str(src), "--fast"]) == cli.EXIT_BUS
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no interface configured" in err and "CAN_INTERFACE" in err
    assert record.main(["-o", "-", "--duration", "0.1"]) == cli.EXIT_BUS
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no interface configured" in err


def test_bus_kwargs_reach_the_bus(clean_env, monkeypatch, log_file, tmp_path):
    """python-can's -b and --bus-kwargs reach can.cli.create_bus_from_namespace."""
    seen = {}
    real = can.cli.create_bus_from_namespace

    def spy(ns, **kw):
        bus = real(ns, **kw)
        seen["kwargs"] = dict(getattr(ns, "bus_kwargs", {}))
        seen["bitrate"] = getattr(ns, "bitrate", None)
        return bus

    monkeypatch.setattr(can.cli, "create_bus_from_namespace", spy)
    src, _ = log_file
    assert replay.main([str(src), "--fast", "-i", "virtual", "-c", channel_name(), "-b", "250000",
                        "--bus-kwargs", "preserve_timestamps=True", "--json", str(tmp_path / "r.json")]) == 0
    assert seen == {"kwargs": {"preserve_timestamps": True}, "bitrate": 250000}


def test_bus_error_names_the_config_file(clean_env, log_file, capsys):
    """An interface that cannot be opened, named only in ~/.canrc: the error
    names the file's interface and channel (an unset environment value hid
    them: 'interface None, channel None')."""
    src, _ = log_file
    (clean_env / ".canrc").write_text("[default]\ninterface = nosuch\nchannel = cfgch\n")
    assert replay.main([str(src), "--fast"]) == 4
    err = capsys.readouterr().err
    assert "interface nosuch, channel cfgch" in err
