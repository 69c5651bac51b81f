"""Results of :meth:`egt.Train.modes`: the natural frequencies and modes of
the lumped torsional model (a spring along each mesh's line of action; see
docs/vibration.md)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Dict, Optional, Sequence, Tuple

import numpy as np

from ._results import _Documented, _document_field, _pandas

if TYPE_CHECKING:  # pragma: no cover
    import pandas
    from matplotlib.axes import Axes


@dataclass(frozen=True, eq=False)
class NaturalMode:
    """One mode of the undamped model."""

    rigid: bool
    """A rigid-body mode (frequency 0): a motion of the kinematics."""
    omega: float
    """Natural frequency [rad/s]."""
    hertz: float
    """Natural frequency [Hz]."""
    multiplicity: int
    """How many modes share this frequency."""
    group: int
    """Index of the first mode with this frequency."""
    shape: np.ndarray
    """Mass-normalised shape (phi^T M phi = 1), one value per coordinate."""
    strain_energy: np.ndarray
    """Share of the strain energy in each spring."""
    kinetic_energy: np.ndarray
    """Share of the kinetic energy in each coordinate."""
    damping_ratio: Optional[float]
    """phi^T C phi / (2 omega), when some damping is given."""


@dataclass(frozen=True)
class Crossing:
    """An input speed at which a mesh's tooth-pass frequency meets a natural frequency."""

    speed: float
    """Input speed [rpm]."""
    gear: str
    mode: int
    """Index into :attr:`Modes.modes`."""
    hertz: float


@dataclass(frozen=True)
class DampedMode:
    """One damped mode: the eigenvalue sigma + i omega_d of the model with its damping."""

    sigma: float
    """Real part [1/s] (negative: decay)."""
    omega_d: float
    """Damped angular frequency [rad/s] (0 for a real root)."""
    hertz_d: float
    """Damped frequency [Hz]."""
    omega_n: float
    """|lambda| [rad/s]."""
    damping_ratio: float
    """-sigma / |lambda| (exactly 1 for each real root of an overdamped motion)."""


@dataclass(frozen=True)
class MeshCheck:
    """One gear pair under a steady load: the compliant model beside the rigid one."""

    gear: str
    rigid_torque: float
    """The torque gear i spends on the mesh in the rigid model, eq. (11) [N m]."""
    compliant_torque: float
    """The same from the springs: force times base radius over the planets [N m]."""
    force: float
    """One planet's mesh force along the line of action [N]."""
    deflection: float
    """One planet's mesh deflection along the line of action [m]."""


@dataclass(frozen=True)
class StaticLoad:
    """The static deflection under a steady input torque (``egt modes --static``)."""

    input_torque: float
    """[N m] on the transmission input."""
    output_torque: float
    """The output's reaction [N m]."""
    meshes: Tuple[MeshCheck, ...]
    springs: Dict[str, Tuple[float, float]]
    """Every spring's (deflection, force): m and N for a mesh, rad and N m otherwise."""
    elements: Dict[str, float]
    """The torques of the elements held rigidly [N m]."""


