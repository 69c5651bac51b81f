"""The :class:`Train`: a validated epicyclic gear train and its analyses.

A thin Pythonic layer over the native ``TrainCore``: it accepts mappings of
link names, fractions and NumPy arrays, fills omitted arguments from the
spec's ``[analysis]`` section (as the CLI does), and wraps the native results
in the classes of :mod:`egt._results` and :mod:`egt._batch`.
"""

from __future__ import annotations

import json
import math
import os
from fractions import Fraction
from numbers import Rational, Real
from pathlib import Path
from typing import (
    TYPE_CHECKING,
    Any,
    Callable,
    Dict,
    List,
    Mapping,
    Optional,
    Sequence,
    Tuple,
    Union,
)

import numpy as np
from numpy.typing import ArrayLike

from . import _batch, _fmu
from ._batch import BatchDynamics, BatchKinematics, BatchPlan
from ._args import ArgumentError, ArgumentKeyError, ArgumentTypeError, count, mapping, number
from ._egt import TrainCore, batch_plan
from ._egt import atlas_member as _atlas_member
from ._egt import fmu_package as _fmu_package
from ._egt import gear as _gear
from ._egt import modes as _modes
from ._egt import shift_table as _shift_table
from ._egt import simulate as _simulate
from ._egt import stability as _stability
from ._motion import Curve, Simulation, StabilityReport
from ._shifts import ShiftMethods
from ._transmission import GearState, ShiftTable
from ._vibration import Modes
from . import _units
from ._results import (
    Circuit,
    Dynamics,
    GearPair,
    Kinematics,
    Link,
    MassMatrix,
    Offset,
    PowerFlow,
)

if TYPE_CHECKING:  # pragma: no cover
    from .sympy_export import SymbolicTrain

Speed = Union[float, int, Fraction, str]
"""An input speed: a number, a Fraction, or exact text such as ``"-162/77"``."""

PathLike = Union[str, "os.PathLike[str]"]


def _speed_arg(name: str, v: Speed, unit: str = "rad/s") -> Tuple[str, float, Optional[str]]:
    """(link, float value, exact text) for the native side, in ``unit``.

    Floats are taken as the decimal they print as (0.1 means 1/10), as a user
    writes them; Fractions, ints and ``"p/q"`` text are exact. A pint
    Quantity is converted to ``unit`` (a float).
    """
    what = f"speed of {name!r}"
    if _units.is_quantity(v):
        v = _units.quantity_in(v, unit, what)
    if isinstance(v, bool):
        raise ArgumentTypeError(f"{what} must be a number, not bool")
    if isinstance(v, str):
        # Exact text goes to the native parser, which bounds its size.
        return (name, 0.0, v.strip())
    if isinstance(v, Rational):
        q = Fraction(int(v.numerator), int(v.denominator))
        return (name, number(q, what), f"{q.numerator}/{q.denominator}")
    if isinstance(v, Real):
        x = number(v, what)
        return (name, x, repr(x) if math.isfinite(x) else None)
    raise ArgumentTypeError(f"{what} must be a number, got {type(v).__name__}")


def _pairs(values: Mapping[str, float], what: str) -> List[Tuple[str, float]]:
    return [(str(name), number(v, f"{what}[{name!r}]")) for name, v in mapping(values, what).items()]


CurveLike = Union[Curve, Tuple[str, float, float, float], Mapping[str, Any]]
"""A torque-speed curve: an :class:`egt.Curve`, a tuple (link, torque, slope,
speed), or a dict with those keys (slope and speed default to 0)."""


