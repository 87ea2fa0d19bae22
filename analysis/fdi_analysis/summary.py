"""The structural summary of a model: counts, DM decomposition, detectability, isolability.

`summarize` computes it once; `fdi_analysis.report` renders it as JSON and Markdown.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from fdi_analysis.dm import DMResult, dulmage_mendelsohn, equivalence_classes
from fdi_analysis.isolability import IsolabilityResult, isolability
from fdi_analysis.model import Model
from fdi_analysis.structure import Structure, StructureError


@dataclass(frozen=True)
class Summary:
    model: Model
    structure: Structure
    dm: DMResult
    equivalence_classes: tuple[tuple[int, ...], ...]
    isolability: IsolabilityResult

    @property
    def redundancy(self) -> int:
        return self.dm.redundancy

    def __repr__(self) -> str:
        iso = self.isolability
        return (f"Summary({self.model.name!r}: redundancy {self.redundancy}, {int(iso.detectable.sum())} of "
                f"{self.structure.nf} faults detectable, {len(iso.classes)} isolability classes)")

    def problems(self) -> list[str]:
        """What keeps the model from a complete diagnosis, each naming the equations, unknowns or faults."""
        return structural_problems(self.structure, self.dm, self.isolability)

    def to_dict(self) -> dict[str, Any]:
        st = self.structure
        eq = st.equations
        var = st.unknowns
        iso = self.isolability
        return {
            "model": self.model.name,
            "description": self.model.description,
            "source": str(self.model.source) if self.model.source else None,
            "symbolic": self.model.symbolic,
            "counts": self.model.counts(),
            "structural_redundancy": self.redundancy,
            "problems": self.problems(),
            "dm": {
                "overdetermined": {"equations": [eq[i] for i in self.dm.plus_eqs],
                                   "unknowns": [var[i] for i in self.dm.plus_vars]},
                "just_determined_blocks": [
                    {"equations": [eq[i] for i in b_eqs], "unknowns": [var[i] for i in b_vars]}
                    for b_eqs, b_vars in self.dm.zero_blocks
                ],
                "underdetermined": {"equations": [eq[i] for i in self.dm.minus_eqs],
                                    "unknowns": [var[i] for i in self.dm.minus_vars]},
                "equivalence_classes": [[eq[i] for i in c] for c in self.equivalence_classes],
            },
            "faults": {
                "detectable": [f for f, d in zip(st.faults, iso.detectable, strict=True) if d],
                "not_detectable": [f for f, d in zip(st.faults, iso.detectable, strict=True) if not d],
                "isolability_classes": [[st.faults[i] for i in c] for c in iso.classes],
                "non_isolable_pairs": [[st.faults[i], st.faults[j]] for i, j in iso.non_isolable_pairs()],
                # [a, b]: a cannot be isolated from b, b can be isolated from a
                "one_way_pairs": [[st.faults[i], st.faults[j]] for i, j in iso.one_way_pairs()],
                "isolable_from": {
                    st.faults[i]: [st.faults[j] for j in range(st.nf) if iso.isolable[i, j]]
                    for i in range(st.nf)
                },
            },
        }


def structural_problems(st: Structure, dm: DMResult, iso: IsolabilityResult) -> list[str]:
    """Clear messages for a structurally singular model (an underdetermined part), a model without
    redundancy (no residual can be built) and faults no residual can see; empty when none applies."""
    out: list[str] = []
    if dm.minus_eqs or dm.minus_vars:
        unknowns = ", ".join(st.unknowns[v] for v in dm.minus_vars)
        eqs = ", ".join(st.equations[e] for e in dm.minus_eqs) or "none"
        out.append(f"structurally singular: the unknowns {unknowns} cannot all be determined "
                   f"({len(dm.minus_vars)} unknowns in {len(dm.minus_eqs)} equations: {eqs}); "
                   "add equations or measurements that determine them")
    if dm.redundancy == 0:
        out.append("no structural redundancy: no equation is left over to build a residual, so no fault is "
                   "detectable; add measurements (equations of known signals)")
    nd = [st.faults[i] for i in range(st.nf) if not iso.detectable[i]]
    if nd and dm.redundancy > 0:
        out.append(f"not detectable (no equation in the overdetermined part): {', '.join(nd)}")
    return out


def require_redundancy(st: Structure) -> None:
    """StructureError naming the problem when the structure has no redundancy: there is no MSO set, no test
    and nothing to select or export (the commands that need tests call this first)."""
    dm = dulmage_mendelsohn(st.X)
    if dm.redundancy == 0:
        problems = structural_problems(st, dm, isolability(st))
        raise StructureError("; ".join(problems) or "no structural redundancy")


def summarize(model: Model) -> Summary:
    st = model.structure()
    return Summary(
        model=model,
        structure=st,
        dm=dulmage_mendelsohn(st.X),
        equivalence_classes=tuple(equivalence_classes(st.X)),
        isolability=isolability(st),
    )
