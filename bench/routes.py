"""The same scenarios as the Rust study, by a computer-algebra route (SymPy,
as the paper did in Maple) and by a straightforward NumPy implementation,
each timed per scenario and compared with the exact rational solution.

Reads OUT_DIR/problems.json (written by the `speed_accuracy` example: the
prepared structure of each train, its parameter values and the exact solution)
and writes OUT_DIR/python.json. Run by `make chart`; see docs/performance.md (history: git log -p -- docs/benchmarks.md).

Routes:
  numpy        one scenario at a time: fill the matrices, np.linalg.solve x3
  numpy-batch  10 000 scenarios at once: stacked arrays, one batched solve each
  sympy        derive the solution symbolically once (LUsolve on symbols, as a
               computer-algebra user would), lambdify it, evaluate per scenario
  sympy-subs   the derived expressions evaluated by substitution (subs/evalf)
"""

from __future__ import annotations

import json
import signal
import sys
import time
from typing import Any, Callable

import numpy as np
import sympy as sp

# Stop deriving symbolically for larger trains once one size takes longer than
# this (seconds): the expressions grow much faster than the trains.
DERIVE_BUDGET = 10.0
# Substitution is slow: only for trains up to this many links.
SUBS_MAX_LINKS = 6
# Plain lambdify (no CSE) spends 24 s generating code at 10 links and grows
# far faster; it is timed up to here, the CSE routes beyond.
PLAIN_MAX_LINKS = 10
# Wall-clock limit on one size's derivation and code generation together.
HARD_BUDGET = 60.0
BATCH = 10_000


def per_call(f: Callable[[], Any], min_seconds: float = 0.05) -> float:
    """Seconds per call: batches of at least min_seconds, the fastest of five."""
    f()
    reps = 1
    while True:
        t = time.perf_counter()
        for _ in range(reps):
            f()
        if time.perf_counter() - t >= min_seconds or reps >= 1 << 22:
            break
        reps *= 2
    best = float("inf")
    for _ in range(5):
        t = time.perf_counter()
        for _ in range(reps):
            f()
        best = min(best, (time.perf_counter() - t) / reps)
    return best


def rel_error(x: np.ndarray, exact: np.ndarray) -> float:
    x = np.asarray(x, dtype=float)
    exact = np.asarray(exact, dtype=float)
    if x.size == 0:
        return 0.0
    if not np.all(np.isfinite(x)):
        return float("inf")
    scale = float(np.max(np.abs(exact)))
    diff = float(np.max(np.abs(x - exact)))
    return diff / scale if scale > 0 else diff


def error(sol: dict[str, np.ndarray], exact: dict[str, list[float]]) -> float:
    return max(rel_error(sol[k], exact[k]) for k in ("speeds", "accelerations", "multipliers", "torques"))


# --- NumPy, one scenario at a time ------------------------------------------


