"""The Dask side of the distributed calls (:meth:`egt.BatchPlan.run_distributed`,
:func:`egt.synth_distributed`): the check that Dask is installed, and a call
run on the caller's client or else on an embedded ``LocalCluster``."""

from __future__ import annotations

import os
from typing import Any, Callable, TypeVar

T = TypeVar("T")


def require(what: str) -> None:
    """An ``ImportError`` naming ``what`` when Dask is not installed."""
    try:
        from dask.distributed import Client, LocalCluster  # noqa: F401
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError(f"{what} needs Dask: pip install 'egt-gears[dask]'") from e


def on_cluster(client: Any, run: Callable[[Any], T]) -> T:
    """``run(client)``; without a client, ``run`` on an embedded ``LocalCluster``
    (one single-threaded worker process per core) kept for the call."""
    if client is not None:
        return run(client)
    from dask.distributed import Client, LocalCluster

    with LocalCluster(  # type: ignore[no-untyped-call]
        n_workers=os.cpu_count() or 1, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, Client(cluster) as c:  # type: ignore[no-untyped-call]
        return run(c)
