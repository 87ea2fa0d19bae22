"""Residual synthesis: solvability rules, causality, rejection reasons, realizable candidates, and the
hand-written ARR3/ARR4 of fw/ reproduced by the generator on simulated signals."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from residual_harness import ROMO_KIN, build_harness, run_harness

from fdi_analysis.fault_matrix import Candidate, fault_matrix
from fdi_analysis.model import Model
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.causality import synthesize
from fdi_analysis.residuals.evaluate import evaluable_segments, in_domain, residual
from fdi_analysis.residuals.generator import DOMAIN_FACTOR
from fdi_analysis.residuals.realizability import realizable_candidates, why_not_realizable
from fdi_analysis.residuals.reasons import NotRealizableError, Reason
from fdi_analysis.residuals.solvability import Solution, Solver
from fdi_analysis.selection.candidates import mso_candidates
from fdi_host.tuning.drives import drive

ARR3 = ["K1", "K2", "D1", "D2", "S1", "S2", "S3", "S4"]
ARR4 = ["K1", "K2", "D1", "D2", "S1", "S2", "S3", "S5"]


@pytest.fixture(scope="module")
def model(repo: Path) -> Model:
    return load_model(repo / "analysis/models/romo_grouped.toml")


def test_solvability_honours_non_invertible_terms(model: Model) -> None:
    s = Solver(model)
    assert "not_solvable_for" in str(s.solve(model.equation("W1.FL"), "omega1"))  # tyre law: Max/Abs/sqrt in omega
    assert "not_solvable_for" in str(s.solve(model.equation("W1.dyn"), "omega1"))  # brake torque tanh(omega)
    # without the marks the linearity check alone rejects them too
    bare = Solver(model)
    for eq, var in (("W1.FL", "omega1"), ("W1.FL", "vx"), ("W1.dyn", "omega1")):
        e = model.equation(eq)
        assert "not linear" in str(bare._solve(replace(e, not_solvable_for=()), var))
    assert "not_solvable_for" in str(s.solve(model.equation("B3"), "psidot"))  # marked in the model file
    fl = s.solve(model.equation("W1.dyn"), "FL1")
    assert isinstance(fl, Solution) and not fl.coefficient.free_symbols
    vy = s.solve(model.equation("K1"), "vy")  # vy = (dvx - ax) / psidot: a division by a signal
    assert isinstance(vy, Solution) and {str(x) for x in vy.coefficient.free_symbols} == {"psidot"}


def test_arr3_causality_matches_the_paper(model: Model) -> None:
    g = synthesize(model, ARR3, "MSO3")
    assert g.residual_equation == "K2" and g.level == 2
    assert [s.var for s in g.steps if s.kind == "derivative"] == ["dvx", "dvy"]
    assert g.knowns == ("ax_m", "ay_m", "psidot_m", "vx_m") and g.faults == ("f1", "f2", "f3", "f4")
    assert "psidot" in g.scaled_by  # multiplied by w^2 like eq. (10)


def test_open_loop_integration_is_rejected_with_a_reason(model: Model) -> None:
    eqs = [
        "B1", "K1", "D1", "W1.FL", "W2.FL", "W3.FL", "W4.FL", "W1.FS", "W2.FS", "W3.FS", "W4.FS", "W1.Fx", "W2.Fx",
        "W3.Fx", "W4.Fx", "W1.dyn", "W2.dyn", "W3.dyn", "W4.dyn", "W1.D", "W2.D", "W3.D", "W4.D", "S1", "S2", "S3",
        "S5",
    ]
    why = why_not_realizable(model, Solver(model), eqs, observer=False)
    assert why is not None and why.kind is Reason.OPEN_LOOP and "integrating" in why.text
    # vx and the four wheel speeds: one observer state per generator only
    with pytest.raises(NotRealizableError, match=r"^not realizable: needs 5 observer states \(vx, omega1, "):
        synthesize(model, eqs, "T4")


def test_quotient_inside_a_tyre_law_is_rejected(model: Model) -> None:
    eqs = [
        "B1", "B2", "K1", "K2", "D1", "D2", "W2.FL", "W3.FL", "W4.FL", "W2.FS", "W3.FS", "W4.FS", "W1.Fx", "W2.Fx",
        "W3.Fx", "W4.Fx", "W1.Fy", "W2.Fy", "W3.Fy", "W4.Fy", "W1.dyn", "W1.D", "S1", "S3", "S4", "S.omega1",
        "S.omega2", "S.omega3", "S.omega4",
    ]
    with pytest.raises(NotRealizableError, match="division by a signal"):
        synthesize(model, eqs, "MSO5754")


def test_realizable_candidates_still_detect_every_fault(model: Model) -> None:
    st = model.structure()
    _, cands = mso_candidates(st, workers=2, progress=False)
    keep, reasons = realizable_candidates(model, cands)
    assert 0 < len(keep) < len(cands)
    assert sum(reasons.values()) == len(cands) - len(keep)
    covered = 0
    for c in keep:
        covered |= c.faults
    assert covered == (1 << st.nf) - 1
    # the observer path (one state by integral causality) adds candidates and recovers fault-matrix
    # elements: without it the wheel-speed sensor faults f22..f25 cannot be told from the steering and tyre
    # faults of their wheel; with it only the steering / tyre-force pairs of each wheel (f6/f18, ...) stay
    plain, plain_reasons = realizable_candidates(model, cands, observer=False)
    assert {c.label for c in plain} < {c.label for c in keep}
    observer_kinds = {Reason.OBSERVER_STATES, Reason.OBSERVER_DERIVATIVE, Reason.OBSERVER_DIVISION,
                      Reason.OBSERVER_OUTPUT, Reason.NOT_OBSERVABLE, Reason.NO_OBSERVER_EQUATION}
    assert not observer_kinds & set(plain_reasons) and Reason.OPEN_LOOP in plain_reasons
    assert observer_kinds & set(reasons)
    full = fault_matrix([c.faults for c in cands], st.nf, "B")
    names = ("none", *st.faults)

    def lost(kept: list[Candidate]) -> set[tuple[str, str]]:
        reached = fault_matrix([c.faults for c in kept], st.nf, "B")
        return {(names[i], names[j]) for i, j in np.argwhere(reached & ~full)}

    wheel_pairs = {(f"f{6 + w}", f"f{18 + w}") for w in range(4)}
    wheel_pairs |= {(b, a) for a, b in wheel_pairs}
    assert lost(keep) == wheel_pairs
    assert wheel_pairs < lost(plain) and {("f6", "f22"), ("f18", "f22")} <= lost(plain)


def test_generator_reproduces_handwritten_arr3_arr4(repo: Path, model: Model, tmp_path: Path) -> None:
    """Same signals through the ROMO target's hand-written ARR3/ARR4 (C) and the generated MSO3/MSO4 (Python): the
    generated residual is -r3 (resp. r4): the same relation multiplied by w^2, the same filters."""
    _, sig = drive("cornering", duration=12.0, faults=[("f4", 6.0, 0.5)])
    p = model.parameter_values()
    c = run_harness(build_harness(repo, tmp_path, [ROMO_KIN["arr3"], ROMO_KIN["arr4"]]), sig,
                    (p["d_x"], p["d_y"])).residuals
    g3 = residual(synthesize(model, ARR3, "MSO3"), sig)
    g4 = residual(synthesize(model, ARR4, "MSO4"), sig)
    for gen, hand, sign in ((g3, c[:, 0], -1.0), (g4, c[:, 1], 1.0)):
        scale = float(np.max(np.abs(hand)))
        assert scale > 0.0
        err = np.max(np.abs(sign * gen - hand))
        assert err < 2e-3 * scale, f"max deviation {err:.3g} of residual scale {scale:.3g}"


MSO6 = ["W1.FL", "W1.dyn", "W1.D", "S1", "S2", "S3", "S4", "S5", "S.omega1"]


def test_operating_domain_from_the_slip_regularisation(model: Model) -> None:
    """A tyre-law residual (slip normalised by Max(..., v_eps)) is evaluable only above DOMAIN_FACTOR * v_eps;
    the kinematic ARR3 has no such floor. Outside the domain no sample is evaluated, and on re-entry the
    generator restarts with a warm-up (as fdi_diag re-arms it)."""
    g6 = synthesize(model, MSO6, "MSO6")
    v_eps = model.parameter_values()["v_eps"]
    assert g6.min_speed == pytest.approx(DOMAIN_FACTOR * v_eps) and "v_eps" in g6.domain()
    assert synthesize(model, ARR3, "MSO3").min_speed == 0.0
    _, sig = drive("straight", duration=8.0)  # from rest: below the minimum speed until ~2 s
    ok = in_domain(g6, sig)
    assert not ok[0] and ok[-1]
    first_in = int(np.argmax(ok))
    segs = evaluable_segments(g6, sig, 100)
    assert [a for a, _ in segs] == [first_in + 100]
    assert len(segs[0][1]) == len(ok) - first_in - 100
    sig2 = {k: v.copy() for k, v in sig.items()}
    sig2["vx_m"][500:520] = 0.0  # a dip below the domain: two runs, the second restarted
    segs2 = evaluable_segments(g6, sig2, 100)
    assert [a for a, _ in segs2] == [first_in + 100, 620]
    full = residual(g6, {k: v[520:] for k, v in sig2.items()})
    assert np.allclose(segs2[1][1], full[100:])


def test_not_solvable_for_survives_elimination(model: Model, tmp_path: Path) -> None:
    """[[eliminate]] carries not_solvable_for into the receiving equation: the pairs of the eliminated
    equation, and every unknown entering through a variable the receiving equation could not be solved for."""
    assert set(model.equation("W1.FL").not_solvable_for) == {"vx", "vy", "psidot", "omega1"}
    assert model.equation("W1.dyn").not_solvable_for == ("omega1",)
    (tmp_path / "m.toml").write_text("""
[model]
name = "chain"
[[unknown]]
name = "a"
[[unknown]]
name = "b"
[[unknown]]
name = "c"
[[known]]
name = "u"
[[known]]
name = "y"
[[equation]]
id = "E1"
expr = "a = tanh(b)"
not_solvable_for = ["b"]
[[equation]]
id = "E2"
expr = "y = a + c"
[[equation]]
id = "E3"
expr = "b = 2*c + u"
[[equation]]
id = "E4"
expr = "u = c"
[[eliminate]]
variable = "a"
equation = "E1"
""")
    m = load_model(tmp_path / "m.toml")
    assert m.equation("E2").not_solvable_for == ("b",)  # y = tanh(b) + c: not solvable for b, still for c
    assert Solver(m).solvable(m.equation("E2"), "c")
    (tmp_path / "m2.toml").write_text((tmp_path / "m.toml").read_text() + """
[[eliminate]]
variable = "b"
equation = "E3"
""")
    m2 = load_model(tmp_path / "m2.toml")
    assert m2.equation("E2").not_solvable_for == ("c",)  # y = tanh(2c + u) + c: c enters through b
