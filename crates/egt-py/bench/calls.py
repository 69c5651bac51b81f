"""Time of one Python batch call, by rows and threads: `BatchPlan.run` on the
6-link chain (dynamics with condition bounds, C-ordered rows, one load per
row), with `threads=1` (the calling thread) and the default (the shared
pool). Prints microseconds a call and nanoseconds a row, best of 5.

Usage (after `make python-dev`, with the chart's train written by `make chart`):
    .venv/bin/python crates/egt-py/bench/calls.py target/speed_accuracy/planetary_chain_6.toml
See docs/performance.md (history: git log -p -- docs/benchmarks.md), "Python's threads=1 on the calling thread".
"""

from __future__ import annotations

import sys
import time

import numpy as np

import egt


def main(path: str) -> None:
    plan = egt.Train.from_file(path).batch("dynamics", condition_bounds=True)
    rng = np.random.default_rng(1)
    load = plan.column("torque.c2")
    for rows in (64, 256, 1024, 10_000):
        params = np.tile(plan.base, (rows, 1))
        params[:, load] = rng.uniform(-100.0, -10.0, rows)
        params = np.ascontiguousarray(params)
        for threads in (1, None):
            plan.run(params, threads=threads)
            calls = max(20, 200_000 // rows)
            best = float("inf")
            for _ in range(5):
                start = time.perf_counter()
                for _ in range(calls):
                    plan.run(params, threads=threads)
                best = min(best, (time.perf_counter() - start) / calls)
            print(
                f"rows {rows:6d} threads {str(threads):4s} "
                f"{best * 1e6:9.1f} us a call {best / rows * 1e9:8.1f} ns a row"
            )


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "target/speed_accuracy/planetary_chain_6.toml")
