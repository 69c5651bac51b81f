# Hand-written stub of the native module `egt._egt` (crates/egt-py/src).
# Checked against the built module by `python -m mypy.stubtest egt`.

from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Tuple, final

import numpy as np
import numpy.typing as npt

__version__: str

_Input = Tuple[str, float, Optional[str]]
# [core result, the CLI's JSON document of it]
_Documented = List[Dict[str, Any]]
_Pair = Tuple[str, float]

@final
class TrainCore:
    @staticmethod
    def from_text(text: str, format: str = "toml", source: str = "<string>") -> TrainCore: ...
    @property
    def name(self) -> Optional[str]: ...
    @property
    def frame(self) -> str: ...
    @property
    def dof(self) -> int: ...
    @property
    def link_names(self) -> List[str]: ...
    @property
    def coordinates(self) -> List[str]: ...
    @property
    def levels(self) -> List[str]: ...
    def checks(self) -> List[str]: ...
    def links(self) -> List[Dict[str, Any]]: ...
    def gears(self) -> List[Dict[str, Any]]: ...
    def circuits(self) -> List[Dict[str, Any]]: ...
    def elements(self) -> List[Tuple[str, str, List[str]]]: ...
    def analysis(self) -> Dict[str, Any]: ...
    def kinematics(self, inputs: List[_Input]) -> _Documented: ...
    def willis_jacobian(self) -> npt.NDArray[np.float64]: ...
    def mass_matrix(self) -> Dict[str, Any]: ...
    def dynamics(
        self,
        torques: Optional[List[_Pair]],
        accelerations: Optional[List[_Pair]],
        driving: Optional[List[str]],
        engaged: List[str],
        inertia: bool = True,
    ) -> _Documented: ...
    def power(
        self,
        speeds: List[_Input],
        torques: Optional[List[_Pair]],
        accelerations: Optional[List[_Pair]],
        driving: Optional[List[str]],
        engaged: List[str],
        losses: bool = True,
        inertia: bool = True,
    ) -> _Documented: ...
    def velocity_matrix(self, inputs: List[str], engaged: List[str] = ...) -> npt.NDArray[np.float64]: ...
    def reduced_mass_matrix(self, inputs: List[str], engaged: List[str] = ...) -> npt.NDArray[np.float64]: ...
    def equivalent_inertia(self, link: str) -> float: ...
    def willis_residual(self, speeds: npt.NDArray[np.float64]) -> float: ...
    def _panic(self) -> None: ...

def structure(core: TrainCore) -> Dict[str, Any]: ...
def atlas(
    links: int, dof: int, level: str, part: Optional[Tuple[int, int]], fractionation: str, search: str = "trees"
) -> List[Dict[str, Any]]: ...
def atlas_member(core: TrainCore, level: str = "rotation") -> Dict[str, Any]: ...
@final
class BatchPlanCore:
    @property
    def parameters(self) -> List[str]: ...
    @property
    def outputs(self) -> List[str]: ...
    @property
    def base(self) -> npt.NDArray[np.float64]: ...
    @property
    def program(self) -> Optional[str]: ...
    def run(
        self, params: npt.NDArray[np.float64], threads: Optional[int] = None
    ) -> Tuple[npt.NDArray[np.float64], List[Tuple[int, str, str]]]: ...
    def run_set(
        self,
        base: npt.NDArray[np.float64],
        varied: List[Tuple[int, npt.NDArray[np.float64]]],
        rows: int,
        threads: Optional[int] = None,
    ) -> Tuple[npt.NDArray[np.float64], List[Tuple[int, str, str]]]: ...
    def describe(self) -> Dict[str, Any]: ...

def batch_plan(
    core: TrainCore,
    compute: str,
    inputs: Optional[List[str]] = None,
    accelerated: Optional[List[str]] = None,
    driving: Optional[List[str]] = None,
    engaged: List[str] = ...,
    gear_state: Optional[str] = None,
    condition_bounds: Optional[bool] = None,
    outputs: Optional[List[str]] = None,
    executor: str = "auto",
) -> BatchPlanCore: ...

_Curve = Tuple[str, float, float, float]

