"""The equations of a train as SymPy objects, as the paper derives them by
computer algebra (Pennestri, sections 3-5 and examples 6.1-6.2).

The structure comes from the validated train (circuits and their transfer
vertices, the turning-pair tree, the eq. (4) chains of carriers and axis
offsets, satellite copies); the numbers do not: every ratio, inertia, mass,
copy count, offset and radius is a named symbol, and :meth:`SymbolicTrain.values`
gives the train's own numbers for substitution.

Symbol names (link and level names are used as written, non-identifier
characters replaced by ``_``; a one-character name is joined without ``_``,
as in the paper):

==============  ==========================================================
``omega_2``     absolute angular speed of link 2 (``omegadot_2``: acceleration)
``tau_1``       Willis ratio of circuit 1 (eq. 2)
``I_2``         moment of inertia of one copy of link 2
``m_3``         mass of one copy of floating link 3 (eq. 4)
``n_s3``        number of satellites link 3 stands for (floating links)
``delta_ab``    distance between axis levels a and b
``r_31``        pitch radius of link 3's wheel in circuit 1 (eq. 11)
``T_2``         torque applied to link 2 (unknown for driving links)
``K_6``         slope dT/dw of the torque-speed curve on link 6 (eq. 13-15)
``lambda_1``    Lagrange multiplier of circuit 1
==============  ==========================================================

Symbols carry no assumptions, so ``sympy.Symbol("tau_1")`` is the same
symbol as ``train.to_sympy().tau[0]``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from ._args import ArgumentError, ArgumentKeyError, ArgumentTypeError

try:
    import sympy
except ImportError:  # pragma: no cover - depends on the environment
    # Raised inside the handler, so the original error stays chained as context.
    raise ImportError("Train.to_sympy() needs SymPy: pip install 'egt[sympy]'")

__all__ = ["SymbolicTrain", "SymbolicDynamics"]

CircuitRef = Union[int, str]
"""A circuit: its number m (from 1, as in the paper) or its gear pair's name."""


def _ident(name: str) -> str:
    return re.sub(r"\W", "_", name)


def _join(prefix: str, name: str) -> str:
    """``prefix`` + name, with ``_`` unless the name is one character (``n_s3``, ``n_s_sun``)."""
    s = _ident(name)
    return f"{prefix}{s}" if len(s) == 1 else f"{prefix}_{s}"


def _expr(x: Any) -> sympy.Expr:
    if isinstance(x, Fraction):
        return sympy.Rational(x.numerator, x.denominator)
    return sympy.sympify(x)


@dataclass(frozen=True)
class SymbolicDynamics:
    """Inverse dynamics in closed form (eq. 8-11)."""

    Psi: sympy.Matrix
    """[Psi_w] of eq. (8): [psi_w] with one row per prescribed acceleration."""
    accelerations: Dict[str, sympy.Expr]
    """Every coordinate's acceleration from eq. (8)."""
    Q: sympy.Matrix
    """Applied torques, with ``T_<link>`` for the driving links."""
    lambda_star: sympy.Matrix
    """{lambda*} of eq. (10), driving torques substituted (its extra entries are 0)."""
    multipliers: Tuple[sympy.Expr, ...]
    """lambda_1 ... lambda_jG."""
    driving_torques: Dict[str, sympy.Expr]
    """Each driving link's torque, from lambda*_{jG+k} = 0."""
    _train: "SymbolicTrain"

    def mesh_torque(self, link: str, circuit: CircuitRef) -> sympy.Expr:
        """lambda_m psi_w^T[s, m]: the torque link s spends on mesh m (eq. 7)."""
        m = self._train._circuit(circuit)
        return sympy.simplify(self.multipliers[m] * self._train.willis_coefficient(m + 1, link))

    def mesh_force(self, link: str, circuit: CircuitRef) -> sympy.Expr:
        """F_sm = lambda_m psi_w^T[s, m] / r_sm (eq. 11)."""
        m = self._train._circuit(circuit)
        return sympy.simplify(self.mesh_torque(link, m + 1) / self._train.radius(link, m + 1))


