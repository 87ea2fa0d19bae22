"""The truth plant's tyre: the Magic Formula of PAC2002 with combined slip, as published by CommonRoad
(`commonroad-vehicle-models`, BSD, `vehiclemodels.utils.tire_model`: Althoff and Würsching, "CommonRoad: Vehicle
Models", 2020), with CommonRoad's published parameter set (the ADAMS handbook tyre,
``vehiclemodels/parameters/parameters_tire.yaml``), read from the installed package at run time.

Why not CommonRoad's functions themselves: they are scalar Python, called 16 times per wheel step; the truth plant
needs them compiled (numba) to run faster than real time. The formulas below are written from the same published
equations with the same simplifications (turn slip neglected, camber zero, the stiffness K = p_k1 * Fz), and
tests/host/test_truth_tyre.py checks them against CommonRoad's functions over slip, slip angle and load.

Conventions of this module (the diagnosis model's): the longitudinal slip ``kappa`` is positive when the wheel
drives (R*omega > v), the slip angle ``alpha`` is positive when the contact point slides to the wheel's left
(alpha ~ vS/|vL|); FL is positive forward, FS positive to the left (so FS opposes alpha). CommonRoad's slip is
positive when braking (s = 1 - R*omega/u); its functions get ``-kappa``.

Scaling to the vehicle: the published tyre's forces are proportional to the load (D = mu * Fz, K = p_k1 * Fz), so
it carries ROMO's loads (2.6 kN static) as they are; at the static load its cornering stiffness is
21.9 * 2565 N = 56 kN/rad, against the diagnosis model's 50 kN/rad. Two scale factors, the Magic Formula's own
lambda factors: ``mu_scale`` multiplies the peak friction (D_x, D_y: a road of friction mu over the tyre's
published peak), ``stiffness_scale`` the slip stiffnesses (K_x, K_y: the tyre-stiffness spread of the envelope).
"""

from __future__ import annotations

import math
from functools import cache
from importlib import resources

import numba
import numpy as np
import yaml
from numpy.typing import NDArray

from fdi_host.errors import FdiHostError

FloatArray = NDArray[np.float64]

# The parameter names of CommonRoad's tyre file, in the order of the array the compiled functions take.
FIELDS: tuple[str, ...] = (
    "p_cx1", "p_dx1", "p_dx3", "p_ex1", "p_kx1", "p_hx1", "p_vx1", "r_bx1", "r_bx2", "r_cx1", "r_ex1", "r_hx1",
    "p_cy1", "p_dy1", "p_dy3", "p_ey1", "p_ky1", "p_hy1", "p_hy3", "p_vy1", "p_vy3", "r_by1", "r_by2", "r_by3",
    "r_cy1", "r_ey1", "r_hy1", "r_vy1", "r_vy3", "r_vy4", "r_vy5", "r_vy6",
)
_I = {name: i for i, name in enumerate(FIELDS)}
P_CX1, P_DX1, P_EX1, P_KX1, P_HX1, P_VX1 = (_I[n] for n in ("p_cx1", "p_dx1", "p_ex1", "p_kx1", "p_hx1", "p_vx1"))
R_BX1, R_BX2, R_CX1, R_EX1, R_HX1 = (_I[n] for n in ("r_bx1", "r_bx2", "r_cx1", "r_ex1", "r_hx1"))
P_CY1, P_DY1, P_EY1, P_KY1 = (_I[n] for n in ("p_cy1", "p_dy1", "p_ey1", "p_ky1"))
R_BY1, R_BY2, R_BY3, R_CY1, R_EY1, R_HY1 = (_I[n] for n in ("r_by1", "r_by2", "r_by3", "r_cy1", "r_ey1", "r_hy1"))
R_VY1, R_VY4, R_VY5, R_VY6 = (_I[n] for n in ("r_vy1", "r_vy4", "r_vy5", "r_vy6"))
SOURCE = "commonroad-vehicle-models: vehiclemodels/parameters/parameters_tire.yaml"


class TyreParameterError(FdiHostError, ValueError):
    """CommonRoad's tyre file is missing or lacks a parameter."""


@cache
def published_parameters() -> dict[str, float]:
    """CommonRoad's published tyre parameters (name -> value), read from the installed package."""
    try:
        text = resources.files("vehiclemodels").joinpath("parameters/parameters_tire.yaml").read_text("utf-8")
    except (ModuleNotFoundError, FileNotFoundError) as exc:
        raise TyreParameterError(f"{SOURCE} not found: pip install commonroad-vehicle-models") from exc
    tire = (yaml.safe_load(text) or {}).get("tire", {})
    missing = [n for n in FIELDS if n not in tire]
    if missing:
        raise TyreParameterError(f"{SOURCE}: no {', '.join(missing)}")
    return {n: float(tire[n]) for n in FIELDS}


