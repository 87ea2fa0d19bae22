"""The truth plant: a dual-track vehicle written from vehicle-dynamics physics, independent of the diagnosis model.

Nothing here is read from the model file. The body moves in the road plane (vx, vy, yaw rate r) and, on a
spring-damper suspension per corner with an anti-roll bar per axle, in heave z, roll phi and pitch theta; the
suspension forces are the wheel loads (massless wheels, rigid tyres vertically), so the loads follow the body's
motion instead of the diagnosis model's quasi-static formula. Conventions: x forward, y left, z up; roll phi
positive lifts the left side, pitch theta positive lowers the nose (right-handed about y).

    m (dvx - vy r) = sum Fx_i - F_drag - m g sin(theta_g)                 road grade theta_g, uphill positive
    m (dvy + vx r) = sum Fy_i - m g cos(theta_g) sin(phi_g)              road bank phi_g, left side higher
    Iz dr          = sum (x_i Fy_i - y_i Fx_i)
    m ddz          = sum Fz_i - m g cos(theta_g) cos(phi_g)
    Ix ddphi       = sum y_i Fz_i + h sum Fy_i + m g_n h phi
    Iy ddtheta     = -sum x_i Fz_i - h sum Fx_i + m g_n h theta
    Fz_i           = max(0, Fz0_i - k z_i - c dz_i -+ K_arb phi / w),  z_i = z - x_i theta + y_i phi
    J_w domega_i   = K_TM_i i_i (1 + a sin(N angle_i)) + f_TM - pad_i A r P tanh(omega_i / omega_b) + f_DB
                     - R_i c_rr Fz_i tanh(omega_i / 0.5) - R_i FL_i

Tyres: PAC2002 with combined slip (`fdi_host.sim.tyre`, CommonRoad's published functions and parameters) on the
relaxed slips kappa_i, alpha_i of first-order relaxation (lengths sigma_x, sigma_y):

    sigma_x dkappa_i = (R_i omega_i - vL_i) - |vL_i| kappa_i      sigma_y dalpha_i = vS_i - |vL_i| alpha_i

which keeps the slips finite at standstill (a tyre then acts as a spring) and adds the tyre lag; below 2 m/s a
fading damping term on the slip velocity damps the tyre-spring modes (Pacejka's low-speed damping). Faults
f18..f21 add to FL and FS of their wheel, f10..f13 to the motor torque and f14..f17 to the brake torque, as Table
I places them. The accelerometer's specific force (what it measures: the non-gravitational force per mass) is
returned in the sensor frame, which rolls and pitches with the body.

Integration: fixed step h (default 0.5 ms, two per 1 kHz control period), semi-implicit: velocities from the
forces at the start of the step (wheel speeds linearly implicit in the brake, rolling-resistance and damping
terms), then positions and relaxed slips from the new velocities (the slips implicit in their |vL| decay), which
keeps the undamped tyre-spring modes (<= 130 rad/s) stable. Compiled with numba: one 1 kHz period costs a few
microseconds.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from fdi_host.sim.tyre import P_DY1, combined_forces
from fdi_host.sim.vehicle_envelope import Vehicle

FloatArray = NDArray[np.float64]
G = 9.81

# state vector
STATE_NAMES: tuple[str, ...] = (
    "vx", "vy", "psidot", "z", "dz", "roll", "droll", "pitch", "dpitch",
    "omega1", "omega2", "omega3", "omega4", "kappa1", "kappa2", "kappa3", "kappa4",
    "alpha1", "alpha2", "alpha3", "alpha4", "angle1", "angle2", "angle3", "angle4", "distance", "heading",
)
N_STATE = len(STATE_NAMES)
VX, VY, YR, Z, DZ, ROLL, DROLL, PITCH, DPITCH = range(9)
OMEGA, KAPPA, ALPHA, ANGLE, DIST, HEAD = 9, 13, 17, 21, 25, 26

# vehicle parameter vector
PARAM_NAMES: tuple[str, ...] = (
    "m", "Iz", "Ix", "Iy", "h", "l_f", "l_r", "w", "k_susp", "c_susp", "k_arb_f", "k_arb_r",
    "R1", "R2", "R3", "R4", "J_w", "mu_peak", "tyre_stiffness", "sigma_x", "sigma_y", "CdA", "rho_air", "c_rr",
    "K_TM1", "K_TM2", "K_TM3", "K_TM4", "ripple", "ripple_per_rev", "pad1", "pad2", "pad3", "pad4", "A_DB", "r_DB",
    "omega_brake", "grade", "bank",
)
_P = {n: i for i, n in enumerate(PARAM_NAMES)}
(PM, PIZ, PIX, PIY, PH, PLF, PLR, PW, PK, PC, PKAF, PKAR) = range(12)
PR, PJW, PMU, PST, PSX, PSY, PCDA, PRHO, PCRR = 12, 16, 17, 18, 19, 20, 21, 22, 23
PKTM, PRIP, PRIPN, PPAD, PADB, PRDB, POMB, PGRADE, PBANK = 24, 28, 29, 30, 34, 35, 36, 37, 38

# recorded per 1 kHz sample (at the start of the period)
RECORDED_NAMES: tuple[str, ...] = (
    "Fz1", "Fz2", "Fz3", "Fz4", "FL1", "FL2", "FL3", "FL4", "FS1", "FS2", "FS3", "FS4",
    "spec_fx", "spec_fy", "ax", "ay", "road_grade", "road_bank", "mu_left", "mu_right", "F_drag",
)
N_REC = len(RECORDED_NAMES)
# inputs per period: true steering angles, motor currents, axle pressures; plant faults f10..f21
N_INPUT = 10
N_PLANT_FAULTS = 12
V_LOW = 2.0  # m/s, below it the tyre's low-speed damping fades in
C_LOW_X = 1500.0  # N s/m, low-speed damping of the longitudinal slip velocity
C_LOW_Y = 4000.0  # N s/m, of the lateral
KAPPA_MAX, ALPHA_MAX = 1.5, 1.2


def parameter_vector(v: Vehicle) -> FloatArray:
    """The vehicle as the compiled plant's parameter vector (order of PARAM_NAMES)."""
    vals = [v.m, v.Iz, v.Ix, v.Iy, v.h, v.l_f, v.l_r, v.w, v.k_susp, v.c_susp, v.k_arb_f, v.k_arb_r, *v.R, v.J_w,
            v.mu_peak, v.tyre_stiffness, v.sigma_x, v.sigma_y, v.CdA, v.rho_air, v.c_rr, *v.K_TM, v.ripple,
            v.ripple_per_rev, *v.pad_mu, v.piston_area, v.disc_radius, v.omega_brake, v.grade, v.bank]
    return np.array(vals, dtype=np.float64)


