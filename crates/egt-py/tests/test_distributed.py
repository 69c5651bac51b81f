"""Dask scale-out (issues 16, 46): the design search's partitions, a batch's
row chunks and the atlas's parts as tasks on a 2-worker LocalCluster give
exactly the single-process results, also when a worker dies mid-run; plans
and trains pickle to the workers through their specs."""

from __future__ import annotations

import os
import pickle
from pathlib import Path
from typing import Iterator

import numpy as np
import pytest

import egt

import dask.distributed as distributed

ROOT = Path(__file__).resolve().parents[3]
C4 = ROOT / "examples" / "synth" / "ford_c4_simpson.toml"


@pytest.fixture(scope="module")
def client() -> Iterator[object]:
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as c:
            yield c


def key(r: egt.SynthResult) -> list:
    return [(c.score, [(t.sun, t.ring, t.planet) for t in c.sets.values()]) for c in r.candidates]


def test_synth_distributed_equals_single_process_even_when_a_worker_dies(client: object, tmp_path: Path) -> None:
    single = egt.synth(C4, top=50)
    dist = egt.synth_distributed(C4, client=client, partitions=8, top=50)
    assert dist.partitions == 8
    assert key(dist) == key(single)
    assert dist.stats["leaves"] == single.stats["leaves"]
    # One task kills its worker on the way; the partition runs again and
    # nothing is lost or counted twice.
    marker = str(tmp_path / "died")
    again = egt.synth_distributed(C4, client=client, partitions=8, top=50, _fail_once=marker)
    assert os.path.exists(marker)
    assert key(again) == key(single)
    assert again.stats["leaves"] == single.stats["leaves"]


def concept_key(r: egt.SynthResult) -> list:
    return [(c.score, c.concept["structure"] if c.concept else None, sorted(c.layout.items()),
             [(t.sun, t.ring) for t in c.sets.values()],
             c.concept.get("tooth_options") if c.concept else None) for c in r.candidates]


def test_a_concept_search_over_dask_equals_one_process(client: object) -> None:
    """The concept search's structures split into tasks (structure i in part
    i mod K) give the one-process candidates, structures, layouts and tooth
    options included."""
    spec = ROOT / "examples" / "synth" / "concept_ford_c4.toml"
    single = egt.synth(spec, top=30)
    dist = egt.synth_distributed(spec, client=client, partitions=7, top=30)
    assert dist.partitions == 7
    assert concept_key(dist) == concept_key(single)
    assert dist.stats["structures"] == single.stats["structures"] > 100
    assert dist.stats["structures_searched"] == single.stats["structures_searched"]
    best = single.candidates[0]
    assert best.concept is not None and best.concept["output"]
    assert best.concept["tooth_options"], "the best concept lists its other teeth"
    # The candidate's train is egt's, with the ratios reported.
    table = best.train().shift_table()
    assert {g.state: g.ratio_exact for g in table.gears} == best.ratios


def test_batch_monte_carlo_over_tooth_tolerances_runs_distributed(fig3: egt.Train, client: object) -> None:
    plan = fig3.batch("dynamics")
    rng = np.random.default_rng(7)
    base = np.array([[30, 20], [18, 32]])
    teeth = base[None, :, :] + rng.integers(-2, 3, size=(3000, 2, 2))
    teeth[5, 0, 0] = 0  # a refused row keeps its global number
    params = plan.params(teeth=teeth)
    local = plan.run(params)
    dist = plan.run_distributed(params, client=client, chunks=7)
    np.testing.assert_array_equal(dist.values, local.values)
    np.testing.assert_array_equal(dist.ok, local.ok)
    assert sorted(dist.errors) == sorted(local.errors) and 5 in dist.errors
    assert all(dist.errors[r].kind == local.errors[r].kind for r in local.errors)
    # The plan pickles through its train's spec and the batch arguments.
    again = pickle.loads(pickle.dumps(plan))
    np.testing.assert_array_equal(again.run(params[0][:10]).values, local.values[:10])


@pytest.mark.parametrize("links, level", [(7, "rotation"), (8, "displacement")])
def test_the_atlas_in_parts_on_a_cluster_is_the_single_process_atlas(client: object, links: int,
                                                                    level: str) -> None:
    """Issue 46: 7 parts (not a divisor of anything in particular) over two
    workers give every member once (8 links displacement: the published
    6 360)."""
    one = egt.atlas(links, level=level)
    parts = egt.atlas_distributed(links, level=level, parts=7, client=client)
    assert sorted(m["code"] for m in parts) == sorted(m["code"] for m in one)
    assert len({m["code"] for m in parts}) == len(one) == {(7, "rotation"): 152, (8, "displacement"): 6360}[
        (links, level)]
    with pytest.raises(egt.SpecError, match="level"):
        egt.atlas_distributed(6, level="other", parts=2, client=client)


def test_the_levels_first_atlas_in_parts_on_a_cluster_is_the_tree_first_atlas(client: object) -> None:
    """Issue 46: the levels-first search (`egt enumerate --search levels`)
    split over two workers gives the tree-first atlas at the displacement
    level, each member once; its parts cannot split rotation graphs."""
    one = egt.atlas(8, level="displacement")
    parts = egt.atlas_distributed(8, level="displacement", parts=7, client=client, search="levels")
    assert sorted(m["code"] for m in parts) == sorted(m["code"] for m in one)
    assert len(parts) == 6360
    # one process, rotation level: the same rotation graphs and counts
    assert sorted((m["code"], m["displacement_graphs"]) for m in egt.atlas(7, search="levels")) == sorted(
        (m["code"], m["displacement_graphs"]) for m in egt.atlas(7))
    with pytest.raises(egt.SpecError, match="part"):
        egt.atlas(7, part=(0, 2), search="levels")
    with pytest.raises(egt.SpecError, match="search"):
        egt.atlas(7, search="other")
