"""Records and result classes returned by :class:`egt.Train`.

Every class is a frozen dataclass of plain Python values and NumPy arrays,
with ``to_dict()`` and, where a table is natural, ``to_pandas()`` (pandas is
optional and imported only there).

``to_dict()`` of an analysis result is the document the CLI prints for the
same analysis with ``--format json`` (``Kinematics`` is ``egt kinematics``,
``Dynamics`` is ``egt dynamics``, ``PowerFlow`` is ``egt power``, and so on):
one shape whichever front end made the result, built by the same Rust code.
The records of the spec (``Link``, ``GearPair``, ``Circuit``) give their
fields.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Dict, Iterable, Iterator, Mapping, Optional, Sequence, Tuple

import copy

import numpy as np

from ._args import ArgumentKeyError

if TYPE_CHECKING:  # pragma: no cover
    import pandas


def _pandas() -> Any:
    try:
        import pandas
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError(
            "to_pandas() needs pandas: pip install 'egt[pandas]'"
        ) from e
    return pandas


def _html_table(caption: str, headers: Sequence[str], rows: Iterable[Sequence[Any]]) -> str:
    """A small HTML table for notebooks (``_repr_html_``), every cell escaped."""
    from html import escape

    def cell(v: Any) -> str:
        if v is None:
            return ""
        if isinstance(v, float):
            return f"{v:.6g}"
        return escape(str(v))

    head = "".join(f"<th>{escape(h)}</th>" for h in headers)
    body = "".join("<tr>" + "".join(f"<td>{cell(v)}</td>" for v in r) + "</tr>" for r in rows)
    return f"<table><caption>{escape(caption)}</caption><tr>{head}</tr>{body}</table>"


def _convert_document(
    doc: Dict[str, Any], unit: str, k: float, q: Optional[Fraction]
) -> Dict[str, Any]:
    """A kinematics document in another unit: speeds times ``k``, exact
    speeds times ``q`` (None where the factor is not rational); ratios stay."""
    doc = copy.deepcopy(doc)

    def convert(rec: Dict[str, Any]) -> None:
        if rec.get("speed") is not None:
            rec["speed"] = rec["speed"] * k
        if rec.get("exact") is not None:
            rec["exact"] = None if q is None else str(Fraction(rec["exact"]) * q)

    for key in ("inputs", "links", "relative"):
        for rec in doc.get(key, ()):
            convert(rec)
    if unit == "rad/s":
        doc.pop("unit", None)
    else:
        doc["unit"] = unit
    return doc


def _document_field() -> Any:
    """The private ``_document`` field of a :class:`_Documented` result."""
    return field(default_factory=dict, repr=False, compare=False)


class _Documented:
    """A result whose ``to_dict()`` is the CLI's JSON document of it."""

    _document: Dict[str, Any]

    def to_dict(self) -> Dict[str, Any]:
        """The document the CLI prints for the same analysis with
        ``--format json`` (a fresh copy: JSON-ready, names not indices)."""
        return copy.deepcopy(self._document)


def _frac(text: Optional[str]) -> Optional[Fraction]:
    return None if text is None else Fraction(text)


def _fstr(x: Optional[Fraction]) -> Optional[str]:
    return None if x is None else str(x)


@dataclass(frozen=True)
class Link:
    """A link (rigid body) with its optional physical data."""

    name: str
    inertia: Optional[float]
    """Moment of inertia of one copy about its own axis [kg m^2]."""
    mass: Optional[float]
    """Mass of one copy [kg]."""
    copies: int
    """Identical satellites this link stands for (the paper's n_s)."""
    wheels: Optional[int]
    sized: bool
    """False for a planet given without a tooth count (its own speed is unknown)."""
    frame: bool

    def to_dict(self) -> Dict[str, Any]:
        return dict(self.__dict__)


@dataclass(frozen=True)
class GearPair:
    """A gear pair (geared edge) and its data."""

    name: str
    gear_i: str
    gear_j: str
    ratio: Optional[float]
    """Willis ratio tau = (w_i - w_k) / (w_j - w_k)."""
    ratio_exact: Optional[Fraction]
    teeth: Optional[Tuple[int, int]]
    mesh: Optional[str]
    radii: Optional[Tuple[float, float]]
    efficiency: float

    def to_dict(self) -> Dict[str, Any]:
        d = dict(self.__dict__)
        d["ratio_exact"] = _fstr(self.ratio_exact)
        return d


