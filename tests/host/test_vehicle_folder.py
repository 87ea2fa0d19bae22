"""A user's vehicle, end to end (issue 46): a folder made in a temporary directory outside the checkout from a model
that no file of the project names (two tanks with a metered outlet, its own DBC, scenario and fault sizes, all
written here), through every tool with ``--vehicle PATH``: the analysis and export (`fdi-vehicle regenerate`), the
plugin's build (`fdi-vehicle build`, CMake), a simulated faulty drive over its bus (`fdi-sim`), its replay with a
score (`fdi-replay --offline --truth`), the tuning's check (`fdi-tune calibrate --check`) and the quality suite in its
quick form (`fdi-quality --quick`). Nothing is written inside the checkout."""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from fdi_host.cli import main as sim_main
from fdi_host.ecu.bindings import Diagnoser, Ecu, table_info
from fdi_host.quality.cli import main as quality_main
from fdi_host.replay import main as replay_main
from fdi_host.tuning.cli import main as tune_main
from fdi_host.vehicle import resolve
from fdi_host.vehicle_cli import main as vehicle_main

REPO = Path(__file__).resolve().parents[2]
SKIP_DIRS = {".git", ".venv", "build", "out", "__pycache__", ".pytest_cache", ".mypy_cache", ".ruff_cache",
             ".hypothesis", ".ipynb_checkpoints"}

MODEL = """\
[model]
name = "two_tanks"
description = "Two tanks in series: a pump fills the upper one, a pipe drains it into the lower one, a metered outlet"

[parameters]
A = { value = 0.02, unit = "m^2" }
c = { value = 8.0e-5, unit = "m^2.5/s", desc = "Torricelli coefficient of a pipe" }

[[unknown]]
name = "upper"
[[unknown]]
name = "lower"
[[unknown]]
name = "d_upper"
[[unknown]]
name = "d_lower"
[[unknown]]
name = "q_in"
[[unknown]]
name = "q_mid"
[[unknown]]
name = "q_out"

[[known]]
name = "pump_cmd"
input = true
[[known]]
name = "level_up"
[[known]]
name = "level_low"
[[known]]
name = "outflow"

[[fault]]
name = "pump_loss"
[[fault]]
name = "leak_upper"
[[fault]]
name = "clog_mid"
[[fault]]
name = "level_up_offset"
[[fault]]
name = "level_low_offset"
[[fault]]
name = "meter_offset"

[[equation]]
id = "BU"
expr = "A*d_upper = q_in - q_mid - leak_upper"
[[equation]]
id = "BL"
expr = "A*d_lower = q_mid - q_out"
[[equation]]
id = "PM"
expr = "q_in = pump_cmd - pump_loss"
[[equation]]
id = "PI"
expr = "q_mid = c*(upper - lower)/sqrt(Abs(upper - lower)) - clog_mid"
not_solvable_for = ["upper", "lower"]
[[equation]]
id = "PO"
expr = "q_out = c*sqrt(Abs(lower))"
not_solvable_for = ["lower"]
[[equation]]
id = "SU"
expr = "level_up = upper + level_up_offset"
[[equation]]
id = "SL"
expr = "level_low = lower + level_low_offset"
[[equation]]
id = "SQ"
expr = "outflow = q_out + meter_offset"
[[equation]]
id = "DU"
differential = ["d_upper", "upper"]
[[equation]]
id = "DL"
differential = ["d_lower", "lower"]
"""

SCENARIO = """\
[drive]
dt = 0.01
duration = 200.0

[drive.initial]
upper = 0.4
lower = 0.2

[drive.inputs.pump_cmd]
offset = 3.6e-5
sines = [[6.0e-6, 90.0], [3.0e-6, 23.0]]

[drive.noise]
level_up = 2.0e-4
level_low = 2.0e-4
outflow = 2.0e-7

[reference]
seed = 20

[calibration]
seeds = [21, 22]
warmup = 5.0
"""

SIZES = """\
[requirement]
pump_loss = 4.0e-6
leak_upper = 4.0e-6
clog_mid = 4.0e-6
level_up_offset = 0.01
level_low_offset = 0.01
meter_offset = 4.0e-7

[limits]
pump_loss = 2.0e-5
leak_upper = 2.0e-5
clog_mid = 2.0e-5
level_up_offset = 0.05
level_low_offset = 0.05
meter_offset = 2.0e-6
"""

