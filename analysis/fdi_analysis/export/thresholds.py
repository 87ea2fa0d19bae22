"""The thresholds TOML file (`Thresholds`): gate, design point, the hand-written kinds' variances, the operating
envelope's definition ([envelope]: signals, votes, margin), and its generated parts, the hand-maintained part above
them kept byte for byte: the [selection] table (the tests on board, by practical isolability, written by
`fdi-analyze practical`) and, last, the [generated] table (variance per generated residual), the [observer] table
(the reference sensitivity of each observer generator's gain design) and the [envelope_limits] table (per envelope
signal, margin times the calibration drives' magnitude) and the [estimation] table (what each test's on-line estimator
follows), written by `fdi-tune calibrate`."""

from __future__ import annotations

import math
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fdi_analysis.errors import FdiError, InputError, fields_of
from fdi_analysis.residuals.generator import Generator
from fdi_analysis.residuals.observer import ObserverReference


class MissingSigmaError(FdiError, ValueError):
    """A generator of the table without a calibrated sigma in the thresholds file."""


@dataclass(frozen=True)
class Envelope:
    """The operating envelope the gates are calibrated in (fw/include/fdi_table.h): outside it when at least `votes`
    of `signals` exceed their limits (margin times the calibration drives' magnitude: their largest on the model plant,
    a high percentile on the truth-plant fleet)."""

    signals: tuple[str, ...]
    votes: int
    margin: float
    limits: dict[str, float] = field(default_factory=dict)  # written by `fdi-tune calibrate` ([envelope_limits])

    @staticmethod
    def of(doc: Mapping[str, object], limits: Mapping[str, object]) -> Envelope:
        sig = doc.get("signals")
        votes, margin = doc.get("votes"), doc.get("margin")
        if not (isinstance(sig, list) and sig and all(isinstance(x, str) for x in sig) and len(set(sig)) == len(sig)):
            raise InputError("[envelope] signals: a list of distinct signal names")
        if not (isinstance(votes, int) and 1 <= votes <= len(sig)):
            raise InputError(f"[envelope] votes: an integer 1..{len(sig)} (the number of signals)")
        if not (isinstance(margin, (int, float)) and margin >= 1.0):
            raise InputError("[envelope] margin: a number >= 1")
        lim = {str(k): float(v) for k, v in limits.items() if isinstance(v, (int, float))}
        return Envelope(tuple(sig), votes, float(margin), lim)


@dataclass(frozen=True)
class Thresholds:
    """Residual normalisation per generator kind: gate (in standard deviations) and fault-free variance."""

    design: tuple[float, float, float, float]  # dt, cutoff_hz, zeta, obs_gain
    gate: float
    variance: dict[str, float]
    source: str
    generated: dict[str, float] = field(default_factory=dict)  # by MSO equation set (space separated)
    selection: tuple[str, ...] = ()  # equation sets of the practical selection ([selection]); () = structural
    observer: dict[str, float] = field(default_factory=dict)  # c_ref of the observer generators ([observer])
    envelope: Envelope | None = None  # [envelope] with its calibrated [envelope_limits]; None: no envelope
    # [estimation]: by equation set, the groups of uncertain quantities the diagnoser may estimate on line for the
    # test (fdi_analysis.residuals.estimation: one name, or several entering as one offset)
    estimation: dict[str, tuple[tuple[str, ...], ...]] = field(default_factory=dict)
    # [design] max_tyre_accel [m/s^2]: the tyre-law tests' domain, |(ax_m, ay_m)| <= this (0: no limit;
    # Generator.max_accel)
    max_tyre_accel: float = 0.0

    @staticmethod
    def load(path: Path) -> Thresholds:
        """The thresholds file at `path`; an `InputError` naming the file for a file that is not TOML, lacks a
        required table or key, or holds a value of the wrong type."""
        try:
            doc = tomllib.loads(path.read_text(encoding="utf-8"))
        except tomllib.TOMLDecodeError as exc:
            raise InputError(f"{path}: not a TOML file: {exc}") from exc
        except (OSError, UnicodeDecodeError) as exc:
            raise InputError(f"{path}: cannot read: {exc}") from exc
        with fields_of(path, InputError):
            return Thresholds._of(doc, path)

    @staticmethod
    def _of(doc: dict[str, Any], path: Path) -> Thresholds:
        d = doc["design"]
        return Thresholds(
            design=(float(d["dt"]), float(d["cutoff_hz"]), float(d["zeta"]), float(d["obs_gain"])),
            gate=float(doc["gate"]),
            variance={str(k): float(v) for k, v in doc["variance"].items()},
            source=str(path),
            generated={str(k): float(v) for k, v in doc.get("generated", {}).items()},
            selection=tuple(str(t) for t in doc.get("selection", {}).get("tests", [])),
            observer={str(k): float(v) for k, v in doc.get("observer", {}).items()},
            envelope=(Envelope.of(doc["envelope"], doc.get("envelope_limits", {})) if "envelope" in doc else None),
            estimation=_estimation(doc.get("estimation", {}), path),
            max_tyre_accel=float(d.get("max_tyre_accel", 0.0)),
        )

    def sigmas(self, generators: Sequence[Generator]) -> list[float]:
        """The calibrated fault-free standard deviation of each generator ([generated], by its equation set);
        `MissingSigmaError` names the generators without one."""
        missing = [g.name for g in generators if " ".join(g.equations) not in self.generated]
        if missing:
            raise MissingSigmaError(f"{self.source} has no calibrated sigma for {', '.join(missing)}; run "
                                    "fdi-tune calibrate")
        return [math.sqrt(self.generated[" ".join(g.equations)]) for g in generators]

    def observer_reference(self) -> ObserverReference:
        """The reference of the observer generators' gain design: the [observer] table's c_ref values."""
        return ObserverReference(c_ref=self.observer)


