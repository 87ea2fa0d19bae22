"""Packaging facts checked in the checkout (scripts/test_wheel.sh checks the built wheel in a clean venv): one
version for the Python and the C package, license metadata, python-sat optional, every shipped file with one
source, ``--version`` on every command line, and exit codes 1 (runtime) / 2 (usage) with one-line errors."""

from __future__ import annotations

import importlib.metadata
import json
import os
import re
import shutil
import subprocess
import sys
import tomllib
from collections.abc import Callable
from pathlib import Path

import pytest

from fdi_analysis import resources as analysis_resources
from fdi_analysis.cli.common import EXIT_ERROR, one_line
from fdi_host import resources as host_resources

REPO = Path(__file__).resolve().parents[1]
VERSION = (REPO / "VERSION").read_text(encoding="utf-8").strip()
PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))
ENTRY_POINTS: dict[str, str] = PYPROJECT["project"]["scripts"]


def _metadata(code: str) -> str:
    """Run `code` outside the checkout (its working folder could hold a stale *.egg-info)."""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd="/")
    return out.stdout.strip()


def test_one_version_for_the_python_and_the_c_package(tmp_path: Path) -> None:
    assert re.fullmatch(r"\d+\.\d+\.\d+", VERSION)
    assert "version" not in PYPROJECT["project"] and "version" in PYPROJECT["project"]["dynamic"]
    assert PYPROJECT["tool"]["setuptools"]["dynamic"]["version"] == {"file": "VERSION"}
    assert _metadata("import fdi_analysis; print(fdi_analysis.__version__)") == VERSION
    cmake = (REPO / "CMakeLists.txt").read_text(encoding="utf-8")
    assert not re.search(r"project\([^)]*VERSION\s+\d", cmake), "CMakeLists.txt writes a version of its own"
    if shutil.which("cmake") is None:
        pytest.skip("no cmake")
    subprocess.run(["cmake", "-S", str(REPO), "-B", str(tmp_path), "-DFDI_BUILD_TESTS=OFF", "-DFDI_BUILD_BENCH=OFF"],
                   check=True, capture_output=True)
    cache = (tmp_path / "CMakeCache.txt").read_text(encoding="utf-8")
    assert f"CMAKE_PROJECT_VERSION:STATIC={VERSION}\n" in cache
    assert f'set(PACKAGE_VERSION "{VERSION}")' in (tmp_path / "fw" / "fdiConfigVersion.cmake").read_text(
        encoding="utf-8")


def test_license_metadata_and_optional_python_sat() -> None:
    assert (REPO / "LICENSE").read_text(encoding="utf-8").startswith("MIT License")
    assert PYPROJECT["project"]["license"] == "MIT"
    doc = json.loads(_metadata(
        "import json, importlib.metadata as m; md = m.metadata('romo-fdi'); "
        "print(json.dumps({'license': md['License-Expression'], 'requires': m.requires('romo-fdi')}))"))
    assert doc["license"] == "MIT"
    required = [r for r in doc["requires"] if "extra ==" not in r]
    assert not [r for r in required if "dev" in r or r.startswith(("python-sat", "dask"))], required
    assert any(r.startswith("python-sat") and 'extra == "sat"' in r for r in doc["requires"])
    assert any(r.startswith("dask[distributed]") and 'extra == "fleet"' in r for r in doc["requires"])
    assert any(r.startswith("dask[distributed]") and 'extra == "dev"' in r for r in doc["requires"])


def _dist(name: str) -> str:
    """A distribution's name in normalised form (PEP 503)."""
    return re.sub(r"[-_.]+", "-", name).lower()


def _pins() -> dict[str, str]:
    """constraints.txt: distribution -> pinned version (every line `name==version`)."""
    pins: dict[str, str] = {}
    for n, line in enumerate((REPO / "constraints.txt").read_text(encoding="utf-8").splitlines(), 1):
        if line.startswith("#") or not line.strip():
            continue
        m = re.fullmatch(r"([A-Za-z0-9][A-Za-z0-9._-]*)==(\S+)", line.strip())
        assert m, f"constraints.txt:{n}: not name==version: {line!r}"
        assert _dist(m[1]) not in pins, f"constraints.txt:{n}: {m[1]} pinned twice"
        pins[_dist(m[1])] = m[2]
    return pins


def test_every_dependency_is_pinned_and_installed_at_its_pin() -> None:
    """The committed generated C and CI's results hold for one set of versions: every dependency that
    pyproject.toml declares (build, run, extras) is pinned in constraints.txt, and the environment running these
    tests has the pinned version of every pinned distribution it holds (scripts/bootstrap.sh installs them so)."""
    pins = _pins()
    declared = [*PYPROJECT["build-system"]["requires"], *PYPROJECT["project"]["dependencies"],
                *(r for extra in PYPROJECT["project"]["optional-dependencies"].values() for r in extra)]
    names = {_dist(re.split(r"[\s\[<>=!~;]", r, maxsplit=1)[0]) for r in declared}
    assert not sorted(names - set(pins)), f"declared in pyproject.toml, not pinned in constraints.txt: " \
        f"{sorted(names - set(pins))}"
    installed = {_dist(d.metadata["Name"]): d.version for d in importlib.metadata.distributions()}
    moved = {n: (v, installed[n]) for n, v in pins.items() if n in installed and installed[n] != v}
    assert not moved, f"installed versions differ from constraints.txt (pinned, installed): {moved}; " \
        "run bash scripts/bootstrap.sh"


