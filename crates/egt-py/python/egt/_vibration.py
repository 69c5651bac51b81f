"""Results of :meth:`egt.Train.modes`: the natural frequencies and modes of
the lumped torsional model (a spring along each mesh's line of action; see
docs/vibration.md)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Dict, Optional, Sequence, Tuple

import numpy as np

from ._results import _Documented, _document_field


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
    _document: Dict[str, Any] = _document_field()

    @property
    def frequencies(self) -> np.ndarray:
        """Every mode's frequency [Hz], rigid-body modes (0) first."""
        return np.array([m.hertz for m in self.modes], dtype=np.float64)

    @classmethod
    def _from_core(cls, raw: Sequence[Any]) -> "Modes":
        """From the core's result and the CLI's document of it (names, not indices)."""
        _, d = raw
        meshing = d["meshing"]
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
        )
