"""Model uncertainty (issue 45): the declarations of the model format and their errors, the decoupling of the
residuals from unknown parameters and inputs (structure, cost, and numerically: a decoupled residual does not move
when the road grade does, while the nominal one moves by its analytic sensitivity), and the uncertainty
sensitivities against central differences of generators designed for perturbed vehicles."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import sympy

from fdi_analysis.cli import main as analyze
from fdi_analysis.dm import redundancy
from fdi_analysis.model import Model, ModelError
from fdi_analysis.model_loader import load_model
from fdi_analysis.residuals.causality import synthesize
from fdi_analysis.residuals.evaluate import residual, sensitivity_series
from fdi_analysis.residuals.uncertainty_sensitivity import (
    UncertaintySolver,
    bounded_whole,
    far_end,
    is_offset_like,
    offset_like,
    spread_series,
    uncertainties,
    uncertainty_sensitivities,
)
from fdi_analysis.robustness import analyse
from fdi_analysis.uncertainty import at_values, decoupled, perturbed

# A cart on a slope: mass m uncertain, accelerometer bias b (slowly varying), slope theta (unknown input).
CART_VARS = """
[model]
name = "cart"
[parameters]
m = { value = 100.0, unit = "kg", range = [90.0, 120.0] }
g = { value = 9.81 }
[[unknown]]
name = "v"
[[unknown]]
name = "dv"
[[unknown]]
name = "F"
[[known]]
name = "v_m"
[[known]]
name = "a_m"
[[known]]
name = "F_m"
[[fault]]
name = "f1"
[[fault]]
name = "f2"
[[fault]]
name = "f3"
"""
CART_NUISANCES = """
[[unknown_parameter]]
name = "b"
unit = "m/s^2"
range = [-0.1, 0.1]
drift = 0.001
[[unknown_input]]
name = "theta"
unit = "rad"
range = [-0.05, 0.05]
"""
CART_EQUATIONS = """
[[equation]]
id = "E1"
expr = "m*dv = F - m*g*sin(theta)"
[[equation]]
id = "E2"
expr = "a_m = dv + g*sin(theta) + b + f1"
[[equation]]
id = "E3"
expr = "v_m = v + f2"
[[equation]]
id = "E4"
expr = "F_m = F + f3"
[[equation]]
id = "D"
differential = ["dv", "v"]
"""
CART = CART_VARS + CART_NUISANCES + CART_EQUATIONS


def _load(tmp_path: Path, text: str, name: str = "cart.toml") -> Model:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return load_model(p)


# ------------------------------------------------------------------------------------------------ declarations
def test_declarations_load_and_the_nominal_model_is_the_model_without_them(tmp_path: Path) -> None:
    m = _load(tmp_path, CART)
    assert [(n.name, n.kind, n.range, n.drift) for n in m.nuisances] == [
        ("b", "slow", (-0.1, 0.1), 0.001), ("theta", "input", (-0.05, 0.05), 0.0)]
    assert list(m.uncertain_parameters()) == ["m"]
    assert m.parameters["m"].range == (90.0, 120.0)
    plain = CART_VARS.replace(', range = [90.0, 120.0]', '') + CART_EQUATIONS.replace(
        " - m*g*sin(theta)", "").replace(" + g*sin(theta) + b", "")
    ref = _load(tmp_path, plain, "plain.toml")
    assert [e.id for e in m.equations] == [e.id for e in ref.equations]
    for e, r in zip(m.equations, ref.equations, strict=True):
        assert (e.unknowns, e.knowns, e.faults) == (r.unknowns, r.knowns, r.faults), e.id
        if e.differential is None:
            assert sympy.simplify(e.residual - r.residual) == 0, e.id
    # the nuisances stay symbols in the raw equations (what decoupling starts from)
    raw = {e.id: e for e in m.nuisance_equations}
    assert {"b", "theta"} <= {str(s) for s in raw["E2"].rhs.free_symbols}


BAD_DECLARATIONS = [
    (CART.replace("range = [90.0, 120.0]", "range = [120.0, 90.0]"), "m", "empty"),
    (CART.replace("range = [90.0, 120.0]", "range = [110.0, 120.0]"), "m", "outside its range"),
    (CART.replace("range = [90.0, 120.0]", "range = [90.0]"), "m", "[lo, hi]"),
    (CART.replace("range = [90.0, 120.0]", 'range = [90.0, "a lot"]'), "m", "upper bound"),
    (CART.replace("g = { value = 9.81 }", 'g = { expr = "9.81", range = [9.7, 9.9] }'), "g", "'expr' parameter"),
    (CART.replace("range = [-0.1, 0.1]\ndrift", "drift"), "b", "needs a 'range'"),
    (CART.replace("drift = 0.001", "drift = -1.0"), "b", "drift"),
    (CART.replace('name = "theta"\nunit = "rad"', 'name = "theta"\nunit = "rad"\nspeed = 3'), "theta", "speed"),
    (CART.replace('name = "theta"', 'name = "b"'), "b", "twice"),
    (CART.replace('name = "theta"', 'name = "v"'), "v", ""),
    (CART.replace('[[unknown_input]]\nname = "theta"', '[[unknown_input]]\nname = "wind"\nrange = [0.0, 9.0]\n'
                  '[[unknown_input]]\nname = "theta"'), "wind", "appears in no equation"),
]


@pytest.mark.parametrize(("text", "symbol", "needle"), BAD_DECLARATIONS)
def test_bad_declarations_name_the_file_and_the_symbol(tmp_path: Path, text: str, symbol: str, needle: str) -> None:
    p = tmp_path / "bad.toml"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(ModelError) as info:
        load_model(p)
    msg = str(info.value)
    assert msg.startswith(str(p)), msg
    assert info.value.symbol == symbol and f"'{symbol}'" in msg, msg
    assert needle in msg, msg


def test_romo_declares_the_truth_plant_envelope(repo: Path) -> None:
    """Every quantity of the truth plant's envelope that the model holds lies inside the model's declared
    range (the model may be wider, never narrower)."""
    from fdi_host.sim.scenario import load_scenario
    from fdi_host.sim.vehicle_envelope import ENVELOPE, NOMINAL

    m = load_model(repo / "analysis/models/romo_quasistatic.toml")
    declared = {u.name: u.range for u in uncertainties(m)}
    p = m.parameters

    def envelope(name: str, nominal: float) -> tuple[float, float]:
        kind, lo, hi = ENVELOPE[name]
        return (lo * nominal, hi * nominal) if kind == "rel" else (lo, hi)

    pairs = {
        "m": envelope("m", NOMINAL.m), "Iz": envelope("Iz", NOMINAL.Iz), "h_CoG": envelope("h", NOMINAL.h),
        **{f"R{i}": envelope("R", NOMINAL.R[i - 1]) for i in (1, 2, 3, 4)}, "K_TM": envelope("K_TM", NOMINAL.K_TM[0]),
        "mu_DB": envelope("pad_mu", NOMINAL.pad_mu[0]), "mu_max": envelope("mu_peak", 1.0),
        "k_t": tuple(x * p["k_t"].value for x in envelope("tyre_stiffness", 1.0)),
        "g_x": tuple(p["g"].value * math.sin(math.atan(x)) for x in envelope("grade", 1.0)),
        "g_y": tuple(p["g"].value * math.sin(math.atan(x)) for x in envelope("bank", 1.0)),
        "b_ax": envelope("bias_ax", 1.0), "b_ay": envelope("bias_ay", 1.0), "b_r": envelope("bias_yaw", 1.0),
    }
    # the road's friction: the wet patch and the split friction of the scenarios scale the dry peak friction
    patches = [p.mu for sc in ("wet_patch", "country_road", "urban") for p in load_scenario(sc).road.patches]
    pairs["mu_max"] = (pairs["mu_max"][0] * min(patches, default=1.0), pairs["mu_max"][1])
    for name, (lo, hi) in pairs.items():
        d_lo, d_hi = declared[name]
        tol = 1e-9 * max(abs(lo), abs(hi))
        assert d_lo <= lo + tol and hi <= d_hi + tol, (name, (lo, hi), (d_lo, d_hi))
    # drag at the top speed of the scenarios (30 m/s) with the largest drag area, and rolling resistance at
    # the heaviest static wheel load with 20 % load transfer
    _, _, cda = ENVELOPE["CdA"]
    assert 0.5 * NOMINAL.rho_air * cda * 30.0**2 <= declared["F_res"][1]
    _, _, c_rr = ENVELOPE["c_rr"]
    load = envelope("m", NOMINAL.m)[1] * 9.81 / 4 * 1.2
    assert c_rr * load * envelope("R", NOMINAL.R[0])[1] <= declared["M_rr1"][1]


def test_romo_declares_the_accelerometer_tilt_of_the_truth_plant(repo: Path) -> None:
    """The body-fixed accelerometer of the truth plant pitches and rolls with the body: it reads g sin(pitch) per
    m/s^2 of longitudinal acceleration and g sin(roll) per m/s^2 of lateral acceleration more (suspension
    compliance; the model's c_ax, c_ay). Measured on the nominal vehicle and on the envelope's corners that tilt it
    most and least (heaviest and highest CoG, lightest and lowest), in the slalom (both accelerations): inside the
    declared ranges."""
    import dataclasses

    from fdi_host.sim.scenario import load_scenario
    from fdi_host.sim.truth_sim import simulate_truth
    from fdi_host.sim.vehicle_envelope import ENVELOPE, NOMINAL

    declared = {u.name: u.range for u in uncertainties(load_model(repo / "analysis/models/romo_quasistatic.toml"))}
    corners = [NOMINAL]
    for a in (1, 2):
        m = NOMINAL.m * ENVELOPE["m"][a]
        h = NOMINAL.h * ENVELOPE["h"][a]
        corners.append(dataclasses.replace(NOMINAL, name=f"corner {a}", m=m, h=h))
    for v in corners:
        tr = simulate_truth(load_scenario("slalom"), [], vehicle=v, seed=1, duration=12.0).true
        pitch_gain = float(np.polyfit(tr["ax"], 9.81 * np.sin(-tr["pitch"]), 1)[0])
        roll_gain = float(np.polyfit(tr["ay"], 9.81 * np.sin(tr["roll"]), 1)[0])
        assert declared["c_ax"][0] <= pitch_gain <= declared["c_ax"][1], (v.name, pitch_gain)
        assert declared["c_ay"][0] <= roll_gain <= declared["c_ay"][1], (v.name, roll_gain)


# ------------------------------------------------------------------------------------------------ decoupling
def test_decoupled_structure_and_cost(tmp_path: Path) -> None:
    m = _load(tmp_path, CART)
    assert redundancy(m.structure().X) == 2
    th = decoupled(m, ["theta"])
    assert "theta" in {v.name for v in th.unknowns} and [n.name for n in th.nuisances] == ["b"]
    assert redundancy(th.structure().X) == 1
    b = decoupled(m, ["b"])  # b and db unknowns, D.b and C.b equations: the redundancy stays
    assert [e.id for e in b.equations][-2:] == ["D.b", "C.b"]
    assert redundancy(b.structure().X) == 2
    assert redundancy(decoupled(m, ["b"], strict=True).structure().X) == 1
    assert redundancy(decoupled(decoupled(m, ["theta"]), ["b"], strict=True).structure().X) == 0
    with pytest.raises(ModelError, match="'wind' is not an unknown parameter or input"):
        decoupled(m, ["wind"])
    r = analyse(m)
    assert r.nominal.redundancy == 2 and len(r.nominal.detectable) == 3
    assert r.everything_strict.redundancy == 0 and r.everything_strict.detectable == ()
    # the slope: E1 and E2 both hold it, so only the whole model is left as a test (f1, f2, f3 detected, none
    # isolable); the bias with its zero derivative costs nothing; against a bias of any time course the
    # accelerometer fault is not detectable any more
    each = {c.nuisances: c for c in r.each}
    assert each[("theta",)].redundancy == 1 and each[("theta",)].lost_isolability
    assert each[("b",)].free and each[("b",)].redundancy == 2
    strict_b = next(c for c in r.each_strict if c.nuisances == ("b",))
    assert strict_b.lost_detectability == ("f1",)
    assert r.chosen.nuisances == ("b",) and r.bounded == ("theta",)


def test_robustness_cli_writes_its_report(tmp_path: Path) -> None:
    p = tmp_path / "cart.toml"
    p.write_text(CART, encoding="utf-8")
    assert analyze(["robustness", str(p), "--mso", "--workers", "1", "-o", str(tmp_path / "out")]) == 0
    doc = json.loads((tmp_path / "out/robustness.json").read_text())
    assert doc["nominal"]["redundancy"] == 2 and doc["nominal"]["msos"] >= 1
    assert (tmp_path / "out/robustness.png").stat().st_size > 10_000
    assert "| nothing (nominal model) | 2 (+0) |" in (tmp_path / "out/robustness.md").read_text()
    plain = tmp_path / "plain.toml"
    plain.write_text(CART_VARS + CART_EQUATIONS.replace(" - m*g*sin(theta)", "").replace(
        " + g*sin(theta) + b", ""), encoding="utf-8")
    assert analyze(["robustness", str(plain)]) == 1  # nothing to decouple: an error, not an empty report


# A body force balance along x (grouped ROMO): with the grade decoupled, the accelerometer (S1) takes the
# place of the kinematic acceleration; the nominal test of the same balance uses K1 and the speed's derivative.
DECOUPLED_B1 = ["B1", "K1", "D1", "S1", "S2", "S3", "S4", "S5", "W1.FL", "W2.FL", "W3.FL", "W4.FL", "W1.FS",
                "W2.FS", "W3.FS", "W4.FS", "W1.Fx", "W2.Fx", "W3.Fx", "W4.Fx", "S.omega1", "S.omega2", "S.omega3",
                "S.omega4"]
NOMINAL_B1 = [e for e in DECOUPLED_B1 if e != "S1"]


def _noise_free_drive(model: Model, scenario: str, duration: float) -> dict[str, np.ndarray]:
    from fdi_host.sim.plant import Plant
    from fdi_host.sim.scenario import load_scenario
    from fdi_host.sim.vehicle_sim import SimConfig, simulate

    res = simulate(load_scenario(scenario), [], plant=Plant(model), config=SimConfig(noise_scale=0.0),
                   duration=duration)
    step = round(0.01 / res.config.dt)
    return {k: np.asarray(v[::step], dtype=float) for k, v in res.measured.items()}


def test_a_decoupled_residual_does_not_see_the_grade(repo: Path) -> None:
    """Noise-free model-plant drives on a flat road and on a 4 % grade (the plant compiled from the model at
    g_x = g sin(atan(0.04))): the residual decoupled from the grade stays where it was, the nominal one moves by
    its analytic sensitivity times the grade."""
    grouped = load_model(repo / "analysis/models/romo_grouped.toml")
    quasi = load_model(repo / "analysis/models/romo_quasistatic.toml")
    grade = quasi.parameters["g"].value * math.sin(math.atan(0.04))
    dec = decoupled(grouped, ["g_x"])
    g_dec = synthesize(dec, DECOUPLED_B1, "dec")
    g_nom = synthesize(grouped, NOMINAL_B1, "nom")
    sens_nom = uncertainty_sensitivities(grouped, g_nom)
    sens = dict(sens_nom)
    assert "g_x" in sens and "g_x" not in dict(uncertainty_sensitivities(dec, g_dec))
    # the grade and the driving resistance enter the body-x balance as constants (an offset an on-line
    # estimator can take), the mass with the manoeuvre
    assert {"g_x", "F_res"} <= set(offset_like(sens_nom)) and "m" not in offset_like(sens_nom)
    assert not is_offset_like(sens_nom) and is_offset_like(tuple((n, sens[n]) for n in ("g_x", "F_res")))
    assert sens["g_x"] == pytest.approx(-grouped.parameters["m"].value)
    flat = _noise_free_drive(quasi, "straight", 10.0)
    hill = _noise_free_drive(at_values(quasi, {"g_x": grade}), "straight", 10.0)
    k = slice(300, None)  # after the filters' start
    r_flat, r_hill = residual(g_nom, flat)[k], residual(g_nom, hill)[k]
    shift = np.median(r_hill - r_flat)
    predicted = np.median(sensitivity_series(
        replace(g_nom, sensitivities=(("g_x", sens["g_x"]),)), hill)["g_x"][k]) * grade
    assert abs(shift) > 100.0  # N: m g sin(theta) ~ 410 N on the nominal vehicle
    assert shift == pytest.approx(predicted, rel=0.02)
    d_flat, d_hill = residual(g_dec, flat)[k], residual(g_dec, hill)[k]
    # the decoupled residual does not move (measured: 0.006 N against 410 N); what is left of it are the
    # filters' lag transients while the speed changes, which differ a little between the two trajectories (the
    # grade changes the acceleration phases: up to 10 N apart, its own peaks 40-50 N on either drive)
    assert abs(np.median(d_hill - d_flat)) < 1e-4 * abs(shift)
    assert np.max(np.abs(d_hill - d_flat)) < 0.05 * abs(shift)
    assert np.max(np.abs(d_hill)) < 0.2 * abs(shift)


# ------------------------------------------------------------------------------------------------ sensitivities
MSO7 = ["W2.FL", "W2.dyn", "W2.D", "S1", "S2", "S3", "S4", "S5", "S.omega2"]


def test_uncertainty_sensitivities_are_the_finite_differences(repo: Path) -> None:
    """d r / d theta of the wheel-2 spin test against central differences of the residual of generators
    designed for vehicles at theta0 +- h (r ~ s (theta_vehicle - theta_model): -dr/dtheta_model = s), on a
    cornering drive; h a thousandth of the quantity's half range (the tyre law's Max is a kink in R and the
    wheel speed: a wider step straddles it). The road's friction, an input that may sit anywhere in its range
    (`bounded_whole`), against the secant of generators for the nominal and the far-end vehicle."""
    m = load_model(repo / "analysis/models/romo_grouped.toml")
    us = UncertaintySolver(m)
    g = synthesize(m, MSO7, "MSO7")
    sens = uncertainty_sensitivities(m, g, us)
    names = [n for n, _ in sens]
    assert {"m", "h_CoG", "R2", "mu_max", "k_t", "K_TM", "mu_DB", "b_ax", "b_ay", "b_r", "g_x", "g_y",
            "M_rr2", "c_ax", "c_ay"} == set(names)
    assert "M_rr1" not in names and "Iz" not in names  # not in the equations of wheel 2's test
    # noise-free: the residual is cleared of its divisions (which hold R), so on noisy data a generator for
    # another R also scales the noise; the sensitivity is that of consistent data
    sig = _noise_free_drive(load_model(repo / "analysis/models/romo_quasistatic.toml"), "cornering", 8.0)
    k = slice(300, None)
    by = {u.name: u for u in us.quantities}
    for name, expr in sens:
        if name not in ("m", "R2", "k_t", "mu_max", "b_ax", "g_x", "M_rr2", "c_ax"):
            continue
        series = sensitivity_series(replace(g, sensitivities=((name, expr),)), sig)[name][k]
        u = by[name]
        if bounded_whole(u):  # the road's friction: the secant to the far end of its range (dry to ice)
            far = far_end(u)
            there = residual(synthesize(at_values(m, {name: u.nominal + far}), MSO7, "far"), sig)[k]
            fd = -(there - residual(g, sig)[k]) / far
        else:
            h = 1e-3 * u.half_width
            up = residual(synthesize(at_values(m, {name: u.nominal + h}), MSO7, "up"), sig)[k]
            dn = residual(synthesize(at_values(m, {name: u.nominal - h}), MSO7, "dn"), sig)[k]
            fd = -(up - dn) / (2 * h)
        scale = np.max(np.abs(series))
        assert scale > 0.0, name
        assert np.max(np.abs(fd - series)) <= 1e-3 * scale, name
    total, parts = spread_series(g, sens, {u.name: u.half_width for u in us.quantities}, sig)
    assert set(parts) == set(names)
    assert np.allclose(total, sum(parts.values()))


def test_perturbed_model_holds_one_perturbation_and_no_fault(tmp_path: Path) -> None:
    m = _load(tmp_path, CART)
    p = perturbed(m, "m")
    assert [f.name for f in p.faults] == ["unc__m"] and "m" not in p.parameters
    e1 = p.equation("E1")
    assert e1.faults == ("unc__m",)
    assert {str(s) for s in p.equation("E2").rhs.free_symbols} == {"dv"}  # theta, b nominal (0); f1 zero
    with pytest.raises(ModelError, match="'g' is not an uncertain parameter"):
        perturbed(m, "g")
    v = at_values(m, {"theta": 0.02, "m": 110.0})
    assert v.parameters["m"].value == 110.0
    assert {str(s) for s in v.equation("E1").rhs.free_symbols} == {"F", "m", "g"}
    with pytest.raises(ModelError, match="'wind' is not a parameter"):
        at_values(m, {"wind": 1.0})