def test_shipped_files_have_one_source_in_the_repository() -> None:
    """Each shipped folder is read from its source in a checkout, and no copy of it is kept in a package folder
    (the wheel's copies are made by the build; scripts/test_wheel.sh compares them byte for byte)."""
    data = (*analysis_resources.PACKAGE_DATA, *host_resources.PACKAGE_DATA)
    assert {d.source for d in data} == {"analysis/models", "dbc", "host_tools/scenarios", "host_tools/vehicles"}
    for d in data:
        assert d.sources(REPO), f"{d.source}: nothing to ship"
        assert d.path() == REPO / d.source
        root = REPO / ("analysis" if d.package == "fdi_analysis" else "host_tools") / d.package
        assert not (root / d.folder).exists(), f"{root / d.folder}: a copy of {d.source} in the source tree"
    from fdi_host.can.dbc import DEFAULT_DBC
    from fdi_host.sim.plant import DEFAULT_MODEL
    from fdi_host.sim.scenario import FAULT_SIZES_FILE, available

    assert DEFAULT_DBC == REPO / "dbc" / "romo.dbc" and DEFAULT_MODEL == REPO / "analysis/models/romo_quasistatic.toml"
    assert FAULT_SIZES_FILE == REPO / "host_tools/scenarios/fault_sizes.toml"
    assert {"fig6", "cornering", "straight", "slalom", "low_speed"} <= set(available())
    assert "fault_sizes" not in available()  # the file beside the scenarios is not one
    assert analysis_resources.model_file("romo_grouped") == REPO / "analysis/models/romo_grouped.toml"
    assert analysis_resources.model_file("romo_grouped.toml") == Path("romo_grouped.toml")  # a path stays a path


def _main(entry: str) -> Callable[[list[str]], int]:
    module, func = entry.split(":")
    return getattr(__import__(module, fromlist=[func]), func)  # type: ignore[no-any-return]


@pytest.mark.parametrize("name", sorted(ENTRY_POINTS))
def test_every_command_line_has_version(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        _main(ENTRY_POINTS[name])(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"{name} {VERSION}"


def _bad_inputs(tmp: Path) -> list[tuple[str, list[str], int, str]]:
    """(program, arguments, exit code, what the one error line names)."""
    (tmp / "garbage.toml").write_text("this is = = not toml\n", encoding="utf-8")
    (tmp / "binary.toml").write_bytes(b"\xff\xfe\x00 model")
    (tmp / "bad.json").write_text("{", encoding="utf-8")
    blf = tmp / "corrupt.blf"
    blf.write_bytes(b"LOGG" + os.urandom(400))
    (tmp / "free.log").write_text("", encoding="utf-8")
    (tmp / "sizes.toml").write_text("[sizes]\nf1 = 0\n", encoding="utf-8")
    (tmp / "truth.json").write_text("[1, 2", encoding="utf-8")
    (tmp / "scen.toml").write_text("[scenario\n", encoding="utf-8")
    missing = tmp / "missing.toml"
    return [
        ("fdi-analyze", ["report", str(missing)], EXIT_ERROR, "missing.toml"),
        ("fdi-analyze", ["report", str(tmp / "garbage.toml")], EXIT_ERROR, "garbage.toml"),
        ("fdi-analyze", ["mso", str(tmp / "binary.toml")], EXIT_ERROR, "binary.toml"),
        ("fdi-analyze", ["select", str(tmp / "bad.json"), "--no-progress"], EXIT_ERROR, "bad.json"),
        ("fdi-analyze", ["no-such-command"], 2, "invalid choice"),
        ("fdi-replay", [str(blf), "--offline"], EXIT_ERROR, "corrupt.blf"),
        ("fdi-replay", [str(tmp / "free.log"), "--offline"], EXIT_ERROR, "free.log"),
        ("fdi-replay", [str(tmp / "missing.blf"), str(blf)], EXIT_ERROR, "missing.blf"),
        ("fdi-replay", [str(tmp / "x.txt"), "--offline"], 2, "x.txt"),
        ("fdi-quality", ["--quick", "--sizes", str(tmp / "sizes.toml")], EXIT_ERROR, "sizes.toml"),
        ("fdi-quality", ["--quick", "--sizes", str(missing)], EXIT_ERROR, "missing.toml"),
        ("fdi-tune", ["residuals", str(missing), "--thresholds", str(missing), "--log", str(blf)], EXIT_ERROR,
         "missing.toml"),
        ("fdi-sim", ["--scenario", str(tmp / "scen.toml"), "--duration", "0.1"], EXIT_ERROR, "scen.toml"),
        ("fdi-sim", ["--scenario", "no_such_scenario", "--duration", "0.1"], 2, "no_such_scenario"),
        ("fdi-sim", ["--scenario", "fig6", "--duration", "0.2", "--out", str(tmp / "o.blf"), "--truth",
                     str(tmp / "truth.json" / "t.json"), "--quiet"], EXIT_ERROR, "truth.json"),
    ]


def test_bad_input_is_one_line_naming_the_file(tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    failures = []
    for prog, argv, code, names in _bad_inputs(tmp_path):
        try:
            got: int | str | None = _main(ENTRY_POINTS[prog])(argv)
        except SystemExit as exc:
            got = exc.code
        err = capfd.readouterr().err
        lines = [ln for ln in err.splitlines() if ": error:" in ln]  # besides: argparse's usage, progress bars
        if got != code or len(lines) != 1 or names not in lines[0] or "Traceback" in err:
            failures.append(f"{prog} {' '.join(argv)}: exit {got} (want {code}), stderr {err!r}")
    assert not failures, "\n".join(failures)


def test_one_line_folds_messages_and_names_the_file() -> None:
    assert one_line(FileNotFoundError(2, "No such file or directory", "a/b.toml")) == \
        "a/b.toml: No such file or directory"
    assert one_line(ValueError("first\n  second")) == "first second"
