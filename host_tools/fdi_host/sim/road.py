"""The road of a drive: grade and bank along the route, and the friction of road patches (wet, split friction).

Read from a scenario's ``[road]`` table (the model plant ignores it: its model has no road)::

    [road]
    grade = { s = [0, 150, 300], value = [0.0, 0.06, -0.04] }   # tan of the slope along the travel, uphill +
    bank = { s = [0, 200], value = [0.0, 0.03] }                 # tan of the slope across, left side higher +

    [[road.patch]]          # friction of a stretch, as a share of the vehicle's dry peak friction
    start = 120.0           # m of distance travelled
    end = 160.0
    mu = 0.6
    side = "both"           # both | left | right (split friction)

Distance is the path length the vehicle has travelled (grade and bank are met along the path, whatever the
vehicle's heading). Between the points of ``s`` grade and bank are linear, beyond them constant.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fdi_host.errors import FdiHostError

FloatArray = NDArray[np.float64]
SIDES = ("both", "left", "right")


class RoadError(FdiHostError, ValueError):
    """A [road] table that is not well formed."""


@dataclass(frozen=True)
class Patch:
    start: float
    end: float
    mu: float
    side: str = "both"


@dataclass(frozen=True)
class Road:
    grade_s: tuple[float, ...] = (0.0,)
    grade: tuple[float, ...] = (0.0,)
    bank_s: tuple[float, ...] = (0.0,)
    bank: tuple[float, ...] = (0.0,)
    patches: tuple[Patch, ...] = ()

    @property
    def flat(self) -> bool:
        return not any(self.grade) and not any(self.bank) and not self.patches

    def arrays(self) -> tuple[FloatArray, ...]:
        """(grade_s, grade, bank_s, bank, patch_start, patch_end, patch_mu_left, patch_mu_right) for the
        compiled plant."""
        ps = np.array([p.start for p in self.patches], dtype=np.float64)
        pe = np.array([p.end for p in self.patches], dtype=np.float64)
        ml = np.array([p.mu if p.side in ("both", "left") else 1.0 for p in self.patches], dtype=np.float64)
        mr = np.array([p.mu if p.side in ("both", "right") else 1.0 for p in self.patches], dtype=np.float64)
        return (np.asarray(self.grade_s, dtype=np.float64), np.asarray(self.grade, dtype=np.float64),
                np.asarray(self.bank_s, dtype=np.float64), np.asarray(self.bank, dtype=np.float64), ps, pe, ml, mr)

    def at(self, s: float) -> tuple[float, float, float, float]:
        """(grade, bank, friction share left, right) at distance `s`."""
        mu_l = mu_r = 1.0
        for p in self.patches:
            if p.start <= s < p.end:
                mu_l *= p.mu if p.side in ("both", "left") else 1.0
                mu_r *= p.mu if p.side in ("both", "right") else 1.0
        return (float(np.interp(s, self.grade_s, self.grade)), float(np.interp(s, self.bank_s, self.bank)),
                mu_l, mu_r)


def _profile(doc: Any, what: str, where: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
    if not isinstance(doc, Mapping) or set(doc) != {"s", "value"}:
        raise RoadError(f"{where}: road.{what} needs exactly 's' and 'value' lists")
    try:
        s = tuple(float(x) for x in doc["s"])
        v = tuple(float(x) for x in doc["value"])
    except (TypeError, ValueError) as exc:
        raise RoadError(f"{where}: road.{what}: 's' and 'value' must be lists of numbers") from exc
    if not s or len(s) != len(v) or any(b <= a for a, b in itertools.pairwise(s)):
        raise RoadError(f"{where}: road.{what} needs increasing 's' and as many values")
    if any(abs(x) > 0.3 for x in v):
        raise RoadError(f"{where}: road.{what} beyond 30 % ({max(v, key=abs)}): a road, not a wall")
    return s, v


def road_from_dict(doc: Mapping[str, Any] | None, where: str) -> Road:
    """The [road] table of a scenario (None: a flat dry road)."""
    if not doc:
        return Road()
    unknown = set(doc) - {"grade", "bank", "patch"}
    if unknown:
        raise RoadError(f"{where}: unknown keys {sorted(unknown)} in [road] (grade, bank, patch)")
    gs, g = _profile(doc["grade"], "grade", where) if "grade" in doc else ((0.0,), (0.0,))
    bs, b = _profile(doc["bank"], "bank", where) if "bank" in doc else ((0.0,), (0.0,))
    patches = []
    for k, tab in enumerate(doc.get("patch", [])):
        if not isinstance(tab, Mapping) or not {"start", "end", "mu"} <= set(tab) or set(tab) - {
                "start", "end", "mu", "side"}:
            raise RoadError(f"{where}: road.patch {k + 1} needs start, end, mu (and optionally side)")
        p = Patch(float(tab["start"]), float(tab["end"]), float(tab["mu"]), str(tab.get("side", "both")))
        if p.end <= p.start or not 0.05 <= p.mu <= 1.5 or p.side not in SIDES:
            raise RoadError(f"{where}: road.patch {k + 1}: needs end > start, 0.05 <= mu <= 1.5, side in {SIDES}")
        patches.append(p)
    return Road(gs, g, bs, b, tuple(patches))
