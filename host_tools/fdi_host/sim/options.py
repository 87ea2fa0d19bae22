"""The command-line options that define a simulated drive, shared by fdi-sim, fdi-sim live and fdi-live
(light: no simulator import, so the bus processes start fast)."""

from __future__ import annotations

import argparse

DEFAULT_SCENARIO = "fig6"


def add_drive_arguments(ap: argparse.ArgumentParser, noise: bool = True) -> None:
    """The options that define a simulated drive (read by simulate_from_args), shared by fdi-sim, fdi-sim live
    and fdi-live (which passes them on; noise=False leaves out --no-noise)."""
    ap.add_argument("--scenario", default=DEFAULT_SCENARIO,
                    help="scenario name in host_tools/scenarios or a TOML path (default fig6; for a vehicle with the "
                         "generic simulator: the vehicle's scenario)")
    ap.add_argument("--fault", action="append", default=[], metavar="SPEC", help="fault to inject (repeatable)")
    ap.add_argument("--no-scenario-faults", action="store_true", help="ignore the faults of the scenario file")
    ap.add_argument("--duration", type=float, help="override the scenario duration [s]")
    ap.add_argument("--seed", type=int, help="override the noise seed")
    ap.add_argument("--truth-vehicle", metavar="nominal|SEED", default=None,
                    help="drive the truth plant (vehicle-dynamics physics, not the diagnosis model) with the nominal "
                         "vehicle or the vehicle drawn from the envelope with this seed; default: the model plant")
    if noise:
        ap.add_argument("--no-noise", action="store_true", help="switch sensor noise off (quantisation stays)")
