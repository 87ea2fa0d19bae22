"""Host tools of the ROMO FDI project, in layers (a layer imports only the ones above it in this list, and the
structural analysis `fdi_analysis` below them all):

  sim/      the vehicle simulator built from the model file, scenarios, Table I faults, sensors
  can/      frame type, DBC, E2E, logs, a drive's CAN traffic and the ECU's view of it
  ecu/      the C ECU core through ctypes: sessions and offline replay
  tuning/   closed loop: screening, calibration, fault-size sweep, residuals on a log (``fdi-tune``)
  paper/    the paper's ARR3/ARR4 and Fig. 6
  live/     programs on a bus: sender, ``fdi-sim live``, ``fdi-ecu``, ``fdi-live``
  monitor/  scoring a run against the ground truth (``fdi-monitor``)
  quality/  the quality suite (``fdi-quality``)
  replay    recorded logs back onto a bus or through the ECU (``fdi-replay``)
  fleet     many logs through the ECU on local processes or a Dask cluster, one quality table (``fdi-replay DIR``)
  cli       ``fdi-sim``, whose subcommands span the simulator, the paper and the live bus

Beside the layers: `resources` (the shipped DBC and scenarios, in a checkout or an installed wheel).

For a notebook or a script, the API of `fdi_host.api`, loaded on first use (``import fdi_host`` stays light)::

    import fdi_host
    drive = fdi_host.simulate("fig6", faults=["f4@8s:0.5:end=14s"], duration=20)
    d = fdi_host.diagnose(drive)      # step by step: d.time, d.detected, d.candidates, d.ratios, d.to_dataframe()
    d = fdi_host.diagnose_log("drive.blf")   # a recorded CAN log (fdi_host.replay is the fdi-replay module)
"""

from __future__ import annotations

import importlib
from typing import Any

# The package root is a facade above every layer: these names come from fdi_host.api, imported when one of them is
# first used (PEP 562), so that importing a low layer (or setup.py's `from fdi_host import resources`) never loads it.
API_NAMES = ("simulate", "diagnose", "diagnose_log", "Drive", "Diagnosis")
__all__ = list(API_NAMES)


def __getattr__(name: str) -> Any:
    if name in API_NAMES:
        return getattr(importlib.import_module("fdi_host.api"), name)
    raise AttributeError(f"module 'fdi_host' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