@dataclass(frozen=True)
class Circuit:
    """One row of the fundamental-circuit table (paper Table 1)."""

    index: int
    """m, counting from 1 (circuit m is gear pair m)."""
    gear: str
    gear_i: str
    gear_j: str
    carrier: str
    """The transfer vertex k."""
    levels: Tuple[str, str]
    """Turning-pair levels: gear i side, gear j side."""
    ratio: Optional[float]
    ratio_exact: Optional[Fraction]
    path: Tuple[str, ...]
    """The circuit's links from gear i through the tree to gear j."""

    def to_dict(self) -> Dict[str, Any]:
        d = dict(self.__dict__)
        d["ratio_exact"] = _fstr(self.ratio_exact)
        d["levels"] = list(self.levels)
        d["path"] = list(self.path)
        return d


@dataclass(frozen=True)
class Offset:
    """The distance between two axis levels (the paper's delta_xy)."""

    levels: Tuple[str, str]
    distance: float
    source: str


@dataclass(frozen=True)
class RelativeSpeed:
    """A floating link's speed relative to the link carrying it."""

    link: str
    carrier: str
    speed: float
    exact: Optional[Fraction]


@dataclass(frozen=True, eq=False)
class Kinematics(_Documented, Mapping[str, float]):
    """Speeds of every link for one set of inputs.

    A read-only mapping link name -> speed [rad/s]; the arrays follow
    ``links`` (link order, the frame's speed is 0). ``to_dict()`` is
    ``egt kinematics --format json`` (with a ``unit`` field when the unit is
    not rad/s).
    """

    links: Tuple[str, ...]
    speeds: np.ndarray
    known: np.ndarray
    """False where a speed is unknown (a planet given without teeth)."""
    exact: Optional[Dict[str, Fraction]]
    """Exact speeds, when every ratio and input is exact."""
    relative: Tuple[RelativeSpeed, ...]
    residual: float
    """Largest Willis residual |psi_m| relative to the largest speed (eq. 2)."""
    condition: float
    warnings: Tuple[str, ...]
    unit: str = "rad/s"
    """The unit of ``speeds``, ``exact`` and the relative speeds."""
    _document: Dict[str, Any] = _document_field()

    @classmethod
    def _from_core(
        cls, links: Tuple[str, ...], d: Mapping[str, Any], document: Dict[str, Any], unit: str = "rad/s"
    ) -> "Kinematics":
        """From the core's `Speeds` (its serde form: ids are indices, exact
        values text) and the CLI's document of it."""
        exact = d["exact"]
        if unit != "rad/s":
            document = {**document, "unit": unit}
        return cls(
            _document=document,
            unit=unit,
            links=links,
            speeds=np.asarray(d["speed"], dtype=np.float64),
            known=np.asarray(d["known"], dtype=bool),
            exact=None if exact is None else {n: Fraction(x) for n, x in zip(links, exact)},
            relative=tuple(
                RelativeSpeed(links[r["link"]], links[r["carrier"]], r["speed"], _frac(r["exact"]))
                for r in d["relative"]
            ),
            residual=d["residual"],
            condition=d["condition"],
            warnings=tuple(d["warnings"]),
        )

    def _repr_html_(self) -> str:
        exact = self.exact or {}
        return _html_table(
            f"speeds [{self.unit}], Willis residual {self.residual:.2g}",
            ["link", "speed", "exact"],
            ((n, float(v), exact.get(n)) for n, v in zip(self.links, self.speeds)),
        )

    def to(self, unit: str) -> "Kinematics":
        """The same speeds in ``unit`` (``"rad/s"``, ``"rpm"``, ``"rev/s"``,
        ``"deg/s"``). Exact values survive only where the factor is rational
        (rpm <-> rev/s); otherwise ``exact`` is None."""
        from . import _units

        k = _units.factor(self.unit) / _units.factor(unit)
        exact_factors = {("rev/s", "rpm"): Fraction(60), ("rpm", "rev/s"): Fraction(1, 60)}
        q = Fraction(1) if self.unit == unit else exact_factors.get((self.unit, unit))
        return replace(
            self,
            _document=_convert_document(self._document, unit, k, q),
            unit=unit,
            speeds=self.speeds * k,
            exact=None if self.exact is None or q is None else {n: x * q for n, x in self.exact.items()},
            relative=tuple(
                RelativeSpeed(r.link, r.carrier, r.speed * k, None if r.exact is None or q is None else r.exact * q)
                for r in self.relative
            ),
        )

    def __getitem__(self, name: str) -> float:
        try:
            return float(self.speeds[self.links.index(name)])
        except ValueError:
            raise ArgumentKeyError(name) from None

    def __iter__(self) -> Iterator[str]:
        return iter(self.links)

    def __len__(self) -> int:
        return len(self.links)


    def to_pandas(self) -> "pandas.DataFrame":
        pd = _pandas()
        return pd.DataFrame(
            {
                "speed": self.speeds,
                "known": self.known,
                "exact": [None if self.exact is None else self.exact[n] for n in self.links],
            },
            index=pd.Index(self.links, name="link"),
        )


