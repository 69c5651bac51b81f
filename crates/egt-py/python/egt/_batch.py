"""NumPy argument handling and results of the batch (screening) API.

Arguments are normalised here, once, into C-contiguous float64 (or int64 for
tooth counts) arrays of one row per scenario; the native side re-checks shapes
and solves the rows in parallel with the GIL released. Per-row failures are
reported in ``ok`` / ``errors``; failed rows hold 0.0, never NaN.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple

import numpy as np
from numpy.typing import ArrayLike

if TYPE_CHECKING:  # pragma: no cover
    import pandas

__all__ = ["RowError", "BatchKinematics", "BatchDynamics"]


def _numeric(x: ArrayLike, what: str) -> np.ndarray:
    """``x`` as an array of real numbers (bool, complex, object, text refused)."""
    a = np.asarray(x)
    if a.dtype.kind not in "iuf":
        raise TypeError(
            f"`{what}` must hold real numbers (int or float), got dtype {a.dtype}"
        )
    return a


def _rows_of(a: np.ndarray, per_row_ndim: int) -> Optional[int]:
    """The number of rows of ``a`` if it has a row axis, None if it broadcasts."""
    if a.ndim == per_row_ndim + 1:
        return int(a.shape[0])
    return None


def common_rows(arrays: Iterable[Tuple[str, np.ndarray, int]]) -> int:
    """The common row count of the per-row arrays; 1 when everything broadcasts."""
    rows: Optional[int] = None
    first = ""
    for what, a, nd in arrays:
        if a.ndim not in (nd, nd + 1):
            raise ValueError(
                f"`{what}` must have {nd} dimension(s) (one scenario) or {nd + 1} "
                f"(one row per scenario), got shape {a.shape}"
            )
        r = _rows_of(a, nd)
        if r is None:
            continue
        if rows is None:
            rows, first = r, what
        elif r != rows:
            raise ValueError(
                f"`{what}` has {r} rows but `{first}` has {rows}: every per-row array "
                "must have one row per scenario"
            )
    return 1 if rows is None else rows


def rows_matrix(a: np.ndarray, rows: int, cols: int, what: str) -> np.ndarray:
    """Broadcast ``a`` ((cols,) or (rows, cols)) to C-contiguous float64 (rows, cols)."""
    if a.ndim == 2 and a.shape[1] != cols:
        raise ValueError(f"`{what}` must have {cols} column(s), got shape {a.shape}")
    if a.ndim == 1 and a.shape[0] != cols:
        raise ValueError(f"`{what}` must have {cols} entries per row, got shape {a.shape}")
    if a.ndim not in (1, 2):
        raise ValueError(f"`{what}` must have shape ({cols},) or (rows, {cols}), got {a.shape}")
    return np.ascontiguousarray(np.broadcast_to(a.astype(np.float64, copy=False), (rows, cols)))


def columns(
    values: Mapping[str, ArrayLike], what: str
) -> Tuple[List[str], List[np.ndarray]]:
    """Names and arrays (scalar or one value per row) of a name -> values mapping."""
    names: List[str] = []
    arrays: List[np.ndarray] = []
    for name, v in values.items():
        names.append(str(name))
        arrays.append(_numeric(v, f"{what}[{name!r}]"))
    return names, arrays


def stack_columns(arrays: Sequence[np.ndarray], rows: int) -> np.ndarray:
    """Per-name scalars or (rows,) vectors as one C-contiguous (rows, k) float64 array."""
    out = np.zeros((rows, len(arrays)), dtype=np.float64)
    for k, a in enumerate(arrays):
        out[:, k] = np.broadcast_to(a.astype(np.float64, copy=False), (rows,))
    return out


def teeth_array(x: ArrayLike, rows: int, gears: int) -> np.ndarray:
    """Tooth counts (gears, 2) or (rows, gears, 2) as C-contiguous int64 (rows, gears, 2).

    Float arrays are accepted when they hold whole numbers; the sign and size of
    each count are checked per row by the native side.
    """
    a = _numeric(x, "teeth")
    if a.shape[-2:] != (gears, 2):
        raise ValueError(f"`teeth` must end in shape ({gears}, 2), got {a.shape}")
    if a.dtype.kind == "f":
        if not np.all(np.isfinite(a)) or not np.all(a == np.round(a)):
            raise ValueError("`teeth` must hold whole numbers")
    if a.dtype.kind == "u" and a.size and int(a.max()) > np.iinfo(np.int64).max:
        raise ValueError("`teeth` holds values too large for a tooth count")
    return np.ascontiguousarray(np.broadcast_to(a.astype(np.int64), (rows, gears, 2)))


@dataclass(frozen=True)
class RowError:
    """Why one row of a batch failed."""

    row: int
    kind: str
    """The error kind, as ``EgtError.kind`` (e.g. ``"singular"``, ``"invalid_teeth"``)."""
    message: str


def _errors(raw: Sequence[Tuple[int, str, str]]) -> Dict[int, RowError]:
    return {r: RowError(r, k, m) for r, k, m in raw}


@dataclass(frozen=True, eq=False)
class BatchKinematics:
    """Speeds of every link for every scenario (row)."""

    links: Tuple[str, ...]
    speeds: np.ndarray
    """(rows, links) float64; 0.0 in failed rows."""
    condition: np.ndarray
    residual: np.ndarray
    known: np.ndarray
    ok: np.ndarray
    """(rows,) bool: False where the row failed (see ``errors``)."""
    errors: Dict[int, RowError]

    @classmethod
    def _from_raw(cls, links: Tuple[str, ...], d: Mapping[str, Any]) -> "BatchKinematics":
        return cls(
            links=links,
            speeds=d["speed"],
            condition=d["condition"],
            residual=d["residual"],
            known=d["known"],
            ok=d["ok"],
            errors=_errors(d["errors"]),
        )

    def __len__(self) -> int:
        return int(self.speeds.shape[0])

    def speed(self, link: str) -> np.ndarray:
        """The speeds of one link over all rows."""
        return self.speeds[:, self.links.index(link)]

    def to_dict(self) -> Dict[str, Any]:
        return {
            "links": list(self.links),
            "speeds": self.speeds.tolist(),
            "condition": self.condition.tolist(),
            "residual": self.residual.tolist(),
            "ok": self.ok.tolist(),
            "errors": {str(r): {"kind": e.kind, "message": e.message} for r, e in self.errors.items()},
        }

    def to_pandas(self) -> "pandas.DataFrame":
        from ._results import _pandas

        pd = _pandas()
        df = pd.DataFrame(self.speeds, columns=list(self.links))
        df["ok"] = self.ok
        df["error"] = [self.errors[r].message if r in self.errors else None for r in range(len(self))]
        return df


@dataclass(frozen=True, eq=False)
class BatchDynamics:
    """Inverse dynamics for every scenario (row)."""

    links: Tuple[str, ...]
    driving: Tuple[str, ...]
    driving_torques: np.ndarray
    """(rows, len(driving)) float64; 0.0 in failed rows."""
    accelerations: np.ndarray
    """(rows, links)."""
    multipliers: np.ndarray
    """(rows, constraints): Willis rows then engaged elements."""
    conditions: np.ndarray
    """(rows, 2): condition estimates of [Psi_w] (eq. 8) and the force system (eq. 10)."""
    ok: np.ndarray
    errors: Dict[int, RowError]

    @classmethod
    def _from_raw(
        cls, links: Tuple[str, ...], driving: Tuple[str, ...], d: Mapping[str, Any]
    ) -> "BatchDynamics":
        return cls(
            links=links,
            driving=driving,
            driving_torques=d["driving_torques"],
            accelerations=d["acceleration"],
            multipliers=d["multipliers"],
            conditions=d["conditions"],
            ok=d["ok"],
            errors=_errors(d["errors"]),
        )

    def __len__(self) -> int:
        return int(self.driving_torques.shape[0])

    def driving_torque(self, link: str) -> np.ndarray:
        """The solved torque on one driving link over all rows."""
        return self.driving_torques[:, self.driving.index(link)]

    def to_dict(self) -> Dict[str, Any]:
        return {
            "links": list(self.links),
            "driving": list(self.driving),
            "driving_torques": self.driving_torques.tolist(),
            "accelerations": self.accelerations.tolist(),
            "multipliers": self.multipliers.tolist(),
            "conditions": self.conditions.tolist(),
            "ok": self.ok.tolist(),
            "errors": {str(r): {"kind": e.kind, "message": e.message} for r, e in self.errors.items()},
        }

    def to_pandas(self) -> "pandas.DataFrame":
        from ._results import _pandas

        pd = _pandas()
        df = pd.DataFrame(self.driving_torques, columns=[f"T_{n}" for n in self.driving])
        df["ok"] = self.ok
        df["error"] = [self.errors[r].message if r in self.errors else None for r in range(len(self))]
        return df