_MESSAGES = (  # (id, name, prefix, cycle ms, delay ms, data id, signals: (name, start, factor, max, unit))
    (256, "PumpCommand", "PMP", 10, 0, 8448, (("Flow", 16, "0.0001", "6.5535", "l/min"),)),
    (272, "Levels", "LVL", 10, 2, 8464, (("Upper", 16, "1e-05", "0.65535", "m"), ("Lower", 32, "1e-05", "0.65535",
                                                                                  "m"))),
    (288, "Outlet", "OUT", 20, 4, 8480, (("Flow", 16, "0.0001", "6.5535", "l/min"),)),
)
_MODEL_SIGNALS = {"PMP_Flow": ("pump_cmd", 60000), "LVL_Upper": ("level_up", None), "LVL_Lower": ("level_low", None),
                  "OUT_Flow": ("outflow", 60000)}


def _dbc() -> str:
    """The rig's CAN database: three E2E-protected sensor messages and the diagnosis frame of the C ECU core."""
    lines = ['VERSION "two-tanks 1"', "", "", "NS_ :", "\tCM_", "\tBA_DEF_", "\tBA_", "\tVAL_", "\tBA_DEF_DEF_", "",
             "BS_:", "", "BU_: PLANT FDI", ""]
    header = (("CRC", 0, 8, "255"), ("Counter", 8, 4, "14"), ("Status", 12, 4, "15"))
    for fid, name, pre, *_, signals in _MESSAGES:
        lines.append(f"BO_ {fid} {name}: 8 PLANT")
        lines += [f' SG_ {pre}_{s} : {start}|{n}@1+ (1,0) [0|{hi}] "" FDI' for s, start, n, hi in header]
        lines += [f' SG_ {pre}_{s} : {start}|16@1+ ({f},0) [0|{hi}] "{u}" FDI' for s, start, f, hi, u in signals]
        lines.append("")
    lines += ["BO_ 512 FDI_Diagnosis: 8 FDI",
              *(f' SG_ FDI_{s} : {start}|{n}@1+ (1,0) [0|{hi}] "" PLANT' for s, start, n, hi in header),
              ' SG_ FDI_AlarmMask : 16|12@1+ (1,0) [0|4095] "" PLANT',
              ' SG_ FDI_CandidateFaults : 28|25@1+ (1,0) [0|33554431] "" PLANT',
              ' SG_ FDI_IsolationClass : 53|8@1+ (1,0) [0|255] "" PLANT', "",
              'BA_DEF_  "BusType" STRING ;', 'BA_DEF_  "Baudrate" INT 10000 1000000;',
              'BA_DEF_ BO_  "GenMsgCycleTime" INT 0 10000;', 'BA_DEF_ BO_  "GenMsgStartDelayTime" INT 0 10000;',
              'BA_DEF_ BO_  "E2EProfile" STRING ;', 'BA_DEF_ BO_  "E2EDataID" INT 0 65535;',
              'BA_DEF_ SG_  "ModelSignal" STRING ;', 'BA_DEF_ SG_  "ModelFactor" FLOAT 0 1000000;',
              'BA_DEF_DEF_  "BusType" "CAN";', 'BA_DEF_DEF_  "Baudrate" 500000;',
              'BA_DEF_DEF_  "GenMsgCycleTime" 0;', 'BA_DEF_DEF_  "GenMsgStartDelayTime" 0;',
              'BA_DEF_DEF_  "E2EProfile" "";', 'BA_DEF_DEF_  "E2EDataID" 0;', 'BA_DEF_DEF_  "ModelSignal" "";',
              'BA_DEF_DEF_  "ModelFactor" 1;', 'BA_ "BusType" "CAN";', 'BA_ "Baudrate" 500000;']
    for fid, _, _, cycle, delay, data_id, _ in (*_MESSAGES, (512, "", "", 10, 9, 8704, ())):
        lines += [f'BA_ "GenMsgCycleTime" BO_ {fid} {cycle};', f'BA_ "GenMsgStartDelayTime" BO_ {fid} {delay};',
                  f'BA_ "E2EProfile" BO_ {fid} "P11";', f'BA_ "E2EDataID" BO_ {fid} {data_id};']
    for signal, (known, factor) in _MODEL_SIGNALS.items():
        fid = next(m[0] for m in _MESSAGES if m[2] == signal.split("_")[0])
        lines.append(f'BA_ "ModelSignal" SG_ {fid} {signal} "{known}";')
        if factor is not None:
            lines.append(f'BA_ "ModelFactor" SG_ {fid} {signal} {factor};')
    return "\n".join(lines) + "\n"


