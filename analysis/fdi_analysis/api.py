"""The analysis as one object for a notebook or a script: a diagnosis model and what can be asked of it.

    import fdi_analysis as fa
    m = fa.DiagnosisModel.load("romo_grouped")        # a shipped model by name, a TOML model, an FDT JSON file
    m = fa.DiagnosisModel.from_matrices(X, F, Z)       # or incidence matrices (FDT convention for X: 0/1/2/3)
    m.dm().redundancy                                  # Dulmage-Mendelsohn decomposition, with names
    for t in m.msos(): ...                             # every MSO set, streamed (constant memory)
    m.mtes()                                           # minimal test equation supports
    iso = m.isolability(); iso.plot(ax=ax)             # single-fault isolability, drawn into the caller's Axes
    iso.one_way_pairs()                                # (a, b): a not isolable from b, b isolable from a
    sel = m.select(method="B"); sel.plot(ax=ax)        # optimal test selection (paper Fig. 5 for the plot)
    sel.to_dataframe(), m.fault_matrix_frame(sel.tests) # labelled pandas tables (the `notebook` extra)
    m.export_c("out/gen", thresholds="romo_thresholds") # the firmware's C table and residual generators

For Fault Diagnosis Toolbox users: ``model.MSO()`` is `DiagnosisModel.msos`, ``model.MTES()`` `mtes`,
``model.IsolabilityAnalysis(ax=...)`` ``isolability().plot(ax=...)``, ``model.PlotDM()`` `plot_dm`.

Every method returns a frozen dataclass (names, not indices, where a person reads them); the objects of the
underlying modules stay reachable (`DiagnosisModel.model`, `.structure`, `TestSelection.selection`) for code
that needs them. Plots never choose a backend: they draw into ``ax`` when given, else into a new figure, and
return the figure. In a notebook every result shows as a labelled HTML table (``_repr_html_``) and prints as a line
or two (``repr``); ``to_dataframe()`` and the ``*_frame`` methods give pandas DataFrames with the names as labels
(pandas: ``pip install 'romo-fdi[notebook]'``).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import numpy.typing as npt

from fdi_analysis import mso
from fdi_analysis.dm import DMResult, dulmage_mendelsohn
from fdi_analysis.errors import FdiError
from fdi_analysis.fault_matrix import Candidate, Method, signature_matrix
from fdi_analysis.isolability import IsolabilityResult
from fdi_analysis.model import Model
from fdi_analysis.model_loader import load_model, model_from_structure
from fdi_analysis.resources import model_file, thresholds_file
from fdi_analysis.selection import Selection, greedy
from fdi_analysis.selection import optimal as optimal_selection
from fdi_analysis.structure import Structure
from fdi_analysis.summary import Summary, summarize
from fdi_analysis.tables import NO_FAULT, html_table, matrix_frame, matrix_html, name_list, require_pandas

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


class ApiError(FdiError, ValueError):
    """A question the model cannot answer (e.g. C export of a structure-only model)."""


@dataclass(frozen=True)
class Decomposition:
    """The Dulmage-Mendelsohn decomposition by name: the overdetermined part M+ (where residuals come from), the
    just-determined blocks of M0 in solving order, the underdetermined part M-."""

    overdetermined: tuple[str, ...]  # equations of M+
    overdetermined_unknowns: tuple[str, ...]
    just_determined: tuple[tuple[tuple[str, ...], tuple[str, ...]], ...]  # (equations, unknowns) per block
    underdetermined: tuple[str, ...]  # equations of M-
    underdetermined_unknowns: tuple[str, ...]
    redundancy: int  # |M+| - |var(M+)|
    result: DMResult  # the same by index into the structure

    def _parts(self) -> list[tuple[str, tuple[str, ...], tuple[str, ...]]]:
        zero_eqs = tuple(e for eqs, _ in self.just_determined for e in eqs)
        zero_vars = tuple(v for _, vs in self.just_determined for v in vs)
        return [("M+ (overdetermined)", self.overdetermined, self.overdetermined_unknowns),
                (f"M0 (just-determined, {len(self.just_determined)} blocks)", zero_eqs, zero_vars),
                ("M- (underdetermined)", self.underdetermined, self.underdetermined_unknowns)]

    def __repr__(self) -> str:
        return (f"Decomposition(M+: {len(self.overdetermined)} equations, {len(self.overdetermined_unknowns)} "
                f"unknowns, redundancy {self.redundancy}; M0: {len(self.just_determined)} blocks; M-: "
                f"{len(self.underdetermined)} equations)")

    def _repr_html_(self) -> str:
        rows = [[len(e), len(v), name_list(e, 12, "-"), name_list(v, 12, "-")] for _, e, v in self._parts()]
        return html_table(rows, ["equations", "unknowns", "equation names", "unknown names"],
                          [p for p, _, _ in self._parts()],
                          f"Dulmage-Mendelsohn decomposition: structural redundancy {self.redundancy}", "part")


@dataclass(frozen=True)
class TestSet:
    """A set of equations a test (residual) can be built from, with the faults it reacts to. `cost` is its
    number of unknowns where known (MSO sets: equations - 1), `label` its name in a selection (MSO6)."""

    equations: tuple[str, ...]
    faults: tuple[str, ...]
    mask: int  # bit i = equation i of the structure
    cost: int = -1
    label: str = ""

    def __repr__(self) -> str:
        cost = f", cost {self.cost}" if self.cost >= 0 else ""
        return (f"TestSet({self.label + ': ' if self.label else ''}{len(self.equations)} equations{cost}; faults "
                f"{name_list(self.faults, 8)})")


@dataclass(frozen=True)
class IsolabilityAnalysis:
    """Structural single-fault detectability and isolability: ``isolable[i, j]`` says fault i can be told apart
    from fault j; `classes` are the groups of mutually non-isolable detectable faults."""

    faults: tuple[str, ...]
    detectable: tuple[str, ...]
    not_detectable: tuple[str, ...]
    classes: tuple[tuple[str, ...], ...]
    isolable: npt.NDArray[np.bool_]
    summary: Summary

    def non_isolable_pairs(self) -> list[tuple[str, str]]:
        """Pairs of detectable faults that cannot be isolated from each other in either direction (each pair once)."""
        return [(self.faults[i], self.faults[j]) for i, j in self.summary.isolability.non_isolable_pairs()]

    def one_way_pairs(self) -> list[tuple[str, str]]:
        """Pairs (a, b) of detectable faults isolable one way only: a cannot be isolated from b, but b can be
        isolated from a (``isolable[a, b]`` false, ``isolable[b, a]`` true). When a occurs, b stays a candidate."""
        return [(self.faults[i], self.faults[j]) for i, j in self.summary.isolability.one_way_pairs()]

    def __repr__(self) -> str:
        both, one = len(self.non_isolable_pairs()), len(self.one_way_pairs())
        return (f"IsolabilityAnalysis({len(self.faults)} faults, {len(self.detectable)} detectable, "
                f"{len(self.classes)} classes; {both} pair{'' if both == 1 else 's'} not isolable, {one} "
                f"pair{'' if one == 1 else 's'} isolable one way only)")

    def _repr_html_(self) -> str:
        caption = (f"{self.summary.model.name}: fault in the row cannot be isolated from the fault in the column "
                   f"(●). {len(self.detectable)} of {len(self.faults)} detectable; not detectable: "
                   f"{name_list(self.not_detectable, 10)}; isolable one way only: "
                   f"{name_list([f'{a} -> {b}' for a, b in self.one_way_pairs()], 10)}")
        return matrix_html(~self.isolable, self.faults, self.faults, caption, "fault \\ from", diagonal="-")

    def to_dataframe(self) -> Any:
        """``isolable`` as a pandas DataFrame: rows and columns are the faults; True where the row fault can be
        isolated from the column fault."""
        return matrix_frame(self.isolable, self.faults, self.faults, "fault", "isolable from")

    def plot(self, ax: Axes | None = None) -> Figure:
        """The isolability matrix (filled: row fault not isolable from column fault) into `ax` or a new figure."""
        from fdi_analysis.plots import plot_isolability

        return plot_isolability(self.summary, ax=ax)


@dataclass(frozen=True)
class MsoAnalysis:
    """What `DiagnosisModel.mso_summary` found, without the sets: their number, sizes and fault signatures (one entry
    per signature: how many MSO sets have it and the smallest of them), by name. `summary` is the
    `fdi_analysis.mso.MsoSummary` it comes from."""

    model: str
    faults: tuple[str, ...]
    count: int
    by_equations: dict[int, int]  # MSO sets with k equations
    signatures: tuple[mso.SignatureEntry, ...]
    complete: bool
    elapsed_s: float
    summary: mso.MsoSummary

    @property
    def by_unknowns(self) -> dict[int, int]:
        return self.summary.by_unknowns

    def signature_faults(self, entry: mso.SignatureEntry) -> tuple[str, ...]:
        """The faults of a signature entry by name."""
        return tuple(self.faults[k] for k in mso.bits(entry.faults))

    def __repr__(self) -> str:
        sizes = f", {min(self.by_equations)}..{max(self.by_equations)} equations" if self.by_equations else ""
        return (f"MsoAnalysis({self.model!r}: {self.count:,} MSO sets{sizes}, {len(self.signatures):,} fault "
                f"signatures{'' if self.complete else ', INCOMPLETE'})")

    def _repr_html_(self) -> str:
        sizes = sorted(self.by_equations)
        rows = [[k, k - 1, self.by_equations[k]] for k in sizes]
        caption = (f"{self.model}: {self.count:,} MSO sets with {len(self.signatures):,} distinct fault signatures "
                   f"({'complete' if self.complete else 'interrupted: partial counts'}, {self.elapsed_s:.2f} s)")
        return html_table(rows, ["equations", "unknowns", "MSO sets"], None, caption)

    def to_dataframe(self) -> Any:
        """One row per fault signature: its MSO sets' count, the size of the smallest, and one Boolean column per
        fault (True: the signature's tests react to it), most frequent signatures first."""
        pd = require_pandas()
        order = sorted(self.signatures, key=lambda e: (-e.count, e.smallest_size, e.faults))
        cols = {"MSO sets": [e.count for e in order], "smallest (equations)": [e.smallest_size for e in order]}
        cols |= {f: [bool(e.faults >> k & 1) for e in order] for k, f in enumerate(self.faults)}
        return pd.DataFrame(cols, index=pd.Index([", ".join(self.signature_faults(e)) for e in order],
                                                 name="signature"))


@dataclass(frozen=True)
class TestSelection:
    """A minimal set of tests reaching the isolability of all candidates under `method` (A: a signature
    contained in another confuses, B: only identical ones). `proven`: count and cost shown minimal."""

    method: Method
    kind: str  # "optimal" or "greedy"
    tests: tuple[TestSet, ...]
    cost: int  # total unknowns
    proven: bool
    candidates: int  # how many candidate tests (one per fault signature) it chose from
    faults: tuple[str, ...]
    selection: Selection  # what fdi_analysis.selection returned, by index

    @property
    def labels(self) -> tuple[str, ...]:
        """The tests' names (``MSO6``; ``t1``, ``t2``, ... where a test has none)."""
        return tuple(t.label or f"t{k + 1}" for k, t in enumerate(self.tests))

    def signature_matrix(self) -> npt.NDArray[np.bool_]:
        """``[t, k]``: selected test t reacts to fault k."""
        return np.array([[f in t.faults for f in self.faults] for t in self.tests], dtype=bool).reshape(
            len(self.tests), len(self.faults))

    def fault_matrix(self) -> npt.NDArray[np.bool_]:
        """The paper's fault matrix of the selected tests under the selection's method (row = occurred fault,
        column = diagnosed; index 0 = no fault, then the faults): `fault_matrix_frame` labels it."""
        from fdi_analysis.fault_matrix import fault_matrix

        fi = {f: k for k, f in enumerate(self.faults)}
        return fault_matrix([mso.to_mask([fi[f] for f in t.faults]) for t in self.tests], len(self.faults),
                            self.method)

    def fault_matrix_frame(self) -> Any:
        """`fault_matrix` as a pandas DataFrame labelled by fault, the fault-free case as ``(no fault)``."""
        labels = (NO_FAULT, *self.faults)
        return matrix_frame(self.fault_matrix(), labels, labels, "occurred", "diagnosed as")

    def to_dataframe(self) -> Any:
        """The selection's signature matrix as a pandas DataFrame: a row per test (its label), a column per fault;
        True where the test reacts to the fault."""
        return matrix_frame(self.signature_matrix(), self.labels, self.faults, "test", "fault")

    def __repr__(self) -> str:
        return (f"TestSelection({self.kind}, method {self.method}: {len(self.tests)} tests "
                f"({name_list(self.labels, 8)}), cost {self.cost}, {'proven' if self.proven else 'not proven'} "
                f"minimal, from {self.candidates} candidates)")

    def _repr_html_(self) -> str:
        fsm = self.signature_matrix()
        rows = [[t.cost, len(t.equations), *fsm[k]] for k, t in enumerate(self.tests)]
        caption = (f"{self.kind} selection, method {self.method}: {len(self.tests)} tests, cost {self.cost} unknowns "
                   f"({'proven' if self.proven else 'not proven'} minimal, {self.candidates} candidates); ● = the "
                   "test reacts to the fault")
        return html_table(rows, ["cost", "equations", *self.faults], self.labels, caption, "test")

    def plot(self, ax: Axes | None = None) -> Figure:
        """Faults per selected test (the paper's Fig. 5) into `ax` or a new figure."""
        from fdi_analysis.plots import plot_selected_faults

        return plot_selected_faults(self.signature_matrix(), self.faults, list(self.labels),
                                    f"{self.kind} selection, method {self.method}", ax=ax)


@dataclass(frozen=True)
class ExportResult:
    """The files `DiagnosisModel.export_c` wrote (table and residual generators) and the table's C name."""

    files: tuple[Path, ...]
    name: str


class DiagnosisModel:
    """A diagnosis model: equations over unknowns, known signals and faults (from a TOML model file, an FDT
    structure, or incidence matrices) and the structural analysis of it."""

    def __init__(self, model: Model) -> None:
        self.model = model

    # ------------------------------------------------------------------------------------- construction
    @classmethod
    def load(cls, path: str | Path) -> DiagnosisModel:
        """A model file (``.toml``), an FDT structure (``.json``, X/F/Z), or the name of a shipped model
        (``romo_quasistatic``, ``romo_grouped``, ``romo_full_vertical``, ``three_tank``)."""
        return cls(load_model(model_file(path)))

    @classmethod
    def from_matrices(cls, X: npt.ArrayLike, F: npt.ArrayLike, Z: npt.ArrayLike | None = None, *,
                      equations: Sequence[str] | None = None, unknowns: Sequence[str] | None = None,
                      faults: Sequence[str] | None = None, knowns: Sequence[str] | None = None,
                      name: str = "structure") -> DiagnosisModel:
        """A structure-only model from incidence matrices (rows = equations): X over unknowns (FDT convention:
        1 incidence, in a differential constraint 3 the derivative and 2 the integrated variable), F over
        faults, Z over known signals (optional). Names default to e1.., x1.., f1.., z1..."""
        x = np.asarray(X, dtype=np.int8)
        f = np.asarray(F, dtype=np.int8)
        if x.ndim != 2 or f.ndim != 2:
            raise ApiError(f"X and F must be matrices, got shapes {x.shape} and {f.shape}")
        z = np.zeros((x.shape[0], 0), dtype=np.int8) if Z is None else np.asarray(Z, dtype=np.int8)
        ne = x.shape[0]
        st = Structure(
            equations=tuple(equations) if equations is not None else tuple(f"e{i + 1}" for i in range(ne)),
            unknowns=tuple(unknowns) if unknowns is not None else tuple(f"x{i + 1}" for i in range(x.shape[1])),
            knowns=tuple(knowns) if knowns is not None else tuple(f"z{i + 1}" for i in range(z.shape[1])),
            faults=tuple(faults) if faults is not None else tuple(f"f{i + 1}" for i in range(f.shape[1])),
            X=x, F=f, Z=z, name=name,
        )
        return cls(model_from_structure(st))

    # ------------------------------------------------------------------------------------------ names
    @property
    def name(self) -> str:
        return self.model.name

    @cached_property
    def structure(self) -> Structure:
        return self.model.structure()

    @property
    def equations(self) -> tuple[str, ...]:
        return self.structure.equations

    @property
    def unknowns(self) -> tuple[str, ...]:
        return self.structure.unknowns

    @property
    def knowns(self) -> tuple[str, ...]:
        return self.structure.knowns

    @property
    def faults(self) -> tuple[str, ...]:
        return self.structure.faults

    def __repr__(self) -> str:
        st = self.structure
        return (f"DiagnosisModel({self.name!r}: {st.ne} equations, {st.nx} unknowns, {st.nz} knowns, "
                f"{st.nf} faults)")

    def _repr_html_(self) -> str:
        st = self.structure
        desc = {f.name: f.desc for f in self.model.faults}
        rows = [[desc.get(f, "")] for f in st.faults]
        caption = (f"{self.name}: {st.ne} equations, {st.nx} unknowns, {st.nz} knowns ({name_list(st.knowns, 8)}), "
                   f"{st.nf} faults, structural redundancy {self.dm().redundancy}")
        return html_table(rows, ["description"], st.faults, caption, "fault")

    # ------------------------------------------------------------------------------------------ analysis
    def dm(self) -> Decomposition:
        """The Dulmage-Mendelsohn decomposition."""
        st = self.structure
        r = dulmage_mendelsohn(st.X)
        eq, var = st.equations, st.unknowns
        return Decomposition(
            overdetermined=tuple(eq[i] for i in r.plus_eqs),
            overdetermined_unknowns=tuple(var[i] for i in r.plus_vars),
            just_determined=tuple((tuple(eq[i] for i in e), tuple(var[i] for i in v)) for e, v in r.zero_blocks),
            underdetermined=tuple(eq[i] for i in r.minus_eqs),
            underdetermined_unknowns=tuple(var[i] for i in r.minus_vars),
            redundancy=r.redundancy,
            result=r,
        )

    def _test_set(self, equations: int, faults: int | None = None, cost: int = -1, label: str = "") -> TestSet:
        st = self.structure
        eqs = mso.bits(equations)
        fmask = faults if faults is not None else mso.to_mask(np.flatnonzero(st.equation_faults(eqs)).tolist())
        return TestSet(tuple(st.equations[i] for i in eqs), tuple(st.faults[k] for k in mso.bits(fmask)),
                       equations, cost, label)

    def msos(self) -> Iterator[TestSet]:
        """Every MSO set once, streamed from the native search (constant memory; ROMO grouped: 1.8 million).
        For counts and the fault-signature table without the sets, `mso_summary`."""
        p = mso.prepare(self.structure)
        for eqs in mso.iter_msos(p):
            yield self._test_set(eqs, p.faults_of(eqs), eqs.bit_count() - 1)

    def mso_summary(self, workers: int = 2, progress: bool = False) -> MsoAnalysis:
        """Count, size histogram and fault-signature table of the MSO sets (on `workers` processes)."""
        r = mso.find_msos(self.structure, workers=workers, progress=progress)
        return MsoAnalysis(self.name, self.faults, r.count, dict(r.by_equations), r.signatures, r.complete,
                           r.elapsed_s, r)

    def mtes(self) -> tuple[TestSet, ...]:
        """The minimal test equation supports (for models whose MSO sets are too many to enumerate)."""
        res = mso.mtes(self.structure)
        return tuple(self._test_set(t.equations, t.faults) for t in res.mtes)

    def isolability(self) -> IsolabilityAnalysis:
        """Structural single-fault detectability and isolability."""
        s = self.summary()
        iso: IsolabilityResult = s.isolability
        f = self.faults
        return IsolabilityAnalysis(
            faults=f,
            detectable=tuple(f[i] for i in range(len(f)) if iso.detectable[i]),
            not_detectable=tuple(f[i] for i in range(len(f)) if not iso.detectable[i]),
            classes=tuple(tuple(f[i] for i in c) for c in iso.classes),
            isolable=iso.isolable.copy(),
            summary=s,
        )

    def summary(self) -> Summary:
        """Everything `fdi-analyze report` prints (DM, equivalence classes, isolability), for `fdi_analysis.report`."""
        return summarize(self.model)

    def candidates(self, kind: Literal["mso", "mtes"] = "mso", realizable: bool = False,
                   workers: int = 2) -> list[Candidate]:
        """The candidate tests of a selection: one MSO set (or MTES) per fault signature, the cheapest; with
        `realizable` only those with a sequential residual generator (what `export_c` can put on board)."""
        from fdi_analysis.selection.candidates import mso_candidates, mtes_candidates

        st = self.structure
        cands = mso_candidates(st, workers=workers, progress=False)[1] if kind == "mso" else mtes_candidates(st)[1]
        if realizable:
            if not self.model.symbolic:
                raise ApiError(f"{self.name}: realizability needs the equations (a TOML model), this model is a "
                               "structure only")
            from fdi_analysis.residuals.realizability import realizable_candidates

            cands, _ = realizable_candidates(self.model, cands)
        return cands

    def select(self, method: Method = "B", *, optimal: bool = True, candidates: Literal["mso", "mtes"] = "mso",
               realizable: bool = False, time_limit_s: float = 60.0, workers: int = 2) -> TestSelection:
        """The fewest tests (then the fewest unknowns) that reach the isolability of all candidates under
        `method` (exact, `fdi_analysis.selection.optimal`), or with ``optimal=False`` the paper's greedy one."""
        if method not in ("A", "B"):
            raise ApiError(f"method {method!r}: use 'A' or 'B'")
        cands = self.candidates(candidates, realizable, workers)
        nf = self.structure.nf
        sel = optimal_selection(cands, nf, method, time_limit_s) if optimal else greedy(cands, nf, method)
        tests = tuple(self._test_set(t.equations, t.faults, t.cost, t.label) for t in sel.tests)
        return TestSelection(method, sel.kind, tests, sel.total_cost, sel.proven, len(cands), self.faults, sel)

    def fault_matrix(self, tests: Sequence[TestSet], method: Method = "B") -> npt.NDArray[np.bool_]:
        """The paper's fault matrix of `tests` (row = occurred fault, column = diagnosed, index 0 = no fault, then
        the faults in model order); `fault_matrix_frame` is the same with labels."""
        from fdi_analysis.fault_matrix import fault_matrix

        fi = {f: k for k, f in enumerate(self.faults)}
        return fault_matrix([mso.to_mask([fi[f] for f in t.faults]) for t in tests], len(self.faults), method)

    def fault_matrix_frame(self, tests: Sequence[TestSet], method: Method = "B") -> Any:
        """`fault_matrix` as a pandas DataFrame: rows (occurred) and columns (diagnosed as) labelled by fault name,
        the fault-free case as ``(no fault)``."""
        labels = (NO_FAULT, *self.faults)
        return matrix_frame(self.fault_matrix(tests, method), labels, labels, "occurred", "diagnosed as")

    def signature_matrix(self, tests: Sequence[TestSet]) -> npt.NDArray[np.bool_]:
        """``[t, k]``: test t reacts to fault k."""
        fi = {f: k for k, f in enumerate(self.faults)}
        cands = [Candidate(t.mask, mso.to_mask([fi[f] for f in t.faults]), t.cost) for t in tests]
        return signature_matrix(cands, len(self.faults))

    def signature_frame(self, tests: Sequence[TestSet]) -> Any:
        """`signature_matrix` as a pandas DataFrame: a row per test (its label, else ``t1``, ``t2``, ...), a column
        per fault."""
        labels = [t.label or f"t{k + 1}" for k, t in enumerate(tests)]
        return matrix_frame(self.signature_matrix(tests), labels, self.faults, "test", "fault")

    # ------------------------------------------------------------------------------------------ plots
    def plot_dm(self, ax: Axes | None = None) -> Figure:
        """The incidence matrix in DM order with the faults as columns on its right, into `ax` or a new figure."""
        from fdi_analysis.plots import plot_dm

        return plot_dm(self.summary(), ax=ax)

    def plot_isolability(self, ax: Axes | None = None) -> Figure:
        """`IsolabilityAnalysis.plot` of the model's isolability."""
        return self.isolability().plot(ax=ax)

    def plot_fault_matrix(self, tests: Sequence[TestSet], ax: Axes | None = None, title: str = "") -> Figure:
        """The paper's Fig. 4 for `tests`: methods A and B in one matrix (row = occurred fault, 0 = no fault)."""
        from fdi_analysis.plots import plot_fault_matrix

        return plot_fault_matrix(self.fault_matrix(tests, "A"), self.fault_matrix(tests, "B"), self.faults,
                                 title or f"{self.name}: fault matrix of {len(tests)} tests", ax=ax)

    # ------------------------------------------------------------------------------------------ export
    def export_c(self, out: str | Path, thresholds: str | Path, *, fault_sizes: str | Path | None = None,
                 name: str = "fdi_romo_table", workers: int = 2, uncalibrated: bool = False) -> ExportResult:
        """Write the firmware's diagnosis table (NAME.h/.c) and residual generators to `out`, as ``fdi-analyze
        export-c`` does: the tests of the thresholds file's selection, or the optimal realizable selection.
        `thresholds` is a file or the name of a shipped one (``romo_thresholds``); `fault_sizes` a file
        (host_tools/scenarios/fault_sizes.toml: the stated size per test, see ``fdi-tune fault-sizes``). A test
        without a calibrated variance is refused unless `uncalibrated` (``--uncalibrated``: placeholders, marked)."""
        from fdi_analysis.cli.export import generate_all

        if self.model.source is None or not self.model.symbolic:
            raise ApiError(f"{self.name}: C export needs a model file with equations (TOML); this one is "
                           "a structure only")
        out = Path(out)
        files = generate_all(self.model.source, thresholds_file(thresholds), out, name, workers, False,
                             Path(fault_sizes) if fault_sizes is not None else None, uncalibrated=uncalibrated)
        out.mkdir(parents=True, exist_ok=True)
        written = []
        for fname, text in files.items():
            (out / fname).write_text(text, encoding="utf-8")
            written.append(out / fname)
        return ExportResult(tuple(written), name)