def stability(
    core: TrainCore,
    coordinates: Optional[List[str]] = None,
    curves: Optional[List[_Curve]] = None,
    speeds: Optional[List[_Pair]] = None,
) -> _Documented: ...
def modes(
    core: TrainCore,
    state: Optional[str] = None,
    campbell: Optional[Tuple[float, float]] = None,
    static_torque: Optional[float] = None,
) -> _Documented: ...
def simulate(
    core: TrainCore,
    t_end: Optional[float] = None,
    dt: Optional[float] = None,
    method: Optional[str] = None,
    initial: Optional[List[_Pair]] = None,
    curves: Optional[List[_Curve]] = None,
    torque: Optional[Callable[[float, npt.NDArray[np.float64]], npt.NDArray[np.float64]]] = None,
    every: int = 0,
) -> _Documented: ...
def shift_sim(
    core: TrainCore,
    from_: str,
    to: str,
    input_speed: float,
    input_torque: Optional[float],
    torque_table: Optional[List[Tuple[float, float]]],
    road_load: Tuple[float, float, float],
    vehicle_inertia: float,
    mu: Tuple[float, float],
    mu_decay: Optional[float],
    off_going: Optional[List[float]],
    on_coming: Optional[List[float]],
    ramps: List[Tuple[str, List[float]]],
    t_end: float,
    rtol: float,
    atol: float,
    method: str,
    max_steps: Optional[int],
    output_shaft: Optional[Tuple[float, float]],
    losses: bool,
) -> Dict[str, Any]: ...
def shift_named(
    core: TrainCore,
    name: str,
    rtol: float,
    atol: float,
    method: str,
    max_steps: Optional[int],
) -> Dict[str, Any]: ...
def shift_names(core: TrainCore) -> List[str]: ...
def ratios_from_teeth(
    core: TrainCore, teeth: npt.NDArray[np.int64]
) -> Tuple[npt.NDArray[np.float64], List[Tuple[int, str, str]]]: ...
@final
class SearchCore:
    def __new__(
        cls,
        text: str,
        base_text: str,
        format: str = ...,
        base_format: str = ...,
        source: str = ...,
        base_source: str = ...,
        top: Optional[int] = ...,
    ) -> SearchCore: ...
    @property
    def sets(self) -> List[str]: ...
    @property
    def top(self) -> int: ...
    @property
    def max_partitions(self) -> int: ...
    def run(self, part: int = ..., parts: int = ...) -> Dict[str, Any]: ...
    def candidate_spec(self, candidate: str) -> str: ...
    def merge(self, results: str, top: int) -> Dict[str, Any]: ...

def search_inputs(
    path: Optional[str] = ..., text: Optional[str] = ..., format: Optional[str] = ...
) -> Tuple[str, str, str, str, str, str]: ...
def gear(core: TrainCore, state: str) -> _Documented: ...
def shift_table(core: TrainCore) -> _Documented: ...
def cli(args: List[str]) -> int: ...
def fmu_package(
    core: TrainCore,
    text: str,
    format: str,
    stem: str,
    model_identifier: Optional[str],
    bundled: Optional[PathLike[str]],
) -> bytes: ...

class EgtError(Exception):
    kind: Optional[str]
    """The error variant in snake case (e.g. ``"unknown_link"``, ``"singular"``)."""
    names: Optional[Tuple[str, ...]]
    """The offending links, pairs, fields or levels."""
    state: Optional[str]
    """The gear state an analysis failed in, if any."""

class SpecError(EgtError):
    path: Optional[str]
    value: Optional[float]
    suggestion: Optional[str]

class SpecSyntaxError(SpecError):
    source: Optional[str]
    line: Optional[int]
    column: Optional[int]
    message: Optional[str]

class TopologyError(EgtError):
    links: Optional[Tuple[str, ...]]
    pairs: Optional[Tuple[str, ...]]
    levels: Optional[Tuple[str, ...]]
    dof: Optional[int]
    parts: Optional[List[List[str]]]

class TransmissionError(EgtError):
    elements: Optional[Tuple[str, ...]]
    gears: Optional[Tuple[str, ...]]
    free: Optional[Tuple[str, ...]]
    dof: Optional[int]
    input: Optional[str]
    output: Optional[str]
    suggestion: Optional[str]

class AnalysisError(EgtError): ...

class InputError(AnalysisError):
    dof: Optional[int]
    given: Optional[int]
    what: Optional[str]
    link: Optional[str]

class UnderdeterminedError(AnalysisError):
    free: Optional[Tuple[str, ...]]

class InconsistentError(AnalysisError):
    conflicting: Optional[Tuple[str, ...]]

class SingularError(AnalysisError):
    what: Optional[str]
    detail: Optional[str]

class IllConditionedError(AnalysisError):
    what: Optional[str]
    condition: Optional[float]
    threshold: Optional[float]

class MissingDataError(AnalysisError):
    what: Optional[str]
    analysis: Optional[str]
    hint: Optional[str]

class SelfLockingError(AnalysisError): ...

class NonFiniteError(AnalysisError):
    what: Optional[str]
    detail: Optional[str]

class InternalError(EgtError): ...
