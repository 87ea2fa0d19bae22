"""The C header of the hand-written kinematic table's calibration (fw/vehicles/romo/generated/fdi_kin_calibration.h):
its residual variances and reaction sizes, rendered from what `fdi_host.tuning.kin_calibration` measures on
simulated drives. The numbers come from there; the text, like every generated file's, from the templates here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from string import Template

from fdi_analysis.export.c_text import banner, comment_text


@dataclass(frozen=True)
class KinTest:
    """One kinematic test's calibration: its label, the fault-free residual's statistics, the calibrated sigma and
    variance, the synthetic manoeuvre's variance and the variance written (the larger)."""

    label: str
    rms: float
    peak: float
    sigma: float
    measured_variance: float
    synthetic_variance: float
    variance: float


@dataclass(frozen=True)
class KinCalibrationFile:
    """Everything fdi_kin_calibration.h states: the command that made it, how (gate, margins, drives, seeds), the
    tests and per fault (by name) the reaction size of each test."""

    command: str
    gate: float
    margin: float
    scenarios: tuple[str, ...]
    seeds: tuple[int, ...]
    tests: tuple[KinTest, ...]
    faults: tuple[str, ...]
    sizes: tuple[tuple[float, ...], ...]  # row per fault, column per test
    window_s: float
    size_seeds: tuple[int, ...]
    exoneration_margin: float


HEADER_FMT = Template("""\
${banner}
/*
 * fdi_kin_calibration.h - residual variances and reaction sizes of the kinematic table (fdi_kin_table.c).
 * Variances:
 * the smallest sigma with no raw alarm (gate ${gate} sigma, CUSUM k 1.5, h 150) in any fault-free drive
 * (${scenarios}; noise seeds ${seeds}; simulator host_tools/fdi_host,
 * through the C ECU core), times ${margin}; at least the variance measured on the synthetic manoeuvre
 * of the C unit tests (tests/fw/fdi_test_vehicle.h), so that the table holds in both environments.
 */
#ifndef FDI_KIN_CALIBRATION_H
#define FDI_KIN_CALIBRATION_H

${variances}

/* Reaction sizes, row fault j, column test i (fdi_table.h test_size): the size of fault j (its unit) at
 * which test i alarms within ${window} s of a step in the cornering drive (seeds ${size_seeds}), the grid value
 * above the first alarm; 0: no alarm up to the fault's limit in host_tools/scenarios/fault_sizes.toml. */
#define FDI_KIN_TEST_SIZES \\
    { \\
${size_rows}
    }
#define FDI_KIN_EXONERATION_MARGIN ${exoneration_margin}f

#endif /* FDI_KIN_CALIBRATION_H */
""")

VARIANCE_FMT = Template("""\
/* ${label}: simulator fault-free RMS ${rms}, peak ${peak}, calibrated sigma ${sigma} (variance ${measured}); \
synthetic manoeuvre variance ${synthetic} */
#define FDI_KIN_VARIANCE_${number} ${variance}f""")

SIZE_ROW_FMT = Template("        ${values}, /* ${fault} */ \\")


def _float(x: float) -> str:
    """The shortest text that reads back as the same double (the header's literals round-trip)."""
    return repr(float(x))


def render(f: KinCalibrationFile) -> str:
    """The text of fdi_kin_calibration.h."""
    if len(f.sizes) != len(f.faults) or any(len(row) != len(f.tests) for row in f.sizes):
        raise ValueError(f"reaction sizes: {len(f.sizes)} rows for {len(f.faults)} faults, each with one size per "
                         f"test ({len(f.tests)})")
    variances = "\n".join(VARIANCE_FMT.substitute(
        label=comment_text(t.label), rms=f"{t.rms:.3g}", peak=f"{t.peak:.3g}", sigma=f"{t.sigma:.3g}",
        measured=f"{t.measured_variance:.3g}", synthetic=f"{t.synthetic_variance:.3g}", number=i + 1,
        variance=_float(t.variance)) for i, t in enumerate(f.tests))
    rows = "\n".join(SIZE_ROW_FMT.substitute(values=", ".join(f"{_float(x)}f" for x in row), fault=comment_text(fault))
                     for fault, row in zip(f.faults, f.sizes, strict=True))
    return HEADER_FMT.substitute(
        banner=banner(f.command), gate=f"{f.gate:g}", scenarios=", ".join(f.scenarios),
        seeds=", ".join(map(str, f.seeds)), margin=f"{f.margin:g}", variances=variances, window=f"{f.window_s:g}",
        size_seeds=", ".join(map(str, f.size_seeds)), size_rows=rows,
        exoneration_margin=_float(f.exoneration_margin))


def labels_of(names: Sequence[str]) -> tuple[str, ...]:
    """The labels of the table's test names ("MSO1: ..." -> "MSO1")."""
    return tuple(n.split(":")[0] for n in names)
