"""Design search from Python: :func:`synth` (one process, every core) and
:func:`synth_distributed` (partitions as tasks on a Dask cluster, an embedded
``LocalCluster`` by default). The search itself is egt-core's
(``egt_core::design``); see ``docs/synth.md``."""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

from . import _dask
from ._args import ArgumentError, count
from ._egt import SearchCore, search_inputs
from ._results import _html_table, _pandas

if TYPE_CHECKING:  # pragma: no cover
    import pandas

    from ._train import Train

Job = Tuple[str, str, str, str, str, str, Optional[int]]
"""What a search is built from, as strings (so that it pickles to workers):
search text, its format and name, base text, its format and name, top."""


@dataclass(frozen=True)
class SetTeeth:
    """One unknown set of a candidate: the smallest-sun teeth of its basic
    ratio k = ring / sun (ring planet / (sun planet2) for a stepped planet;
    and k2 = ring / sun2 for a Ravigneaux set), and how many tooth sets give
    the same basic ratios (so the same gear ratios)."""

    sun: int
    """The sun (a Ravigneaux set's small sun)."""
    ring: int
    planet: int
    """The planet meshing the sun (a Ravigneaux set's short pinion)."""
    basic: Fraction
    alternatives: int
    sun2: Optional[int] = None
    """A Ravigneaux set's large sun."""
    planet2: Optional[int] = None
    """A Ravigneaux set's long pinion, a double-pinion set's outer pinion, or
    a stepped planet's wheel on the ring."""
    basic2: Optional[Fraction] = None
    """ring / sun2 of a Ravigneaux set."""


@dataclass(frozen=True)
class Candidate:
    """A candidate train: teeth per unknown set and its exact ratios."""

    rank: int
    score: float
    """Root mean square of (ratio - target) / target over the targeted states."""
    spread: Optional[float]
    sets: Dict[str, SetTeeth]
    ratios: Dict[str, Fraction]
    """Every gear state's ratio, exactly (float(x) for the float)."""
    layout: Dict[str, Tuple[str, ...]] = field(default_factory=dict)
    """The freed shift elements' links (the search spec's ``[layout]``)."""
    spec: str = field(default="", repr=False)
    """The candidate's train spec (JSON text): the base train with these
    teeth and this layout."""
    concept: Optional[Dict[str, Any]] = None
    """A concept search's structure: ``shafts`` (each named by its members,
    ``P1.carrier=P4.ring``), ``held``, ``input``, ``output``,
    ``equivalent_positions`` and ``equivalent_layouts`` (the same
    transmission), ``tooth_options`` (the concept's other tooth sets meeting
    the targets, best first: ``basic``, ``teeth``, ``ratios``, ``score``;
    ``tooth_options_cut`` if their search hit ``max_nodes``), ``structure``
    (member ids). A concept search reports each concept once: ``top``
    counts concepts."""
    same_ratio_teeth: Dict[str, Tuple[Dict[str, Any], ...]] = field(default_factory=dict)
    """Per set, every admissible tooth set with the same basic ratios."""
    efficiency: Optional[float] = None
    """Lowest efficiency over the targeted states."""
    element_torque: Optional[float] = None
    """Largest engaged element torque per unit input torque over the targeted states."""
    mesh_torque: Optional[float] = None
    """Largest mesh multiplier (torque on a mesh's first gear) per unit input torque over the targeted states."""
    planet_speed: Optional[float] = None
    """Largest planet speed relative to its carrier per unit input speed over the targeted states."""

    def train(self) -> "Train":
        """The candidate's train, for every analysis (e.g. ``.shift_table()``)."""
        from ._train import Train

        return Train.from_str(self.spec, "json", f"candidate-{self.rank}")


@dataclass(frozen=True)
class SynthResult:
    """The best candidates of a search and what it cost."""

    candidates: Tuple[Candidate, ...]
    stats: Dict[str, float]
    seconds: float
    partitions: int

    def to_pandas(self) -> "pandas.DataFrame":
        """One row per candidate: score, spread, each set's sun/ring/planet
        (sun2 of a Ravigneaux set; planet2 of a set whose planets have two
        wheels), each ratio."""
        pd = _pandas()
        rows: List[Dict[str, Any]] = []
        for c in self.candidates:
            row: Dict[str, Any] = {"rank": c.rank, "score": c.score, "spread": c.spread}
            for name, t in c.sets.items():
                row.update({f"{name}.sun": t.sun, f"{name}.ring": t.ring, f"{name}.planet": t.planet})
                if t.sun2 is not None:
                    row[f"{name}.sun2"] = t.sun2
                if t.planet2 is not None:
                    row[f"{name}.planet2"] = t.planet2
            row.update({f"ratio.{s}": float(x) for s, x in c.ratios.items()})
            row.update({f"layout.{e}": "+".join(links) for e, links in c.layout.items()})
            if c.concept is not None:
                row.update({"input": c.concept["input"], "output": c.concept["output"],
                            "shafts": " ".join(c.concept["shafts"])})
            rows.append(row)
        return pd.DataFrame(rows).set_index("rank") if rows else pd.DataFrame()

    def _repr_html_(self) -> str:
        return _html_table(
            f"design search: {len(self.candidates)} candidates, {self.stats.get('tooth_space', 0):.3g} tooth combinations, {self.seconds:.3g} s",
            ["rank", "score", "sets (sun/ring/planet)", "ratios"],
            (
                (c.rank, c.score, "  ".join(f"{n} {t.sun}/{t.ring}/{t.planet}" for n, t in c.sets.items()),
                 "  ".join(f"{s} {float(x):.4g}" for s, x in c.ratios.items()))
                for c in self.candidates
            ),
        )