def initial_state(v: Vehicle, speed: float) -> FloatArray:
    """Rolling straight at `speed` on a flat road, the body at its static equilibrium."""
    x = np.zeros(N_STATE)
    x[VX] = speed
    for i in range(4):
        x[OMEGA + i] = speed / v.R[i]
    return x


@numba.njit(cache=True)
def _road(s: float, gs: FloatArray, gv: FloatArray, bs: FloatArray, bv: FloatArray, ps: FloatArray,
          pe: FloatArray, pml: FloatArray, pmr: FloatArray, goff: float, boff: float
          ) -> tuple[float, float, float, float]:
    grade = min(0.08, max(-0.08, goff + np.interp(s, gs, gv)))
    bank = min(0.05, max(-0.05, boff + np.interp(s, bs, bv)))
    mul = 1.0
    mur = 1.0
    for k in range(ps.size):
        if ps[k] <= s < pe[k]:
            mul *= pml[k]
            mur *= pmr[k]
    return grade, bank, mul, mur


@numba.njit(cache=True)
def step(x: FloatArray, u: FloatArray, f: FloatArray, p: FloatArray, tp: FloatArray, gs: FloatArray,
         gv: FloatArray, bs: FloatArray, bv: FloatArray, ps: FloatArray, pe: FloatArray, pml: FloatArray,
         pmr: FloatArray, h: float, nsub: int, rec: FloatArray) -> bool:
    """Advance the state `x` in place by `nsub` steps of `h` with inputs `u` (delta1..4, iTM1..4, P_f, P_r) and
    plant faults `f` (f10..f21); `rec` gets the RECORDED_NAMES quantities at the start. False if not finite."""
    m, Iz, Ix, Iy, hc = p[PM], p[PIZ], p[PIX], p[PIY], p[PH]
    lf, lr, w = p[PLF], p[PLR], p[PW]
    L = lf + lr
    xs = (lf, lf, -lr, -lr)
    ys = (0.5 * w, -0.5 * w, 0.5 * w, -0.5 * w)
    fz0 = (m * G * lr / (2 * L), m * G * lr / (2 * L), m * G * lf / (2 * L), m * G * lf / (2 * L))
    mu_scale0 = p[PMU] / tp[P_DY1]
    Fz = np.zeros(4)
    FL = np.zeros(4)
    FS = np.zeros(4)
    vL = np.zeros(4)
    vS = np.zeros(4)
    for j in range(nsub):
        grade, bank, mul, mur = _road(x[DIST], gs, gv, bs, bv, ps, pe, pml, pmr, p[PGRADE], p[PBANK])
        thg = math.atan(grade)
        phg = math.atan(bank)
        gx = G * math.sin(thg)
        gy = G * math.cos(thg) * math.sin(phg)
        gn = G * math.cos(thg) * math.cos(phg)
        vx, vy, r = x[VX], x[VY], x[YR]
        roll, pitch = x[ROLL], x[PITCH]
        sumFx = 0.0
        sumFy = 0.0
        sumFz = 0.0
        Mz = 0.0
        Mx_susp = 0.0
        My_susp = 0.0
        jac = np.zeros(4)
        dom = np.zeros(4)
        for i in range(4):
            zi = x[Z] - xs[i] * pitch + ys[i] * roll
            dzi = x[DZ] - xs[i] * x[DPITCH] + ys[i] * x[DROLL]
            karb = p[PKAF] if i < 2 else p[PKAR]
            arb = -karb * roll / w if i % 2 == 0 else karb * roll / w
            Fz[i] = max(0.0, fz0[i] - p[PK] * zi - p[PC] * dzi + arb)
            d = u[i]
            cd, sd = math.cos(d), math.sin(d)
            uu = vx - ys[i] * r
            vv = vy + xs[i] * r
            vL[i] = uu * cd + vv * sd
            vS[i] = -uu * sd + vv * cd
            Ri = p[PR + i]
            mu_i = mu_scale0 * (mul if i % 2 == 0 else mur)
            fl, fs = combined_forces(x[KAPPA + i], x[ALPHA + i], Fz[i], tp, mu_i, p[PST])
            fade = max(0.0, 1.0 - abs(vL[i]) / V_LOW)
            fl += C_LOW_X * fade * (Ri * x[OMEGA + i] - vL[i])
            fs -= C_LOW_Y * fade * vS[i]
            fl += f[8 + i]  # f18..f21: tyre force faults on both components, as the model places them
            fs += f[8 + i]
            FL[i] = fl
            FS[i] = fs
            Fx = fl * cd - fs * sd
            Fy = fl * sd + fs * cd
            sumFx += Fx
            sumFy += Fy
            sumFz += Fz[i]
            Mz += xs[i] * Fy - ys[i] * Fx
            Mx_susp += ys[i] * Fz[i]
            My_susp -= xs[i] * Fz[i]
            # wheel spin
            om = x[OMEGA + i]
            P = u[8] if i < 2 else u[9]
            tb = math.tanh(om / p[POMB])
            trr = math.tanh(om / 0.5)
            brake_gain = p[PPAD + i] * p[PADB] * p[PRDB] * P
            torque = (p[PKTM + i] * u[4 + i] * (1.0 + p[PRIP] * math.sin(p[PRIPN] * x[ANGLE + i])) + f[i]
                      - brake_gain * tb + f[4 + i] - Ri * p[PCRR] * Fz[i] * trr - Ri * fl)
            dom[i] = torque / p[PJW]
            jac[i] = (-brake_gain * (1.0 - tb * tb) / p[POMB] - Ri * p[PCRR] * Fz[i] * (1.0 - trr * trr) / 0.5
                      - Ri * C_LOW_X * fade * Ri) / p[PJW]
        F_drag = 0.5 * p[PRHO] * p[PCDA] * vx * abs(vx)
        fx_spec = (sumFx - F_drag) / m
        fy_spec = sumFy / m
        ax = fx_spec - gx
        ay = fy_spec - gy
        dvx = ax + vy * r
        dvy = ay - vx * r
        dr = Mz / Iz
        ddz = (sumFz - m * gn) / m
        ddroll = (Mx_susp + hc * sumFy + m * gn * hc * roll) / Ix
        ddpitch = (My_susp - hc * sumFx + m * gn * hc * pitch) / Iy
        if j == 0:
            fz_spec = sumFz / m
            for i in range(4):
                rec[i] = Fz[i]
                rec[4 + i] = FL[i]
                rec[8 + i] = FS[i]
            rec[12] = fx_spec * math.cos(pitch) - fz_spec * math.sin(pitch)
            rec[13] = fy_spec * math.cos(roll) + fz_spec * math.sin(roll)
            rec[14] = ax
            rec[15] = ay
            rec[16] = grade
            rec[17] = bank
            rec[18] = mul
            rec[19] = mur
            rec[20] = F_drag
        # velocities
        x[VX] = vx + h * dvx
        x[VY] = vy + h * dvy
        x[YR] = r + h * dr
        x[DZ] += h * ddz
        x[DROLL] += h * ddroll
        x[DPITCH] += h * ddpitch
        for i in range(4):
            x[OMEGA + i] += h * dom[i] / (1.0 - h * jac[i])
        # positions and relaxed slips from the new velocities
        x[Z] += h * x[DZ]
        x[ROLL] += h * x[DROLL]
        x[PITCH] += h * x[DPITCH]
        x[DIST] += h * math.hypot(x[VX], x[VY])
        x[HEAD] += h * x[YR]
        vx, vy, r = x[VX], x[VY], x[YR]
        for i in range(4):
            x[ANGLE + i] = np.fmod(x[ANGLE + i] + h * x[OMEGA + i], 2.0 * math.pi)
            d = u[i]
            cd, sd = math.cos(d), math.sin(d)
            uu = vx - ys[i] * r
            vv = vy + xs[i] * r
            vl = uu * cd + vv * sd
            vs = -uu * sd + vv * cd
            a = h * abs(vl)
            k = (x[KAPPA + i] + h * (p[PR + i] * x[OMEGA + i] - vl) / p[PSX]) / (1.0 + a / p[PSX])
            al = (x[ALPHA + i] + h * vs / p[PSY]) / (1.0 + a / p[PSY])
            x[KAPPA + i] = min(KAPPA_MAX, max(-KAPPA_MAX, k))
            x[ALPHA + i] = min(ALPHA_MAX, max(-ALPHA_MAX, al))
    for i in range(N_STATE):  # noqa: SIM110 (numba compiles loops, not generators)
        if not math.isfinite(x[i]):
            return False
    return True
