"""A vehicle is its manifest (fdi_host.vehicle): the shipped ones are found by name and their committed plugin glue
is what `fdi-vehicle glue` writes; a bad manifest or an unknown vehicle is a clear error naming the file and the key;
every host tool takes ``--vehicle NAME|PATH`` (``--table``, the former name, still parses)."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from fdi_analysis.resources import model_file
from fdi_host.ecu.bindings import Diagnoser, Ecu, EcuError, table_info
from fdi_host.vehicle import VehicleError, add_vehicle_argument, read_manifest, resolve, shipped_vehicles
from fdi_host.vehicle_cli import write_glue


@pytest.mark.parametrize("name", ["kin", "romo", "three_tank"])
def test_shipped_vehicle_glue_is_up_to_date(name: str) -> None:
    v = resolve(name)
    assert v.shipped and v.plugin.glue.is_file()
    assert write_glue(v, check=True), f"{v.plugin.glue} is stale: run fdi-vehicle glue {name}"


def test_shipped_vehicles_name_their_files() -> None:
    assert shipped_vehicles() == ["kin", "romo", "three_tank"]
    romo = resolve("romo")
    assert romo.model == model_file("romo_grouped").resolve() and romo.dbc is not None and romo.has_bus
    assert romo.simulator == "romo" and romo.plugin.params == (("d_x", "FDI_ROMO_KIN_PARAM_D_X"),
                                                               ("d_y", "FDI_ROMO_KIN_PARAM_D_Y"))
    tank = resolve("three_tank")
    assert not tank.has_bus and tank.scenario is not None and tank.simulator == "generic"
    # each plugin holds its own table: the host ECU has no list of vehicles
    assert table_info("kin").n_tests == 4 and table_info("three_tank").n_faults == 10
    assert Ecu("kin", d_x=1.25).config.diag.gen_param[0] == pytest.approx(1.25)  # the plugin names its parameters
    assert Diagnoser("three_tank").table.signal_names == ("u", "y1", "y2", "y3")
    with pytest.raises(EcuError, match="has no bus"):
        Ecu("three_tank")


def _manifest(tmp_path: Path, text: str) -> Path:
    (tmp_path / "model.toml").write_bytes(model_file("three_tank").read_bytes())
    path = tmp_path / "vehicle.toml"
    path.write_text(text, encoding="utf-8")
    return path


GOOD = 'name = "tank"\nmodel = "model.toml"\n[plugin]\ntable = "fdi_tank_table"\ntable_header = "fdi_tank_table.h"\n'


@pytest.mark.parametrize(("text", "needle"), [
    (GOOD + "colour = 1\n", "unknown key(s) ['colour']"),
    (GOOD.replace('name = "tank"', 'name = "my car"'), "name 'my car' is not a C identifier"),
    (GOOD.replace('"model.toml"', '"nosuch.toml"'), "model = 'nosuch.toml': no such file"),
    (GOOD.replace("[plugin]", 'simulator = "warp"\n[plugin]'), "simulator 'warp'"),
    (GOOD.replace('table = "fdi_tank_table"\n', ""), "table and table_header are required"),
    (GOOD + "sources = 3\n", "sources must be a list of paths"),
    (GOOD.split("[plugin]")[0], "no [plugin] table"),
    ("name = = 1\n", "not TOML"),
])
def test_a_bad_manifest_names_the_file_and_the_key(tmp_path: Path, text: str, needle: str) -> None:
    path = _manifest(tmp_path, text)
    with pytest.raises(VehicleError) as err:
        read_manifest(path)
    assert needle in str(err.value) and str(path) in str(err.value)


def test_a_vehicle_folder_is_found_by_path(tmp_path: Path) -> None:
    _manifest(tmp_path, GOOD)
    v = resolve(tmp_path)
    assert (v.name, v.folder, v.shipped) == ("tank", tmp_path.resolve(), False)
    assert v.plugin.glue == tmp_path.resolve() / "generated" / "fdi_tank_plugin.c"
    with pytest.raises(VehicleError, match="fdi-vehicle build"):
        _ = v.library  # not built yet: the message says how
    with pytest.raises(VehicleError, match="neither a shipped one"):
        resolve(tmp_path / "nosuch")


def test_the_option_takes_names_and_paths(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _manifest(tmp_path, GOOD)
    ap = argparse.ArgumentParser()
    add_vehicle_argument(ap)
    assert ap.parse_args([]).vehicle == "romo"
    assert ap.parse_args(["--vehicle", "kin"]).vehicle == "kin"
    assert ap.parse_args(["--table", "kin"]).vehicle == "kin"  # the former name
    assert ap.parse_args(["--vehicle", str(tmp_path)]).vehicle == str(tmp_path.resolve())
    with pytest.raises(SystemExit) as exc:
        ap.parse_args(["--vehicle", "nosuch"])
    assert exc.value.code == 2 and "no vehicle 'nosuch'" in capsys.readouterr().err
