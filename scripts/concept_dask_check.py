"""The 8HP concept search split over a Dask LocalCluster (egt.synth_distributed's
default) gives the one-process candidates: issue 45's check, run by hand
(about 7 minutes on 2 cores; docs/synth.md has the figures).

    egt synth examples/synth/concept_zf_8hp.toml --format json > 8hp.json
    python scripts/concept_dask_check.py 8hp.json 8
"""
import json
import sys
import time

import egt


def main() -> None:
    spec = "examples/synth/concept_zf_8hp.toml"
    one = json.load(open(sys.argv[1]))
    t = time.perf_counter()
    dist = egt.synth_distributed(spec, partitions=int(sys.argv[2]))
    wall = time.perf_counter() - t
    print(f"partitions {dist.partitions}, wall {wall:.1f} s, stats {dist.stats}", flush=True)
    assert len(dist.candidates) == len(one["candidates"]), (len(dist.candidates), len(one["candidates"]))
    for d, o in zip(dist.candidates, one["candidates"]):
        assert d.score == o["score"], (d.score, o["score"])
        assert d.concept == o["concept"], (d.concept, o["concept"])
        assert [(e, list(links)) for e, links in d.layout.items()] == [(e, links) for e, links in o["layout"]]
        assert [(t.sun, t.ring, t.planet) for t in d.sets.values()] == [(s["sun"], s["ring"], s["planet"]) for s in o["sets"]]
        print(d.rank, d.score, d.concept["input"], d.concept["output"], [str(t.basic) for t in d.sets.values()])
    for k in ("structures", "structures_searched", "layouts", "skipped_layouts", "states_checked", "cut"):
        assert dist.stats.get(k, 0) == one["stats"].get(k, 0), (k, dist.stats.get(k), one["stats"].get(k))
    print("identical: candidates, structures, layouts, teeth, tooth options and the structure counts")


if __name__ == "__main__":
    main()
