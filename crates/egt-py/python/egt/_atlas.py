"""``egt.atlas``: the atlas of non-isomorphic gear-train graphs (docs/atlas.md),
its integer arguments checked here so that a negative or huge one is an
:class:`egt.ArgumentError`, never Python's ``OverflowError``; and
``egt.atlas_distributed``, the same atlas as disjoint parts on a Dask cluster."""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Tuple

from . import _dask
from ._args import ArgumentError, count
from ._egt import atlas as _atlas

_MAX = 2**63 - 1


def atlas(
    links: int,
    dof: int = 1,
    level: str = "rotation",
    part: Optional[Tuple[int, int]] = None,
    fractionation: str = "layout",
    search: str = "trees",
) -> List[Dict[str, Any]]:
    """Every member with ``links`` links and ``dof`` DOF at ``level``
    (``"rotation"`` or ``"displacement"``), as dicts (adjacency, links, dof,
    gears, carriers, axes, ...); ``part=(i, k)`` gives one of ``k`` disjoint
    parts, as ``egt enumerate --part i/k`` does. ``search="levels"`` finds
    the same atlas levels first (``egt enumerate --search levels``: faster
    from 9 links on; its parts split the displacement level only)."""
    if part is not None:
        i, k = part
        part = (count(i, "part[0]", _MAX), count(k, "part[1]", _MAX))
    return _atlas(count(links, "links", _MAX), count(dof, "dof", _MAX), level, part, fractionation, search)


def _part(
    links: int, dof: int, level: str, i: int, k: int, fractionation: str, search: str
) -> List[Dict[str, Any]]:
    """One part on a worker."""
    return _atlas(links, dof, level, (i, k), fractionation, search)


def atlas_distributed(
    links: int,
    dof: int = 1,
    level: str = "rotation",
    *,
    parts: Optional[int] = None,
    client: Any = None,
    fractionation: str = "layout",
    search: str = "trees",
) -> List[Dict[str, Any]]:
    """The same atlas as :func:`atlas`, as ``parts`` disjoint parts (``egt
    enumerate --part i/k``) run as tasks on a Dask cluster: ``client`` (a
    ``dask.distributed.Client``), else an embedded ``LocalCluster`` (one
    single-threaded worker process per core) for the call. The parts are
    concatenated, so the members are :func:`atlas`'s, each once (a
    task whose worker is lost runs again; an argument egt refuses raises the
    same error as :func:`atlas`), part after part (an order that may differ
    from :func:`atlas`'s). ``parts`` defaults to four per core. Needs ``pip install 'egt-gears[dask]'``."""
    _dask.require("atlas_distributed")
    links, dof = count(links, "links", _MAX), count(dof, "dof", _MAX)
    n = count(parts if parts is not None else 4 * (os.cpu_count() or 1), "parts", 1_000_000)
    if n < 1:
        raise ArgumentError("parts must be at least 1")

    def run(c: Any) -> List[Dict[str, Any]]:
        futures = c.map(_part, [links] * n, [dof] * n, [level] * n, range(n), [n] * n, [fractionation] * n,
                        [search] * n, retries=2, pure=False)
        return [m for part in c.gather(futures) for m in part]

    return _dask.on_cluster(client, run)
