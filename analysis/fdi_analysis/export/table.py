"""Export a test selection as a vehicle's diagnosis table (fw/include/fdi_table.h types).

Writes ``fdi_<vehicle>_table.h`` and ``.c``: one ``const fdi_table_t`` with the selected MSO sets (fault bitmask,
signals used, the descriptor of its generated generator, gate and variance, interpretation), the signal and fault
names, the fault signature matrix as bitmask rows, the isolability classes, the reaction size of each (fault,
test) that decides exoneration (fdi_analysis.export.fault_sizes), and per test the equations and unknowns of its
MSO set. What goes into the file is computed first (`table_file`), then rendered from the named templates below.
Output is deterministic: the same model and selection give byte-identical files.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from string import Template

from fdi_analysis.errors import FdiError
from fdi_analysis.export.c_expr import c_float
from fdi_analysis.export.c_names import VehicleNames
from fdi_analysis.export.c_text import banner, c_string, comment_text
from fdi_analysis.export.capacity import DEFAULT as DEFAULT_CAPACITY
from fdi_analysis.export.capacity import Capacity
from fdi_analysis.export.fault_sizes import REACTION_WINDOW_S, SENSITIVITY_MARGIN, FaultSizes, test_size_rows
from fdi_analysis.export.generators import kind_name
from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.fault_matrix import Candidate
from fdi_analysis.interpretation import interpret
from fdi_analysis.model import Model
from fdi_analysis.mso.results import bits

MAX_TESTS = 32  # FDI_TABLE_MAX_TESTS of fw/include/fdi_table.h (the table format; the diagnoser's is Capacity)
MAX_FAULTS = 32  # FDI_TABLE_MAX_FAULTS of fw/include/fdi_table.h
NO_GENERATOR = "NULL"


class ExportError(FdiError, ValueError):
    """The selection cannot be expressed in the firmware's table format."""


# ------------------------------------------------------------------------------------------ templates
HEADER_FMT = Template("""\
${banner}
/*
 * ${table}: diagnosis table of model ${model} (${n_tests} tests, ${n_faults} faults), vehicle ${vehicle}.
 * Thresholds: ${thresholds}.
 */
${uncalibrated}#ifndef ${guard}
#define ${guard}

#include "fdi_table.h"

extern const fdi_table_t ${table};
/* Per test: the equations and the unknowns of its MSO set (space separated). */
extern const char *const ${table}_equations[${n_tests}];
extern const char *const ${table}_unknowns[${n_tests}];

#endif /* ${guard} */
""")

SOURCE_FMT = Template("""\
${banner}
${uncalibrated}#include "${table}.h"

#include <stddef.h>

#include "${generators}.h"
#include "${signals}.h"

static const char *const ${vehicle}_fault_names[${n_faults}] = {
${fault_names}
};

static const fdi_test_desc_t ${vehicle}_tests[${n_tests}] = {
${tests}
};

/* Row j: bit i set when test i is sensitive to fault j. */
static const uint32_t ${vehicle}_fault_signature[${n_faults}] = {
${signatures}
};

/* Row j: the faults whose signature equals fault j's (not isolable from it by these tests). */
static const uint32_t ${vehicle}_iso_class[${n_faults}] = {
${classes}
};

/* Row j, column i: size of fault j at which test i reacts (${size_note}). */
static const float ${vehicle}_test_size[${n_faults} * ${n_tests}] = {
${sizes}
};

${envelope}const char *const ${table}_equations[${n_tests}] = {
${equations}
};

const char *const ${table}_unknowns[${n_tests}] = {
${unknowns}
};

const fdi_table_t ${table} = {
    FDI_TABLE_FORMAT_VERSION,
    {${design}},
    ${sig_count},
    ${n_faults}U,
    ${n_tests}U,
    ${signal_names},
    ${vehicle}_fault_names,
    ${vehicle}_tests,
    ${vehicle}_fault_signature,
    ${vehicle}_iso_class,
    ${vehicle}_test_size,
    ${margin},
    ${sens_margin},
    ${envelope_ref},
};
""")