@dataclass(frozen=True, eq=False)
class Modes(_Documented):
    """The torsional modes of a train, bare or in a gear state.

    ``to_dict()`` is ``egt modes --format json``."""

    state: Optional[str]
    dof: int
    """The number of rigid-body modes."""
    coordinates: Tuple[str, ...]
    """Every moving link; a planet's copies as ``name#1``, ``name#2``, ..."""
    inertias: np.ndarray
    """The diagonal mass matrix [kg m^2], per coordinate."""
    springs: Tuple[str, ...]
    """The springs: each planet copy's mesh, torsional springs, compliant elements."""
    constraints: Tuple[str, ...]
    """The engaged elements held rigidly."""
    modes: Tuple[NaturalMode, ...]
    """Rigid-body modes first, then by rising frequency."""
    mesh_orders: Optional[Dict[str, float]]
    """Tooth passes per input revolution by gear pair (one rigid-body mode only)."""
    crossings: Tuple[Crossing, ...]
    """Campbell crossings, by speed (when ``campbell`` was given)."""
    speed_range: Optional[Tuple[float, float]]
    """The input speed range [rpm] of the crossings (when ``campbell`` was given)."""
    static_load: Optional[StaticLoad]
    """The static deflection (when ``static_torque`` was given)."""
    damped: Tuple[DampedMode, ...]
    """The damped modes by rising |lambda| (empty without damping)."""
    _document: Dict[str, Any] = _document_field()

    def to_pandas(self) -> "pandas.DataFrame":
        """One row per mode: frequency, multiplicity, damping ratio, and the
        spring and coordinate with the largest share of its energy."""
        pd = _pandas()
        rows = []
        for k, m in enumerate(self.modes):
            spring = "" if m.rigid else self.springs[int(np.argmax(m.strain_energy))]
            rows.append(
                {
                    "mode": k + 1,
                    "rigid": m.rigid,
                    "hertz": m.hertz,
                    "omega": m.omega,
                    "multiplicity": m.multiplicity,
                    "damping_ratio": m.damping_ratio,
                    "top_spring": spring,
                    "top_strain_share": 0.0 if m.rigid else float(np.max(m.strain_energy)),
                    "top_coordinate": self.coordinates[int(np.argmax(m.kinetic_energy))],
                }
            )
        return pd.DataFrame(rows).set_index("mode")

    def shapes(self) -> "pandas.DataFrame":
        """The mode shapes: a row per coordinate, a column per mode (from 1)."""
        pd = _pandas()
        data = np.column_stack([m.shape for m in self.modes]) if self.modes else np.zeros((len(self.coordinates), 0))
        return pd.DataFrame(data, index=pd.Index(self.coordinates, name="coordinate"), columns=range(1, len(self.modes) + 1))

    def plot(self, ax: Optional["Axes"] = None) -> "Axes":
        """The Campbell diagram (:func:`egt.plot.campbell`)."""
        from .plot import campbell

        return campbell(self, ax)

    @property
    def frequencies(self) -> np.ndarray:
        """Every mode's frequency [Hz], rigid-body modes (0) first."""
        return np.array([m.hertz for m in self.modes], dtype=np.float64)

    @classmethod
    def _from_core(cls, raw: Sequence[Any]) -> "Modes":
        """From the core's result and the CLI's document of it (names, not indices)."""
        _, d = raw
        meshing = d["meshing"]
        st = d.get("static_load")
        static = None
        if st is not None:
            static = StaticLoad(
                input_torque=st["input_torque"],
                output_torque=st["output_torque"],
                meshes=tuple(
                    MeshCheck(m["gear"], m["rigid_torque"], m["compliant_torque"], m["force"], m["deflection"])
                    for m in st["meshes"]
                ),
                springs={x["name"]: (x["deflection"], x["force"]) for x in st["springs"]},
                elements={e["name"]: e["torque"] for e in st["elements"]},
            )
        rng = None if meshing is None or meshing["range"] is None else tuple(meshing["range"])
        return cls(
            _document=d,
            state=d["state"],
            dof=d["dof"],
            coordinates=tuple(c["name"] for c in d["coordinates"]),
            inertias=np.array([c["inertia"] for c in d["coordinates"]], dtype=np.float64),
            springs=tuple(s["name"] for s in d["springs"]),
            constraints=tuple(d["constraints"]),
            modes=tuple(
                NaturalMode(
                    rigid=m["rigid"],
                    omega=m["omega"],
                    hertz=m["hertz"],
                    multiplicity=m["multiplicity"],
                    group=m["group"],
                    shape=np.array(m["shape"], dtype=np.float64),
                    strain_energy=np.array(m["strain_energy"], dtype=np.float64),
                    kinetic_energy=np.array(m["kinetic_energy"], dtype=np.float64),
                    damping_ratio=m["damping_ratio"],
                )
                for m in d["modes"]
            ),
            mesh_orders=None if meshing is None else {o["gear"]: o["order"] for o in meshing["orders"]},
            crossings=()
            if meshing is None
            else tuple(Crossing(c["speed"], c["gear"], c["mode"], c["hertz"]) for c in meshing["crossings"]),
            speed_range=None if rng is None else (float(rng[0]), float(rng[1])),
            static_load=static,
            damped=tuple(
                DampedMode(x["sigma"], x["omega_d"], x["hertz_d"], x["omega_n"], x["damping_ratio"]) for x in d["damped"]
            ),
        )
