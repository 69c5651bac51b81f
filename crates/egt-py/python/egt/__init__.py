"""egt: graph-based kinematics and dynamics of epicyclic gear trains.

After E. Pennestri, "Dynamic Analysis of Epicyclic Gear Train by Means of
Computer Algebra". A gear train is written as a spec (TOML, JSON or a dict),
validated once into a :class:`Train`, and then analysed::

    import egt
    train = egt.load("examples/fig3_example61.toml")
    train.kinematics({"2": 100.0})["4"]        # speed of link 4
    train.dynamics().driving_torques            # eq. (10)
    train.batch_kinematics({"2": 100.0}, teeth=teeth_rows)   # screening, in parallel
    train.to_sympy().mass_matrix                # eq. (3)-(6) symbolically
    egt.load("examples/fig5_example62.toml").stability().verdict
    egt.load("examples/ford_c4_simpson.toml").shift_table()

The native part lives in ``egt._egt`` (Rust, via pyo3); this package adds the
Pythonic surface. Every error is an :class:`EgtError`.
"""

from __future__ import annotations

from ._args import ArgumentError, ArgumentKeyError, ArgumentTypeError
from ._atlas import atlas, atlas_distributed
from ._batch import BatchDynamics, BatchKinematics, BatchPlan, BatchResult, RowError
from ._egt import (
    AnalysisError,
    EgtError,
    IllConditionedError,
    InconsistentError,
    InputError,
    InternalError,
    MissingDataError,
    NonFiniteError,
    SelfLockingError,
    SingularError,
    SpecError,
    SpecSyntaxError,
    TopologyError,
    TransmissionError,
    UnderdeterminedError,
    __version__,
)
from ._results import (
    Circuit,
    Dynamics,
    GearPair,
    Kinematics,
    Link,
    LinkPower,
    MassMatrix,
    MeshLoad,
    MeshPower,
    Offset,
    PowerFlow,
    RelativeSpeed,
)
from ._motion import (
    Curve,
    MasslessDirection,
    Mode,
    OperatingPoint,
    ShiftQuality,
    ShiftSimulation,
    Simulation,
    StabilityReport,
)
from ._synth import SynthResult, synth, synth_distributed
from ._train import CurveLike, Speed, Train, load, loads
from ._transmission import (
    ElementLoad,
    GearPowerFlow,
    GearState,
    Shift,
    ShiftTable,
    Slip,
    Spread,
    Step,
)
from ._vibration import Crossing, DampedMode, MeshCheck, Modes, NaturalMode, StaticLoad

__all__ = [
    "__version__",
    "atlas",
    "atlas_distributed",
    "synth",
    "synth_distributed",
    "SynthResult",
    "Train",
    "load",
    "loads",
    "Speed",
    # results
    "Link",
    "GearPair",
    "Circuit",
    "Offset",
    "RelativeSpeed",
    "Kinematics",
    "MassMatrix",
    "MeshLoad",
    "Dynamics",
    "MeshPower",
    "LinkPower",
    "PowerFlow",
    "BatchPlan",
    "BatchResult",
    "BatchKinematics",
    "BatchDynamics",
    "RowError",
    "Curve",
    "CurveLike",
    "OperatingPoint",
    "Mode",
    "MasslessDirection",
    "StabilityReport",
    "Modes",
    "NaturalMode",
    "Crossing",
    "StaticLoad",
    "MeshCheck",
    "DampedMode",
    "Simulation",
    "ShiftSimulation",
    "ShiftQuality",
    "GearState",
    "ElementLoad",
    "Slip",
    "GearPowerFlow",
    "Step",
    "Spread",
    "Shift",
    "ShiftTable",
    # errors
    "EgtError",
    "SpecError",
    "SpecSyntaxError",
    "TopologyError",
    "TransmissionError",
    "AnalysisError",
    "InputError",
    "UnderdeterminedError",
    "InconsistentError",
    "SingularError",
    "IllConditionedError",
    "MissingDataError",
    "SelfLockingError",
    "NonFiniteError",
    "ArgumentError",
    "ArgumentTypeError",
    "ArgumentKeyError",
    "InternalError",
]