def numpy_matrices(st: dict[str, Any], c: int, v: dict[str, list[float]]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The speed, acceleration and force matrices (eq. 2, 8, 10) and [M] of one scenario."""
    n = st["n"]
    base = np.zeros((n, n))
    for m, cols in enumerate(st["circuits"]):
        t = v["ratios"][m]
        for col, coef in zip(cols, (1.0, -t, t - 1.0)):
            if col is not None:
                base[m, col] += coef
    c0 = len(st["circuits"])
    for e, row in enumerate(st["extras"]):
        for col, coef in row:
            if col is not None:
                base[c0 + e, col] += coef

    def with_rows(cols: list[int], value: float) -> np.ndarray:
        a = base.copy()
        for r, col in enumerate(cols):
            a[c + r, col] = value
        return a

    mass = np.zeros((n, n))
    for e in st["mass"]:
        if e["spin"] is not None:
            k = e["spin"]["column"]
            mass[k, k] += e["copies"] * v["inertia"][e["spin"]["slot"]]
        if e["float"] is not None:
            wgt = e["copies"] * v["mass"][e["float"]["slot"]]
            for a, da in e["float"]["terms"]:
                for bb, db in e["float"]["terms"]:
                    mass[a, bb] += wgt * da * db
    return with_rows(st["inputs"], 1.0), with_rows(st["accelerated"], 1.0), with_rows(st["driving"], -1.0).T, mass


def numpy_scenario(st: dict[str, Any], c: int, v: dict[str, list[float]]) -> dict[str, np.ndarray]:
    n = st["n"]
    aw, aa, ax, mass = numpy_matrices(st, c, v)
    b = np.zeros(n)
    b[c:] = v["speeds"]
    w = np.linalg.solve(aw, b)
    b = np.zeros(n)
    b[c:] = v["accelerations"]
    acc = np.linalg.solve(aa, b)
    r = np.asarray(v["torques"]) - mass @ acc
    x = np.linalg.solve(ax, r)
    return {"speeds": w, "accelerations": acc, "multipliers": x[:c], "torques": x[c:]}


# --- NumPy, many scenarios at once -------------------------------------------


def numpy_batch(st: dict[str, Any], c: int, v: dict[str, list[float]], count: int) -> dict[str, np.ndarray]:
    """The same job for `count` copies of the scenario, vectorised over scenarios."""
    n = st["n"]
    ratios = np.tile(np.asarray(v["ratios"]), (count, 1))
    base = np.zeros((count, n, n))
    for m, cols in enumerate(st["circuits"]):
        t = ratios[:, m]
        for col, coef in zip(cols, (np.ones(count), -t, t - 1.0)):
            if col is not None:
                base[:, m, col] += coef
    c0 = len(st["circuits"])
    for e, row in enumerate(st["extras"]):
        for col, coef in row:
            if col is not None:
                base[:, c0 + e, col] += coef

    def with_rows(cols: list[int], value: float) -> np.ndarray:
        a = base.copy()
        for r, col in enumerate(cols):
            a[:, c + r, col] = value
        return a

    b = np.zeros((count, n, 1))
    b[:, c:, 0] = v["speeds"]
    w = np.linalg.solve(with_rows(st["inputs"], 1.0), b)[..., 0]
    b = np.zeros((count, n, 1))
    b[:, c:, 0] = v["accelerations"]
    acc = np.linalg.solve(with_rows(st["accelerated"], 1.0), b)[..., 0]
    mass = np.zeros((count, n, n))
    for e in st["mass"]:
        if e["spin"] is not None:
            k = e["spin"]["column"]
            mass[:, k, k] += e["copies"] * v["inertia"][e["spin"]["slot"]]
        if e["float"] is not None:
            wgt = e["copies"] * v["mass"][e["float"]["slot"]]
            for a, da in e["float"]["terms"]:
                for bb, db in e["float"]["terms"]:
                    mass[:, a, bb] += wgt * da * db
    r = np.asarray(v["torques"])[None, :] - np.einsum("sij,sj->si", mass, acc)
    ft = np.swapaxes(with_rows(st["driving"], -1.0), 1, 2)
    x = np.linalg.solve(ft, r[..., None])[..., 0]
    return {"speeds": w[0], "accelerations": acc[0], "multipliers": x[0, :c], "torques": x[0, c:]}


# --- SymPy: derive once, evaluate per scenario --------------------------------


def sympy_derive(st: dict[str, Any], c: int, v: dict[str, list[float]]):
    """Symbolic solution of the three systems (eq. 2, 8, 10) in the parameters."""
    n = st["n"]
    g = len(st["circuits"])
    tau = sp.symbols(f"tau0:{g}")
    w_in = sp.symbols(f"w0:{len(st['inputs'])}")
    a_in = sp.symbols(f"a0:{len(st['accelerated'])}")
    q = sp.symbols(f"q0:{n}")
    inertia = sp.symbols(f"I0:{len(v['inertia'])}")
    masses = sp.symbols(f"m0:{len(v['mass'])}")
    base = sp.zeros(n, n)
    for m, cols in enumerate(st["circuits"]):
        for col, coef in zip(cols, (1, -tau[m], tau[m] - 1)):
            if col is not None:
                base[m, col] += coef
    c0 = len(st["circuits"])
    for e, row in enumerate(st["extras"]):
        for col, coef in row:
            if col is not None:
                base[c0 + e, col] += sp.nsimplify(coef)

    def with_rows(cols: list[int], value: int) -> sp.Matrix:
        a = base.copy()
        for r, col in enumerate(cols):
            a[c + r, col] = value
        return a

    bw = sp.Matrix([0] * c + list(w_in))
    ba = sp.Matrix([0] * c + list(a_in))
    w = with_rows(st["inputs"], 1).LUsolve(bw)
    acc = with_rows(st["accelerated"], 1).LUsolve(ba)
    mass = sp.zeros(n, n)
    for e in st["mass"]:
        copies = sp.nsimplify(e["copies"])
        if e["spin"] is not None:
            k = e["spin"]["column"]
            mass[k, k] += copies * inertia[e["spin"]["slot"]]
        if e["float"] is not None:
            wgt = copies * masses[e["float"]["slot"]]
            for a, da in e["float"]["terms"]:
                for bb, db in e["float"]["terms"]:
                    mass[a, bb] += wgt * sp.Float(da) * sp.Float(db)
    r = sp.Matrix(q) - mass * acc
    x = with_rows(st["driving"], -1).T.LUsolve(r)
    symbols = list(tau) + list(w_in) + list(a_in) + list(q) + list(inertia) + list(masses)
    exprs = list(w) + list(acc) + list(x)
    return symbols, exprs


class Budget(Exception):
    """SymPy's one-off work for one train size ran past the budget."""


def _alarm(signum: int, frame: Any) -> None:
    raise Budget()


def split(values: list[float], n: int, c: int) -> dict[str, np.ndarray]:
    vals = np.asarray(values, dtype=float)
    return {"speeds": vals[:n], "accelerations": vals[n : 2 * n], "multipliers": vals[2 * n : 2 * n + c], "torques": vals[2 * n + c :]}


def main() -> None:
    out_dir = sys.argv[1] if len(sys.argv) > 1 else "target/speed_accuracy"
    with open(f"{out_dir}/problems.json", encoding="utf-8") as fh:
        problems = json.load(fh)
    rows: list[dict[str, Any]] = []
    derive_ok = True
    for prob in problems:
        st, c, v, exact = prob["structure"], prob["constraints"], prob["values"], prob["exact"]
        links, n = prob["links"], st["n"]

        sol = numpy_scenario(st, c, v)
        secs = per_call(lambda: numpy_scenario(st, c, v))
        rows.append({"route": "numpy", "links": links, "seconds": secs, "error": error(sol, exact)})
        print(f"{links:>2} links  numpy          {secs * 1e6:10.3f} us  error {rows[-1]['error']:.1e}", file=sys.stderr)

        sol = numpy_batch(st, c, v, BATCH)
        secs = per_call(lambda: numpy_batch(st, c, v, BATCH), 0.2) / BATCH
        rows.append({"route": "numpy-batch", "links": links, "seconds": secs, "error": error(sol, exact)})
        print(f"{links:>2} links  numpy-batch    {secs * 1e6:10.3f} us  error {rows[-1]['error']:.1e}", file=sys.stderr)

        if not derive_ok:
            continue
        # Derivation (the symbolic solves) and code generation (lambdify) are
        # timed apart; the strongest SymPy route a good user writes is
        # lambdify with common-subexpression elimination, evaluated over
        # NumPy arrays of many scenarios at once.
        signal.signal(signal.SIGALRM, _alarm)
        signal.alarm(int(HARD_BUDGET))
        try:
            t0 = time.perf_counter()
            symbols, exprs = sympy_derive(st, c, v)
            derive = time.perf_counter() - t0
            plain = links <= PLAIN_MAX_LINKS
            t0 = time.perf_counter()
            f = sp.lambdify(symbols, exprs, "math") if plain else None
            codegen = time.perf_counter() - t0
            t0 = time.perf_counter()
            f_cse = sp.lambdify(symbols, exprs, "math", cse=True)
            codegen_cse = time.perf_counter() - t0
            t0 = time.perf_counter()
            f_vec = sp.lambdify(symbols, exprs, "numpy", cse=True)
            codegen_vec = time.perf_counter() - t0
        except Budget:
            derive_ok = False
            rows.append({"route": "sympy-budget", "links": links, "seconds": None, "error": None, "budget_seconds": HARD_BUDGET})
            print(f"sympy: {links} links did not derive and generate code within {HARD_BUDGET:.0f} s; stopping", file=sys.stderr)
            continue
        finally:
            signal.alarm(0)
        args = list(v["ratios"]) + list(v["speeds"]) + list(v["accelerations"]) + list(v["torques"]) + list(v["inertia"]) + list(v["mass"])
        if f is not None:
            sol = split(f(*args), n, c)
            secs = per_call(lambda: f(*args))
            rows.append({"route": "sympy", "links": links, "seconds": secs, "error": error(sol, exact),
                         "derive_seconds": derive, "codegen_seconds": codegen})
            print(f"{links:>2} links  sympy          {secs * 1e6:10.3f} us  error {rows[-1]['error']:.1e}  (derived in {derive:.2f} s, lambdify {codegen:.2f} s)", file=sys.stderr)
        else:
            rows.append({"route": "sympy-derive", "links": links, "seconds": None, "error": None, "derive_seconds": derive})
        sol = split(f_cse(*args), n, c)
        secs = per_call(lambda: f_cse(*args))
        rows.append({"route": "sympy-cse", "links": links, "seconds": secs, "error": error(sol, exact), "codegen_seconds": codegen_cse})
        print(f"{links:>2} links  sympy-cse      {secs * 1e6:10.3f} us  error {rows[-1]['error']:.1e}  (lambdify cse {codegen_cse:.2f} s)", file=sys.stderr)
        # BATCH scenarios at once: every argument an array; the first ratio
        # moves by one ulp per row (as egt's rows do), the rest repeat.
        batch_args = [np.full(BATCH, a, dtype=np.float64) for a in args]
        batch_args[0] = np.nextafter(batch_args[0], np.inf) if BATCH > 1 else batch_args[0]
        batch_args[0][::2] = args[0]
        out = f_vec(*batch_args)
        sol = split([np.asarray(o, dtype=np.float64).reshape(-1)[0] for o in out], n, c)
        secs = per_call(lambda: f_vec(*batch_args), 0.2) / BATCH
        rows.append({"route": "sympy-cse-batch", "links": links, "seconds": secs, "error": error(sol, exact), "codegen_seconds": codegen_vec})
        print(f"{links:>2} links  sympy-cse-batch{secs * 1e6:10.3f} us  error {rows[-1]['error']:.1e}  (lambdify numpy cse {codegen_vec:.2f} s)", file=sys.stderr)
        if links <= SUBS_MAX_LINKS:
            subs = dict(zip(symbols, [sp.Float(a, 17) for a in args]))

            def by_subs() -> list[float]:
                return [float(e.subs(subs).evalf(17)) for e in exprs]

            sol = split(by_subs(), n, c)
            secs = per_call(by_subs, 0.2)
            rows.append({"route": "sympy-subs", "links": links, "seconds": secs, "error": error(sol, exact)})
            print(f"{links:>2} links  sympy-subs     {secs * 1e6:10.3f} us  error {rows[-1]['error']:.1e}", file=sys.stderr)
        if derive + codegen_cse + codegen_vec > DERIVE_BUDGET:
            derive_ok = False
            print(f"sympy: stopping after {links} links (derivation and CSE code generation took {derive + codegen_cse + codegen_vec:.0f} s)", file=sys.stderr)
    with open(f"{out_dir}/python.json", "w", encoding="utf-8") as fh:
        json.dump({"numpy": np.__version__, "sympy": sp.__version__, "rows": rows}, fh, indent=1)
    print(f"wrote {out_dir}/python.json", file=sys.stderr)


if __name__ == "__main__":
    main()