ENVELOPE_FMT = Template("""\
/* The operating envelope the gates were calibrated in (fdi_table.h; [envelope] of
   ${thresholds}): outside it when at least ${votes} of these signals exceed their limits,
   ${margin} x their largest magnitude in the calibration drives. */
static const uint8_t ${vehicle}_envelope_signals[${n}] = {${signals}};
static const float ${vehicle}_envelope_limits[${n}] = {${limits}};
static const fdi_table_envelope_t ${vehicle}_envelope = {
    ${n}U, ${votes}U, ${vehicle}_envelope_signals, ${vehicle}_envelope_limits};

""")

UNCALIBRATED_FMT = Template("""\
/* UNCALIBRATED: variances are placeholders (1.0); do not use on a vehicle.
   No calibrated variance ([generated]) in ${thresholds} for ${tests}.
   Exported with --uncalibrated: calibrate them (fdi-tune calibrate) and export again. */
""")

TEST_FMT = Template("""\
    {.gen = ${generator}, .interpretation = ${interpretation},
     .mso_id = ${mso_id}U, .fault_mask = 0x${fault_mask}U, .input_mask = ${inputs},
     .gate = ${gate}, .variance = ${variance}, .response_steps = ${response_steps}U},""")
MASK_ROW_FMT = Template("    0x${mask}U, /* ${fault} */")
SIZE_ROW_FMT = Template("    ${sizes}, /* ${fault} */")
STRING_ROW_FMT = Template("    ${text},")


# ------------------------------------------------------------------------------------------ data model
@dataclass(frozen=True)
class TestRow:
    mso_id: int
    generator: str  # C expression of the descriptor pointer, or NULL
    fault_mask: int
    inputs: str  # C mask expression
    gate: float
    variance: float
    response_steps: int
    interpretation: str
    equations: str
    unknowns: str


@dataclass(frozen=True)
class TableFile:
    banner: str
    names: VehicleNames
    model: str
    thresholds: str
    design: tuple[float, float, float, float]
    faults: tuple[str, ...]  # short names (f4)
    fault_names: tuple[str, ...]  # name and description
    tests: tuple[TestRow, ...]
    signatures: tuple[int, ...]
    classes: tuple[int, ...]
    sizes: tuple[tuple[float, ...], ...]
    size_note: str
    margin: float
    envelope: tuple[tuple[str, float], ...] = ()  # (signal, limit) of the calibrated envelope; () = none
    envelope_votes: int = 0
    envelope_margin: float = 0.0
    placeholders: tuple[str, ...] = ()  # tests whose variance is a placeholder (1.0; exported `uncalibrated`)


# ------------------------------------------------------------------------------------------ computing
def _check_counts(n_tests: int, n_faults: int, capacity: Capacity) -> None:
    """Refuse a table the firmware cannot hold: the table format's limits, then the diagnoser's capacity."""
    if not 0 < n_tests <= MAX_TESTS:
        raise ExportError(f"{n_tests} tests selected; the firmware table holds 1..{MAX_TESTS}")
    too_many = capacity.exceeded("max_tests", n_tests, "tests selected")
    if too_many:
        raise ExportError(too_many)
    if n_faults > MAX_FAULTS:
        raise ExportError(f"{n_faults} faults; the firmware table holds at most {MAX_FAULTS}")


