"""MSO sets, test supports and isolability of a Structure, on a native (C) search engine.

    from fdi_analysis.mso import find_msos, iter_msos, mtes, isolability, reduce_intermediate
    summary = find_msos(structure, workers=2)          # count, size histogram, fault-signature table
    for eqs in iter_msos(structure): ...               # each MSO set once, as an int bitset over equations

Equation and fault sets are ints (bit i = equation/fault i of the structure); `bits()` lists the indices.
"""

from .engine import Prepared, find_msos, iter_msos, mplus, prepare
from .mtes import Isolability, isolability, isolability_from_signatures, minimal_signatures, mtes
from .reduction import Reduction, intermediate_variables, reduce_intermediate
from .refjson import load_reference, structure_from_reference
from .results import MsoSummary, MtesResult, SignatureEntry, TestSupport, bits, to_mask

__all__ = [
    "Isolability",
    "MsoSummary",
    "MtesResult",
    "Prepared",
    "Reduction",
    "SignatureEntry",
    "TestSupport",
    "bits",
    "find_msos",
    "intermediate_variables",
    "isolability",
    "isolability_from_signatures",
    "iter_msos",
    "load_reference",
    "minimal_signatures",
    "mplus",
    "mtes",
    "prepare",
    "reduce_intermediate",
    "structure_from_reference",
    "to_mask",
]
