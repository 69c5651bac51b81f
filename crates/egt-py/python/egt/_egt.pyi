# Hand-written stub of the native module `egt._egt` (crates/egt-py/src).
# Checked against the built module by `python -m mypy.stubtest egt`.

from typing import Any, Dict, List, Optional, Tuple, final

import numpy as np
import numpy.typing as npt

__version__: str

_Input = Tuple[str, float, Optional[str]]
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
    def kinematics(self, inputs: List[_Input]) -> Dict[str, Any]: ...
    def willis_jacobian(self) -> npt.NDArray[np.float64]: ...
    def mass_matrix(self) -> Dict[str, Any]: ...
    def dynamics(
        self,
        torques: List[_Pair],
        accelerations: List[_Pair],
        driving: List[str],
        engaged: List[str],
        inertia: bool = True,
    ) -> Dict[str, Any]: ...
    def power(
        self,
        speeds: List[_Input],
        torques: List[_Pair],
        accelerations: List[_Pair],
        driving: List[str],
        engaged: List[str],
        losses: bool = True,
        inertia: bool = True,
    ) -> Dict[str, Any]: ...
    def velocity_matrix(self, inputs: List[str], engaged: List[str] = ...) -> npt.NDArray[np.float64]: ...
    def reduced_mass_matrix(self, inputs: List[str], engaged: List[str] = ...) -> npt.NDArray[np.float64]: ...
    def equivalent_inertia(self, link: str) -> float: ...
    def willis_residual(self, speeds: npt.NDArray[np.float64]) -> float: ...
    def _panic(self) -> None: ...

def structure(core: TrainCore) -> Dict[str, Any]: ...
def batch_kinematics(
    core: TrainCore,
    inputs: List[str],
    speeds: npt.NDArray[np.float64],
    ratios: Optional[npt.NDArray[np.float64]] = None,
    teeth: Optional[npt.NDArray[np.int64]] = None,
    threads: Optional[int] = None,
) -> Dict[str, Any]: ...
def batch_dynamics(
    core: TrainCore,
    driving: List[str],
    accelerated: List[str],
    alpha: npt.NDArray[np.float64],
    torque_links: List[str],
    torques: npt.NDArray[np.float64],
    ratios: Optional[npt.NDArray[np.float64]] = None,
    teeth: Optional[npt.NDArray[np.int64]] = None,
    inertia_links: List[str] = ...,
    inertias: Optional[npt.NDArray[np.float64]] = None,
    mass_links: List[str] = ...,
    masses: Optional[npt.NDArray[np.float64]] = None,
    engaged: List[str] = ...,
    threads: Optional[int] = None,
) -> Dict[str, Any]: ...

class EgtError(Exception):
    kind: Optional[str]
    """The error variant in snake case (e.g. ``"unknown_link"``, ``"singular"``)."""
    names: Optional[Tuple[str, ...]]
    """The offending links, pairs, fields or levels."""

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

class InternalError(EgtError): ...