def table_file(model: Model, tests: Sequence[Candidate], thresholds: Thresholds, names: VehicleNames, banner: str,
               generated: Sequence[bool] | None = None, sizes: FaultSizes | None = None,
               response_s: Sequence[float] | None = None,
               domain_inputs: Sequence[Sequence[str]] | None = None, uncalibrated: bool = False,
               capacity: Capacity = DEFAULT_CAPACITY) -> TableFile:
    """What goes into the table files. `generated[k]` true (the default for every test): test k runs the
    generated generator of slot (number of generated tests before it), with the variance of its equation set
    from thresholds.generated (without one: refused unless `uncalibrated`, then 1.0, a placeholder the files
    mark); false: no on-board generator (NULL, always "not evaluable"). `response_s[k]`: the time test k's residual
    needs to show a fault (`residuals.evaluate.response_time` of its generator; default REACTION_WINDOW_S, the window
    of the fault-size sweep), written as whole steps of the design point. `domain_inputs[k]`: the signals test k's
    generator reads for its operating domain besides the MSO set's own. `capacity`: the capacities the firmware is
    built with (export.capacity; default: the C defaults): more tests than its FDI_DIAG_MAX_TESTS are refused."""
    st = model.structure()
    _check_counts(len(tests), st.nf, capacity)
    gen = list(generated) if generated is not None else [True] * len(tests)
    placeholders = _placeholders(st.equations, tests, gen, thresholds, uncalibrated)
    known_order = [v.name for v in model.knowns]
    unknown_order = [v.name for v in model.unknowns]
    rows = []
    for k, t in enumerate(tests):
        eqs = [st.equations[e] for e in bits(t.equations)]
        extra = set(domain_inputs[k]) if domain_inputs is not None else set()
        knowns = sorted({z for e in bits(t.equations) for z in model.equations[e].knowns} | extra,
                        key=known_order.index)
        unknowns = sorted({x for e in bits(t.equations) for x in model.equations[e].unknowns},
                          key=unknown_order.index)
        generator = kind_name(sum(gen[:k]), names) if gen[k] else NO_GENERATOR
        variance = thresholds.generated.get(" ".join(eqs), 1.0) if gen[k] else 1.0
        number = re.fullmatch(r"MSO(\d+)", t.label)
        seconds = response_s[k] if response_s is not None else REACTION_WINDOW_S
        steps = max(1, math.ceil(seconds / thresholds.design[0] - 1e-9))
        rows.append(TestRow(int(number.group(1)) if number else k + 1, generator, t.faults, names.mask_expr(knowns),
                            thresholds.gate, variance, steps, interpret(model, eqs), " ".join(eqs),
                            " ".join(unknowns)))
    signatures = [sum(1 << i for i, t in enumerate(tests) if t.faults >> j & 1) for j in range(st.nf)]
    classes = [sum(1 << k for k in range(st.nf) if signatures[k] == signatures[j]) for j in range(st.nf)]
    size_rows, margin = test_size_rows(list(st.faults), [t.label for t in tests], signatures, sizes)
    size_note = (f"reaction sizes from {sizes.source}, 0 = no reaction within the fault's limits" if sizes is not None
                 else "1 on the signature (no fault sizes given: classic exoneration)")
    env = thresholds.envelope
    envelope: tuple[tuple[str, float], ...] = ()
    if env is not None:
        missing = [s for s in env.signals if s not in env.limits]
        unknown = [s for s in env.signals if s not in known_order]
        if unknown:
            raise ExportError(f"[envelope] of {thresholds.source}: {', '.join(unknown)} not measured signals of "
                              f"{model.name}")
        if missing:
            raise ExportError(f"{thresholds.source} defines an [envelope] without calibrated limits of "
                              f"{', '.join(missing)}: run fdi-tune calibrate")
        envelope = tuple((s, env.limits[s]) for s in env.signals)
    return TableFile(
        banner=banner, names=names, model=model.name, thresholds=thresholds.source, design=thresholds.design,
        faults=tuple(st.faults), fault_names=tuple(f"{f.name} {f.desc}".strip() for f in model.faults),
        tests=tuple(rows), signatures=tuple(signatures), classes=tuple(classes), placeholders=placeholders,
        sizes=tuple(tuple(r) for r in size_rows), size_note=size_note, margin=margin, envelope=envelope,
        envelope_votes=env.votes if env is not None else 0, envelope_margin=env.margin if env is not None else 0.0)


def _placeholders(equations: Sequence[str], tests: Sequence[Candidate], generated: Sequence[bool],
                  thresholds: Thresholds, uncalibrated: bool) -> tuple[str, ...]:
    """The tests with a generator but no calibrated variance in thresholds.generated; `ExportError` if there are any
    and the export was not asked for an uncalibrated table."""
    missing = tuple(t.label for t, g in zip(tests, generated, strict=True)
                    if g and " ".join(equations[e] for e in bits(t.equations)) not in thresholds.generated)
    if missing and not uncalibrated:
        raise ExportError(f"{thresholds.source} has no calibrated variance ([generated]) for {', '.join(missing)}: "
                          "run fdi-tune calibrate, or export placeholders (1.0) with --uncalibrated")
    return missing