@dataclass(frozen=True, eq=False)
class MassMatrix:
    """The mass matrix [M] of eq. (6) over the coordinates (every link but the frame)."""

    coordinates: Tuple[str, ...]
    matrix: np.ndarray
    offsets: Tuple[Offset, ...]
    notes: Tuple[str, ...]

    def to_dict(self) -> Dict[str, Any]:
        return {
            "coordinates": list(self.coordinates),
            "matrix": self.matrix.tolist(),
            "offsets": [
                {"levels": list(o.levels), "distance": o.distance, "source": o.source}
                for o in self.offsets
            ],
            "notes": list(self.notes),
        }

    def to_pandas(self) -> "pandas.DataFrame":
        pd = _pandas()
        return pd.DataFrame(self.matrix, index=list(self.coordinates), columns=list(self.coordinates))


@dataclass(frozen=True)
class MeshLoad:
    """The multiplier, torques and tangential forces of one gear pair (eq. 7, 11)."""

    gear: str
    multiplier: float
    torque_i: float
    """Torque gear i spends on the mesh, lambda_m psi_w[m, i]."""
    torque_j: float
    torque_carrier: float
    force: Optional[Tuple[float, float]]
    """F_im, F_jm of eq. (11) (all copies together), when pitch radii are known."""


@dataclass(frozen=True, eq=False)
class Dynamics(_Documented):
    """Inverse dynamics (eq. 6-11): accelerations, torques, multipliers, mesh loads.

    ``to_dict()`` is ``egt dynamics --format json``."""

    links: Tuple[str, ...]
    accelerations: np.ndarray
    """Angular acceleration of every link (link order)."""
    torques: np.ndarray
    """Applied torque on every link, known and solved; the frame's entry is the housing torque."""
    driving_torques: Dict[str, float]
    multipliers: np.ndarray
    """Lagrange multipliers: Willis rows, then engaged shift elements."""
    element_torques: np.ndarray
    meshes: Tuple[MeshLoad, ...]
    conditions: Tuple[float, float]
    warnings: Tuple[str, ...]
    _document: Dict[str, Any] = _document_field()

    @classmethod
    def _from_core(
        cls, links: Tuple[str, ...], gears: Tuple[str, ...], d: Mapping[str, Any], document: Dict[str, Any]
    ) -> "Dynamics":
        """From the core's `InverseDynamics` (its serde form: ids are indices)
        and the CLI's document of it."""
        return cls(
            _document=document,
            links=links,
            accelerations=np.asarray(d["acceleration"], dtype=np.float64),
            torques=np.asarray(d["torque"], dtype=np.float64),
            driving_torques={links[l]: t for l, t in d["driving_torques"]},
            multipliers=np.asarray(d["multipliers"], dtype=np.float64),
            element_torques=np.asarray(d["element_torques"], dtype=np.float64),
            meshes=tuple(
                MeshLoad(
                    gear=gears[m["gear"]],
                    multiplier=m["multiplier"],
                    torque_i=m["torque_i"],
                    torque_j=m["torque_j"],
                    torque_carrier=m["torque_carrier"],
                    force=None if m["force"] is None else tuple(m["force"]),
                )
                for m in d["meshes"]
            ),
            conditions=tuple(d["conditions"]),
            warnings=tuple(d["warnings"]),
        )

    def _repr_html_(self) -> str:
        rows = [(n, float(a), float(t)) for n, a, t in zip(self.links, self.accelerations, self.torques)]
        meshes = _html_table(
            "meshes", ["gear pair", "multiplier", "force i", "force j"],
            ((m.gear, m.multiplier, *(m.force or (None, None))) for m in self.meshes),
        )
        return _html_table("inverse dynamics", ["link", "acceleration", "torque"], rows) + meshes


    def to_pandas(self) -> "pandas.DataFrame":
        pd = _pandas()
        return pd.DataFrame(
            {"acceleration": self.accelerations, "torque": self.torques},
            index=pd.Index(self.links, name="link"),
        )


