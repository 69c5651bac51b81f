"""Batch vs a Python loop of single calls, on the paper's Fig. 3 train.

Run from the repository root after `make python-dev`:

    .venv/bin/python crates/egt-py/bench/bench_batch.py [--rows N] [--loop-rows N]

Prints one Markdown table (the one in docs/python.md). The loop is timed on
`--loop-rows` scenarios and reported per row; the batch on `--rows`.
Timings are wall-clock medians of several repeats on a shared machine: read
them as orders of magnitude.
"""

from __future__ import annotations

import argparse
import os
import pathlib
import platform
import statistics
import time
from typing import Callable, List, Optional, Tuple

import numpy as np

import egt

ROOT = pathlib.Path(__file__).resolve().parents[3]
SPEC = ROOT / "examples" / "fig3_example61.toml"


def best_of(f: Callable[[], object], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", type=int, default=1_000_000)
    ap.add_argument("--loop-rows", type=int, default=5_000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    rng = np.random.default_rng(1)
    train = egt.load(SPEC)
    n, m = args.rows, args.loop_rows

    speeds = rng.uniform(10, 300, n)
    loads = rng.uniform(-80, -10, n)
    alpha = rng.uniform(-20, 20, n)
    zs = rng.integers(18, 60, size=(n, 2, 2))
    spec_text = SPEC.read_text()

    def teeth_loop() -> None:
        for r in range(m):
            z = zs[r]
            s = spec_text.replace("teeth = [30, 20]", f"teeth = [{z[0, 0]}, {z[0, 1]}]").replace(
                "teeth = [18, 32]", f"teeth = [{z[1, 0]}, {z[1, 1]}]"
            )
            try:
                egt.loads(s).kinematics({"2": float(speeds[r])})
            except egt.EgtError:
                pass

    kin = train.batch("kinematics")
    kin_params, _ = kin.params({"speed.2": speeds})
    dyn = train.batch("dynamics")
    dyn_params, _ = dyn.params({"accel.4": alpha, "torque.4": loads})
    kin_teeth_params, _ = kin.params({"speed.2": speeds}, teeth=zs)

    cases: List[Tuple[str, Callable[[], object], Callable[[Optional[int]], object], egt.BatchPlan, np.ndarray]] = [
        (
            "kinematics, input speed varies",
            lambda: [train.kinematics({"2": float(v)}) for v in speeds[:m]],
            lambda th: train.batch_kinematics({"2": speeds}, threads=th),
            kin,
            kin_params,
        ),
        (
            "inverse dynamics, load and acceleration vary",
            lambda: [
                train.dynamics(torques={"4": float(t)}, accelerations={"4": float(a)}, driving=["2"])
                for t, a in zip(loads[:m], alpha[:m])
            ],
            lambda th: train.batch_dynamics(["2"], torques={"4": loads}, accelerations={"4": alpha}, threads=th),
            dyn,
            dyn_params,
        ),
        (
            "kinematics, tooth counts vary (the loop rebuilds the train)",
            teeth_loop,
            lambda th: train.batch_kinematics({"2": speeds}, teeth=zs, threads=th),
            kin,
            kin_teeth_params,
        ),
    ]
    print(f"Fig. 3 train, {n} batch rows, loop timed on {m} rows; "
          f"{platform.python_implementation()} {platform.python_version()}, "
          f"{os.cpu_count()} CPUs, egt {egt.__version__}\n")
    print("| scenario | Python loop of single calls | `batch_*` (all threads) | `BatchPlan.run`, 1 thread | `BatchPlan.run`, all threads | speed-up, `batch_*` | speed-up, `run` |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for name, loop, wrapper, plan, params in cases:
        t_loop = best_of(loop, max(1, args.repeats // 2)) / m
        wrapper(None)  # warm up
        tw = best_of(lambda: wrapper(None), args.repeats) / n
        t1 = best_of(lambda: plan.run(params, threads=1), args.repeats) / n
        tn = best_of(lambda: plan.run(params), args.repeats) / n
        us = lambda t: f"{t * 1e6:.3g} µs"  # noqa: E731
        print(f"| {name} | {us(t_loop)} | {us(tw)} | {us(t1)} | {us(tn)} | {t_loop / tw:.0f}x | {t_loop / tn:.0f}x |")


if __name__ == "__main__":
    main()
