"""Shared helpers of the residual tests: a C harness that runs generator descriptors of a vehicle target on the
generic core (fw/src), and the generators of the committed ROMO table re-synthesised."""

from __future__ import annotations

import itertools
import re
import shutil
import subprocess
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.model import Model
from fdi_analysis.residuals.causality import synthesize
from fdi_analysis.residuals.generator import Generator

ROMO = Path("fw/vehicles/romo")
SIGNALS = ["ax_m", "ay_m", "psidot_m", "vx_m", "vy_m", "delta1_m", "delta2_m", "delta3_m", "delta4_m", "iTM1_m",
           "iTM2_m", "iTM3_m", "iTM4_m", "P_f_m", "P_r_m", "omega1_m", "omega2_m", "omega3_m", "omega4_m"]
ROMO_KIN = {"x_deriv": "&fdi_romo_kin_x_deriv", "y_deriv": "&fdi_romo_kin_y_deriv", "arr3": "&fdi_romo_kin_arr3",
            "arr4": "&fdi_romo_kin_arr4", "x_obs": "&fdi_romo_kin_x_obs", "y_obs": "&fdi_romo_kin_y_obs"}

HARNESS = r"""
#include <stdio.h>
#include <stdlib.h>
#include "fdi_gen.h"
extern const fdi_gen_desc_t *const harness_gens[];
extern const int harness_n_gens;
/* argv: n_signals, sensitivities (0/1), 4 generator parameters, spread (0/1); stdin: n_signals values per line;
   stdout per line: for each generator its residual, then (with sensitivities) its sensitivities, then (with spread)
   its adaptive threshold's spread (0 for a hand-written generator).
   Hand-written generators run on their own instance; the slots of a generator set run through the set's bank and
   step (every signal usable, all restarted at the first frame); residual and sensitivities 0 at the first frame. */
int main(int argc, char **argv) {
    static fdi_svf_t filt[32][FDI_GEN_MAX_FILTERS];
    static fdi_obs_t obs[32];
    static fdi_svf_t bank[FDI_GEN_MAX_BANK];
    static fdi_obs_t set_obs[FDI_GEN_MAX_SLOTS];
    static float set_r[FDI_GEN_MAX_SLOTS];
    static float set_sens[256];
    static float set_spread[FDI_GEN_MAX_SLOTS];
    static float set_reg[FDI_GEN_MAX_SLOTS * FDI_EST_MAX_PARAMS]; /* the regressors, written with the spread */
    static unsigned counts[FDI_GEN_MAX_SLOTS];
    static uint8_t at[FDI_GEN_MAX_SLOTS], sens_at[FDI_GEN_MAX_SLOTS];
    fdi_gen_param_t par;
    fdi_gen_t gen[32];
    const fdi_gen_set_t *set = NULL;
    uint32_t run = 0U, live = 0U;
    int k, first = 1, i, ns, with_sens, with_spread;
    fdi_gen_config_t cfg = {0.01f, 1.0f, 0.7071f, 2.0f, {0.0f, 0.0f, 0.0f, 0.0f}};
    float sens[32];
    if (argc != 8) return 1;
    ns = atoi(argv[1]);
    with_sens = atoi(argv[2]);
    with_spread = atoi(argv[7]);
    for (i = 0; i < 4; ++i) cfg.param[i] = strtof(argv[3 + i], NULL);
    if (fdi_gen_param_init(&par, &cfg) != FDI_OK) return 2;
    for (k = 0; k < harness_n_gens; ++k) {
        const fdi_gen_desc_t *d = harness_gens[k];
        if (fdi_gen_desc_check(d) != FDI_OK) return 3;
        if (d->set != NULL) {
            if ((set != NULL) && (set != d->set)) return 3;
            set = d->set;
            run |= (uint32_t)1U << d->slot;
            counts[d->slot] = fdi_gen_sens_count(d);
        } else if (fdi_gen_init(&gen[k], d, filt[k], FDI_GEN_MAX_FILTERS, &obs[k]) != FDI_OK) {
            return 3;
        }
    }
    {
        unsigned off = 0U;
        for (i = 0; i < (int)FDI_GEN_MAX_SLOTS; ++i) {
            at[i] = (uint8_t)i;
            sens_at[i] = (uint8_t)off;
            off += counts[i];
        }
        if (off > 256U) return 3;
    }
    for (;;) {
        fdi_frame_t in;
        for (i = 0; i < 32; ++i) in.value[i] = 0.0f;
        for (i = 0; i < ns; ++i) { if (scanf("%f", &in.value[i]) != 1) return 0; }
        if (set != NULL) {
            fdi_gen_io_t io;
            uint32_t failed;
            (void)fdi_gen_derive(set, &in, 0xFFFFFFFFU);
            failed = fdi_gen_bank_step(set, bank, &par.svf, &in, 0xFFFFFFFFU, first ? 0U : live);
            live = 0xFFFFFFFFU & ~failed;
            io.par = &par; io.in = &in; io.bank = bank; io.obs = set_obs; io.r = set_r; io.at = at;
            io.sens = set_sens; io.sens_at = at; io.run = run; io.restart = first ? run : 0U;
            io.sens_mask = with_sens ? run : 0U; io.failed = 0U;
            io.sens_at = sens_at;
            for (i = 0; i < (int)FDI_GEN_MAX_SLOTS; ++i) set_spread[i] = 0.0f;
            io.spread = with_spread ? set_spread : NULL;
            io.reg = with_spread ? set_reg : NULL; /* fdi_gen.h: non-NULL when spread is */
            set->step(&io);
            if ((failed != 0U) || (io.failed != 0U)) return 4;
        }
        for (k = 0; k < harness_n_gens; ++k) {
            const fdi_gen_desc_t *d = harness_gens[k];
            float r = 0.0f;
            float spread = 0.0f;
            unsigned j, n = with_sens ? fdi_gen_sens_count(d) : 0U;
            fdi_status_t st = FDI_OK;
            for (j = 0U; j < n; ++j) sens[j] = 0.0f;
            if (d->set != NULL) {
                if (!first) {
                    r = set_r[d->slot];
                    spread = set_spread[d->slot];
                    for (j = 0U; j < n; ++j) sens[j] = set_sens[sens_at[d->slot] + j];
                }
            } else if (first) {
                st = fdi_gen_reset(&gen[k], &par, &in);
            } else {
                st = fdi_gen_step(&gen[k], &par, &in, &r, with_sens ? sens : NULL);
            }
            if (st != FDI_OK) return 4;
            printf("%.9g", (double)r);
            for (j = 0U; j < n; ++j) printf(" %.9g", (double)sens[j]);
            if (with_spread) printf(" %.9g", (double)spread);
            printf("%s", (k + 1 < harness_n_gens) ? " " : "\n");
        }
        first = 0;
    }
}
"""


