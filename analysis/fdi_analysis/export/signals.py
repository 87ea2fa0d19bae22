"""The signal frame of a vehicle as C (``fdi_<vehicle>_signals.h/.c``): index and mask of every measured signal.

The generic library (fw/include/fdi_frame.h) numbers signals only; the model's knowns, in the model's order,
are the vehicle's frame: ``<VEHICLE>_SIG_<NAME>`` (index), ``<VEHICLE>_SIGM_<NAME>`` (mask), the count, the
mask of all and the names. Computed first (`signals_file`), rendered from the named templates below.
"""

from __future__ import annotations

from dataclasses import dataclass
from string import Template

from fdi_analysis.errors import FdiError
from fdi_analysis.export.c_names import VehicleNames
from fdi_analysis.export.c_text import c_string, comment_text
from fdi_analysis.model import Model

MAX_SIGNALS = 32  # FDI_FRAME_MAX_SIGNALS of fw/include/fdi_frame.h


class SignalsError(FdiError, ValueError):
    """A model whose measured signals do not fit the frame."""


@dataclass(frozen=True)
class Signal:
    name: str
    index: int
    index_macro: str
    mask_macro: str
    note: str  # unit and description, for the comment


@dataclass(frozen=True)
class SignalsFile:
    banner: str
    names: VehicleNames
    model: str
    signals: tuple[Signal, ...]

    @property
    def all_mask(self) -> int:
        return (1 << len(self.signals)) - 1


HEADER_FMT = Template("""\
${banner}
/*
 * ${base}.h - the signal frame of vehicle ${vehicle}: the ${count} measured signals of model ${model}, in the
 * model's order. ${prefix}_SIG_<NAME> is the signal's index in fdi_frame_t.value[], ${prefix}_SIGM_<NAME> its
 * bit in validity and input masks (fdi_frame.h).
 */
#ifndef ${guard}
#define ${guard}

#include "fdi_frame.h"
#include "fdi_static_assert.h"

#define ${count_macro} ${count}U

${index_lines}

${mask_lines}
#define ${prefix}_SIGM_ALL 0x${all_mask}U

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(${count_macro} <= FDI_FRAME_MAX_SIGNALS, fdi_sa_${vehicle}_signal_count);
/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(${prefix}_SIGM_ALL == (${all_masks}), fdi_sa_${vehicle}_signal_mask);

/* The model's name of each signal, by index. */
extern const char *const ${names_array}[${count_macro}];

#endif /* ${guard} */
""")

INDEX_FMT = Template("#define ${macro} ${index}U${note}")
MASK_FMT = Template("#define ${macro} 0x${mask}U")

SOURCE_FMT = Template("""\
${banner}
#include "${base}.h"

const char *const ${names_array}[${count_macro}] = {
${name_lines}
};
""")


def signals_file(model: Model, names: VehicleNames, banner: str) -> SignalsFile:
    """What goes into the signals files of `model` for the vehicle `names`."""
    if not 0 < len(model.knowns) <= MAX_SIGNALS:
        raise SignalsError(f"{model.name}: {len(model.knowns)} measured signals; the frame holds 1..{MAX_SIGNALS}")
    macros = [names.sig_index(v.name) for v in model.knowns]
    bad = [v.name for v, m in zip(model.knowns, macros, strict=True) if not m.isascii() or macros.count(m) > 1]
    if bad:
        raise SignalsError(f"{model.name}: signals {', '.join(bad)} have no C macro of their own ({names.prefix}_SIG_ "
                           "and the name in capitals, ASCII): rename them")
    sigs = []
    for k, v in enumerate(model.knowns):
        note = " ".join(x for x in (f"[{v.unit}]" if v.unit else "", v.desc, "(input)" if v.input else "") if x)
        sigs.append(Signal(v.name, k, names.sig_index(v.name), names.sig_mask(v.name), note))
    return SignalsFile(banner, names, model.name, tuple(sigs))


def render(f: SignalsFile) -> tuple[str, str]:
    """Header and source text of the signals files."""
    n = f.names
    common = {"banner": f.banner, "base": n.signals, "count_macro": n.sig_count, "names_array": n.signal_names}
    index_lines = "\n".join(
        INDEX_FMT.substitute(macro=s.index_macro, index=s.index,
                             note=f" /* {comment_text(s.note)} */" if s.note else "")
        for s in f.signals)
    mask_lines = "\n".join(MASK_FMT.substitute(macro=s.mask_macro, mask=f"{1 << s.index:08X}") for s in f.signals)
    header = HEADER_FMT.substitute(common, vehicle=n.vehicle, count=len(f.signals), model=f.model, prefix=n.prefix,
                                   guard=n.signals.upper() + "_H", index_lines=index_lines, mask_lines=mask_lines,
                                   all_mask=f"{f.all_mask:08X}", all_masks=" | ".join(s.mask_macro for s in f.signals))
    source = SOURCE_FMT.substitute(common, name_lines="\n".join(f"    {c_string(s.name)}," for s in f.signals))
    return header, source
