"""Throughput of the design search (issue 16), single process and on Dask.

    .venv/bin/python bench/synth.py

Prints, for the bundled searches and for a looser 8HP search (more leaves to
confirm exactly): tooth combinations covered, branch-and-bound nodes, leaves
(full ratio vectors) evaluated, candidates, wall time, and rates per core;
then the Dask overhead per task on a 2-worker LocalCluster (many partitions
of a search that costs almost nothing, minus the single-process time).
"""

from __future__ import annotations

import os
import statistics
import time
from pathlib import Path

import egt

ROOT = Path(__file__).resolve().parents[1]
ZF = ROOT / "examples" / "synth" / "zf_8hp70.toml"
C4 = ROOT / "examples" / "synth" / "ford_c4_simpson.toml"


def best_of(f, n: int = 5) -> tuple[float, object]:
    times, out = [], None
    for _ in range(n):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main() -> None:
    cores = os.cpu_count() or 1
    loose = ZF.read_text().replace("tolerance = 0.0005", "tolerance = 0.02").replace("top = 10", "top = 100000")
    loose = loose.replace('base = "../zf_8hp70.toml"', f'base = "{ROOT / "examples" / "zf_8hp70.toml"}"')
    print(f"{cores} cores; times are the best of 5 runs")
    print("search | tooth combinations | nodes | leaves | candidates | time | leaves/s/core")
    synth = ROOT / "examples" / "synth"
    for name, search in [
        ("8HP, 3 decimals", ZF),
        ("C4 Simpson", C4),
        ("8HP, tolerance 0.02", loose),
        ("6HP26 Lepelletier (Ravigneaux)", synth / "zf_6hp26_lepelletier.toml"),
        ("AOD Ravigneaux", synth / "ford_aod_ravigneaux.toml"),
        ("8HP, all 5 element positions free too", synth / "zf_8hp70_layout.toml"),
    ]:
        secs, r = best_of(lambda: egt.synth(search))
        s = r.stats
        print(f"{name} | {s['tooth_space']:.3g} | {s['nodes']:.0f} | {s['leaves']:.0f} | {len(r.candidates)} "
              f"| {secs * 1e3:.1f} ms | {s['leaves'] / secs / cores:.3g}")
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, Client(cluster) as client:
        egt.synth_distributed(C4, client=client, partitions=2)  # warm the workers (import, prepare)
        single, _ = best_of(lambda: egt.synth(C4))
        for parts in (8, 64, 256):
            runs = []
            for _ in range(3):
                t0 = time.perf_counter()
                egt.synth_distributed(C4, client=client, partitions=parts)
                runs.append(time.perf_counter() - t0)
            t = statistics.median(runs)
            print(f"Dask, 2 workers, {parts} partitions of the C4 search: {t * 1e3:.1f} ms, "
                  f"{(t - single) / parts * 1e3:.2f} ms per task over the single-process {single * 1e3:.1f} ms")


if __name__ == "__main__":
    main()