def _estimation(raw: object, path: Path) -> dict[str, tuple[tuple[str, ...], ...]]:
    if not isinstance(raw, dict):
        raise InputError(f"{path}: [estimation] must be a table")
    out: dict[str, tuple[tuple[str, ...], ...]] = {}
    for eqs, groups in raw.items():
        if not (isinstance(groups, list) and all(isinstance(g, str) and g.split() for g in groups)):
            raise InputError(f"{path}: [estimation] '{eqs}': a list of quantity names (several in one string: one "
                             "offset)")
        out[" ".join(str(eqs).split())] = tuple(tuple(g.split()) for g in groups)
    return out


MARKER = "# ---- generated residuals: written by `fdi-tune calibrate`, do not edit below ----"
SELECTION_MARKER = "# ---- the tests on board, by practical isolability: written by `fdi-analyze practical` ----"


def with_generated(text: str, rows: Sequence[tuple[str, float, str]], provenance: str,
                   observer: Sequence[tuple[str, float, str]] = (),
                   envelope: Sequence[tuple[str, float, str]] = (),
                   estimation: Sequence[tuple[str, Sequence[Sequence[str]], str]] = ()) -> str:
    """The file's text with its [generated] table (rows: equation set, variance, comment), its [observer]
    table (equation set, c_ref, comment), its [envelope_limits] table (signal, limit, comment) and its [estimation]
    table (equation set, groups of quantity names, comment) replaced."""
    head = text.split(MARKER)[0].rstrip("\n") + "\n\n"
    lines = [MARKER, f"# {provenance}"]

    def table(name: str, entries: Sequence[tuple[str, float, str]], key: Callable[[str], str], digits: str) -> None:
        lines.append(f"[{name}]")
        for k, value, comment in entries:
            lines.extend([f"# {comment}", f"{key(k)} = {value:{digits}}"])

    table("generated", rows, lambda eqs: f'"{eqs}"', ".4g")
    if observer:
        lines += ["", "# reference sensitivity c_ref = RMS of d r / d x on the reference drive (3 significant digits) "
                  "of each observer generator: its gain's regularisation eps = (0.1 c_ref)^2"]
        table("observer", observer, lambda eqs: f'"{eqs}"', ".3g")
    if envelope:
        lines += ["", "# the operating envelope's limits ([envelope]): margin x the calibration drives' magnitude (3 "
                  "significant digits; how, per signal below)"]
        table("envelope_limits", envelope, str, ".3g")
    if estimation:
        lines += ["", "# the quantities each test's on-line estimator follows (fw/include/fdi_est.h; several names "
                  "in one string: one offset)", "[estimation]"]
        for eqs, groups, comment in estimation:
            names = ", ".join('"' + " ".join(g) + '"' for g in groups)
            lines.extend([f"# {comment}", f'"{eqs}" = [{names}]'])
    return head + "\n".join(lines) + "\n"


def with_selection(text: str, tests: Sequence[tuple[str, str]], provenance: str) -> str:
    """The file's text with its [selection] table replaced (just above the generated tables, which are kept);
    tests: (equation set, comment)."""
    hand, _, generated = text.partition(MARKER)
    head = hand.split(SELECTION_MARKER)[0].rstrip("\n") + "\n\n"
    lines = [SELECTION_MARKER, *(f"# {p}" for p in provenance.splitlines()), "[selection]", "tests = ["]
    for eqs, comment in tests:
        lines.append(f"    # {comment}")
        lines.append(f'    "{eqs}",')
    lines.append("]")
    tail = ("\n" + MARKER + generated) if generated or MARKER in text else ""
    return head + "\n".join(lines) + "\n" + tail