@dataclass(frozen=True)
class Harness:
    exe: Path
    signals: tuple[str, ...]  # the frame's signals, in index order
    sens_counts: tuple[int, ...]  # sensitivities each generator outputs


def build_harness(repo: Path, folder: Path, descriptors: Sequence[str], *, sources: Sequence[Path] = (),
                  include_dirs: Sequence[Path] = (), headers: Sequence[str] = ("fdi_romo_generators.h",
                                                                                "fdi_romo_kin.h"),
                  signals: Sequence[str] = tuple(SIGNALS), sens_counts: Sequence[int] | None = None) -> Harness:
    """The harness over the generic core (fw/src) running `descriptors` (C expressions of descriptor pointers,
    e.g. "&fdi_romo_generators[2]"), defined in `sources` (default: the committed ROMO target's generated and
    hand-written generators) with `include_dirs` for their headers."""
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler")
    romo = repo / ROMO
    if not sources:
        sources = [romo / "generated" / "fdi_romo_generators.c", romo / "src" / "fdi_romo_kin.c"]
        include_dirs = [romo / "generated", romo / "include", *include_dirs]
    main = folder / "harness.c"
    main.write_text(HARNESS)
    table = folder / "harness_gens.c"
    table.write_text("".join(f'#include "{h}"\n' for h in headers)
                     + "extern const fdi_gen_desc_t *const harness_gens[];\nextern const int harness_n_gens;\n"
                     + f"const fdi_gen_desc_t *const harness_gens[] = {{{', '.join(descriptors)}}};\n"
                     + f"const int harness_n_gens = {len(descriptors)};\n")
    exe = folder / "harness"
    srcs = sorted(str(p) for p in (repo / "fw/src").glob("*.c"))
    flags = ["-std=c99", "-O1", "-Wall", "-Wextra", "-Wconversion", "-Wdouble-promotion", "-Werror"]
    incs = [f"-I{repo / 'fw/include'}", f"-I{repo / 'fw/src'}", *(f"-I{d}" for d in include_dirs)]
    subprocess.run([cc, *flags, *incs, str(main), str(table), *srcs, *map(str, sources), "-lm", "-o", str(exe)],
                   check=True)
    return Harness(exe, tuple(signals), tuple(sens_counts) if sens_counts is not None else (0,) * len(descriptors))


