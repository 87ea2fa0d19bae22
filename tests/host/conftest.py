"""Fixtures for the host-tool tests: the compiled plant and the CAN database (built once per session)."""

from __future__ import annotations

import pytest

from fdi_host.can.dbc import CanDatabase
from fdi_host.sim.plant import Plant
from fdi_host.sim.vehicle_sim import default_plant


@pytest.fixture(scope="session")
def plant() -> Plant:
    return default_plant()


@pytest.fixture(scope="session")
def db() -> CanDatabase:
    return CanDatabase()