def _curves(curves: Sequence[CurveLike]) -> List[Tuple[str, float, float, float]]:
    out: List[Tuple[str, float, float, float]] = []
    for k, c in enumerate(curves):
        what = f"curves[{k}]"
        if isinstance(c, Curve):
            link, torque, slope, speed = c.link, c.torque, c.slope, c.speed
        elif isinstance(c, Mapping):
            for key in ("link", "torque"):
                if key not in c:
                    raise ArgumentKeyError(f"{what} has no `{key}` (a curve needs link and torque)")
            link, torque, slope, speed = c["link"], c["torque"], c.get("slope", 0.0), c.get("speed", 0.0)
        elif isinstance(c, (tuple, list)) and len(c) == 4:
            link, torque, slope, speed = c
        else:
            raise ArgumentTypeError(f"{what} must be a Curve, a (link, torque, slope, speed) tuple or a dict")
        out.append(
            (
                str(link),
                number(torque, f"{what}.torque"),
                number(slope, f"{what}.slope"),
                number(speed, f"{what}.speed"),
            )
        )
    return out


def _names(values: Sequence[str], what: str) -> List[str]:
    if isinstance(values, str):
        raise ArgumentTypeError(f"`{what}` must be a sequence of names, not a single string")
    return [str(v) for v in values]