def _snapshot() -> dict[str, tuple[int, int]]:
    """Every file of the checkout (outside build and cache folders) with its size and modification time."""
    out: dict[str, tuple[int, int]] = {}
    for root, dirs, files in os.walk(REPO):
        dirs[:] = [d for d in dirs if d not in SKIP_DIRS and not d.endswith(".egg-info")]
        for f in files:
            st = (Path(root) / f).stat()
            out[os.path.relpath(Path(root) / f, REPO)] = (st.st_size, st.st_mtime_ns)
    return out


@pytest.fixture(scope="module")
def made(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """The user's files in a temporary directory; the vehicle folder is made from them in the first test."""
    if shutil.which("cmake") is None:
        pytest.fail("cmake is not installed (scripts/bootstrap.sh installs it): the plugin cannot be built")
    work = tmp_path_factory.mktemp("user")
    assert REPO not in work.parents
    src = work / "from_the_user"
    src.mkdir()
    for name, text in (("two_tanks.toml", MODEL), ("rig.dbc", _dbc()), ("drive.toml", SCENARIO),
                       ("sizes.toml", SIZES)):
        (src / name).write_text(text, encoding="utf-8")
    before = _snapshot()
    cwd = Path.cwd()
    os.chdir(work)
    try:
        yield work
    finally:
        os.chdir(cwd)
    after = _snapshot()
    changed = sorted(k for k in before.keys() | after.keys() if before.get(k) != after.get(k))
    assert not changed, f"the vehicle's tools wrote inside the checkout: {changed[:10]}"


def _ok(main: Callable[[list[str]], int], *argv: str) -> None:
    assert main(list(argv)) == 0, " ".join(argv)


def test_a_users_vehicle_through_every_tool(made: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src, car = made / "from_the_user", made / "cars" / "rig"
    _ok(vehicle_main, "new", str(car), "--model", str(src / "two_tanks.toml"), "--scenario", str(src / "drive.toml"),
        "--dbc", str(src / "rig.dbc"), "--fault-sizes", str(src / "sizes.toml"))
    v = resolve(car)
    assert (v.name, v.has_bus, v.simulator) == ("rig", True, "generic")
    _ok(vehicle_main, "regenerate", str(car))
    report = json.loads((car / "report" / "report.json").read_text(encoding="utf-8"))
    assert (report["model"], report["structural_redundancy"]) == ("two_tanks", 3)
    for f in ("fdi_rig_table.c", "fdi_rig_generators.c", "fdi_rig_plugin.c", "can/fdi_rig_bus.c"):
        assert (car / "generated" / f).is_file(), f
    assert "[generated]" in (car / "thresholds.toml").read_text(encoding="utf-8")  # calibrated on its scenario
    _ok(vehicle_main, "build", str(car))
    assert v.library.is_file()

    # the plugin: the vehicle's table and bus, by its folder
    spec = str(car)
    table = table_info(spec)
    assert table.faults == ("pump_loss", "leak_upper", "clog_mid", "level_up_offset", "level_low_offset",
                            "meter_offset")
    assert Ecu(spec).bus.names == ("PumpCommand", "Levels", "Outlet")
    assert Diagnoser(spec).table.signal_names == ("pump_cmd", "level_up", "level_low", "outflow")

    # a faulty drive of its model plant over its bus, replayed through its ECU and scored
    _ok(sim_main, "--vehicle", spec, "--fault", "level_low_offset@100s:0.01", "--duration", "150",
        "--out", "drive.blf")
    truth = json.loads(Path("drive.truth.json").read_text(encoding="utf-8"))
    assert truth["faults"][0]["fault"] == "level_low_offset" and truth["plant"].startswith("model plant of rig")
    _ok(replay_main, "drive.blf", "--offline", "--vehicle", spec, "--truth", "drive.truth.json", "--out-dir",
        "replay")
    score = json.loads(Path("replay/report.json").read_text(encoding="utf-8"))["score"]
    (fault,) = score["faults"]
    assert fault["fault"] == "level_low_offset" and fault["detected"] and fault["detection_delay"] < 0.5

    # the calibration it shipped is what the tuning computes now; the quick quality suite on its model plant
    _ok(tune_main, "calibrate", "--vehicle", spec, "--check")
    _ok(quality_main, "--vehicle", spec, "--quick", "--out", "quality")
    quality = json.loads(Path("quality/quality.json").read_text(encoding="utf-8"))
    assert quality["plant"].startswith("model plant of rig")
    assert {c["fault"] for c in quality["cases"]} | set(quality["not_covered"]) == set(table.faults)
    assert any(c["detected"] for c in quality["cases"])
    assert "Quality of rig" in capsys.readouterr().out
