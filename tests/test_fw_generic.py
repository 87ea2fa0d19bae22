"""The C library knows no vehicle: the generic core (fw/include, fw/src) and the generic ECU core (fw/ecu/include,
fw/ecu/src) name no measured signal of any model file of analysis/models and no vehicle; what names a vehicle is
generated into (or written as an example in) its own target, fw/vehicles/<vehicle>/."""

from __future__ import annotations

import re
from pathlib import Path

from fdi_analysis.model_loader import load_model

REPO = Path(__file__).resolve().parents[1]
GENERIC = ("fw/include", "fw/src", "fw/ecu/include", "fw/ecu/src")
VEHICLES = sorted(p.name for p in (REPO / "fw/vehicles").iterdir() if p.is_dir())


def _sources() -> dict[str, str]:
    return {str(p.relative_to(REPO)): p.read_text(encoding="utf-8") for d in GENERIC
            for p in sorted((REPO / d).glob("*.[ch]"))}


def _signals() -> set[str]:
    names: set[str] = set()
    for path in sorted((REPO / "analysis/models").glob("*.toml")):
        if "thresholds" in path.name:
            continue
        names |= {k.name for k in load_model(path).knowns}
    return names


def test_no_signal_of_any_model_in_the_generic_code() -> None:
    """Every measured signal of every model file, as a word (also in comments), and as a frame macro. Single
    letters (the three-tank's pump command u) are generic mathematics in a filter's equations (the input u of
    fdi_svf): for them only the macro forms are checked."""
    signals = _signals()
    assert {"vx_m", "omega4_m", "P_f_m", "y1", "u"} <= signals
    found = []
    for path, text in _sources().items():
        for s in signals:
            forms = [rf"_SIGM?_{re.escape(s.upper())}\b"] + ([rf"\b{re.escape(s)}\b"] if len(s) > 1 else [])
            if any(re.search(f, text) for f in forms):
                found.append(f"{path}: {s}")
    assert not found, found


def test_no_vehicle_in_the_generic_code() -> None:
    vehicles = [*VEHICLES, "robomobil", "kinematic"]
    assert {"romo", "three_tank"} <= set(VEHICLES)
    found = [f"{path}: {v}" for path, text in _sources().items() for v in vehicles
             if re.search(rf"\b{re.escape(v)}\b", text, flags=re.IGNORECASE)]
    found += [f"{path}: {m.group(0)}" for path, text in _sources().items()
              for m in re.finditer(r"[\w/]+\.(dbc|toml)\b", text)]  # no vehicle's DBC or model file
    assert not found, found


def test_generic_targets_build_generic_sources_only() -> None:
    """fdi::fdi is fw/src, fdi::fdi_ecu is fw/ecu/src: no generated or vehicle file joins them."""
    fw = (REPO / "fw/CMakeLists.txt").read_text(encoding="utf-8")
    core = fw.split("set(FDI_SOURCES", 1)[1].split(")", 1)[0].split()
    assert core and all(s.startswith("src/fdi_") for s in core)
    ecu = (REPO / "fw/ecu/CMakeLists.txt").read_text(encoding="utf-8")
    assert re.search(r"add_library\(fdi_ecu STATIC src/fdi_ecu\.c\)", ecu)
    lib = fw.split("add_library(fdi STATIC", 1)[1].split(")", 1)[0]
    assert lib.strip() == "${FDI_SOURCES}"
