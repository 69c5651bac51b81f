"""Results of :meth:`egt.Train.stability`, :meth:`egt.Train.simulate` and
:meth:`egt.Train.simulate_shift`.

Sign convention (eq. 13-15, as in the spec): a curve is an *applied* torque
T = T0 + K (w - w0) on a link, positive along positive rotation, so K = dT/dw.
The linearised motion is [M] dw' = [K] dw with [M] = V^T M V and
[K] = V^T diag(K) V; a mode grows as e^(lambda t) with (lambda [M] - [K]) X = 0.
A motor whose torque falls as it speeds up (K < 0) is stabilising. The paper's
eq. (16)-(18) carry the opposite sign and its eq. (26) names the vector, not
the matrix: see docs/errata.md and docs/stability.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Dict, Mapping, Optional, Sequence, Tuple

import numpy as np

from ._results import _Documented, _document_field, _pandas

if TYPE_CHECKING:  # pragma: no cover
    import pandas


def _array(v: Any) -> np.ndarray:
    return np.asarray(v, dtype=np.float64)


def _matrix(rows: Any) -> np.ndarray:
    """A matrix from its rows (the core's serde form), 2-D even when empty."""
    a = np.asarray(rows, dtype=np.float64)
    return a if a.ndim == 2 else np.zeros((len(rows), 0))


@dataclass(frozen=True)
class Curve:
    """A linearised torque-speed curve T = torque + slope (w - speed) on a link (eq. 13-15)."""

    link: str
    torque: float
    slope: float = 0.0
    """dT/dw of the applied torque [N m s]."""
    speed: float = 0.0
    """The speed at which the torque is ``torque`` [rad/s]."""


@dataclass(frozen=True, eq=False)
class OperatingPoint:
    """The operating point and whether it is a steady state."""

    source: str
    """``"speeds"`` (given or the spec's) or ``"equilibrium"`` (of the curves)."""
    speeds: np.ndarray
    """Every link's speed (link order)."""
    torques: np.ndarray
    """The curves' applied torque on every link there."""
    reduced_torque: np.ndarray
    """V^T T: zero at a steady state."""
    residual: float
    steady: bool
    equilibrium: Optional[np.ndarray]
    equilibrium_condition: Optional[float]


@dataclass(frozen=True, eq=False)
class Mode:
    """One eigenvalue of (lambda [M] - [K]) X = 0 and its mode."""

    eigenvalue: float
    """lambda [1/s]: deviations grow as e^(lambda t)."""
    time_constant: Optional[float]
    coordinates: np.ndarray
    """X in the driving coordinates (largest link speed 1)."""
    speeds: np.ndarray
    """V X: every link's speed in the mode."""


@dataclass(frozen=True, eq=False)
class MasslessDirection:
    """A direction of the driving coordinates without inertia (an algebraic torque balance)."""

    coordinates: np.ndarray
    speeds: np.ndarray
    links: Tuple[str, ...]
    slope: float


@dataclass(frozen=True, eq=False)
class StabilityReport(_Documented):
    """Stability of a train about an operating point (paper section 5, any DOF).

    ``to_dict()`` is ``egt stability --format json``."""

    coordinates: Tuple[str, ...]
    """The F driving links (columns of [V])."""
    source: str
    """How they were chosen: ``"given"``, ``"spec_speeds"`` or ``"automatic"``."""
    velocity_matrix: np.ndarray
    """[V] (eq. 23) by link: row i is link i (the frame's row is zero)."""
    mass_matrix: np.ndarray
    """V^T M V (eq. 25)."""
    slope_matrix: np.ndarray
    """V^T diag(K) V (eq. 26, corrected)."""
    link_slopes: np.ndarray
    gamma_condition: float
    orthogonality: float
    """|psi_w V| relative (eq. 24): zero in exact arithmetic."""
    operating: OperatingPoint
    eigenvalues: np.ndarray
    """Largest first."""
    modes: Tuple[Mode, ...]
    verdict: str
    """``"stable"``, ``"unstable"`` or ``"marginal"``."""
    reason: str
    margin: float
    """The largest eigenvalue (positive: unstable)."""
    tolerance: float
    massless: Tuple[MasslessDirection, ...]
    rk4_step_limit: Optional[float]
    stiffness: Optional[float]
    residual: float
    warnings: Tuple[str, ...]
    _document: Dict[str, Any] = _document_field()

    @property
    def stable(self) -> bool:
        return self.verdict == "stable"

    @classmethod
    def _from_core(cls, links: Tuple[str, ...], raw: Sequence[Any]) -> "StabilityReport":
        """From the core's `StabilityReport` (its serde form: ids are indices)
        and the CLI's document of it."""
        d, document = raw
        m, o, st = d["model"], d["operating"], d["stability"]
        eq = o["equilibrium"]
        return cls(
            _document=document,
            coordinates=tuple(links[c] for c in m["coordinates"]),
            source=m["source"],
            velocity_matrix=_matrix(m["velocity"]),
            mass_matrix=_matrix(m["mass"]),
            slope_matrix=_matrix(m["slope"]),
            link_slopes=_array(m["link_slope"]),
            gamma_condition=m["gamma_condition"],
            orthogonality=m["orthogonality"],
            operating=OperatingPoint(
                source=o["source"],
                speeds=_array(o["speed"]),
                torques=_array(o["torque"]),
                reduced_torque=_array(o["reduced_torque"]),
                residual=o["residual"],
                steady=o["steady"],
                equilibrium=None if eq is None else _array(eq),
                equilibrium_condition=o["equilibrium_condition"],
            ),
            eigenvalues=_array(st["eigenvalues"]),
            modes=tuple(
                Mode(x["eigenvalue"], x["time_constant"], _array(x["coordinates"]), _array(x["speeds"]))
                for x in st["modes"]
            ),
            verdict=st["verdict"],
            reason=st["reason"],
            margin=st["margin"],
            tolerance=st["tolerance"],
            massless=tuple(
                MasslessDirection(
                    _array(x["coordinates"]),
                    _array(x["speeds"]),
                    tuple(links[l] for l in x["links"]),
                    x["slope"],
                )
                for x in st["massless"]
            ),
            rk4_step_limit=st["rk4_step_limit"],
            stiffness=st["stiffness"],
            residual=st["residual"],
            warnings=tuple(d["warnings"]),
        )

    def plot(self, ax: Any = None) -> Any:
        """The eigenvalues and the verdict (:func:`egt.plot.eigenvalues`)."""
        from . import plot

        return plot.eigenvalues(self, ax)


@dataclass(frozen=True, eq=False)
class Simulation(_Documented):
    """A simulated time series (eq. 12 in reduced coordinates) and its checks.

    ``to_dict()`` is ``egt simulate --format json`` (with the equilibrium of
    the curves when the torques came from curves, not a Python function)."""

    links: Tuple[str, ...]
    method: str
    dt: float
    steps: int
    t: np.ndarray
    """(samples,) times [s], 0 first."""
    speeds: np.ndarray
    """(samples, links) speeds."""
    drift: np.ndarray
    """Willis drift max|psi| / max|w| per sample (eq. 2)."""
    energy: np.ndarray
    work: np.ndarray
    power: np.ndarray
    max_drift: float
    energy_error: float
    """max |E - E0 - W| relative: the integration error."""
    diverged: Optional[Tuple[float, str]]
    """(time, reason) when the solution blew up; the samples end there."""
    rk4_step_limit: Optional[float]
    eigenvalues: np.ndarray
    newton_iterations: int
    halvings: int
    warnings: Tuple[str, ...]
    _document: Dict[str, Any] = _document_field()

    @classmethod
    def _from_core(cls, links: Tuple[str, ...], raw: Sequence[Any]) -> "Simulation":
        """From the core's `Simulation` (its serde form: one record per
        sample) and the CLI's document of it."""
        d, document = raw
        samples = d["samples"]
        div = d["diverged"]

        def series(key: str) -> np.ndarray:
            return _array([x[key] for x in samples])

        return cls(
            _document=document,
            links=links,
            method=d["method"],
            dt=d["dt"],
            steps=d["steps"],
            t=series("t"),
            speeds=np.asarray([x["speed"] for x in samples], dtype=np.float64).reshape(
                len(samples), len(links)
            ),
            drift=series("drift"),
            energy=series("energy"),
            work=series("work"),
            power=series("power"),
            max_drift=d["max_drift"],
            energy_error=d["energy_error"],
            diverged=None if div is None else (div["t"], div["reason"]),
            rk4_step_limit=d["rk4_step_limit"],
            eigenvalues=_array(d["eigenvalues"]),
            newton_iterations=d["newton_iterations"],
            halvings=d["halvings"],
            warnings=tuple(d["warnings"]),
        )

    def speed(self, link: str) -> np.ndarray:
        """One link's speed over time."""
        return self.speeds[:, self.links.index(link)]

    def plot(self, ax: Any = None, links: Optional[Sequence[str]] = None) -> Any:
        """Link speeds against time (:func:`egt.plot.simulation`)."""
        from . import plot

        return plot.simulation(self, ax, links)

    def to_pandas(self) -> "pandas.DataFrame":
        pd = _pandas()
        df = pd.DataFrame(self.speeds, columns=list(self.links), index=pd.Index(self.t, name="t"))
        df["energy"] = self.energy
        df["work"] = self.work
        return df


def _at(v: Optional[Mapping[str, Any]]) -> Optional[Tuple[float, float]]:
    """A measure and its time, ``(t, value)``, or None."""
    return None if v is None else (v["t"], v["value"])


def _span(v: Optional[Sequence[float]]) -> Optional[Tuple[float, float]]:
    return None if v is None else (v[0], v[1])


@dataclass(frozen=True)
class ShiftQuality:
    """The phases and shift-quality measures of a gear change
    (``ShiftSimulation.quality``; docs/shift_dynamics.md, "Phases and shift
    quality"). Output torques in N m; a measure that cannot be defined (no
    such phase, no lock, no vehicle inertia) is None. Measures at a time are
    ``(t, value)``."""

    torque_phase: Optional[Tuple[float, float]]
    """(start, end) [s]: the on-coming capacity starts, to the last off-going
    element's release."""
    inertia_phase: Optional[Tuple[float, float]]
    """(start, end) [s]: that release, to the on-coming lock."""
    output_torque_start: Optional[float]
    """Output torque of the first sample (t = 0) [N m]: the dip's reference."""
    output_torque_end: Optional[float]
    """Output torque of the last sample [N m]: the overshoot's reference."""
    dip: Optional[Tuple[float, float]]
    """(t, lowest output torque in the torque phase minus ``output_torque_start``) [s, N m]."""
    overshoot: Optional[Tuple[float, float]]
    """(t, highest output torque from the inertia phase to the lock minus
    ``output_torque_end``) [s, N m]."""
    oscillation_after_lock: Optional[float]
    """Peak-to-peak output torque from the lock to the end [N m]."""
    jerk: Optional[Tuple[float, float]]
    """(t, largest abs(dT_out/dt) / vehicle inertia between samples at distinct
    times) [s, rad/s^3]; the steps at mode changes are excluded."""
    largest_step: Optional[Tuple[float, float]]
    """(t, largest jump of the output torque at a mode change, right minus left limit) [s, N m]."""
    peak_power: Tuple[Optional[Tuple[float, float]], ...]
    """Per element (``ShiftSimulation.elements``): (t, largest abs(torque * slip)) [s, W]."""

    @classmethod
    def _from_core(cls, q: Mapping[str, Any]) -> "ShiftQuality":
        """From the ``quality`` object of the shift's document."""
        return cls(
            torque_phase=_span(q["torque_phase"]),
            inertia_phase=_span(q["inertia_phase"]),
            output_torque_start=q["output_torque_start"],
            output_torque_end=q["output_torque_end"],
            dip=_at(q["dip"]),
            overshoot=_at(q["overshoot"]),
            oscillation_after_lock=q["oscillation_after_lock"],
            jerk=_at(q["jerk"]),
            largest_step=_at(q["largest_step"]),
            peak_power=tuple(_at(e["peak_power"]) for e in q["elements"]),
        )


@dataclass(frozen=True, eq=False)
class ShiftSimulation(_Documented):
    """A gear change in time (``Train.simulate_shift``; docs/shift_dynamics.md).

    Element arrays have a column per changing element: the off-going ones,
    then the on-coming ones (``elements``): two in a single swap, four in a
    double swap. ``to_dict()`` is ``egt shift-sim --format json``.
    """

    links: Tuple[str, ...]
    elements: Tuple[str, ...]
    """The elements with a capacity: ``off_going``, ``on_coming``, then ``held``."""
    off_going: Tuple[str, ...]
    """Elements of the old gear that the new one does not engage (released)."""
    on_coming: Tuple[str, ...]
    """Elements of the new gear that the old one does not engage (applied)."""
    kept: Tuple[str, ...]
    """Elements engaged in both gears without a capacity (locked throughout)."""
    held: Tuple[str, ...]
    """Elements engaged in both gears given a capacity (``ramps``): they slip
    when their torque exceeds it, and have their columns in ``elements``."""
    kept_torque: np.ndarray
    """(samples, kept) torques of the kept elements on their first link [N m]."""
    t: np.ndarray
    """(samples,) times [s]. A mode change has two samples at its time: the
    old mode's state there (the left limit), then the new mode's."""
    speeds: np.ndarray
    """(samples, links) link speeds [rad/s]."""
    slip: np.ndarray
    """(samples, elements) slip speeds [rad/s]."""
    element_torque: np.ndarray
    """(samples, elements) torques of the elements on their first link [N m]."""
    output_torque: np.ndarray
    """(samples,) torque delivered to the vehicle [N m]."""
    dissipated: np.ndarray
    """(samples, elements) energy each element has dissipated so far [J]."""
    energy_residual: np.ndarray
    """(samples,) W_applied - dKE - E_friction - E_lock (- E_mesh with losses) [J]."""
    dof: np.ndarray
    """(samples,) degrees of freedom of the mode."""
    changes: Tuple[Tuple[float, str, str, int], ...]
    """(time, element, now, DOF) of every mode change."""
    shift_start: Optional[float]
    lock_time: Optional[float]
    shift_time: Optional[float]
    output_torque_range: Tuple[float, float]
    """(largest, smallest) output torque."""
    energy: Tuple[float, ...]
    """Energy each element dissipated over the run [J]."""
    lock_loss: float
    mesh_loss: Optional[float]
    rest_time: Optional[float]
    """When the train came to rest and stayed (every link stopped, held by its
    elements or parked by the road load) [s]; else ``None``."""
    """Energy the meshes lost over the run [J], with ``losses=True``; else ``None``."""
    max_energy_residual: float
    steps: int
    method: str
    """``explicit``, ``implicit`` or ``explicit, then implicit``."""
    stiff: Optional[Tuple[float, float, float]]
    """(time, explicit step, decay rate 1/s) where a stiff mode began to limit
    the explicit steps, if one did."""
    quality: ShiftQuality
    """The torque and inertia phases and the shift-quality measures."""
    _document: Dict[str, Any] = _document_field()

    @classmethod
    def _from_core(cls, links: Tuple[str, ...], d: Dict[str, Any]) -> "ShiftSimulation":
        """From the CLI's document of the run (the core's `ShiftResult` and a version)."""
        samples = d["samples"]
        n = len(samples)

        def series(key: str) -> np.ndarray:
            return _array([x[key] for x in samples])

        def per_element(key: str) -> np.ndarray:
            return np.asarray([x[key] for x in samples], dtype=np.float64).reshape(n, len(d["elements"]))

        return cls(
            _document=d,
            links=links,
            elements=tuple(d["elements"]),
            off_going=tuple(d["off_going"]),
            on_coming=tuple(d["on_coming"]),
            kept=tuple(d["kept"]),
            held=tuple(d.get("held", ())),
            kept_torque=np.asarray([x["kept_torque"] for x in samples], dtype=np.float64).reshape(n, len(d["kept"])),
            t=series("t"),
            speeds=np.asarray([x["speed"] for x in samples], dtype=np.float64).reshape(n, len(links)),
            slip=per_element("slip"),
            element_torque=per_element("element_torque"),
            output_torque=series("output_torque"),
            dissipated=per_element("dissipated"),
            energy_residual=series("energy_residual"),
            dof=np.asarray([x["dof"] for x in samples], dtype=np.int64),
            changes=tuple((c["t"], c["element"], c["now"], c["dof"]) for c in d["changes"]),
            shift_start=d["shift_start"],
            lock_time=d["lock_time"],
            shift_time=d["shift_time"],
            output_torque_range=(d["output_torque_range"][0], d["output_torque_range"][1]),
            energy=tuple(d["dissipated"]),
            lock_loss=d["lock_loss"],
            mesh_loss=d.get("mesh_loss"),
            rest_time=d.get("rest_time"),
            max_energy_residual=d["max_energy_residual"],
            steps=d["steps"],
            method=d["method"],
            stiff=None if d["stiff"] is None else (d["stiff"]["t"], d["stiff"]["h"], d["stiff"]["rate"]),
            quality=ShiftQuality._from_core(d["quality"]),
        )

    def speed(self, link: str) -> np.ndarray:
        """One link's speed over time."""
        return self.speeds[:, self.links.index(link)]

    def to_pandas(self) -> "pandas.DataFrame":
        """The time series: link speeds, then slip, torque and dissipated
        energy per element, each kept element's torque, output torque, energy
        residual and DOF; indexed by t."""
        pd = _pandas()
        df = pd.DataFrame(self.speeds, columns=list(self.links), index=pd.Index(self.t, name="t"))
        for k, e in enumerate(self.elements):
            df[f"slip_{e}"] = self.slip[:, k]
            df[f"torque_{e}"] = self.element_torque[:, k]
            df[f"dissipated_{e}"] = self.dissipated[:, k]
        for k, e in enumerate(self.kept):
            df[f"torque_{e}"] = self.kept_torque[:, k]
        df["output_torque"] = self.output_torque
        df["energy_residual"] = self.energy_residual
        df["dof"] = self.dof
        return df
