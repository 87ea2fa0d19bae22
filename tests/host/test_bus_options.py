"""The bus options every program takes (`fdi_host.live.bus`): python-can's full configuration as can.Bus() reads
it (command line, a configuration file and its section, the environment, ~/.canrc), the fallback when nothing
names a bus (vcan0 where the kernel has it, else the simulated bus with a note, never a bus called vcan that is
not one), the reader through python-can's public API, and a replay and a live ECU over a `virtual` bus named in
a python-can configuration file (in one process: python-can's virtual bus does not cross processes)."""

from __future__ import annotations

import argparse
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import can
import pytest

from fdi_host.can.frame import Frame
from fdi_host.can.logs import read_log
from fdi_host.ecu.session import DIAG_ID
from fdi_host.live import bus as bus_mod
from fdi_host.live.bus import (
    CAN_EFF_FLAG,
    DEFAULT_CHANNEL,
    BusArg,
    BusConfigError,
    BusOptions,
    BusReader,
    add_bus_arguments,
    open_bus,
    open_cli_bus,
    parse_bus_value,
    resolve_bus,
)
from fdi_host.live.sender import send_paced


@pytest.fixture(autouse=True)
def no_user_config(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Iterator[Path]:
    """Neither the environment nor the user's python-can files of the machine running the tests: a private
    ~/.canrc (absent unless a test writes it)."""
    for name in ("CAN_INTERFACE", "CAN_CHANNEL", "CAN_BITRATE", "CAN_CONFIG"):
        monkeypatch.delenv(name, raising=False)
    canrc = tmp_path / "canrc"
    monkeypatch.setattr(can.util, "CONFIG_FILES", [str(canrc)])
    yield canrc


def _parse(*argv: str) -> BusOptions:
    ap = argparse.ArgumentParser(exit_on_error=False)
    add_bus_arguments(ap)
    return BusOptions.from_args(ap.parse_args(list(argv)))


def _config(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


# ------------------------------------------------------------------------------------------- options
def test_bus_options_parse_typed() -> None:
    opts = _parse("--interface", "pcan", "--channel", "PCAN_USBBUS1", "--bitrate", "500000", "--fd",
                  "--data-bitrate", "2000000", "--bus-arg", "app_name=CANalyzer", "--bus-arg", "rx_queue_size=0x10",
                  "--bus-arg", "receive_own_messages=true", "--bus-arg", "serial='0012'", "--bus-arg", "f=1.5",
                  "--can-config", "bus.ini", "--can-context", "vehicle")
    assert (opts.interface, opts.channel, opts.bitrate, opts.fd, opts.data_bitrate) == \
        ("pcan", "PCAN_USBBUS1", 500000, True, 2000000)
    assert opts.config_file == Path("bus.ini") and opts.context == "vehicle" and opts.given
    assert opts.kwargs() == {"interface": "pcan", "channel": "PCAN_USBBUS1", "bitrate": 500000, "fd": True,
                             "data_bitrate": 2000000, "app_name": "CANalyzer", "rx_queue_size": 16,
                             "receive_own_messages": True, "serial": "0012", "f": 1.5}
    assert _parse(*opts.argv()) == opts  # what fdi-live hands to the programs it starts
    assert _parse("--no-fd").fd is False and _parse().fd is None and not _parse().given
    assert [parse_bus_value(v) for v in ("123", "-4", "0x1F", "2.5", "True", "off", "yes", '"7"', "can0")] == \
        [123, -4, 31, 2.5, True, False, True, "7", "can0"]


@pytest.mark.parametrize("argv, message", [
    (["--bus-arg", "novalue"], "expected KEY=VALUE"),
    (["--bus-arg", "1x=2"], "expected KEY=VALUE"),
    (["--bus-arg", "bitrate=500000"], "use --bitrate for bitrate"),
    (["--bus-arg", "channel=can0"], "use --channel"),
    (["--bitrate", "0"], "must be > 0"),
    (["--bitrate", "fast"], "a whole number of bit/s"),
])
def test_bad_bus_options_are_usage_errors(argv: list[str], message: str) -> None:
    with pytest.raises(argparse.ArgumentError, match=message):
        _parse(*argv)


def test_every_program_takes_the_bus_options() -> None:
    from fdi_host.live.ecu import build_parser as ecu_parser
    from fdi_host.live.runner import build_parser as live_parser
    from fdi_host.live.sim import build_parser as sim_parser
    from fdi_host.monitor.cli import build_parser as monitor_parser
    from fdi_host.replay import build_parser as replay_parser

    argv = ["--interface", "kvaser", "--channel", "0", "--bitrate", "250000", "--bus-arg", "single_handle=true",
            "--can-config", "x.ini"]
    for parser, extra in ((ecu_parser, []), (monitor_parser, []), (sim_parser, []), (live_parser, []),
                          (replay_parser, ["d.log"])):
        ap = parser()
        opts = BusOptions.from_args(ap.parse_args([*argv, *extra]))
        assert opts == BusOptions("kvaser", "0", 250000, None, None, (BusArg("single_handle", True,
                                                                              "single_handle=true"),), Path("x.ini"))
        assert "--can-config FILE" in ap.format_help() and "--interface pcan --channel PCAN_USBBUS1" in \
            ap.format_help()


# ------------------------------------------------------------------------------------------- configuration
def test_a_configuration_file_naming_a_virtual_bus_is_honoured(tmp_path: Path) -> None:
    cfg = _config(tmp_path / "bus.ini", "[default]\ninterface = virtual\nchannel = cfg-default\n"
                  "receive_own_messages = False\n\n[bench]\ninterface = virtual\nchannel = cfg-bench\n"
                  "bitrate = 500000\n")
    default = resolve_bus(BusOptions(config_file=cfg))
    assert default.kwargs == {"interface": "virtual", "channel": "cfg-default", "receive_own_messages": False}
    assert default.source == f"python-can configuration {cfg}" and default.note is None
    bench = resolve_bus(BusOptions(config_file=cfg, context="bench"))
    assert (bench.interface, bench.channel, bench.kwargs["bitrate"]) == ("virtual", "cfg-bench", 500000)
    assert bench.describe() == "virtual cfg-bench (500 kbit/s)"
    # the command line first, the rest from the file (python-can's order)
    mixed = resolve_bus(BusOptions(channel="cli", config_file=cfg, context="bench"))
    assert (mixed.interface, mixed.channel, mixed.kwargs["bitrate"]) == ("virtual", "cli", 500000)
    a, b = open_bus(BusOptions(config_file=cfg)), can.Bus(interface="virtual", channel="cfg-default")
    try:
        assert a.channel_info == "Virtual bus channel cfg-default"
        a.send(can.Message(arbitration_id=0x123, data=b"\x01", is_extended_id=False))
        got = b.recv(timeout=1.0)
        assert got is not None and got.arbitration_id == 0x123
    finally:
        a.shutdown()
        b.shutdown()
    with pytest.raises(BusConfigError, match=r"no section \[nope\] \(its sections: \[default\], \[bench\]\)"):
        resolve_bus(BusOptions(config_file=cfg, context="nope"))
    with pytest.raises(BusConfigError, match=r"missing\.ini: no such python-can configuration file"):
        resolve_bus(BusOptions(config_file=tmp_path / "missing.ini"))


def test_environment_and_canrc_are_honoured(monkeypatch: pytest.MonkeyPatch, no_user_config: Path) -> None:
    _config(no_user_config, "[default]\ninterface = virtual\nchannel = from-canrc\nbitrate = 250000\n")
    cfg = resolve_bus(BusOptions())
    assert (cfg.interface, cfg.channel, cfg.kwargs["bitrate"]) == ("virtual", "from-canrc", 250000)
    assert cfg.source == "python-can configuration"
    monkeypatch.setenv("CAN_CHANNEL", "from-env")
    monkeypatch.setenv("CAN_BITRATE", "125000")
    cfg = resolve_bus(BusOptions())  # the environment before the file
    assert (cfg.interface, cfg.channel, cfg.kwargs["bitrate"]) == ("virtual", "from-env", 125000)
    monkeypatch.setenv("CAN_INTERFACE_bench", "udp_multicast")  # the suffix as the context is spelt
    cfg = resolve_bus(BusOptions(context="bench"))
    assert (cfg.interface, cfg.channel) == ("udp_multicast", "from-env")


def test_without_configuration_vcan_or_the_simulated_bus_with_a_note(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(bus_mod, "vcan_available", lambda channel="vcan0": True)
    vcan = resolve_bus(BusOptions())
    assert (vcan.interface, vcan.channel, vcan.note, vcan.source) == ("socketcan", "vcan0", None, "default")
    monkeypatch.setattr(bus_mod, "vcan_available", lambda channel="vcan0": False)
    sim = resolve_bus(BusOptions(bitrate=500000))
    assert (sim.interface, sim.channel, sim.kwargs["bitrate"]) == ("udp_multicast", DEFAULT_CHANNEL, 500000)
    assert sim.note is not None and sim.note.startswith("no SocketCAN vcan0 (") and "simulated bus" in sim.note
    assert "the simulated bus" in sim.describe()
    # channel defaults per interface when no source names one
    assert resolve_bus(BusOptions(interface="socketcan")).channel == "vcan0"
    assert resolve_bus(BusOptions(interface="udp_multicast")).channel == DEFAULT_CHANNEL
    assert "channel" not in resolve_bus(BusOptions(interface="pcan")).kwargs  # the interface's own default


def test_this_machine_is_never_called_vcan_without_af_can() -> None:
    from fdi_host.live.netns import vcan_available

    cfg = resolve_bus(BusOptions())
    if vcan_available():
        assert (cfg.interface, cfg.channel) == ("socketcan", "vcan0")
    else:
        assert cfg.interface == "udp_multicast" and cfg.note is not None and "vcan0" in cfg.note


def test_a_bus_that_cannot_be_opened_is_one_error_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert open_cli_bus("fdi-x", BusOptions(interface="socketcan", channel="fdi-no-such-if")) is None
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("fdi-x: error: cannot open the CAN bus (socketcan fdi-no-such-if): ")
    assert open_cli_bus("fdi-x", BusOptions(interface="no-such-interface")) is None
    assert "Unknown interface type" in capsys.readouterr().err


# ------------------------------------------------------------------------------------------- reading
def test_reader_drains_every_queued_frame_through_recv() -> None:
    tx = can.Bus(interface="virtual", channel="reader-test")
    rx = can.Bus(interface="virtual", channel="reader-test")
    try:
        for i in range(10):
            tx.send(can.Message(arbitration_id=0x100 + i if i % 2 else 0x18DAF100 + i, data=bytes([i]),
                                is_extended_id=i % 2 == 0))
        time.sleep(0.05)
        one = BusReader(rx, drain=False).read(0.5)
        got = BusReader(rx).read(0.5)
        assert len(one) == 1 and len(got) == 9
        ids = [fid for fid, _, _ in one + got]
        assert ids[0] == 0x18DAF100 | CAN_EFF_FLAG and ids[1] == 0x101
        assert [d for _, d, _ in one + got] == [bytes([i]) for i in range(10)]
        assert BusReader(rx).read(0.01) == []
    finally:
        tx.shutdown()
        rx.shutdown()


# ------------------------------------------------------------------------------------------- replay and live
@pytest.fixture(scope="module")
def drive_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from fdi_host.cli import main as sim_main

    out = tmp_path_factory.mktemp("busdrive") / "d.trc"
    assert sim_main(["--scenario", "straight", "--no-scenario-faults", "--duration", "2", "--out", str(out),
                     "--quiet"]) == 0
    return out


def test_replay_onto_a_virtual_bus_named_in_a_configuration_file(drive_log: Path, tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    from fdi_host.replay import main as replay_main

    cfg = _config(tmp_path / "bus.ini", "[replay]\ninterface = virtual\nchannel = replay-cfg\n")
    rx = open_bus(BusOptions(config_file=cfg, context="replay"))
    try:
        assert replay_main([str(drive_log), "--speed", "max", "--can-config", str(cfg), "--can-context",
                            "replay"]) == 0
        got = []
        while (m := rx.recv(timeout=0.0)) is not None:
            got.append((m.arbitration_id, bytes(m.data)))
    finally:
        rx.shutdown()
    assert got == [(f.frame_id, f.data) for f in read_log(drive_log)]
    assert "onto virtual replay-cfg in" in capsys.readouterr().out


def test_live_ecu_over_a_virtual_bus_named_in_a_configuration_file(drive_log: Path, tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture[str]) -> None:
    """fdi-ecu on the bus of a python-can configuration file, fed by a sender on the same configuration: every
    frame in, a diagnosis frame per step out."""
    from fdi_host.live.ecu import main as ecu_main

    cfg = _config(tmp_path / "can.conf", "[default]\ninterface = virtual\nchannel = live-cfg\n")
    drive = read_log(drive_log)
    frames = [f for f in drive if f.timestamp - drive[0].timestamp < 1.0]
    ready = tmp_path / "ecu.ready"
    diag: list[Frame] = []

    def sender() -> None:
        deadline = time.monotonic() + 30.0
        while not ready.exists() and time.monotonic() < deadline:
            time.sleep(0.01)
        bus = open_bus(BusOptions(config_file=cfg))
        try:
            send_paced(bus, frames, 2.0)
            t_end = time.monotonic() + 0.3
            while time.monotonic() < t_end:  # the diagnosis frames the ECU sends back on the same bus
                m = bus.recv(timeout=0.05)
                if m is not None and m.arbitration_id == DIAG_ID:
                    diag.append(Frame(m.timestamp, m.arbitration_id, bytes(m.data)))
        finally:
            bus.shutdown()

    thread = threading.Thread(target=sender, daemon=True)
    thread.start()
    rx_log = tmp_path / "rx.csv"
    rc = ecu_main(["--can-config", str(cfg), "--vehicle", "kin", "--idle-exit", "0.5", "--duration", "60",
                   "--ready-file", str(ready), "--rx-log", str(rx_log), "--quiet", "--rcvbuf", "0"])
    thread.join(timeout=30.0)
    out = capsys.readouterr().out
    assert rc == 0, out
    assert f"fdi-ecu: {len(frames)} frames in" in out
    assert [(f.frame_id, f.data) for f in read_log(rx_log)] == [(f.frame_id, f.data) for f in frames]
    assert diag, "no diagnosis frame came back over the configured bus"


def test_fdi_live_refuses_a_virtual_bus_and_passes_the_options_on(tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    from fdi_host.live.runner import main as live_main

    cfg = _config(tmp_path / "bus.ini", "[default]\ninterface = virtual\nchannel = x\n")
    assert live_main(["--can-config", str(cfg), "--out-dir", str(tmp_path / "out")]) == 1
    assert "virtual bus lives inside one process" in capsys.readouterr().err
    assert live_main(["--transport", "bus", "--interface", "virtual", "--out-dir", str(tmp_path / "out")]) == 1
    assert not (tmp_path / "out" / "ecu.json").exists()  # refused before starting anything


def test_fdi_live_chooses_the_bus_and_hands_it_to_the_programs(monkeypatch: pytest.MonkeyPatch,
                                                               capsys: pytest.CaptureFixture[str]) -> None:
    """Which bus each transport gives the three programs (their command lines are recorded, nothing is run)."""
    import subprocess

    from fdi_host.live import runner
    from fdi_host.live.netns import NetnsCheck

    started: list[tuple[list[str], str]] = []
    monkeypatch.setattr(runner, "run_here", lambda args, bus, label: started.append((bus, label)) or 0)
    monkeypatch.setattr(runner, "inside_private_netns", lambda: False)
    monkeypatch.setattr(runner, "check_unshare", lambda: NetnsCheck(True, "ok"))
    unshared: list[list[str]] = []
    monkeypatch.setattr(runner.subprocess, "run", lambda cmd, **kw: unshared.append(cmd)
                        or subprocess.CompletedProcess(cmd, 0))

    monkeypatch.setattr(runner, "vcan_available", lambda channel="vcan0": True)
    assert runner.main([]) == 0
    assert started.pop() == (["--interface", "socketcan", "--channel", "vcan0"], "socketcan vcan0")

    monkeypatch.setattr(runner, "vcan_available", lambda channel="vcan0": False)
    monkeypatch.setattr(bus_mod, "vcan_available", lambda channel="vcan0": False)
    assert runner.main(["--channel", "239.74.163.9"]) == 0  # re-run in a private network namespace, with a note
    assert not started and unshared and "fdi_host.live.runner" in unshared[-1]
    assert "fdi-live: no SocketCAN vcan0 (" in capsys.readouterr().err
    assert runner.main(["--transport", "current", "--channel", "239.74.163.9"]) == 0
    assert started.pop() == (["--interface", "udp_multicast", "--channel", "239.74.163.9"],
                             "udp_multicast 239.74.163.9")

    argv = ["--interface", "pcan", "--channel", "PCAN_USBBUS1", "--bitrate", "500000", "--bus-arg", "x=1"]
    assert runner.main(argv) == 0  # a bus option: that bus, the same options for every program
    assert started.pop() == (argv, "pcan PCAN_USBBUS1 (500 kbit/s) (from the command line)")
