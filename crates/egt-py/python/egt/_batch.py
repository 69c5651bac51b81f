"""The batch (screening) API: a train prepared once, evaluated for many rows.

A :class:`BatchPlan` wraps egt-core's batch plan: named parameter columns
(``ratio.<gear>``, ``speed.<link>``, ``accel.<link>``, ``torque.<link>``,
``inertia.<link>``, ``mass.<link>``, ``efficiency.<gear>``), a base row with the
spec's values, and named output columns. Arguments are normalised here, once,
into a C-contiguous float64 parameter matrix (one row per scenario); the native
side solves the rows in parallel with the GIL released. Per-row failures are
reported in ``ok`` / ``errors``; failed rows hold 0.0, never NaN.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
from numpy.typing import ArrayLike

from . import _dask
from ._args import ArgumentError, ArgumentKeyError, ArgumentTypeError, count
from ._egt import BatchPlanCore, TrainCore
from ._egt import ratios_from_teeth as _ratios_from_teeth

if TYPE_CHECKING:  # pragma: no cover
    import pandas


def _numeric(x: ArrayLike, what: str) -> np.ndarray:
    """``x`` as an array of real numbers (bool, complex, object, text refused)."""
    a = np.asarray(x)
    if a.dtype.kind not in "iuf":
        raise ArgumentTypeError(
            f"`{what}` must hold real numbers (int or float), got dtype {a.dtype}"
        )
    return a


def _rows_of(a: np.ndarray, per_row_ndim: int) -> Optional[int]:
    """The number of rows of ``a`` if it has a row axis, None if it broadcasts."""
    if a.ndim == per_row_ndim + 1:
        return int(a.shape[0])
    return None


def common_rows(arrays: Sequence[Tuple[str, np.ndarray, int]], given: Optional[int] = None) -> int:
    """The common row count of the per-row arrays; 1 when everything
    broadcasts; ``given`` (a ``rows=`` argument) if not None, which every
    per-row array must agree with."""
    rows: Optional[int] = None
    first = ""
    for what, a, nd in arrays:
        if a.ndim not in (nd, nd + 1):
            raise ArgumentError(
                f"`{what}` must have {nd} dimension(s) (one scenario) or {nd + 1} "
                f"(one row per scenario), got shape {a.shape}"
            )
        r = _rows_of(a, nd)
        if r is None:
            continue
        if rows is None:
            rows, first = r, what
        elif r != rows:
            raise ArgumentError(
                f"`{what}` has {r} rows but `{first}` has {rows}: every per-row array "
                "must have one row per scenario"
            )
    if given is not None:
        given = count(given, "rows", 2**48)
        if rows not in (None, given):
            raise ArgumentError(f"rows={given} disagrees with the per-row arrays")
        return given
    return 1 if rows is None else rows


def rows_matrix(a: np.ndarray, rows: int, cols: int, what: str) -> np.ndarray:
    """Broadcast ``a`` ((cols,) or (rows, cols)) to C-contiguous float64 (rows, cols)."""
    if a.ndim == 2 and a.shape[1] != cols:
        raise ArgumentError(f"`{what}` must have {cols} column(s), got shape {a.shape}")
    if a.ndim == 1 and a.shape[0] != cols:
        raise ArgumentError(f"`{what}` must have {cols} entries per row, got shape {a.shape}")
    if a.ndim not in (1, 2):
        raise ArgumentError(f"`{what}` must have shape ({cols},) or (rows, {cols}), got {a.shape}")
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
        raise ArgumentError(f"`teeth` must end in shape ({gears}, 2), got {a.shape}")
    if a.dtype.kind == "f":
        if not np.all(np.isfinite(a)) or not np.all(a == np.round(a)):
            raise ArgumentError("`teeth` must hold whole numbers")
    if a.dtype.kind == "u" and a.size and int(a.max()) > np.iinfo(np.int64).max:
        raise ArgumentError("`teeth` holds values too large for a tooth count")
    return np.ascontiguousarray(np.broadcast_to(a.astype(np.int64), (rows, gears, 2)))



@dataclass(frozen=True)
class RowError:
    """Why one row of a batch failed."""

    row: int
    kind: str
    """The error kind, as ``EgtError.kind`` (e.g. ``"singular"``, ``"invalid_teeth"``)."""
    message: str


def _pandas() -> Any:
    from ._results import _pandas as p

    return p()


@dataclass(frozen=True, eq=False)
class BatchResult:
    """The outputs of a batch: one row per scenario, one named column per output.

    Failed rows hold 0.0 in every column (never NaN): check ``ok``/``errors``.
    ``power.efficiency`` is 0.0 in a row without input power.
    """

    outputs: Tuple[str, ...]
    values: np.ndarray
    """(rows, outputs) float64."""
    ok: np.ndarray
    """(rows,) bool: False where the row failed (see ``errors``)."""
    errors: Dict[int, RowError]

    def __len__(self) -> int:
        return int(self.values.shape[0])

    def __getitem__(self, name: str) -> np.ndarray:
        """One output column over all rows, e.g. ``result["torque.2"]``."""
        try:
            return self.values[:, self.outputs.index(name)]
        except ValueError:
            raise ArgumentKeyError(f"no output column {name!r} (outputs: {', '.join(self.outputs)})") from None

    def driving_torque(self, link: str) -> np.ndarray:
        """The solved torque on a driving link over all rows (column
        ``driving_torque.<link>``; ``torque.<link>`` in older egt-core)."""
        for name in (f"driving_torque.{link}", f"torque.{link}"):
            if name in self.outputs:
                return self[name]
        raise ArgumentKeyError(f"{link!r} is not a driving link of this batch")

    @property
    def driving(self) -> Tuple[str, ...]:
        """The driving links (whose torques the rows solve)."""
        new = [c.split(".", 1)[1] for c in self.outputs if c.startswith("driving_torque.")]
        return tuple(new or [c.split(".", 1)[1] for c in self.outputs if c.startswith("torque.")])

    def to_dict(self) -> Dict[str, Any]:
        return {
            "outputs": list(self.outputs),
            "values": self.values.tolist(),
            "ok": self.ok.tolist(),
            "errors": {str(r): {"kind": e.kind, "message": e.message} for r, e in self.errors.items()},
        }

    def to_pandas(self) -> "pandas.DataFrame":
        pd = _pandas()
        df = pd.DataFrame(self.values, columns=list(self.outputs))
        df["ok"] = self.ok
        df["error"] = [self.errors[r].message if r in self.errors else None for r in range(len(self))]
        return df


class BatchPlan:
    """A train prepared for many scenarios (build it with :meth:`egt.Train.batch`).

    Each scenario is a row of :attr:`parameters`; :meth:`params` builds the
    matrix from the base row (the spec's values) and the columns you vary,
    :meth:`run` solves it in parallel with the GIL released.
    """

    __slots__ = ("_core", "compute", "parameters", "outputs", "_gears", "_train", "_recipe")

    def __init__(
        self,
        core: BatchPlanCore,
        compute: str,
        gears: Sequence[str],
        train: TrainCore,
        recipe: Optional[Tuple[Any, Tuple[Any, ...]]] = None,
    ) -> None:
        self._core = core
        self.compute = compute
        self.parameters: Tuple[str, ...] = tuple(core.parameters)
        self.outputs: Tuple[str, ...] = tuple(core.outputs)
        self._gears = tuple(gears)
        self._train = train
        self._recipe = recipe

    @property
    def base(self) -> np.ndarray:
        """The spec's own parameter values (NaN where the spec gives none)."""
        return self._core.base

    @property
    def program(self) -> Optional[str]:
        """The plan's straight-line program: ``"compiled"`` (to machine code
        for the train: a wheel built with ``--features jit``), ``"interpreted"``
        (the default build, ``executor="interpreted"``, a machine without
        AVX-512 or AVX2, or ``EGT_JIT=0``), or None (no
        program: rows are solved in
        SIMD groups of eight; see ``condition_bounds`` in
        :meth:`egt.Train.batch`). Rows that vary only loads, speeds or
        accelerations share one factorisation instead, whatever this says."""
        return self._core.program

    def __repr__(self) -> str:
        return f"<egt.BatchPlan {self.compute}: {len(self.parameters)} parameters -> {len(self.outputs)} outputs>"

    def __reduce__(self) -> Tuple[Any, Tuple[Any, ...]]:
        if self._recipe is None:
            raise ArgumentTypeError("this plan was not made by Train.batch and cannot be pickled")
        train, args = self._recipe
        return (_rebuild_plan, (train, args))

    def column(self, name: str) -> int:
        try:
            return self.parameters.index(name)
        except ValueError:
            raise ArgumentKeyError(
                f"no parameter column {name!r} (parameters: {', '.join(self.parameters)})"
            ) from None

    def params(
        self,
        values: Optional[Mapping[str, ArrayLike]] = None,
        *,
        ratios: Optional[ArrayLike] = None,
        teeth: Optional[ArrayLike] = None,
        rows: Optional[int] = None,
    ) -> Tuple[np.ndarray, Dict[int, RowError]]:
        """The parameter matrix (Fortran order): the base row repeated, with
        the columns in ``values`` (name -> scalar or one value per row) and
        the ratio columns from ``ratios`` ((gears,) or (rows, gears)) or
        ``teeth`` ((gears, 2) or (rows, gears, 2)) replaced. Also returns the
        rows whose tooth counts are invalid."""
        names, cols = columns(values or {}, "values")
        per_row: List[Tuple[str, np.ndarray, int]] = [(f"values[{n!r}]", c, 0) for n, c in zip(names, cols)]
        r_arr = None if ratios is None else _numeric(ratios, "ratios")
        t_arr = None if teeth is None else _numeric(teeth, "teeth")
        if r_arr is not None and t_arr is not None:
            raise ArgumentError("give either `ratios` or `teeth`, not both")
        if r_arr is not None:
            per_row.append(("ratios", r_arr, 1))
        if t_arr is not None:
            per_row.append(("teeth", t_arr, 2))
        n_rows = common_rows(per_row, rows)
        # Fortran order: each column contiguous, as the native side solves
        # it (no transposition either way; :meth:`run` keeps the order).
        p = np.empty((n_rows, len(self.parameters)), dtype=np.float64, order="F")
        p[:] = self.base
        bad: Dict[int, RowError] = {}
        ratio_cols = [self.column(f"ratio.{g}") for g in self._gears]
        if r_arr is not None:
            p[:, ratio_cols] = rows_matrix(r_arr, n_rows, len(self._gears), "ratios")
        if t_arr is not None:
            # The core's one rule (signs from the mesh kinds, bounds on the counts).
            z = teeth_array(t_arr, n_rows, len(self._gears))
            tau, refused = _ratios_from_teeth(self._train, z)
            bad = {r: RowError(r, k, m) for r, k, m in refused}
            p[:, ratio_cols] = tau
        for n, c in zip(names, cols):
            p[:, self.column(n)] = np.broadcast_to(c.astype(np.float64, copy=False), (n_rows,))
        return p, bad

    def run(
        self,
        params: Union[ArrayLike, Tuple[np.ndarray, Dict[int, RowError]], Mapping[str, ArrayLike]],
        *,
        threads: Optional[int] = None,
    ) -> BatchResult:
        """Solve every row of ``params`` ((rows, parameters) or one row), or of
        what :meth:`params` returned (the matrix and its refused rows, which
        are then reported failed): ``plan.run(plan.params({...}))``.

        ``params`` may also be a mapping of the columns you vary, name ->
        one value per row or one value for every row, the others keeping
        the base row's values: ``plan.run({"ratio.P1/sun-planet": r,
        "torque.c2": -40.0})``. No parameter matrix is built: only the
        columns given row by row are read, so a sweep of two parameters of
        a 35-parameter plan holds and reads 2 columns, not 35. The numbers
        are those of the matrix written out, bit for bit; the values come
        back in Fortran order.

        A Fortran-ordered matrix (as :meth:`params` builds) is solved column
        by column and the values come back in Fortran order, each output
        column contiguous; any other is solved as C-ordered rows. Both give
        the same numbers bit for bit.

        ``threads`` (default: every core, through the shared pool) sizes a
        private pool; ``threads=1`` solves on the calling thread with no pool,
        the cheapest way to call with small batches or from threads or
        processes of your own (a 64-row call: about 15 microseconds against 140
        through a pool of one thread)."""
        refused: Dict[int, RowError] = {}
        if isinstance(params, tuple) and len(params) == 2 and isinstance(params[1], dict):
            params, refused = params
        threads = self._threads(threads)
        if isinstance(params, Mapping):
            return self._run_set(params, threads)
        a = _numeric(params, "params")
        if a.ndim == 1:
            a = a.reshape(1, -1)
        if a.ndim != 2 or a.shape[1] != len(self.parameters):
            raise ArgumentError(
                f"params must have shape (rows, {len(self.parameters)}), got {a.shape}"
            )
        a = np.asarray(a, dtype=np.float64)
        if not a.flags.f_contiguous or a.flags.c_contiguous:
            a = np.ascontiguousarray(a)
        # A Fortran-ordered matrix (as :meth:`params` builds) is solved
        # column by column and its outputs come back in Fortran order too.
        _check_refused(refused, a.shape[0])
        values, raw = self._core.run(a, threads)
        return self._result(values, raw, refused)

    @staticmethod
    def _threads(threads: Optional[int]) -> Optional[int]:
        if threads is None:
            return None
        # More threads than cores are capped by the native side.
        n = count(threads, "threads", 2**32)
        if n < 1:
            raise ArgumentError(f"threads must be a positive integer, got {threads}")
        return int(n)

    def _run_set(
        self, values: Mapping[str, ArrayLike], threads: Optional[int], rows: Optional[int] = None
    ) -> BatchResult:
        """:meth:`run` of the columns in ``values``, the others at the base row's values."""
        names, cols = columns(values, "params")
        per_row = [(f"params[{n!r}]", c, 0) for n, c in zip(names, cols)]
        n_rows = common_rows(per_row, rows)
        base = np.array(self.base, dtype=np.float64)
        varied: Dict[int, np.ndarray] = {}
        for n, c in zip(names, cols):
            k = self.column(n)
            if c.ndim == 0:
                base[k] = float(c)
                varied.pop(k, None)
            else:
                varied[k] = np.ascontiguousarray(c, dtype=np.float64)
        vals, raw = self._core.run_set(base, list(varied.items()), n_rows, threads)
        return self._result(vals, raw, {})

    def _result(
        self, values: np.ndarray, raw: List[Tuple[int, str, str]], refused: Dict[int, RowError]
    ) -> BatchResult:
        ok = np.ones(values.shape[0], dtype=bool)
        errors = {r: RowError(r, k, m) for r, k, m in raw}
        errors.update(refused)  # rows params() refused (their ratios were placeholders)
        # (Indexing with an empty list costs more than a small batch's solve.)
        if refused:
            values[list(refused), :] = 0.0
        if errors:
            ok[list(errors)] = False
        return BatchResult(self.outputs, values, ok, errors)

    def run_distributed(
        self,
        params: Union[ArrayLike, Tuple[np.ndarray, Dict[int, RowError]]],
        *,
        client: Any = None,
        chunks: Optional[int] = None,
        threads: Optional[int] = 1,
    ) -> BatchResult:
        """:meth:`run` over a Dask cluster (see :func:`egt._batch.run_distributed`)."""
        return run_distributed(self, params, client=client, chunks=chunks, threads=threads)

    def evaluate(
        self,
        values: Optional[Mapping[str, ArrayLike]] = None,
        *,
        ratios: Optional[ArrayLike] = None,
        teeth: Optional[ArrayLike] = None,
        rows: Optional[int] = None,
        threads: Optional[int] = None,
    ) -> BatchResult:
        """:meth:`params` then :meth:`run`; rows with invalid teeth are failed rows.

        With ``values`` alone (no ``ratios`` or ``teeth``) no matrix is built:
        the columns go to :meth:`run` as a mapping, the same numbers bit for bit."""
        if ratios is None and teeth is None:
            return self._run_set(values or {}, self._threads(threads), rows)
        return self.run(self.params(values, ratios=ratios, teeth=teeth, rows=rows), threads=threads)


def _rebuild_plan(train: Any, args: Tuple[Any, ...]) -> "BatchPlan":
    """A plan from its recipe; a worker process keeps the plans it rebuilt."""
    key = (train._spec, tuple(tuple(a) if isinstance(a, list) else a for a in args))
    plan = _PLANS.get(key)
    if plan is None:
        plan = train.batch(args[0], inputs=args[1], accelerated=args[2], driving=args[3],
                           engaged=args[4], gear_state=args[5], condition_bounds=args[6],
                           outputs=args[7])
        _PLANS[key] = plan
    return plan


# Worker-local state: plans rebuilt in this process, by recipe.
_PLANS: Dict[Any, "BatchPlan"] = {}


def _run_chunk(plan: "BatchPlan", rows: np.ndarray, threads: Optional[int]) -> BatchResult:
    # A deserialised block may be unaligned or read-only: the native side
    # wants an owned, aligned, C-contiguous float64 array.
    return plan.run(np.array(rows, dtype=np.float64, order="C", copy=True), threads=threads)


def _check_refused(refused: Mapping[Any, Any], rows: int) -> None:
    """The refused rows given with a matrix (what :meth:`BatchPlan.params`
    returns): each a row number of the matrix with a :class:`RowError`, or an
    :class:`ArgumentError` naming the first that is not."""
    for r, e in refused.items():
        if isinstance(r, bool) or not isinstance(r, (int, np.integer)) or not 0 <= r < rows:
            raise ArgumentError(
                f"refused row {r!r} is not a row of the {rows}-row params matrix"
            )
        if not isinstance(e, RowError):
            raise ArgumentTypeError(
                f"refused row {r} must map to an egt.RowError, got {type(e).__name__}"
            )


def run_distributed(
    plan: "BatchPlan",
    params: Union[ArrayLike, Tuple[np.ndarray, Dict[int, RowError]]],
    *,
    client: Any = None,
    chunks: Optional[int] = None,
    threads: Optional[int] = 1,
) -> BatchResult:
    """:meth:`BatchPlan.run` for batches that outgrow one machine: the rows in
    ``chunks`` contiguous blocks, each a Dask task on ``client`` (an embedded
    ``LocalCluster`` by default), the plan rebuilt once per worker from its
    spec; the results are concatenated in row order, failed rows and their
    errors kept with their global row numbers. Needs ``egt-gears[dask]``."""
    _dask.require("run_distributed")
    refused: Dict[int, RowError] = {}
    if isinstance(params, tuple) and len(params) == 2 and isinstance(params[1], dict):
        params, refused = params
    a = np.ascontiguousarray(_numeric(params, "params"), dtype=np.float64)
    if a.ndim == 1:
        a = a.reshape(1, -1)
    n = a.shape[0]
    _check_refused(refused, n)
    k = count(chunks if chunks is not None else 4 * (os.cpu_count() or 1), "chunks", 1_000_000)
    k = max(1, min(k, n))
    bounds = [(n * i // k, n * (i + 1) // k) for i in range(k)]

    def run(c: Any) -> BatchResult:
        futures = [c.submit(_run_chunk, plan, a[lo:hi], threads, pure=False, retries=2) for lo, hi in bounds]
        parts = c.gather(futures)
        values = np.concatenate([p.values for p in parts], axis=0)
        ok = np.concatenate([p.ok for p in parts])
        errors: Dict[int, RowError] = {}
        for (lo, _), p in zip(bounds, parts):
            for r, e in p.errors.items():
                errors[lo + r] = RowError(lo + r, e.kind, e.message)
        errors.update(refused)
        values[list(refused), :] = 0.0
        ok[list(refused)] = False
        return BatchResult(plan.outputs, values, ok, errors)

    return _dask.on_cluster(client, run)


def _known_columns(
    res: BatchResult, prefix: str, links: Sequence[str]
) -> np.ndarray:
    """Per-link (rows, links) array from the ``<prefix>.<link>`` output columns (0 elsewhere)."""
    out = np.zeros((len(res), len(links)), dtype=np.float64)
    for k, name in enumerate(links):
        col = f"{prefix}.{name}"
        if col in res.outputs:
            out[:, k] = res[col]
    return out


@dataclass(frozen=True, eq=False)
class BatchKinematics:
    """Speeds of every link for every scenario (row)."""

    links: Tuple[str, ...]
    speeds: np.ndarray
    """(rows, links) float64; 0.0 in failed rows and for links of unknown speed."""
    known: np.ndarray
    """(links,) bool: False for a planet given without teeth (and True for the frame)."""
    condition: np.ndarray
    """(rows,) condition estimate of the Willis system."""
    ok: np.ndarray
    errors: Dict[int, RowError]

    @classmethod
    def _from_result(cls, links: Tuple[str, ...], known: np.ndarray, res: BatchResult) -> "BatchKinematics":
        return cls(
            links=links,
            speeds=_known_columns(res, "speed", links),
            known=known,
            condition=np.ascontiguousarray(res["cond.speeds"]),
            ok=res.ok,
            errors=res.errors,
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
            "ok": self.ok.tolist(),
            "errors": {str(r): {"kind": e.kind, "message": e.message} for r, e in self.errors.items()},
        }

    def to_pandas(self) -> "pandas.DataFrame":
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
    """(rows, constraints): Willis rows (gear-pair order), then engaged elements."""
    forces: Dict[str, np.ndarray]
    """Gear pair -> (rows,) tangential force lambda_m / r_i (eq. 11), for pairs with radii."""
    conditions: np.ndarray
    """(rows, 3): condition estimates of the speed system, [Psi_w] (eq. 8) and eq. (10)."""
    ok: np.ndarray
    errors: Dict[int, RowError]

    @classmethod
    def _from_result(
        cls, links: Tuple[str, ...], driving: Tuple[str, ...], res: BatchResult
    ) -> "BatchDynamics":
        lam = [c for c in res.outputs if c.startswith("lambda.")]
        return cls(
            links=links,
            driving=driving,
            driving_torques=np.stack([res.driving_torque(d) for d in driving], axis=1)
            if driving
            else np.zeros((len(res), 0)),
            accelerations=_known_columns(res, "accel", links),
            multipliers=np.stack([res[c] for c in lam], axis=1) if lam else np.zeros((len(res), 0)),
            forces={c[len("force."):]: np.ascontiguousarray(res[c]) for c in res.outputs if c.startswith("force.")},
            conditions=np.stack(
                [res["cond.speeds"], res["cond.accelerations"], res["cond.forces"]], axis=1
            ),
            ok=res.ok,
            errors=res.errors,
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
            "forces": {g: f.tolist() for g, f in self.forces.items()},
            "conditions": self.conditions.tolist(),
            "ok": self.ok.tolist(),
            "errors": {str(r): {"kind": e.kind, "message": e.message} for r, e in self.errors.items()},
        }

    def to_pandas(self) -> "pandas.DataFrame":
        pd = _pandas()
        df = pd.DataFrame(self.driving_torques, columns=[f"T_{n}" for n in self.driving])
        df["ok"] = self.ok
        df["error"] = [self.errors[r].message if r in self.errors else None for r in range(len(self))]
        return df