def parameter_array() -> FloatArray:
    """The published parameters as the array the compiled functions take (order of FIELDS)."""
    p = published_parameters()
    return np.array([p[n] for n in FIELDS], dtype=np.float64)


@numba.njit(cache=True, fastmath=False)
def _mf(B: float, C: float, E: float, x: float) -> float:
    """The Magic Formula's shape: C * atan(B x - E (B x - atan(B x)))."""
    bx = B * x
    return C * math.atan(bx - E * (bx - math.atan(bx)))


@numba.njit(cache=True)
def pure_longitudinal(kappa: float, Fz: float, p: FloatArray, mu_scale: float, stiffness_scale: float) -> float:
    """F_x0 for pure longitudinal slip `kappa` (positive driving); CommonRoad's formula_longitudinal at -kappa."""
    k = kappa + p[P_HX1]  # CommonRoad negates its braking-positive slip into this driving-positive one
    C = p[P_CX1]
    D = p[P_DX1] * mu_scale * Fz
    K = Fz * p[P_KX1] * stiffness_scale
    B = K / (C * D) if D > 0.0 else 0.0
    return float(D * math.sin(_mf(B, C, p[P_EX1], k) + Fz * p[P_VX1]))


@numba.njit(cache=True)
def pure_lateral(alpha_cr: float, Fz: float, p: FloatArray, mu_scale: float, stiffness_scale: float) -> float:
    """F_y0 for pure slip angle `alpha_cr` (CommonRoad's formula_lateral at camber 0: no shifts)."""
    C = p[P_CY1]
    D = p[P_DY1] * mu_scale * Fz
    K = Fz * p[P_KY1] * stiffness_scale
    B = K / (C * D) if D > 0.0 else 0.0
    return float(D * math.sin(_mf(B, C, p[P_EY1], alpha_cr)))


@numba.njit(cache=True)
def combined_forces(kappa: float, alpha: float, Fz: float, p: FloatArray, mu_scale: float,
                    stiffness_scale: float) -> tuple[float, float]:
    """(FL, FS) in the wheel frame for slip `kappa` (driving positive) and slip angle `alpha` (contact point
    sliding left positive, the same sign as CommonRoad's) at load `Fz`: PAC2002 pure slip weighted by the
    combined-slip functions G_x, G_y and the kappa-induced side force, as CommonRoad's formula_longitudinal_comb
    and formula_lateral_comb."""
    if Fz <= 0.0:
        return 0.0, 0.0
    k_cr = -kappa  # CommonRoad's slip (braking positive) for the combined-slip functions
    a_cr = alpha  # CommonRoad's slip angle has our sign (atan(v/u) - delta); p_ky1 < 0 makes FS oppose it
    F0x = pure_longitudinal(kappa, Fz, p, mu_scale, stiffness_scale)
    F0y = pure_lateral(a_cr, Fz, p, mu_scale, stiffness_scale)
    mu_y = p[P_DY1] * mu_scale
    # G_x(alpha): CommonRoad's formula_longitudinal_comb
    s_h = p[R_HX1]
    Bxa = p[R_BX1] * math.cos(math.atan(p[R_BX2] * k_cr))
    Cxa, Exa = p[R_CX1], p[R_EX1]
    Fx = F0x / math.cos(_mf(Bxa, Cxa, Exa, s_h)) * math.cos(_mf(Bxa, Cxa, Exa, a_cr + s_h))
    # G_y(kappa) and S_Vy(kappa): CommonRoad's formula_lateral_comb (camber 0)
    s_hk = p[R_HY1]
    Byk = p[R_BY1] * math.cos(math.atan(p[R_BY2] * (a_cr - p[R_BY3])))
    Cyk, Eyk = p[R_CY1], p[R_EY1]
    D_vyk = mu_y * Fz * p[R_VY1] * math.cos(math.atan(p[R_VY4] * a_cr))
    S_vyk = D_vyk * math.sin(p[R_VY5] * math.atan(p[R_VY6] * k_cr))
    Fy = F0y / math.cos(_mf(Byk, Cyk, Eyk, s_hk)) * math.cos(_mf(Byk, Cyk, Eyk, k_cr + s_hk)) + S_vyk
    return Fx, Fy
