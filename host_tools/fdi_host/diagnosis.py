"""An ECU's diagnosis step by step, as arrays: what `fdi_host.diagnose` returns, for a notebook to look at, tabulate
and plot.

    d = fdi_host.diagnose(drive)            # or fdi_host.diagnose_log("drive.blf")
    d.time, d.detected, d.isolated          # per step: time on the drive's clock [s], flags
    d.candidates, d.candidate_matrix()      # per step: fault bitmask (bit j = d.faults[j]) / Booleans [step, fault]
    d.status, d.residuals, d.ratios         # per step and test (d.tests): status code (STATUS), residual, ratio
    d.to_dataframe()                        # all of it, indexed by time (pandas)
    d.plot(ax=ax); d.plot_ratios(ax=ax)     # candidates over time / test ratios against the gate (1)

A step's values are those of the ECU's result after the step (`fdi_host.ecu.bindings.EcuResult`), one entry per
diagnosis frame the ECU sends.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from fdi_analysis.tables import html_table, name_list, require_pandas
from fdi_host.ecu.bindings import TEST_STATUS_NAMES, EcuResult, TableInfo

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

STATUS: tuple[str, ...] = TEST_STATUS_NAMES  # status codes: 0 ok, 1 alarm, 2 not evaluable
_EPISODES_SHOWN = 12  # candidate episodes listed in the HTML view


def _split(label: str, sep: str) -> tuple[str, str]:
    """("MSO1", "kinematics; ...") of "MSO1: kinematics; ...", ("f1", "ax sensor") of "f1 ax sensor"."""
    name, _, rest = label.partition(sep)
    return name.strip(), rest.strip()


@dataclass(frozen=True, repr=False, eq=False)
class Diagnosis:
    """The diagnosis after every step of an ECU on table `table`. Faults and tests are named by the table
    (`faults`, `tests`; their descriptions in `fault_descriptions`, `test_descriptions`)."""

    table: str
    source: str  # what was diagnosed (a drive's label, a log file)
    faults: tuple[str, ...]
    tests: tuple[str, ...]
    fault_descriptions: tuple[str, ...]
    test_descriptions: tuple[str, ...]
    time: NDArray[np.float64]  # [step] s, the step's time (fdi_host.api: its boundary k * dt from the drive's t = 0)
    detected: NDArray[np.bool_]  # [step]
    isolated: NDArray[np.bool_]  # [step]
    candidates: NDArray[np.int64]  # [step] fault bitmask, bit j = faults[j]
    alarms: NDArray[np.int64]  # [step] test bitmask of the tests in alarm, bit i = tests[i]
    status: NDArray[np.int8]  # [step, test] index into STATUS
    residuals: NDArray[np.float64]  # [step, test]
    ratios: NDArray[np.float64]  # [step, test] residual over the test's gate (alarm beyond 1)

    @classmethod
    def from_results(cls, results: Sequence[EcuResult], table: TableInfo, source: str = "",
                     t_offset: float = 0.0) -> Diagnosis:
        """Arrays of per-step ECU results; a step's time is its ECU time (unwrapped microseconds) plus `t_offset`."""
        n, nt = len(results), table.n_tests
        t_us = np.array([r.t_us for r in results], dtype=np.int64)
        t_us += (1 << 32) * np.concatenate([[0], np.cumsum(np.diff(t_us) < 0)]).astype(np.int64)[:n]
        code = {s: k for k, s in enumerate(STATUS)}
        faults = [_split(f, " ") for f in table.fault_names]
        tests = [_split(t, ":") for t in table.test_names]
        return cls(
            table=table.name, source=source,
            faults=tuple(f for f, _ in faults), tests=tuple(t for t, _ in tests),
            fault_descriptions=tuple(d for _, d in faults), test_descriptions=tuple(d for _, d in tests),
            time=(t_us * 1e-6 + t_offset).astype(np.float64),
            detected=np.array([r.detected for r in results], dtype=bool),
            isolated=np.array([r.isolated for r in results], dtype=bool),
            candidates=np.array([r.candidates for r in results], dtype=np.int64),
            alarms=np.array([r.alarm_mask for r in results], dtype=np.int64),
            status=np.array([[code[s] for s in r.test_status] for r in results], dtype=np.int8).reshape(n, nt),
            residuals=np.array([r.residuals for r in results], dtype=np.float64).reshape(n, nt),
            ratios=np.array([r.ratios for r in results], dtype=np.float64).reshape(n, nt),
        )

    # ------------------------------------------------------------------------------------------ questions
    def __len__(self) -> int:
        return int(self.time.size)

    def candidate_matrix(self) -> NDArray[np.bool_]:
        """``[step, j]``: fault `faults[j]` is a candidate after the step."""
        bits = (self.candidates[:, None] >> np.arange(len(self.faults), dtype=np.int64)) & 1
        return np.asarray(bits == 1, dtype=bool)

    def candidate_names(self, step: int) -> tuple[str, ...]:
        """The candidate faults after step `step` (an index: -1 is the last step)."""
        mask = int(self.candidates[step])
        return tuple(f for j, f in enumerate(self.faults) if mask >> j & 1)

    def alarm_matrix(self) -> NDArray[np.bool_]:
        """``[step, i]``: test `tests[i]` is in alarm after the step."""
        return np.asarray(self.status == STATUS.index("alarm"), dtype=bool)

    @property
    def first_detection(self) -> float | None:
        """Time of the first step with a detection [s], None when there is none."""
        hit = np.flatnonzero(self.detected)
        return float(self.time[hit[0]]) if hit.size else None

    def episodes(self) -> list[tuple[float, float, tuple[str, ...]]]:
        """Runs of steps with one and the same non-empty candidate set: (first time, last time, candidates)."""
        if not len(self):
            return []
        change = np.flatnonzero(np.diff(self.candidates)) + 1
        starts = np.concatenate([[0], change])
        ends = np.concatenate([change, [len(self)]]) - 1
        return [(float(self.time[a]), float(self.time[b]), self.candidate_names(int(a)))
                for a, b in zip(starts, ends, strict=True) if self.candidates[a]]

    # ------------------------------------------------------------------------------------------ views
    def __repr__(self) -> str:
        span = f", {self.time[0]:.2f}..{self.time[-1]:.2f} s" if len(self) else ""
        first = self.first_detection
        found = ("no detection" if first is None else
                 f"detected in {int(self.detected.sum())} steps from {first:.2f} s, isolated in "
                 f"{int(self.isolated.sum())}; last candidates {name_list(self.candidate_names(-1), 6)}")
        return f"Diagnosis({self.table}: {len(self)} steps{span}, {len(self.tests)} tests; {found})"

    def _test_rows(self) -> list[list[object]]:
        alarm = self.alarm_matrix()
        rows: list[list[object]] = []
        for i in range(len(self.tests)):
            hit = np.flatnonzero(alarm[:, i])
            evaluable = self.status[:, i] != STATUS.index("not_evaluable")
            ratio = np.abs(self.ratios[evaluable, i])
            rows.append([int(hit.size), f"{self.time[hit[0]]:.2f}" if hit.size else "-",
                         float(ratio.max()) if ratio.size else "-",
                         f"{100.0 * (1.0 - evaluable.mean()):.0f}" if len(self) else "-", self.test_descriptions[i]])
        return rows

    def _repr_html_(self) -> str:
        tests = html_table(self._test_rows(), ["alarm steps", "first alarm [s]", "max |ratio|", "not evaluable [%]",
                                               "description"], self.tests, repr(self), "test")
        eps = self.episodes()
        rows: list[list[object]] = [[f"{a:.2f}", f"{b:.2f}", ", ".join(c)] for a, b, c in eps[:_EPISODES_SHOWN]]
        more = f" (first {_EPISODES_SHOWN} of {len(eps)})" if len(eps) > _EPISODES_SHOWN else ""
        runs = html_table(rows, ["from [s]", "to [s]", "candidates"], None, f"candidate faults over time{more}")
        return tests + runs

    def to_dataframe(self) -> Any:
        """Every step as a row of a pandas DataFrame indexed by time [s]; the columns have two levels:
        ``diagnosis`` (detected, isolated, candidates as text), ``candidate`` (one Boolean column per fault),
        ``status`` (per test: ok / alarm / not_evaluable), ``residual`` and ``ratio`` (per test). So
        ``df["ratio"]`` holds the test ratios with the tests as columns."""
        pd = require_pandas()
        cand = self.candidate_matrix()
        text = [", ".join(f for f, on in zip(self.faults, row, strict=True) if on) for row in cand]
        cols: dict[tuple[str, str], Any] = {
            ("diagnosis", "detected"): self.detected, ("diagnosis", "isolated"): self.isolated,
            ("diagnosis", "candidates"): text,
        }
        cols |= {("candidate", f): cand[:, j] for j, f in enumerate(self.faults)}
        cols |= {("status", t): pd.Categorical.from_codes(self.status[:, i], categories=list(STATUS))
                 for i, t in enumerate(self.tests)}
        cols |= {("residual", t): self.residuals[:, i] for i, t in enumerate(self.tests)}
        cols |= {("ratio", t): self.ratios[:, i] for i, t in enumerate(self.tests)}
        df = pd.DataFrame(cols, index=pd.Index(self.time, name="time [s]"))
        df.columns.names = ["quantity", "name"]
        return df

    # ------------------------------------------------------------------------------------------ plots
    def plot(self, ax: Axes | None = None, faults: Sequence[str] | None = None) -> Figure:
        """The candidate faults over time (a filled cell: the fault is a candidate after the step) below the detection,
        into `ax` or a new figure. `faults`: the rows (default: every fault that was a candidate, else all)."""
        from fdi_host.diagnosis_plots import plot_candidates

        cand = self.candidate_matrix()
        if faults is None:
            ever = np.flatnonzero(cand.any(axis=0))
            rows = ever.tolist() if ever.size else list(range(len(self.faults)))
        else:
            rows = self._indices(self.faults, faults, "faults")
        return plot_candidates(self.time, self.detected, cand[:, rows], [self.faults[j] for j in rows],
                               f"{self.source or self.table}: candidate faults per step", ax)

    def plot_ratios(self, ax: Axes | None = None, tests: Sequence[str] | None = None) -> Figure:
        """Per test its ratio (residual over its gate) over time, the gate at +-1 (the paper's Fig. 6), into `ax` or a
        new figure; steps where a test is not evaluable are left out. `tests`: which (default: all)."""
        from fdi_host.diagnosis_plots import plot_ratios

        cols = list(range(len(self.tests))) if tests is None else self._indices(self.tests, tests, "tests")
        evaluable = self.status[:, cols] != STATUS.index("not_evaluable")
        return plot_ratios(self.time, self.ratios[:, cols], evaluable, [self.tests[i] for i in cols],
                           f"{self.source or self.table}: test ratios (alarm beyond +-1)", ax)

    @staticmethod
    def _indices(names: Sequence[str], wanted: Sequence[str], what: str) -> list[int]:
        unknown = [w for w in wanted if w not in names]
        if unknown:
            raise ValueError(f"not {what} of the table: {unknown}; they are {', '.join(names)}")
        return [list(names).index(w) for w in wanted]
