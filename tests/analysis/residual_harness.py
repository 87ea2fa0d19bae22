"""Shared helpers of the residual tests: simulated drives and a C harness that runs fw generators."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from fdi_analysis.export.thresholds import Thresholds
from fdi_analysis.model import Model
from fdi_analysis.residuals.causality import synthesize
from fdi_analysis.residuals.generator import Generator

SIGNALS = ["ax_m", "ay_m", "psidot_m", "vx_m", "vy_m", "delta1_m", "delta2_m", "delta3_m", "delta4_m", "iTM1_m",
           "iTM2_m", "iTM3_m", "iTM4_m", "P_f_m", "P_r_m", "omega1_m", "omega2_m", "omega3_m", "omega4_m"]

HARNESS = r"""
#include <stdio.h>
#include <stdlib.h>
#include "fdi_gen.h"
/* argv: d_x d_y kind... ; stdin: 19 signals per line; stdout: one residual per kind per line */
int main(int argc, char **argv) {
    fdi_gen_param_t par;
    fdi_gen_t gen[16];
    int nk = argc - 3, k, first = 1;
    fdi_gen_config_t cfg = {0.01f, 1.0f, 0.7071f, 2.0f, 0.0f, 0.0f};
    float v[19];
    cfg.d_x = strtof(argv[1], NULL);
    cfg.d_y = strtof(argv[2], NULL);
    if (fdi_gen_param_init(&par, &cfg) != FDI_OK) return 2;
    for (k = 0; k < nk; ++k) {
        if (fdi_gen_init(&gen[k], (fdi_gen_kind_t)atoi(argv[3 + k])) != FDI_OK) return 3;
    }
    for (;;) {
        fdi_inputs_t in;
        int i;
        for (i = 0; i < 19; ++i) { if (scanf("%f", &v[i]) != 1) return 0; }
        in.ax_m = v[0]; in.ay_m = v[1]; in.psidot_m = v[2]; in.vx_m = v[3]; in.vy_m = v[4];
        in.delta1_m = v[5]; in.delta2_m = v[6]; in.delta3_m = v[7]; in.delta4_m = v[8];
        in.iTM1_m = v[9]; in.iTM2_m = v[10]; in.iTM3_m = v[11]; in.iTM4_m = v[12];
        in.P_f_m = v[13]; in.P_r_m = v[14];
        in.omega1_m = v[15]; in.omega2_m = v[16]; in.omega3_m = v[17]; in.omega4_m = v[18];
        for (k = 0; k < nk; ++k) {
            float r = 0.0f;
            fdi_status_t st = first ? fdi_gen_reset(&gen[k], &par, &in) : fdi_gen_step(&gen[k], &par, &in, &r);
            if (st != FDI_OK) return 4;
            printf("%.9g%s", (double)r, (k + 1 < nk) ? " " : "\n");
        }
        first = 0;
    }
}
"""


def build_harness(repo: Path, folder: Path, generators_c: Path | None = None) -> Path:
    """The harness over fw/src and a generated generator file (default: the committed
    fw/generated/fdi_romo_generators.c)."""
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler")
    main = folder / "harness.c"
    main.write_text(HARNESS)
    exe = folder / "harness"
    srcs = sorted(str(p) for p in (repo / "fw/src").glob("*.c"))
    flags = ["-std=c99", "-O1", "-Wall", "-Wextra", "-Wconversion", "-Wdouble-promotion", "-Werror"]
    gen = generators_c or repo / "fw/generated/fdi_romo_generators.c"
    subprocess.run([cc, *flags, f"-I{repo / 'fw/include'}", f"-I{repo / 'fw/src'}", f"-I{repo / 'fw/generated'}",
                    str(main), *srcs, str(gen), "-lm", "-o", str(exe)], check=True)
    return exe


def run_harness(exe: Path, signals: dict[str, np.ndarray], kinds: list[int], d_x: float,
                d_y: float) -> np.ndarray:
    data = np.column_stack([signals[s] for s in SIGNALS]).astype(np.float32)
    text = "\n".join(" ".join(f"{x:.9g}" for x in row) for row in data.tolist()) + "\n"
    res = subprocess.run([str(exe), repr(d_x), repr(d_y), *map(str, kinds)], input=text, capture_output=True,
                         text=True, check=True)
    return np.loadtxt(res.stdout.splitlines(), ndmin=2)


def committed_generators(repo: Path, model: Model) -> list[Generator]:
    """The generators of the committed table, re-synthesised from its equation sets (slot order)."""
    src = (repo / "fw/generated/fdi_romo_table.c").read_text()
    block = src.split("fdi_romo_table_equations")[1].split("};")[0]
    sets = re.findall(r'"([^"]*)"', block)
    labels = re.findall(r"^/\* (MSO\d+): ", (repo / "fw/generated/fdi_romo_generators.c").read_text(), flags=re.M)
    reference = Thresholds.load(repo / "analysis/models/romo_thresholds.toml").observer_reference()
    return [synthesize(model, s.split(), labels[k] if k < len(labels) else f"T{k + 1}", reference=reference)
            for k, s in enumerate(sets)]
