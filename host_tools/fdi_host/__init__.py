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
"""

__all__: list[str] = []