@dataclass(frozen=True)
class HarnessRun:
    residuals: np.ndarray  # [sample, generator]
    sensitivities: list[np.ndarray]  # per generator [sample, sensitivity]
    spreads: np.ndarray | None = None  # [sample, generator] with `spread`: the adaptive threshold's term


def run_harness(h: Harness, signals: Mapping[str, np.ndarray], params: Sequence[float] = (0.0, 0.0, 0.0, 0.0),
                sens: bool = False, spread: bool = False) -> HarnessRun:
    """Every generator of the harness over the samples of `signals` (frame signals by name; missing ones 0)."""
    n = len(next(iter(signals.values())))
    data = np.column_stack([np.asarray(signals[s], dtype=float) if s in signals else np.zeros(n)
                            for s in h.signals]).astype(np.float32)
    text = "\n".join(" ".join(f"{x:.9g}" for x in row) for row in data.tolist()) + "\n"
    args = [str(len(h.signals)), "1" if sens else "0", *(repr(float(p)) for p in (list(params) + [0.0] * 4)[:4]),
            "1" if spread else "0"]
    res = subprocess.run([str(h.exe), *args], input=text, capture_output=True, text=True, check=True)
    out = np.loadtxt(res.stdout.splitlines(), ndmin=2)
    widths = [1 + (c if sens else 0) + (1 if spread else 0) for c in h.sens_counts]
    starts = np.cumsum([0, *widths])
    cut = 1 if spread else 0
    sens_cols = [out[:, a + 1:b - cut] for a, b in itertools.pairwise(starts)]
    return HarnessRun(out[:, starts[:-1]], sens_cols, out[:, starts[1:] - 1] if spread else None)


def romo_table_c(repo: Path) -> Path:
    return repo / ROMO / "generated" / "fdi_romo_table.c"


def committed_generators(repo: Path, model: Model) -> list[Generator]:
    """The generators of the committed table, re-synthesised from its equation sets (slot order)."""
    src = romo_table_c(repo).read_text()
    block = src.split("fdi_romo_table_equations")[1].split("};")[0]
    sets = re.findall(r'"([^"]*)"', block)
    gens_c = (repo / ROMO / "generated" / "fdi_romo_generators.c").read_text()
    table = gens_c.split("fdi_romo_generators[FDI_ROMO_N_GENERATORS] = {", 1)[1].split("};", 1)[0]
    labels = re.findall(r'^    \{"(\w+)",', table, flags=re.M)
    assert len(labels) == len(sets), (labels, len(sets))  # one descriptor per test, in test order
    reference = Thresholds.load(repo / "analysis/models/romo_thresholds.toml").observer_reference()
    return [synthesize(model, s.split(), labels[k], reference=reference) for k, s in enumerate(sets)]