def _job(search: Union[str, "os.PathLike[str]"], top: Optional[int], format: Optional[str]) -> Job:
    """The strings a search is built from: ``search`` is a file or the text of a search spec."""
    if top is not None:
        top = count(top, "top", 1_000_000)
    text = os.fspath(search)
    if "\n" not in text and Path(text).is_file():
        ins = search_inputs(path=text, format=format)
    else:
        ins = search_inputs(text=text, format=format)
    return (*ins, top)


# Worker-local state: each process prepares a search once and keeps it.
_PREPARED: Dict[Job, SearchCore] = {}


def _prepared(job: Job) -> SearchCore:
    core = _PREPARED.get(job)
    if core is None:
        text, fmt, source, base_text, base_fmt, base_source, top = job
        core = SearchCore(text, base_text, fmt, base_fmt, source, base_source, top)
        _PREPARED[job] = core
    return core


def _run_part(job: Job, part: int, parts: int, fail_once: Optional[str] = None) -> Dict[str, Any]:
    """One partition (a Dask task). ``fail_once``: a path; the first task
    that finds it missing creates it and kills its worker process (the test
    of a lost worker)."""
    if fail_once is not None and not os.path.exists(fail_once):
        open(fail_once, "w").close()
        os._exit(1)
    out: Dict[str, Any] = _prepared(job).run(part, parts)
    return out


def _candidate(core: SearchCore, rank: int, sets: Sequence[str], c: Mapping[str, Any]) -> Candidate:
    return Candidate(
        spec=core.candidate_spec(json.dumps(c)),
        rank=rank,
        score=c["score"],
        spread=c["spread"],
        sets={
            name: SetTeeth(
                t["sun"], t["ring"], t["planet"], Fraction(b), alt,
                t.get("sun2"), t.get("planet2"), None if b2 is None else Fraction(b2),
            )
            for name, t, b, b2, alt in zip(sets, c["teeth"], c["basic"], c["basic2"], c["alternatives"])
        },
        ratios={state: Fraction(exact) for state, _, exact in c["ratios"]},
        layout={e: tuple(links) for e, links in c.get("layout", [])},
        concept=c.get("concept"),
        same_ratio_teeth={name: tuple(ts) for name, ts in zip(sets, c.get("same_ratio_teeth", []))},
        efficiency=c.get("efficiency"),
        element_torque=c.get("element_torque"),
        mesh_torque=c.get("mesh_torque"),
        planet_speed=c.get("planet_speed"),
    )


def _merge(core: SearchCore, results: Sequence[Mapping[str, Any]], top: int, seconds: float) -> SynthResult:
    """Partitions' candidates ranked together and their counts summed, by the
    core (``design::merge``: score, then the sets' teeth)."""
    merged = core.merge(json.dumps(list(results)), top)
    found = merged["candidates"]
    stats: Dict[str, float] = dict(merged["stats"]) if results else {}
    sets = core.sets
    return SynthResult(
        candidates=tuple(_candidate(core, k + 1, sets, c) for k, c in enumerate(found)),
        stats=stats,
        seconds=seconds,
        partitions=len(results),
    )


def synth(
    search: Union[str, "os.PathLike[str]"],
    *,
    top: Optional[int] = None,
    part: Optional[Tuple[int, int]] = None,
    format: Optional[str] = None,
) -> SynthResult:
    """Run a design search on this machine (every core): ``search`` is a
    search-spec file (its ``base`` relative to it) or the spec's text (its
    ``base`` relative to the working directory). ``part=(i, k)`` runs one of
    k disjoint partitions, as ``egt synth --part i/k`` does."""
    job = _job(search, top, format)
    core = _prepared(job)
    i, k = part if part is not None else (0, 1)
    i, k = count(i, "part[0]", 2**63 - 1), count(k, "part[1]", 2**63 - 1)
    start = time.perf_counter()
    result = core.run(i, k)
    return _merge(core, [result], len(result["candidates"]), time.perf_counter() - start)


def synth_distributed(
    search: Union[str, "os.PathLike[str]"],
    *,
    client: Any = None,
    partitions: Optional[int] = None,
    top: Optional[int] = None,
    format: Optional[str] = None,
    _fail_once: Optional[str] = None,
) -> SynthResult:
    """The same search as :func:`synth`, split into ``partitions`` tasks on a
    Dask cluster: ``client`` (a ``dask.distributed.Client``), else an embedded
    ``LocalCluster`` (one single-threaded worker process per core) for the
    call. Each worker prepares the search once and keeps it; a task whose
    worker is lost is run again elsewhere, and each partition is counted
    once, so the result equals :func:`synth`'s. Needs
    ``pip install 'egt-gears[dask]'``."""
    _dask.require("synth_distributed")
    job = _job(search, top, format)
    core = _prepared(job)
    n = partitions if partitions is not None else min(core.max_partitions, 4 * (os.cpu_count() or 1))
    n = count(n, "partitions", 1_000_000)
    if n < 1:
        raise ArgumentError("partitions must be at least 1")

    def run(c: Any) -> SynthResult:
        start = time.perf_counter()
        futures = c.map(_run_part, [job] * n, range(n), [n] * n, [_fail_once] * n, retries=2, pure=False)
        results = c.gather(futures)
        return _merge(core, results, core.top, time.perf_counter() - start)

    return _dask.on_cluster(client, run)