class Train(ShiftMethods):
    """A validated geared kinematic chain (paper section 2) and its analyses.

    Build one with :func:`egt.load`, :func:`egt.loads` or :meth:`Train.from_dict`.
    Per-link arrays follow :attr:`link_names`; matrices over the coordinates
    (every link but the frame) follow :attr:`coordinates`.
    """

    __slots__ = ("_core", "_links", "_gears", "_spec")

    def __init__(self, core: TrainCore, spec: Optional[Tuple[str, str, str]] = None) -> None:
        if not isinstance(core, TrainCore):
            raise ArgumentTypeError("use egt.load, egt.loads or Train.from_dict to build a Train")
        self._core = core
        self._links: Tuple[str, ...] = tuple(core.link_names)
        self._gears: Tuple[str, ...] = tuple(g["name"] for g in core.gears())
        # The spec as written (text, format, source): a Train pickles through it.
        self._spec = spec

    def __reduce__(self) -> Tuple[Any, Tuple[str, str, str]]:
        """Pickle through the spec text, so that trains cross process
        boundaries (multiprocessing, joblib, Dask); validation is repeated on
        load, which is what makes the copy trustworthy."""
        if self._spec is None:
            raise ArgumentTypeError("this Train was not built from a spec text and cannot be pickled")
        return (Train.from_str, self._spec)

    # -- construction ------------------------------------------------------

    @classmethod
    def from_str(cls, text: str, format: str = "toml", source: str = "<string>") -> "Train":
        """Parse and validate a spec written in TOML or JSON."""
        return cls(TrainCore.from_text(text, format, source), (text, format, source))

    @classmethod
    def from_file(cls, path: PathLike) -> "Train":
        """Read a spec file (``.json`` is JSON, anything else TOML)."""
        p = os.fspath(path)
        with open(p, encoding="utf-8") as f:
            text = f.read()
        fmt = "json" if p.lower().endswith(".json") else "toml"
        return cls(TrainCore.from_text(text, fmt, p), (text, fmt, p))

    @classmethod
    def from_dict(cls, spec: Mapping[str, Any]) -> "Train":
        """Validate a spec given as a dict (the JSON form of the spec format)."""
        try:
            text = json.dumps(spec, indent=1, allow_nan=True)
        except TypeError as e:
            raise ArgumentTypeError(f"the spec dict is not JSON-serialisable: {e}") from e
        return cls(TrainCore.from_text(text, "json", "<dict>"), (text, "json", "<dict>"))

    # -- structure ---------------------------------------------------------

    @property
    def name(self) -> Optional[str]:
        """Title from the spec."""
        return self._core.name

    @property
    def frame(self) -> str:
        """The frame (ground) link."""
        return self._core.frame

    @property
    def dof(self) -> int:
        """Degree of freedom."""
        return self._core.dof

    @property
    def link_names(self) -> Tuple[str, ...]:
        """Link names in link order (the order of every per-link array)."""
        return self._links

    @property
    def coordinates(self) -> Tuple[str, ...]:
        """Every link but the frame: the rows/columns of [M], the columns of [psi_w]."""
        return tuple(self._core.coordinates)

    @property
    def levels(self) -> Tuple[str, ...]:
        """Axis level names (a, b, c, ...)."""
        return tuple(self._core.levels)

    @property
    def links(self) -> Tuple[Link, ...]:
        """The links with their data."""
        return tuple(Link(**d) for d in self._core.links())

    @property
    def gears(self) -> Tuple[GearPair, ...]:
        """The gear pairs with their data (gear pair m is circuit m)."""
        out = []
        for d in self._core.gears():
            d = dict(d)
            d.pop("path")
            ex = d["ratio_exact"]
            d["ratio_exact"] = None if ex is None else Fraction(ex)
            out.append(GearPair(**d))
        return tuple(out)

    @property
    def circuits(self) -> Tuple[Circuit, ...]:
        """The fundamental-circuit table (paper Table 1), one row per gear pair."""
        gears = self._core.gears()
        return tuple(
            Circuit(
                index=m + 1,
                gear=c["gear"],
                gear_i=c["gear_i"],
                gear_j=c["gear_j"],
                carrier=c["carrier"],
                levels=(c["level_i"], c["level_j"]),
                ratio=g["ratio"],
                ratio_exact=None if g["ratio_exact"] is None else Fraction(g["ratio_exact"]),
                path=tuple(c["path"]),
            )
            for m, (c, g) in enumerate(zip(self._core.circuits(), gears))
        )

    @property
    def elements(self) -> Dict[str, Tuple[str, Tuple[str, ...]]]:
        """Shift elements: name -> (kind, links)."""
        return {n: (k, tuple(ls)) for n, k, ls in self._core.elements()}

    def check(self) -> List[str]:
        """The topology checks the train passed, in words (section 2)."""
        return list(self._core.checks())

    def atlas_member(self, level: str = "rotation") -> Dict[str, Any]:
        """The member of ``egt.atlas(links, dof, level)`` this train is (docs/atlas.md).

        Raises ``egt.EgtError`` naming the link when a link is in no gear pair's
        circuit (e.g. a housing joined by a bearing only).
        """
        return _atlas_member(self._core, level)

    def _repr_html_(self) -> str:
        from ._results import _html_table

        title = f"{self.name or 'train'}: {len(self._links)} links, DOF {self.dof}, frame {self.frame}"
        return _html_table(
            title + " (fundamental circuits, Table 1)",
            ["circuit", "gear pair", "gear i", "gear j", "carrier", "levels", "ratio"],
            (
                (c.index, c.gear, c.gear_i, c.gear_j, c.carrier, " ".join(c.levels),
                 c.ratio_exact if c.ratio_exact is not None else c.ratio)
                for c in self.circuits
            ),
        )

    def speed_ladder(self, ax: Any = None, *, inputs: Optional[Mapping[str, Speed]] = None) -> Any:
        """The speed ladder (lever diagram): of every gear state when the train
        is a transmission, else of ``inputs`` (:func:`egt.plot.speed_ladder`)."""
        from . import plot

        return plot.speed_ladder(self, ax, inputs=inputs)

    def __repr__(self) -> str:
        return (
            f"<egt.Train {self.name or ''!r}: {len(self._links)} links, "
            f"{len(self._core.gears())} gear pairs, dof={self.dof}>"
        )

    def _names(self) -> Tuple[Tuple[str, ...], Tuple[str, ...], Tuple[str, ...]]:
        """Link, gear-pair and element names by index: the core's ids in its results."""
        return self._links, self._gears, tuple(n for n, _, _ in self._core.elements())

    # -- defaults from the spec's [analysis] section -----------------------

    def _spec_speeds(self) -> List[Tuple[str, float, Optional[str]]]:
        # The core reads a decimal in the spec as the decimal written (as the CLI does).
        return [(n, v, ex) for n, v, ex in self._core.analysis()["speeds"]]

    def _speeds(
        self, inputs: Optional[Mapping[str, Speed]], unit: str = "rad/s"
    ) -> List[Tuple[str, float, Optional[str]]]:
        if inputs is None:
            if unit != "rad/s":
                raise ArgumentError("the spec's [analysis] speeds are in rad/s: give `inputs` with `unit`")
            return self._spec_speeds()
        return [_speed_arg(str(n), v, unit) for n, v in mapping(inputs, "inputs").items()]

    def _loads(
        self,
        torques: Optional[Mapping[str, float]],
        accelerations: Optional[Mapping[str, float]],
        driving: Optional[Sequence[str]],
    ) -> Tuple[
        Optional[List[Tuple[str, float]]], Optional[List[Tuple[str, float]]], Optional[List[str]]
    ]:
        # None keeps the spec's [analysis] value; the core resolves it (as for the CLI).
        return (
            None if torques is None else _pairs(torques, "torques"),
            None if accelerations is None else _pairs(accelerations, "accelerations"),
            None if driving is None else _names(driving, "driving"),
        )

    def _inputs(self, inputs: Optional[Sequence[str]]) -> List[str]:
        if inputs is not None:
            return _names(inputs, "inputs")
        a = self._core.analysis()
        if a["speeds"]:
            return [n for n, _, _ in a["speeds"]]
        return list(a["driving"])

    # -- analyses ----------------------------------------------------------

    def kinematics(
        self, inputs: Optional[Mapping[str, Speed]] = None, *, unit: str = "rad/s"
    ) -> Kinematics:
        """Speeds of every link (Willis equations, eq. 2).

        ``inputs`` maps one link per DOF to its speed in ``unit`` (``"rad/s"``,
        ``"rpm"``, ``"rev/s"``, ``"deg/s"``; or pint Quantities); default: the
        spec's ``[analysis] speeds``. The speeds come back in ``unit``: the
        Willis equations are homogeneous, so the exact rational solution is
        included in any unit when every ratio and input is exact.
        ``.to(unit)`` converts afterwards.
        """
        _units.factor(unit)
        raw, doc = self._core.kinematics(self._speeds(inputs, unit))
        return Kinematics._from_core(self._links, raw, doc, unit)

    def willis_jacobian(self) -> np.ndarray:
        """[psi_w] of eq. (2): rows are circuits, columns the :attr:`coordinates`."""
        return self._core.willis_jacobian()

    def mass_matrix(self) -> MassMatrix:
        """The mass matrix [M] (eq. 3-5) from inertias, masses, copies and axis offsets."""
        d = self._core.mass_matrix()  # the core's MassMatrix: levels by index, rows
        levels = self._core.levels
        return MassMatrix(
            coordinates=self.coordinates,
            matrix=np.asarray(d["matrix"], dtype=np.float64).reshape(
                len(self.coordinates), len(self.coordinates)
            ),
            offsets=tuple(
                Offset((levels[o["levels"][0]], levels[o["levels"][1]]), o["distance"], o["source"])
                for o in d["offsets"]
            ),
            notes=tuple(d["notes"]),
        )

    def dynamics(
        self,
        torques: Optional[Mapping[str, float]] = None,
        accelerations: Optional[Mapping[str, float]] = None,
        driving: Optional[Sequence[str]] = None,
        *,
        engaged: Sequence[str] = (),
        inertia: bool = True,
    ) -> Dynamics:
        """Inverse dynamics (eq. 6-11): driving torques, multipliers, mesh forces.

        ``torques``: known applied torques (positive along positive rotation);
        ``accelerations``: one prescribed acceleration per DOF (omit for the
        static analysis); ``driving``: the DOF links whose torque is solved for;
        ``engaged``: shift elements in force. Omitted arguments come from the
        spec's ``[analysis]`` section. ``inertia=False`` ignores [M].
        """
        t, a, d = self._loads(torques, accelerations, driving)
        raw, doc = self._core.dynamics(t, a, d, _names(engaged, "engaged"), inertia)
        return Dynamics._from_core(self._links, self._gears, raw, doc)

    def power(
        self,
        inputs: Optional[Mapping[str, Speed]] = None,
        torques: Optional[Mapping[str, float]] = None,
        accelerations: Optional[Mapping[str, float]] = None,
        driving: Optional[Sequence[str]] = None,
        *,
        engaged: Sequence[str] = (),
        losses: bool = True,
        inertia: bool = True,
        unit: str = "rad/s",
    ) -> PowerFlow:
        """Power flow through every mesh, with the gear pairs' mesh losses unless ``losses=False``.

        ``inputs``: one speed per DOF, as for :meth:`kinematics` (in ``unit``;
        power is computed in SI, so other units are converted to rad/s and
        the results are in rad/s, N m and W)."""
        t, a, d = self._loads(torques, accelerations, driving)
        speeds = self._speeds(inputs, unit)
        if unit != "rad/s":
            k = _units.factor(unit)
            speeds = [(n, v * k, None) for n, v, _ in speeds]
        raw, docs = self._core.power(speeds, t, a, d, _names(engaged, "engaged"), losses, inertia)
        return PowerFlow._from_core(self._links, self._gears, raw, docs)

    def velocity_matrix(
        self, inputs: Optional[Sequence[str]] = None, *, engaged: Sequence[str] = ()
    ) -> np.ndarray:
        """[V] of eq. (23): coordinate speeds per unit speed of each input (columns)."""
        return self._core.velocity_matrix(self._inputs(inputs), _names(engaged, "engaged"))

    def reduced_mass_matrix(
        self, inputs: Optional[Sequence[str]] = None, *, engaged: Sequence[str] = ()
    ) -> np.ndarray:
        """The reduced mass matrix V^T M V (eq. 25) for the independent ``inputs``."""
        return self._core.reduced_mass_matrix(self._inputs(inputs), _names(engaged, "engaged"))

    def equivalent_inertia(self, link: Optional[str] = None) -> float:
        """Inertia of a 1-DOF train reduced to ``link`` (default: the spec's ``reduce_to``)."""
        if link is None:
            link = self._core.analysis()["reduce_to"]
            if link is None:
                link = self._inputs(None)[0] if self._inputs(None) else ""
        return self._core.equivalent_inertia(str(link))

    def willis_residual(self, speeds: ArrayLike) -> float:
        """max |psi_m| / max |w| for per-link ``speeds`` under the train's ratios (eq. 2)."""
        a = np.ascontiguousarray(_batch._numeric(speeds, "speeds"), dtype=np.float64)
        return self._core.willis_residual(a)

    # -- batches -----------------------------------------------------------

    def batch(
        self,
        compute: str = "dynamics",
        *,
        inputs: Optional[Sequence[str]] = None,
        accelerated: Optional[Sequence[str]] = None,
        driving: Optional[Sequence[str]] = None,
        engaged: Sequence[str] = (),
        gear_state: Optional[str] = None,
        condition_bounds: Optional[bool] = None,
        outputs: Optional[Sequence[str]] = None,
        executor: str = "auto",
    ) -> BatchPlan:
        """Prepare the train for many scenarios (``compute``: ``"kinematics"``,
        ``"dynamics"`` or ``"power"``).

        ``inputs``: links with prescribed speed (default: the spec's
        ``[analysis] speeds``); ``accelerated`` and ``driving`` default to the
        spec's choices, else the inputs. ``gear_state``: a state of the
        transmission (its input speed prescribed, the output's torque solved,
        its engaged elements adding ``lambda.<element>`` reaction columns).
        ``condition_bounds``: when the ``cond.*`` columns are not wanted for
        themselves, estimate a condition only where a cheap upper bound (from
        the LU factors) cannot show it below 1e8 / 2, and solve kinematics
        and ideal dynamics by the train's straight-line program (eliminated
        once, run over 64 rows at a time): the same rows are warned about and
        refused, the other outputs differ by rounding only (within 1e-12 of
        the row's largest), and a ``cond.*`` value at most 5e7 may be that
        bound instead of the estimate (about twice as fast when every row has
        its own ratios; faster again where the machine has AVX-512 or AVX2,
        the program then being compiled for the train:
        :attr:`egt.BatchPlan.program`).
        By default (None) on exactly when ``outputs`` are chosen and none is
        a ``cond.*`` column, as ``egt batch --columns``: the bounds then
        change no warning, refusal or chosen column beyond rounding.
        ``outputs``: the output columns to compute, in that
        order (default: all; :attr:`egt.BatchPlan.outputs` of a plan made
        without it lists them); with ``condition_bounds`` the straight-line
        program then drops every operation they do not need. The rows that
        fail and the chosen columns' numbers do not change.
        ``executor``: how the straight-line program runs, ``"auto"`` (the
        default: compiled to machine code for the train where the machine has
        AVX-512 or AVX2) or ``"interpreted"``, to compare or time them on
        one machine (both give the same numbers, bit for bit; a plan without
        a program takes either). See :class:`egt.BatchPlan`.
        """
        args = (
            compute,
            None if inputs is None else _names(inputs, "inputs"),
            None if accelerated is None else _names(accelerated, "accelerated"),
            None if driving is None else _names(driving, "driving"),
            _names(engaged, "engaged"),
            None if gear_state is None else str(gear_state),
            None if condition_bounds is None else bool(condition_bounds),
            None if outputs is None else _names(outputs, "outputs"),
            str(executor),
        )
        core = batch_plan(self._core, *args)
        # The recipe (this train and the arguments) makes the plan pickle, so
        # that it travels to worker processes (egt.BatchPlan.run_distributed).
        return BatchPlan(core, compute, list(self._gears), self._core, recipe=(self, args))

    def batch_kinematics(
        self,
        inputs: Mapping[str, ArrayLike],
        *,
        ratios: Optional[ArrayLike] = None,
        teeth: Optional[ArrayLike] = None,
        threads: Optional[int] = None,
    ) -> BatchKinematics:
        """Speeds of every link for many scenarios, in parallel with the GIL released.

        ``inputs`` maps each input link to a speed or an array of one speed
        per row; ``ratios`` is ``(gears,)`` or ``(rows, gears)`` Willis ratios,
        or ``teeth`` ``(gears, 2)`` or ``(rows, gears, 2)`` tooth counts
        ``[z_i, z_j]`` (signs from each pair's mesh kind); default: the train's
        ratios. Failed rows are flagged in ``ok`` / ``errors`` and hold 0.0.
        """
        names = [str(n) for n in inputs]
        plan = self.batch("kinematics", inputs=names)
        res = plan.evaluate(
            {f"speed.{n}": v for n, v in zip(names, inputs.values())},
            ratios=ratios,
            teeth=teeth,
            threads=threads,
        )
        known = np.array([d["sized"] for d in self._core.links()], dtype=bool)
        return BatchKinematics._from_result(self._links, known, res)

    def batch_dynamics(
        self,
        driving: Optional[Sequence[str]] = None,
        *,
        accelerations: Optional[Mapping[str, ArrayLike]] = None,
        torques: Optional[Mapping[str, ArrayLike]] = None,
        speeds: Optional[Mapping[str, ArrayLike]] = None,
        ratios: Optional[ArrayLike] = None,
        teeth: Optional[ArrayLike] = None,
        inertias: Optional[Mapping[str, ArrayLike]] = None,
        masses: Optional[Mapping[str, ArrayLike]] = None,
        engaged: Sequence[str] = (),
        threads: Optional[int] = None,
    ) -> BatchDynamics:
        """Inverse dynamics for many scenarios, in parallel with the GIL released.

        Every mapping takes per link a scalar (the same for all rows) or one
        value per row. ``accelerations``: the prescribed accelerations (omit
        for the static analysis: the driving links at rest); ``torques``:
        known applied torques (replacing the spec's); ``inertias`` /
        ``masses``: one copy's data (``copies`` still multiplies); omitted
        ``driving``, ``torques`` and ``accelerations`` come from the spec.
        Failed rows are flagged in ``ok`` / ``errors`` and hold 0.0.
        """
        a = self._core.analysis()
        drv = list(a["driving"]) if driving is None else _names(driving, "driving")
        if accelerations is None:
            acc_names = [n for n, _ in a["accelerations"]] or list(drv)
            acc_values: Dict[str, ArrayLike] = dict(a["accelerations"])
        else:
            # No accelerations: the static analysis, the driving links at rest.
            acc_names = [str(n) for n in accelerations] or list(drv)
            acc_values = {str(n): v for n, v in accelerations.items()}
        speed_links = list(speeds) if speeds is not None else list(acc_names)
        plan = self.batch(
            "dynamics", inputs=[str(n) for n in speed_links], accelerated=acc_names,
            driving=drv, engaged=engaged,
        )
        values: Dict[str, ArrayLike] = {}
        # Speeds do not enter the inverse dynamics of a rigid train; unset ones are 0.
        for n in speed_links:
            values[f"speed.{n}"] = (speeds or {}).get(n, 0.0)
        for n in acc_names:
            values[f"accel.{n}"] = acc_values.get(n, 0.0)
        if torques is not None:
            for c in plan.parameters:
                if c.startswith("torque."):
                    values[c] = 0.0
            for n, v in torques.items():
                values[f"torque.{n}"] = v
        for n, v in (inertias or {}).items():
            values[f"inertia.{n}"] = v
        for n, v in (masses or {}).items():
            values[f"mass.{n}"] = v
        res = plan.evaluate(values, ratios=ratios, teeth=teeth, threads=threads)
        return BatchDynamics._from_result(self._links, tuple(drv), res)

    # -- stability, simulation (section 5, eq. 12-27) ----------------------

    def stability(
        self,
        coordinates: Optional[Sequence[str]] = None,
        *,
        curves: Optional[Sequence[CurveLike]] = None,
        inputs: Optional[Mapping[str, float]] = None,
    ) -> StabilityReport:
        """Stability about an operating point, for any number of DOF.

        ``coordinates``: the F driving links (default: the spec's input links,
        else chosen for conditioning); ``curves``: linearised torque-speed
        curves (default: the spec's ``[[analysis.curves]]``); ``inputs``: the
        operating point, F link speeds as for :meth:`kinematics` (default: the
        spec's speeds, else the equilibrium). See :mod:`egt._motion` for the
        sign convention.
        """
        raw = _stability(
            self._core,
            None if coordinates is None else _names(coordinates, "coordinates"),
            None if curves is None else _curves(curves),
            None if inputs is None else _pairs(inputs, "inputs"),
        )
        return StabilityReport._from_core(self._links, raw)

    def simulate(
        self,
        t_end: Optional[float] = None,
        *,
        dt: Optional[float] = None,
        method: Optional[str] = None,
        initial: Optional[Mapping[str, float]] = None,
        curves: Optional[Sequence[CurveLike]] = None,
        torque: Optional[Callable[[float, np.ndarray], np.ndarray]] = None,
        every: int = 0,
    ) -> Simulation:
        """Integrate the motion in time (eq. 12) from ``initial`` speeds.

        ``method``: ``"rk4"`` (default) or ``"implicit"`` (L-stable SDIRK);
        omitted settings come from the spec's ``[analysis.simulate]``, else
        the defaults the CLI uses too (``dt = t_end / 1000``). The applied torques are the ``curves``
        (default: the spec's), or ``torque(t, speeds) -> torques``, a Python
        function of time and the per-link speed array returning a float64
        array of per-link torques. ``every``: store every n-th step (0: about
        2000 samples).
        """
        every = count(every, "every", 2**32)
        raw = _simulate(
            self._core,
            None if t_end is None else float(t_end),
            None if dt is None else float(dt),
            method,
            None if initial is None else _pairs(initial, "initial"),
            None if curves is None else _curves(curves),
            torque,
            every,
        )
        return Simulation._from_core(self._links, raw)

    # -- transmissions -----------------------------------------------------

    def modes(
        self,
        state: Optional[str] = None,
        *,
        campbell: Optional[Tuple[float, float]] = None,
        static_torque: Optional[float] = None,
    ) -> Modes:
        """Natural frequencies and mass-normalised modes of the lumped
        torsional model (a spring along each mesh's line of action, from the
        spec's ``[compliance]``; docs/vibration.md), bare or in gear state
        ``state``. ``campbell``: an input speed range (MIN, MAX) [rpm] for
        the Campbell crossings, as ``egt modes --campbell --speed MIN:MAX``.
        ``static_torque``: the static deflection under this torque [N m] on
        the transmission input in ``state`` (``Modes.static_load``), as
        ``egt modes --state G --static TORQUE``."""
        rng = None
        if campbell is not None:
            if isinstance(campbell, (str, bytes)) or not isinstance(campbell, Sequence) or len(campbell) != 2:
                raise ArgumentTypeError("campbell must be a (min, max) pair of speeds [rpm]")
            rng = (number(campbell[0], "campbell[0]"), number(campbell[1], "campbell[1]"))
        torque = None
        if static_torque is not None:
            torque = number(static_torque, "static_torque")
            if not math.isfinite(torque):
                raise ArgumentError(f"static_torque must be finite, got {torque}")
            if state is None:
                raise ArgumentError("static_torque needs a gear state: the elements that hold the load")
        return Modes._from_core(_modes(self._core, None if state is None else str(state), rng, torque))

    def gear(self, state: str) -> GearState:
        """One gear state of the transmission, per unit input speed and torque."""
        raw, row = _gear(self._core, str(state))
        return GearState._from_core(self._names(), raw, row)

    def shift_table(self) -> ShiftTable:
        """Every gear state (ratios, element torques, power flow) and the
        table across them: steps, spread, shifts."""
        return ShiftTable._from_core(self._names(), _shift_table(self._core))

    def export_fmu(self, path: PathLike, *, model_identifier: Optional[str] = None) -> Path:
        """Write the train as an FMI 2.0 Co-Simulation unit (a ``.fmu``) at
        ``path`` and return that path, as ``egt fmu`` does (docs/fmu.md): a
        transmission's shift dynamics, or a train without shift elements
        under its curves and applied torques.

        The unit carries egt-fmu's shared library: ``EGT_FMU_LIBRARY`` when
        set, else the one the wheel carries. ``model_identifier`` (a C
        identifier) names the library inside the unit; by default the file's
        stem made one. Raises :class:`TransmissionError` for shift elements
        without gear states, :class:`EgtError` of kind ``"io"`` naming
        ``EGT_FMU_LIBRARY`` when there is no library to read,
        :class:`ArgumentError` for a model identifier that is not a C
        identifier, and ``OSError`` when ``path`` cannot be written.
        """
        if self._spec is None:
            raise ArgumentTypeError("this Train was not built from a spec text and has none to package")
        if model_identifier is not None and not isinstance(model_identifier, str):
            raise ArgumentTypeError(f"model_identifier must be a str, got {type(model_identifier).__name__}")
        out = Path(os.fspath(path))
        text, fmt, _ = self._spec
        out.write_bytes(_fmu_package(self._core, text, fmt, out.stem, model_identifier, _fmu.bundled()))
        return out

    # -- computer algebra --------------------------------------------------

    def to_sympy(self, inputs: Optional[Sequence[str]] = None) -> "SymbolicTrain":
        """The equations of this train as SymPy objects in named symbols.

        Willis equations and Jacobian (eq. 2), kinetic energy and mass matrix
        (eq. 3-5), and for the independent ``inputs`` (default: the spec's
        input links) the velocity matrix [V] and the reduced matrices (eq.
        23-26). Needs SymPy (``pip install 'egt[sympy]'``).
        """
        from .sympy_export import SymbolicTrain

        ins = self._inputs(inputs)
        return SymbolicTrain._from_structure(
            _structure(self._core), self._core.analysis(), ins if ins else None
        )


def _structure(core: TrainCore) -> Dict[str, Any]:
    from ._egt import structure

    return structure(core)


def load(path: PathLike) -> Train:
    """Read and validate a spec file (``.json`` is JSON, anything else TOML)."""
    return Train.from_file(path)


def loads(text: str, format: str = "toml", *, source: str = "<string>") -> Train:
    """Parse and validate a spec from text (``format``: ``"toml"`` or ``"json"``)."""
    return Train.from_str(text, format, source)
