"""The ROMO plant compiled from the model file: a causal ordering of the model's own equations.

Nothing of the physics is written here. The normal equations of ``analysis/models/romo_quasistatic.toml``
are solved, one at a time, for the unknown each of them computes (a causal ordering found by repeatedly
taking an equation with exactly one uncomputed unknown), and the resulting assignment sequence is turned
into one Python function by ``sympy.lambdify`` (``math`` module, common subexpressions eliminated).

Inputs of the plant function: the states (vx, vy, psidot, omega1..4), the true actuator values
(delta1..4, iTM1..4, P_f, P_r), the actuator/tyre faults that appear in normal equations (f10..f21),
and a guess for the two *tear variables* ax, ay.

The algebraic loop. The quasi-static loads Fz depend on ax, ay (eq. 2), the tyre forces on Fz, and ax, ay
on the tyre forces (B1/K1, B2/K2). We tear the loop at (ax, ay): the ordering treats them as inputs and the
two equations left over (K1, K2) become loop residuals ``rho(ax, ay)``. Every quantity in the loop is
*affine* in (ax, ay) (Fz is linear in the accelerations, the tyre law is linear in Fmax = mu*Fz, the body
equations are linear in the forces). That is proved at build time: forward-mode sensitivities
d(.)/d(ax, ay) are generated symbolically through the sequence and checked to be free of every
loop-dependent symbol. The loop is then solved *exactly* per evaluation by one 2x2 linear solve
(a Newton step on an affine function), not by fixed-point iteration and not with a one-step delay.

For the stiff wheel-spin dynamics the function also returns the diagonal Jacobian
d(domega_i)/d(omega_i) (forward mode with seed omega_i, loads frozen), used by the semi-implicit
integrator in `fdi_host.sim.vehicle_sim`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import cast

import numpy as np
import sympy
from numpy.typing import NDArray
from sympy.printing.pycode import PythonCodePrinter

from fdi_analysis.expressions import der
from fdi_analysis.model import Equation, Model
from fdi_analysis.model_loader import load_model
from fdi_analysis.names import in_order
from fdi_analysis.resources import MODELS
from fdi_host.errors import FdiHostError

DEFAULT_MODEL = MODELS.path() / "romo_quasistatic.toml"  # analysis/models/ in a checkout, the copy in a wheel

STATES: tuple[str, ...] = ("vx", "vy", "psidot", "omega1", "omega2", "omega3", "omega4")
TEAR: tuple[str, ...] = ("ax", "ay")
WHEELS: tuple[int, ...] = (1, 2, 3, 4)
# Internal quantities recorded alongside the states (for plots, ground truth and physics tests).
RECORDED: tuple[str, ...] = tuple(
    f"{n}{i}" for n in ("Fz", "FL", "FS", "Fx", "Fy", "sL", "sS", "MTM", "MDB") for i in WHEELS
)

FloatArray = NDArray[np.float64]


def _hoistable(n: sympy.Basic) -> bool:
    if isinstance(n, sympy.Function):
        return True
    if isinstance(n, sympy.Pow):
        e = n.exp
        return not (e.is_Integer and e > 0)
    return False


def _sign(x: float) -> float:
    return 0.0 if x == 0.0 else math.copysign(1.0, x)


def _heaviside(x: float) -> float:
    return 1.0 if x > 0.0 else (0.5 if x == 0.0 else 0.0)


class _Printer(PythonCodePrinter):  # type: ignore[misc]
    """Python printer with plain helpers for sign and Heaviside (sympy would print Piecewise chains)."""

    def _print_sign(self, expr: sympy.Expr) -> str:
        return f"_sign({self._print(expr.args[0])})"

    def _print_Heaviside(self, expr: sympy.Expr) -> str:
        return f"_heaviside({self._print(expr.args[0])})"


class PlantError(FdiHostError, RuntimeError):
    """The model cannot be turned into a simulation (no causal ordering, non-affine loop, ...)."""


def _solve_linear(residual: sympy.Expr, target: sympy.Symbol, where: str) -> sympy.Expr:
    """Solve ``residual = 0`` for `target`; the residual must be linear in it (every equation a
    causal ordering uses here is; a nonlinear one would need an iterative solver and is refused)."""
    coeff = sympy.diff(residual, target)
    if target in coeff.free_symbols or coeff == 0:
        raise PlantError(f"equation {where} is not linear in {target}")
    rest = residual.xreplace({target: sympy.Integer(0)})
    return sympy.Mul(-1, rest, sympy.Pow(coeff, -1))


@dataclass(frozen=True)
class Assignment:
    """``target = expr``, taken from model equation `equation`."""

    target: str
    expr: sympy.Expr
    equation: str


@dataclass(frozen=True)
class PlantEval:
    """One plant evaluation with the algebraic loop solved."""

    xdot: FloatArray  # d/dt of STATES
    jac_omega: FloatArray  # d(domega_i)/d(omega_i), i = 1..4
    accel: FloatArray  # (ax, ay), the loop solution
    recorded: FloatArray  # values of RECORDED


def _derivative_symbol(name: str) -> sympy.Symbol:
    return sympy.Symbol(f"der_{name}", real=True)


def _sym(name: str) -> sympy.Symbol:
    return sympy.Symbol(name, real=True)


def _replace_der(expr: sympy.Expr) -> sympy.Expr:
    """der(x) -> the placeholder symbol der_x, and every symbol declared real (so that sympy
    differentiates Abs and Max into sign and Heaviside instead of complex-valued derivatives)."""
    out = expr.replace(der, lambda a: _derivative_symbol(str(a)))
    return out.xreplace({s: sympy.Symbol(s.name, real=True) for s in out.free_symbols})


class Plant:
    """The compiled plant. Build with `Plant.from_model_file` (or `Plant(model)`)."""

    def __init__(self, model: Model) -> None:
        self.model = model
        self.params: dict[str, float] = model.parameter_values()
        self._psub = {sympy.Symbol(k): sympy.Float(v) for k, v in self.params.items()}
        self._psub.update({_sym(k): sympy.Float(v) for k, v in self.params.items()})
        eqs = model.equations
        measurement = [e for e in eqs if e.kind == "measurement"]
        normal = [e for e in eqs if e.kind == "normal"]
        differential = [e for e in eqs if e.kind == "differential"]
        known_names = {v.name for v in model.knowns}

        # Actuator inputs: unknowns tied to an actuator-side measurement (delta_i, iTM_i, P_a). They are
        # the measurement equations whose known is not a sensor of a state or a loop variable.
        sensed = set(STATES) | set(TEAR) | {"psidot"}
        self.input_equations: tuple[Equation, ...] = tuple(
            e for e in measurement if not (set(e.unknowns) & sensed)
        )
        self.sensor_equations: tuple[Equation, ...] = tuple(
            e for e in measurement if set(e.unknowns) & sensed
        )
        self.inputs: tuple[str, ...] = tuple(e.unknowns[0] for e in self.input_equations)
        for e in self.input_equations:
            if len(e.unknowns) != 1:
                raise PlantError(f"input equation {e.id} has unknowns {e.unknowns}")
        normal_faults = in_order({f for e in normal for f in e.faults}, [f.name for f in model.faults])
        self.faults: tuple[str, ...] = tuple(normal_faults)

        # Derivative targets: dvx, dvy (D1, D2), domega_i (W.D) and der(psidot) inline in B3.
        self.state_derivative: dict[str, str] = {}
        for e in differential:
            assert e.differential is not None
            dx, x = e.differential
            self.state_derivative[x] = dx
        for e in normal:
            for x in e.derivatives:
                self.state_derivative[x] = str(_derivative_symbol(x))
        missing = [s for s in STATES if s not in self.state_derivative]
        if missing:
            raise PlantError(f"no derivative equation for states {missing}")

        given = set(STATES) | set(self.inputs) | set(self.faults) | set(TEAR) | known_names
        self.assignments, self.loop_equations = self._causal_order(normal, given)
        self._build_function()

    @classmethod
    def from_model_file(cls, path: str | Path = DEFAULT_MODEL) -> Plant:
        return cls(load_model(path))

    # ------------------------------------------------------------------------------------------ ordering
    def _causal_order(
        self, normal: Sequence[Equation], given: set[str]
    ) -> tuple[tuple[Assignment, ...], tuple[Equation, ...]]:
        computed = set(given)
        pending = list(normal)
        order: list[Assignment] = []
        progress = True
        while pending and progress:
            progress = False
            for e in list(pending):
                lhs = _replace_der(e.lhs)
                rhs = _replace_der(e.rhs)
                names = {str(s) for s in (lhs - rhs).free_symbols} - set(self.params)
                open_ = sorted(names - computed)
                if len(open_) != 1:
                    continue
                (target,) = open_
                if target in e.not_solvable_for:
                    continue
                order.append(Assignment(target, _solve_linear(lhs - rhs, _sym(target), e.id), e.id))
                computed.add(target)
                pending.remove(e)
                progress = True
        loop = tuple(e for e in pending if not ({str(s) for s in e.residual.free_symbols} - computed
                                                 - set(self.params)))
        stuck = [e.id for e in pending if e not in loop]
        if stuck:
            raise PlantError(f"no causal ordering for equations {stuck} with tear variables {TEAR}")
        if len(loop) != len(TEAR):
            raise PlantError(f"{len(loop)} loop equations left for {len(TEAR)} tear variables")
        for x, dx in self.state_derivative.items():
            if dx not in computed:
                raise PlantError(f"derivative {dx} of {x} is not computed by the ordering")
        return tuple(order), loop

    # ------------------------------------------------------------------------------------------ codegen
    def _forward(self, seeds: Sequence[str], needed: set[str], frozen: set[str]) -> dict[str, dict[str, str]]:
        """Forward-mode sensitivities through the assignment sequence, in chain-rule form.

        For each seed s and each assignment target v in `needed` that depends on s, adds the code line
        ``d_v__s = sum_u de/du * d_u__s`` to ``self._lines`` (right after v's own line is emitted by the
        caller). Returns seed -> {variable: sensitivity variable name}. Frozen variables are constants.
        """
        sens: dict[str, dict[str, str]] = {s: {s: "1.0"} for s in seeds}
        for a in self.assignments:
            self._emit(a.target, a.expr)
            if a.target not in needed:
                continue
            syms = {str(x) for x in a.expr.free_symbols}
            for s in seeds:
                deps = [u for u in sorted(syms) if u in sens[s] and u not in frozen]
                if not deps:
                    continue
                name = f"d_{a.target}__{s}"
                terms = [sympy.diff(a.expr, _sym(u)) * _sym(sens[s][u]) for u in deps]
                self._emit(name, sympy.Add(*terms))
                sens[s][a.target] = name
        return sens

    def _emit(self, target: str, expr: sympy.Expr) -> None:
        """Append ``target = expr`` with parameters as numbers; transcendental functions, powers and
        divisions are hoisted into temporaries shared by all later lines (a sequence-aware CSE)."""
        if target in self._emitted:
            return
        self._emitted.add(target)
        expr = expr.xreplace(self._psub)
        while True:
            leaves = [
                n for n in sympy.preorder_traversal(expr)
                if _hoistable(n) and not any(_hoistable(c) for a in n.args for c in sympy.preorder_traversal(a))
            ]
            if not leaves:
                break
            repl: dict[sympy.Basic, sympy.Symbol] = {}
            for n in leaves:
                if n not in self._memo:
                    name = f"_t{len(self._memo)}"
                    self._memo[n] = _sym(name)
                    self._lines.append(f"    {name} = {self._printer.doprint(n)}")
                repl[n] = self._memo[n]
            expr = expr.xreplace(repl)
        self._lines.append(f"    {target} = {self._printer.doprint(expr)}")

    @staticmethod
    def _needed(assignments: Sequence[Assignment], targets: set[str]) -> set[str]:
        needed = set(targets)
        for a in reversed(assignments):
            if a.target in needed:
                needed |= {str(x) for x in a.expr.free_symbols}
        return needed

    def _check_affine(self) -> None:
        """Every assignment is affine in its loop-dependent inputs with loop-independent coefficients."""
        dependent = set(TEAR)
        for a in self.assignments:
            dep_in = [_sym(u) for u in (str(x) for x in a.expr.free_symbols) if u in dependent]
            if not dep_in:
                continue
            dependent.add(a.target)
            for u in dep_in:
                bad = {str(x) for x in sympy.diff(a.expr, u).free_symbols} & dependent
                if bad:
                    raise PlantError(
                        f"{a.equation}: d{a.target}/d{u} depends on loop variables {sorted(bad)}; "
                        "the algebraic loop is not affine in the tear variables"
                    )
        for e in self.loop_equations:
            r = _replace_der(e.lhs) - _replace_der(e.rhs)
            for u in [x for x in r.free_symbols if str(x) in dependent]:
                if {str(x) for x in sympy.diff(r, u).free_symbols} & dependent:
                    raise PlantError(f"loop residual {e.id} is not affine in the tear variables")

    def _build_function(self) -> None:
        self._check_affine()
        self._printer = _Printer()
        self._lines: list[str] = []
        self._memo: dict[sympy.Basic, sympy.Symbol] = {}
        self._emitted: set[str] = set(STATES) | set(self.inputs) | set(self.faults) | set(TEAR)
        outputs = [self.state_derivative[x] for x in STATES] + list(RECORDED)
        rho = [_replace_der(e.lhs) - _replace_der(e.rhs) for e in self.loop_equations]
        rho_syms = {str(x) for r in rho for x in r.free_symbols}
        need_a = self._needed(self.assignments, set(outputs) | rho_syms)
        omegas = [f"omega{i}" for i in WHEELS]
        need_w = self._needed(self.assignments, {self.state_derivative[o] for o in omegas})
        # One pass emits every assignment once plus the tear sensitivities; a second pass (assignments
        # already emitted) adds the wheel-spin sensitivities.
        sens_a = self._forward(TEAR, need_a, frozen=set())
        sens_w = self._forward(omegas, need_w, frozen=set(TEAR))
        ret: list[str] = list(outputs)
        ret += [sens_a[t].get(n, "0.0") for n in outputs for t in TEAR]
        for k, r in enumerate(rho):
            self._emit(f"rho_{k}", r)
            ret.append(f"rho_{k}")
        for k, r in enumerate(rho):
            for t in TEAR:
                terms = [sympy.diff(r, u) * _sym(sens_a[t][str(u)]) for u in r.free_symbols
                         if str(u) in sens_a[t]]
                self._emit(f"drho_{k}__{t}", sympy.Add(*terms))
                ret.append(f"drho_{k}__{t}")
        ret += [sens_w[o].get(self.state_derivative[o], "0.0") for o in omegas]
        self.n_out = len(outputs)
        self.arg_names: tuple[str, ...] = STATES + self.inputs + self.faults + TEAR
        src = "def _plant(" + ", ".join(self.arg_names) + "):\n" + "\n".join(self._lines)
        src += "\n    return (" + ", ".join(ret) + ",)\n"
        self.source = src
        namespace: dict[str, object] = {"math": math, "_sign": _sign, "_heaviside": _heaviside}
        exec(compile(src, f"<plant {self.model.name}>", "exec"), namespace)
        self._fn = cast(Callable[..., Sequence[float]], namespace["_plant"])

    # ------------------------------------------------------------------------------------------ numeric
    def evaluate(
        self, x: Sequence[float], u: Sequence[float], f: Sequence[float], accel_guess: Sequence[float]
    ) -> PlantEval:
        """Evaluate the plant at states `x`, inputs `u`, faults `f`; solve the loop from `accel_guess`."""
        a0x, a0y = float(accel_guess[0]), float(accel_guess[1])
        out = self._fn(*x, *u, *f, a0x, a0y)
        n = self.n_out
        vals = out[:n]
        sens = out[n : 3 * n]
        r1, r2, j11, j12, j21, j22 = out[3 * n : 3 * n + 6]
        jac = out[3 * n + 6 : 3 * n + 10]
        det = j11 * j22 - j12 * j21
        dax = -(j22 * r1 - j12 * r2) / det
        day = -(-j21 * r1 + j11 * r2) / det
        res = np.fromiter(
            (vals[k] + sens[2 * k] * dax + sens[2 * k + 1] * day for k in range(n)), float, count=n
        )
        ns = len(STATES)
        return PlantEval(
            xdot=res[:ns], jac_omega=np.asarray(jac, dtype=float), accel=np.array([a0x + dax, a0y + day]),
            recorded=res[ns:],
        )

    def rhs(
        self, args: Sequence[float], record: bool
    ) -> tuple[list[float], list[float], float, float, list[float] | None]:
        """Fast path for the integrator: `args` = states, inputs, faults, (ax, ay) guess.

        Returns (xdot, jac_omega, ax, ay, recorded or None) as Python floats.
        """
        out = self._fn(*args)
        n = self.n_out
        ns = len(STATES)
        r1, r2, j11, j12, j21, j22 = out[3 * n : 3 * n + 6]
        det = j11 * j22 - j12 * j21
        dax = -(j22 * r1 - j12 * r2) / det
        day = -(-j21 * r1 + j11 * r2) / det
        xdot = [out[k] + out[n + 2 * k] * dax + out[n + 2 * k + 1] * day for k in range(ns)]
        rec = (
            [out[k] + out[n + 2 * k] * dax + out[n + 2 * k + 1] * day for k in range(ns, n)] if record else None
        )
        return xdot, list(out[3 * n + 6 : 3 * n + 10]), args[-2] + dax, args[-1] + day, rec

    def contact_velocity_function(self) -> Callable[[float, float, float], list[tuple[float, float]]]:
        """Body-frame contact-point velocity of each wheel, from W_i.vL and W_i.vS at delta_i = 0."""
        by_target = {a.target: a.expr for a in self.assignments}
        exprs = []
        for i in WHEELS:
            zero = {_sym(f"delta{i}"): sympy.Integer(0)}
            exprs += [by_target[f"vL{i}"].xreplace(zero), by_target[f"vS{i}"].xreplace(zero)]
        exprs = [e.xreplace(self._psub) for e in exprs]
        fn = sympy.lambdify([_sym("vx"), _sym("vy"), _sym("psidot")], exprs, modules="math")

        def contact(vx: float, vy: float, psidot: float) -> list[tuple[float, float]]:
            v = fn(vx, vy, psidot)
            return [(float(v[2 * k]), float(v[2 * k + 1])) for k in range(len(WHEELS))]

        return contact

    def input_functions(self) -> Callable[[Sequence[float], Sequence[float]], list[float]]:
        """Map actuator-side sensor values and faults to the true actuator inputs (S.delta_i, S.iTM_i,
        S.P_a solved for the unknown): ``g(known_values, fault_values) -> true inputs``, argument order
        `input_known_names` and all 25 model faults, result order `inputs`."""
        exprs = []
        for e in self.input_equations:
            target = _sym(e.unknowns[0])
            r = _replace_der(e.lhs) - _replace_der(e.rhs)
            exprs.append(_solve_linear(r, target, e.id).xreplace(self._psub))
        knowns = [_sym(e.knowns[0]) for e in self.input_equations]
        faults = [_sym(v.name) for v in self.model.faults]
        fn = sympy.lambdify([knowns, faults], exprs, modules="math")

        def g(kv: Sequence[float], fv: Sequence[float]) -> list[float]:
            return [float(v) for v in fn(kv, fv)]

        return g

    @property
    def input_known_names(self) -> tuple[str, ...]:
        return tuple(e.knowns[0] for e in self.input_equations)

    def measurement_functions(self) -> dict[str, Callable[[dict[str, FloatArray]], FloatArray]]:
        """Known name -> vectorised function of the true signals and faults (all measurement equations).

        Each measurement equation is solved for its known, e.g. ``vx_m = vx - d_y*psidot + f4`` and
        ``delta1_m = delta1 - f6``.
        """
        fns: dict[str, Callable[[dict[str, FloatArray]], FloatArray]] = {}
        for e in (*self.sensor_equations, *self.input_equations):
            (known,) = e.knowns
            ks = sympy.Symbol(known)
            expr = _solve_linear(e.residual, ks, e.id).xreplace(self._psub)
            names = sorted(str(s) for s in expr.free_symbols)
            raw = sympy.lambdify([sympy.Symbol(n) for n in names], expr, modules="numpy")
            fns[known] = _bind(raw, tuple(names))
        return fns


def _bind(raw: Callable[..., object], names: tuple[str, ...]) -> Callable[[dict[str, FloatArray]], FloatArray]:
    def fn(sig: dict[str, FloatArray]) -> FloatArray:
        first = next(iter(sig.values()))
        return np.broadcast_to(np.asarray(raw(*(sig[n] for n in names)), dtype=float), first.shape).copy()

    return fn