@dataclass(frozen=True)
class MeshPower:
    """Power in one mesh."""

    gear: str
    absolute: Tuple[float, float, float]
    """Power sent into the mesh by gear i, gear j and the carrier (absolute frame)."""
    rolling: float
    """The power the driving gear sends in the carrier's frame."""
    driver: Optional[str]
    """``"gear_i"``, ``"gear_j"`` or None (no rolling power)."""
    efficiency: float
    loss: float


@dataclass(frozen=True)
class LinkPower:
    """Power of one link: from its external torque, and stored in its inertia."""

    link: str
    external: float
    inertial: float


@dataclass(frozen=True, eq=False)
class PowerFlow(_Documented):
    """Power flow through every mesh, with or without mesh losses.

    ``to_dict()`` is ``egt power --format json``."""

    speeds: Kinematics
    dynamics: Dynamics
    meshes: Tuple[MeshPower, ...]
    links: Tuple[LinkPower, ...]
    input_power: float
    output_power: float
    loss: float
    kinetic_rate: float
    """dK/dt = w^T M w'."""
    efficiency: Optional[float]
    circulation_ratio: float
    """Largest branch power over the input power (> 1: power circulates)."""
    circulating: Optional[Tuple[Tuple[str, ...], Tuple[str, ...]]]
    """The meshes and shafts carrying more than the input power."""
    iterations: int
    notes: Tuple[str, ...] = field(default_factory=tuple)
    _document: Dict[str, Any] = _document_field()

    @classmethod
    def _from_core(
        cls, links: Tuple[str, ...], gears: Tuple[str, ...], d: Mapping[str, Any], documents: Mapping[str, Any]
    ) -> "PowerFlow":
        """From the core's `PowerFlow` (its serde form: ids are indices) and
        the CLI's documents of it, of its speeds and of its dynamics."""
        circ = d["circulating"]
        return cls(
            _document=documents["power"],
            speeds=Kinematics._from_core(links, d["speeds"], documents["speeds"]),
            dynamics=Dynamics._from_core(links, gears, d["dynamics"], documents["dynamics"]),
            meshes=tuple(
                MeshPower(
                    gear=gears[m["gear"]],
                    absolute=tuple(m["absolute"]),
                    rolling=m["rolling"],
                    driver=None if m["driver"] == "none" else m["driver"],
                    efficiency=m["efficiency"],
                    loss=m["loss"],
                )
                for m in d["meshes"]
            ),
            links=tuple(LinkPower(links[p["link"]], p["external"], p["inertial"]) for p in d["links"]),
            input_power=d["input_power"],
            output_power=d["output_power"],
            loss=d["loss"],
            kinetic_rate=d["kinetic_rate"],
            efficiency=d["efficiency"],
            circulation_ratio=d["circulation_ratio"],
            circulating=None
            if circ is None
            else (tuple(gears[g] for g in circ[0]), tuple(links[l] for l in circ[1])),
            iterations=d["iterations"],
            notes=tuple(d["notes"]),
        )

    @property
    def balance(self) -> float:
        """input - output - loss - dK/dt: zero up to round-off (energy balance)."""
        return self.input_power - self.output_power - self.loss - self.kinetic_rate

    def plot(self, ax: Any = None) -> Any:
        """Rolling power and loss per mesh (:func:`egt.plot.power_flow`)."""
        from . import plot

        return plot.power_flow(self, ax)

    def _repr_html_(self) -> str:
        return _html_table(
            f"power flow: in {self.input_power:.6g} W, out {self.output_power:.6g} W, loss {self.loss:.6g} W",
            ["gear pair", "rolling power", "driver", "efficiency", "loss"],
            ((m.gear, m.rolling, m.driver, m.efficiency, m.loss) for m in self.meshes),
        )

    def to_pandas(self) -> "pandas.DataFrame":
        pd = _pandas()
        return pd.DataFrame(
            {
                "p_gear_i": [m.absolute[0] for m in self.meshes],
                "p_gear_j": [m.absolute[1] for m in self.meshes],
                "p_carrier": [m.absolute[2] for m in self.meshes],
                "rolling": [m.rolling for m in self.meshes],
                "driver": [m.driver for m in self.meshes],
                "efficiency": [m.efficiency for m in self.meshes],
                "loss": [m.loss for m in self.meshes],
            },
            index=pd.Index([m.gear for m in self.meshes], name="gear"),
        )
