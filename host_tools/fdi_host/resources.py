"""The host tools' shipped files: the CAN database and the drive scenarios (with the fault-size file), found in
an installed wheel through `importlib.resources` and in a checkout at their source folders (see
`fdi_analysis.resources`, which also ships the model files). Standard library only: setup.py imports it."""

from __future__ import annotations

from fdi_analysis.resources import DataDir

DBC = DataDir("fdi_host", "data/dbc", "dbc", "*.dbc")
SCENARIOS = DataDir("fdi_host", "data/scenarios", "host_tools/scenarios", "*.toml")
VEHICLES = DataDir("fdi_host", "data/vehicles", "host_tools/vehicles", "*.toml")  # the shipped vehicles' manifests
PACKAGE_DATA: tuple[DataDir, ...] = (DBC, SCENARIOS, VEHICLES)