class SymbolicTrain:
    """A train's equations in named symbols. Build it with :meth:`egt.Train.to_sympy`."""

    frame: str
    coordinates: Tuple[str, ...]
    omega: sympy.Matrix
    omega_dot: sympy.Matrix
    tau: Tuple[sympy.Symbol, ...]
    willis: Tuple[sympy.Expr, ...]
    """psi_m = w_i - tau_m w_j + (tau_m - 1) w_k (eq. 2), the frame's speed 0."""
    jacobian: sympy.Matrix
    """[psi_w]: rows are circuits, columns the coordinates."""
    inertia: Dict[str, sympy.Symbol]
    mass: Dict[str, sympy.Symbol]
    """Masses of the floating links (the only ones eq. 4 needs)."""
    copies: Dict[str, sympy.Expr]
    offsets: Dict[Tuple[str, str], sympy.Symbol]
    kinetic_energy: sympy.Expr
    """K = sum of eq. (3) and eq. (4) over the links."""
    mass_matrix: sympy.Matrix
    """[M] = the Hessian of K in the coordinate speeds (eq. 6)."""
    inputs: Optional[Tuple[str, ...]]
    velocity_matrix: Optional[sympy.Matrix]
    """[V] of eq. (23) for ``inputs``."""
    reduced_mass_matrix: Optional[sympy.Matrix]
    """V^T M V (eq. 25) for ``inputs``."""
    slopes: Dict[str, sympy.Symbol]
    """``K_<link>`` for the links with a torque-speed curve in the spec."""
    reduced_stiffness: Optional[sympy.Matrix]
    """V^T diag(K) V for ``inputs`` and ``slopes`` (eq. 26, see :meth:`reduced_stiffness_for`)."""

    _s: Mapping[str, Any]
    _symbols: Dict[str, sympy.Symbol]
    _links: Dict[str, Mapping[str, Any]]
    _circuits: List[Mapping[str, Any]]

    def __init__(self) -> None:
        raise ArgumentTypeError("use Train.to_sympy() to build a SymbolicTrain")

    @classmethod
    def _from_structure(
        cls,
        s: Mapping[str, Any],
        analysis: Mapping[str, Any],
        inputs: Optional[Sequence[str]],
    ) -> "SymbolicTrain":
        self = object.__new__(cls)
        self._s = s
        self._symbols = {}
        self.frame = s["frame"]
        self.coordinates = tuple(s["coordinates"])
        self._links = {d["name"]: d for d in s["links"]}
        self._circuits = list(s["circuits"])
        self.omega = sympy.Matrix([self.symbol(f"omega_{_ident(n)}") for n in self.coordinates])
        self.omega_dot = sympy.Matrix([self.symbol(f"omegadot_{_ident(n)}") for n in self.coordinates])
        self.tau = tuple(self.symbol(f"tau_{m + 1}") for m in range(len(self._circuits)))
        self.willis = tuple(self._psi(m) for m in range(len(self._circuits)))
        self.jacobian = sympy.Matrix(
            [[sympy.diff(psi, w) for w in self.omega] for psi in self.willis]
        ) if self._circuits else sympy.zeros(0, len(self.coordinates))

        # Kinetic energy, eq. (3) and (4).
        self.inertia, self.mass, self.copies, self.offsets = {}, {}, {}, {}
        K = sympy.Integer(0)
        for name in self.coordinates:
            d = self._links[name]
            I = self.symbol(f"I_{_ident(name)}")
            self.inertia[name] = I
            chain = d["chain"]
            floating = bool(chain)
            n: sympy.Expr = (
                self.symbol(_join("n_s", name)) if floating or d["copies"] != 1 else sympy.Integer(d["copies"])
            )
            self.copies[name] = n
            w = self.speed(name)
            K += sympy.Rational(1, 2) * n * I * w**2
            if floating:
                m_ = self.symbol(f"m_{_ident(name)}")
                self.mass[name] = m_
                v = sympy.Integer(0)
                for carrier, la, lb in chain:
                    v += self.speed(carrier) * self.offset(la, lb)
                K += sympy.Rational(1, 2) * n * m_ * v**2
        self.kinetic_energy = sympy.expand(K)
        self.mass_matrix = sympy.hessian(self.kinetic_energy, list(self.omega))

        self.slopes = {c[0]: self.symbol(f"K_{_ident(c[0])}") for c in analysis.get("curves", [])}
        self.inputs = None if inputs is None else tuple(inputs)
        self.velocity_matrix = self.reduced_mass_matrix = self.reduced_stiffness = None
        if self.inputs is not None and len(self.inputs) == len(self.coordinates) - len(self._circuits):
            self.velocity_matrix = self.velocity_matrix_for(self.inputs)
            self.reduced_mass_matrix = self.reduced_mass_matrix_for(self.inputs)
            if self.slopes:
                self.reduced_stiffness = self.reduced_stiffness_for(self.inputs, self.slopes)
        return self

    # -- symbols -----------------------------------------------------------

    def symbol(self, name: str) -> sympy.Symbol:
        """The symbol called ``name`` (created on first use)."""
        if name not in self._symbols:
            self._symbols[name] = sympy.Symbol(name)
        return self._symbols[name]

    @property
    def symbols(self) -> Dict[str, sympy.Symbol]:
        """Every symbol used so far, by name."""
        return dict(self._symbols)

    def speed(self, link: str) -> sympy.Expr:
        """The speed symbol of a link (0 for the frame)."""
        if link == self.frame:
            return sympy.Integer(0)
        return self.omega[self._coord(link)]

    def offset(self, level_a: str, level_b: str) -> sympy.Symbol:
        """The symbol of the distance between two axis levels."""
        levels = list(self._s["levels"])
        a, b = sorted((level_a, level_b), key=levels.index)
        if (a, b) not in self.offsets:
            ia, ib = _ident(a), _ident(b)
            name = f"delta_{ia}{ib}" if len(ia) == 1 and len(ib) == 1 else f"delta_{ia}_{ib}"
            self.offsets[(a, b)] = self.symbol(name)
        return self.offsets[(a, b)]

    def radius(self, link: str, circuit: CircuitRef) -> sympy.Symbol:
        """The pitch-radius symbol of ``link``'s wheel in a circuit (``r_31``)."""
        m = self._circuit(circuit) + 1
        s = _ident(link)
        return self.symbol(f"r_{s}{m}" if len(s) == 1 else f"r_{s}_{m}")

    def torque(self, link: str) -> sympy.Symbol:
        """The torque symbol of a link (``T_2``)."""
        return self.symbol(f"T_{_ident(link)}")

    def _coord(self, link: str) -> int:
        try:
            return self.coordinates.index(link)
        except ValueError:
            raise ArgumentKeyError(f"unknown link {link!r} (coordinates: {', '.join(self.coordinates)})") from None

    def _circuit(self, c: CircuitRef) -> int:
        if isinstance(c, str):
            for m, d in enumerate(self._circuits):
                if d["gear"] == c:
                    return m
            raise ArgumentKeyError(f"no gear pair named {c!r}")
        if not 1 <= int(c) <= len(self._circuits):
            raise ArgumentKeyError(f"circuits are numbered 1..{len(self._circuits)}, got {c}")
        return int(c) - 1

    def _psi(self, m: int) -> sympy.Expr:
        c = self._circuits[m]
        t = self.tau[m]
        return sympy.expand(
            self.speed(c["gear_i"]) - t * self.speed(c["gear_j"]) + (t - 1) * self.speed(c["carrier"])
        )

    def willis_coefficient(self, circuit: CircuitRef, link: str) -> sympy.Expr:
        """The coefficient of w_link in psi_m (also for the frame): psi_w^T[s, m]."""
        m = self._circuit(circuit)
        c = self._circuits[m]
        t = self.tau[m]
        coef = sympy.Integer(0)
        for role, v in (("gear_i", sympy.Integer(1)), ("gear_j", -t), ("carrier", t - 1)):
            if c[role] == link:
                coef += v
        return coef

    # -- reduced matrices (eq. 23-26) --------------------------------------

    def velocity_matrix_for(self, inputs: Sequence[str]) -> sympy.Matrix:
        """[V] = -[Gamma_w]^-1 [Gamma_p] (eq. 23): coordinate speeds per unit input speed."""
        f = len(inputs)
        S = sympy.zeros(f, len(self.coordinates))
        for r, name in enumerate(inputs):
            S[r, self._coord(name)] = 1
        gamma = self.jacobian.col_join(S)
        rhs = sympy.zeros(len(self._circuits), f).col_join(sympy.eye(f))
        if gamma.rows != gamma.cols or sympy.simplify(gamma.det()) == 0:
            raise ArgumentError(f"the inputs {list(inputs)} do not determine the train")
        return gamma.LUsolve(rhs).applyfunc(sympy.factor)

    def reduced_mass_matrix_for(self, inputs: Sequence[str]) -> sympy.Matrix:
        """V^T M V (eq. 25)."""
        V = self.velocity_matrix_for(inputs)
        return (V.T * self.mass_matrix * V).applyfunc(sympy.factor)

    def reduced_stiffness_for(
        self, inputs: Sequence[str], slopes: Mapping[str, Any]
    ) -> sympy.Matrix:
        """V^T diag(K) V: the stiffness of eq. (16), with K_l = dT_l/dw_l on the links in ``slopes``.

        The paper prints eq. (26) as [V]^T {T}; the matrix it means (and
        prints in example 6.2) is V^T diag(K) V, see docs/errata.md. With the
        spec's sign convention (applied torques, T = T0 + K (w - w0)), the
        linearised motion is [M] dw' = [K] dw, so eq. (16)-(18) hold with -[K].
        """
        V = self.velocity_matrix_for(inputs)
        D = sympy.zeros(len(self.coordinates), len(self.coordinates))
        for link, k in slopes.items():
            i = self._coord(link)
            D[i, i] = _expr(k)
        return (V.T * D * V).applyfunc(sympy.factor)

    # -- inverse dynamics (eq. 8-11) ---------------------------------------

    def inverse_dynamics(
        self,
        torques: Mapping[str, Any],
        accelerations: Mapping[str, Any],
        driving: Sequence[str],
        simplify: bool = True,
    ) -> SymbolicDynamics:
        """Closed-form inverse dynamics, following eq. (8)-(10) literally.

        ``torques``: known applied torques (expressions or numbers) by link;
        ``accelerations``: the prescribed accelerations (alpha_out) by link;
        ``driving``: the links whose torque ``T_<link>`` is solved from
        lambda*_{jG+k} = 0.
        """
        n, jg = len(self.coordinates), len(self._circuits)
        f = n - jg
        if len(accelerations) != f or len(driving) != f:
            raise ArgumentError(f"the train has {f} DOF: give {f} accelerations and {f} driving links")
        S = sympy.zeros(f, n)
        alpha = sympy.zeros(jg, 1)
        for r, (name, a) in enumerate(accelerations.items()):
            S[r, self._coord(name)] = 1
        alpha = alpha.col_join(sympy.Matrix([_expr(a) for a in accelerations.values()]))
        Psi = self.jacobian.col_join(S)
        wdot = Psi.LUsolve(alpha)
        Q = sympy.zeros(n, 1)
        for name, t in torques.items():
            Q[self._coord(name)] += _expr(t)
        unknown = [self.torque(d) for d in driving]
        for d, T in zip(driving, unknown):
            Q[self._coord(d)] += T
        lam = Psi.T.LUsolve(Q - self.mass_matrix * wdot)
        sol = sympy.solve(list(lam[jg:]), unknown, dict=True)
        if len(sol) != 1:
            raise ArgumentError("the driving links cannot balance the loads (eq. 10 is singular)")
        lam = lam.subs(sol[0])
        tidy = sympy.simplify if simplify else (lambda e: e)
        return SymbolicDynamics(
            Psi=Psi,
            accelerations={c: tidy(wdot[i]) for i, c in enumerate(self.coordinates)},
            Q=Q.subs(sol[0]),
            lambda_star=lam.applyfunc(tidy),
            multipliers=tuple(tidy(lam[m]) for m in range(jg)),
            driving_torques={d: tidy(sol[0][T]) for d, T in zip(driving, unknown)},
            _train=self,
        )

    # -- numbers -----------------------------------------------------------

    def values(self) -> Dict[sympy.Symbol, sympy.Expr]:
        """The train's own numbers for the symbols (exact ratios as Rationals);
        data the spec does not give is left out."""
        out: Dict[sympy.Symbol, sympy.Expr] = {}
        for m, c in enumerate(self._circuits):
            if c["ratio_exact"] is not None:
                out[self.tau[m]] = sympy.Rational(c["ratio_exact"])
            elif c["ratio"] is not None:
                out[self.tau[m]] = sympy.Float(c["ratio"])
            if c["radii"] is not None:
                out[self.radius(c["gear_i"], m + 1)] = sympy.Float(c["radii"][0])
                out[self.radius(c["gear_j"], m + 1)] = sympy.Float(c["radii"][1])
        for name in self.coordinates:
            d = self._links[name]
            if d["inertia"] is not None:
                out[self.inertia[name]] = sympy.Float(d["inertia"])
            if name in self.mass and d["mass"] is not None:
                out[self.mass[name]] = sympy.Float(d["mass"])
            if isinstance(self.copies[name], sympy.Symbol):
                out[self.copies[name]] = sympy.Integer(d["copies"])
        distances = {(a, b): dist for a, b, dist in self._s["offsets"]}
        for key, sym in self.offsets.items():
            if key in distances:
                out[sym] = sympy.Float(distances[key])
        return out

    def numeric(self, expr: Any, values: Optional[Mapping[Any, Any]] = None) -> np.ndarray:
        """A symbolic result as float64 NumPy: ``expr`` (an expression or a
        matrix) with the train's own numbers (:meth:`values`) and ``values``
        (which win) substituted. Symbols left without a number are refused by
        name (NumPy would otherwise get an object array it cannot use)."""
        subs: Dict[Any, Any] = dict(self.values())
        subs.update(values or {})
        m = sympy.Matrix(expr) if isinstance(expr, (sympy.MatrixBase, list, tuple)) else sympy.Matrix([expr])
        m = m.subs(subs)
        free = sorted(str(x) for x in m.free_symbols)
        if free:
            raise ArgumentError(f"no number for the symbols {', '.join(free)}: pass them in `values`")
        out = np.array(m.evalf(), dtype=np.float64)
        return out if isinstance(expr, (sympy.MatrixBase, list, tuple)) else out.reshape(())

    def __repr__(self) -> str:
        return (
            f"<egt.SymbolicTrain: {len(self.coordinates)} coordinates, "
            f"{len(self._circuits)} Willis equations>"
        )