# ------------------------------------------------------------------------------------------ rendering
def _strings(items: Sequence[str]) -> str:
    return "\n".join(STRING_ROW_FMT.substitute(text=c_string(s)) for s in items)


def render_file(f: TableFile) -> tuple[str, str]:
    """Header and source text of the table files."""
    n = f.names
    table = n.table
    marking = UNCALIBRATED_FMT.substitute(thresholds=comment_text(f.thresholds),
                                          tests=comment_text(", ".join(f.placeholders))) if f.placeholders else ""
    header = HEADER_FMT.substitute(banner=f.banner, table=table, model=f.model, n_tests=len(f.tests),
                                   n_faults=len(f.faults), vehicle=n.vehicle, thresholds=comment_text(f.thresholds),
                                   guard=table.upper() + "_H", uncalibrated=marking)
    tests = "\n".join(TEST_FMT.substitute(
        mso_id=t.mso_id, generator=t.generator, fault_mask=f"{t.fault_mask:08X}", inputs=t.inputs,
        gate=c_float(t.gate), variance=c_float(t.variance), response_steps=t.response_steps,
        interpretation=c_string(t.interpretation))
        for t in f.tests)
    source = SOURCE_FMT.substitute(
        banner=f.banner, uncalibrated=marking, table=table, vehicle=n.vehicle, generators=n.generators,
        signals=n.signals,
        n_faults=len(f.faults),
        n_tests=len(f.tests), fault_names=_strings(f.fault_names), tests=tests,
        signatures="\n".join(MASK_ROW_FMT.substitute(mask=f"{s:08X}", fault=x)
                             for s, x in zip(f.signatures, f.faults, strict=True)),
        classes="\n".join(MASK_ROW_FMT.substitute(mask=f"{c:08X}", fault=x)
                          for c, x in zip(f.classes, f.faults, strict=True)),
        size_note=comment_text(f.size_note),
        sizes="\n".join(SIZE_ROW_FMT.substitute(sizes=", ".join(c_float(x) for x in row), fault=x)
                        for row, x in zip(f.sizes, f.faults, strict=True)),
        equations=_strings([t.equations for t in f.tests]), unknowns=_strings([t.unknowns for t in f.tests]),
        design=", ".join(c_float(x) for x in f.design), sig_count=n.sig_count, signal_names=n.signal_names,
        margin=c_float(f.margin), sens_margin=c_float(SENSITIVITY_MARGIN),
        envelope=ENVELOPE_FMT.substitute(
            thresholds=comment_text(f.thresholds), votes=f.envelope_votes, margin=f"{f.envelope_margin:g}",
            vehicle=n.vehicle, n=len(f.envelope), signals=", ".join(n.sig_index(s) for s, _ in f.envelope),
            limits=", ".join(c_float(x) for _, x in f.envelope)) if f.envelope else "",
        envelope_ref=f"&{n.vehicle}_envelope" if f.envelope else "NULL")
    return header, source


def render(model: Model, tests: Sequence[Candidate], thresholds: Thresholds, name: str, command: str,
           generated: Sequence[bool] | None = None, sizes: FaultSizes | None = None,
           uncalibrated: bool = False) -> tuple[str, str]:
    """The header and source text of the table `name` (e.g. "fdi_romo_table"); see `table_file`."""
    return render_file(table_file(model, tests, thresholds, VehicleNames.of_table(name), banner(command),
                                  generated, sizes, uncalibrated=uncalibrated))


def write(out_dir: Path, name: str, header: str, source: str) -> list[Path]:
    out_dir.mkdir(parents=True, exist_ok=True)
    h, c = out_dir / f"{name}.h", out_dir / f"{name}.c"
    h.write_text(header, encoding="utf-8")
    c.write_text(source, encoding="utf-8")
    return [h, c]
