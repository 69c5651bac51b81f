"""A load sweep (issue 13): 10 000 scenarios of one train whose ratios,
inertias and masses are fixed and whose input speed, prescribed acceleration
and applied torques vary, by the strongest Python routes:

  sympy-cse-batch   the symbolic solution (bench/routes.py's derivation),
                    lambdify(..., "numpy", cse=True), fixed parameters passed
                    as scalars (so CSE folds them once) and the varying ones
                    as arrays of 10 000
  numpy-multi-rhs   the three systems built once and solved for all 10 000
                    right-hand sides in one np.linalg.solve each

Reads target/speed_accuracy/problems.json (`make chart` writes it) and prints
ns per scenario per route and train size, on one thread (OMP/OpenBLAS
threads set to 1). Compare with `cargo bench -p egt-core --bench scenarios --
chain::sweep_loads` (docs/performance.md (history: git log -p -- docs/benchmarks.md)).

    OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 .venv/bin/python bench/sweep.py
"""

from __future__ import annotations

import json
import sys

import numpy as np
import sympy as sp

sys.path.insert(0, "bench")
from routes import numpy_matrices, per_call, sympy_derive  # noqa: E402

BATCH = 10_000


def main() -> None:
    out_dir = sys.argv[1] if len(sys.argv) > 1 else "target/speed_accuracy"
    problems = json.load(open(f"{out_dir}/problems.json", encoding="utf-8"))
    rng = np.random.default_rng(1)
    for prob in problems:
        st, c, v, links = prob["structure"], prob["constraints"], prob["values"], prob["links"]
        if links > 16:
            break
        symbols, exprs = sympy_derive(st, c, v)
        f = sp.lambdify(symbols, exprs, "numpy", cse=True)
        fixed = {"ratios": v["ratios"], "inertia": v["inertia"], "mass": v["mass"]}
        args: list = []
        for key in ["ratios", "speeds", "accelerations", "torques", "inertia", "mass"]:
            for x in v[key]:
                args.append(float(x) if key in fixed else x + rng.standard_normal(BATCH))
        secs = per_call(lambda: f(*args), 0.2) / BATCH
        print(f"{links:>2} links  sympy-cse-batch (load sweep)   {secs * 1e9:8.1f} ns per scenario")

        # NumPy: the matrices once, every right-hand side in one solve.
        n = st["n"]
        aw, aa, ax, mass = numpy_matrices(st, c, v)
        w_in = np.stack([x + rng.standard_normal(BATCH) for x in v["speeds"]])
        a_in = np.stack([x + rng.standard_normal(BATCH) for x in v["accelerations"]])
        torques = np.stack([x + rng.standard_normal(BATCH) for x in v["torques"]])

        def multi_rhs() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            bw = np.zeros((n, BATCH)); bw[c:] = w_in
            ba = np.zeros((n, BATCH)); ba[c:] = a_in
            w = np.linalg.solve(aw, bw)
            acc = np.linalg.solve(aa, ba)
            x = np.linalg.solve(ax, torques - mass @ acc)
            return w, acc, x

        secs = per_call(multi_rhs, 0.2) / BATCH
        print(f"{links:>2} links  numpy-multi-rhs (load sweep)   {secs * 1e9:8.1f} ns per scenario")


if __name__ == "__main__":
    main()
