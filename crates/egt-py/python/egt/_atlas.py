"""``egt.atlas``: the atlas of non-isomorphic gear-train graphs (docs/atlas.md),
its integer arguments checked here so that a negative or huge one is an
:class:`egt.ArgumentError`, never Python's ``OverflowError``."""

from __future__ import annotations

from typing import Any, Dict, List, Optional, Tuple

from ._args import count
from ._egt import atlas as _atlas

_MAX = 2**63 - 1


def atlas(
    links: int,
    dof: int = 1,
    level: str = "rotation",
    part: Optional[Tuple[int, int]] = None,
    fractionation: str = "layout",
) -> List[Dict[str, Any]]:
    """Every member with ``links`` links and ``dof`` DOF at ``level``
    (``"rotation"`` or ``"displacement"``), as dicts (adjacency, links, dof,
    gears, carriers, axes, ...); ``part=(i, k)`` gives one of ``k`` disjoint
    parts, as ``egt enumerate --part i/k`` does."""
    if part is not None:
        i, k = part
        part = (count(i, "part[0]", _MAX), count(k, "part[1]", _MAX))
    return _atlas(count(links, "links", _MAX), count(dof, "dof", _MAX), level, part, fractionation)
