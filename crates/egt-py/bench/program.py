"""Time of the batch's straight-line program from Python, by rows and layout:
`BatchPlan.run(params, threads=1)` on the 6-link chain (dynamics with
condition bounds), a new sun-planet ratio in every row, the matrix C- or
Fortran-ordered, or no matrix: `plan.run({"ratio.P1/sun-planet": r})`, the
other columns at the base row's values. Prints how rows are solved (`plan.program`: "compiled"
or "interpreted"), microseconds a call and nanoseconds a row, best
of 5. Run it with `EGT_JIT=avx2` or `EGT_JIT=0` in the environment to time
the AVX2 code or the interpreter on the same machine.

Usage (after `make python-dev`, with the chart's train written by `make chart`):
    .venv/bin/python crates/egt-py/bench/program.py target/speed_accuracy/planetary_chain_6.toml
See docs/performance.md (history: git log -p -- docs/benchmarks.md), "AVX2 code, the program by default in Python".
"""

from __future__ import annotations

import sys
import time

import numpy as np

import egt


def main(path: str) -> None:
    plan = egt.Train.from_file(path).batch("dynamics", condition_bounds=True)
    rng = np.random.default_rng(1)
    ratio = plan.column("ratio.P1/sun-planet")
    for rows in (1024, 10_000, 100_000):
        column = rng.uniform(-0.9, -0.5, rows)
        for order in ("C", "F", "mapping"):
            if order == "mapping":
                params = {"ratio.P1/sun-planet": column}
            else:
                params = np.tile(plan.base, (rows, 1))
                params[:, ratio] = column
                params = np.asarray(params, order=order)
            plan.run(params, threads=1)
            calls = max(5, 200_000 // rows)
            best = float("inf")
            for _ in range(5):
                start = time.perf_counter()
                for _ in range(calls):
                    plan.run(params, threads=1)
                best = min(best, (time.perf_counter() - start) / calls)
            print(
                f"{plan.program or 'no program'}: {rows:6d} rows, "
                f"{order + '-ordered' if order != 'mapping' else 'a mapping'}: "
                f"{best * 1e6:9.1f} us a call, {best / rows * 1e9:6.1f} ns a row"
            )


if __name__ == "__main__":
    main(sys.argv[1])
