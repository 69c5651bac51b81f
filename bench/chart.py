"""Draw the speed-accuracy chart and refresh the generated sections of the docs.

Reads OUT_DIR/rust.json (the `speed_accuracy` example), OUT_DIR/interpreted/rust.json
(the same example with EGT_JIT=0, if present) and OUT_DIR/python.json (bench/routes.py), writes the SVG chart (time per scenario against relative
error, one point per method and train size, and the flop floor), and replaces
the text between the `<!-- speed-accuracy:begin/end -->` markers of
docs/performance.md and between `<!-- sweeps:begin/end -->` of docs/accuracy.md.
No plotting library: the SVG is written directly, so the figure depends only
on the measurements. Run by `make chart`.
"""

from __future__ import annotations

import json
import math
import re
import sys
from typing import Any

WIDTH, HEIGHT = 960, 600
PANEL2 = 420  # height of the second panel (time against links), below the first
LEFT, RIGHT, TOP, BOTTOM = 80, 250, 50, 70
EXACT_LEVEL = 1e-18  # where an error of exactly 0 is drawn

SERIES = [
    # (key, label, colour, marker)
    ("egt LU", "egt (prepared, in-place LU)", "#d62728", "circle"),
    ("egt batch", "egt batch: 10 000 rows, 8 per SIMD group", "#7b0000", "circle"),
    ("egt program", "egt batch, condition bounds: straight-line program", "#ff9896", "circle"),
    ("egt columns", "egt program, column-major (run_columns)", "#e7969c", "circle"),
    ("egt columns, their outputs", "egt columns, the outputs SymPy and NumPy compute", "#c5b0d5", "circle"),
    ("egt LU + refinement", "egt LU + 1 refinement step", "#ff7f0e", "circle"),
    ("nalgebra LU", "nalgebra LU", "#1f77b4", "square"),
    ("faer LU", "faer LU", "#17becf", "square"),
    ("nalgebra QR", "nalgebra QR", "#9467bd", "diamond"),
    ("nalgebra SVD", "nalgebra SVD", "#8c564b", "diamond"),
    ("exact rationals", "exact rationals (Rust)", "#7f7f7f", "triangle"),
    ("numpy", "NumPy, one scenario at a time", "#2ca02c", "square"),
    ("numpy-batch", "NumPy, 10 000 scenarios stacked", "#98df8a", "square"),
    ("sympy", "SymPy: lambdify, one scenario at a time", "#e377c2", "triangle"),
    ("sympy-cse", "SymPy: lambdify(cse=True), one at a time", "#f7b6d2", "triangle"),
    ("sympy-cse-batch", "SymPy: lambdify(cse=True) over 10 000 scenarios", "#ad494a", "triangle"),
    ("sympy-subs", "SymPy: derive, subs/evalf", "#bcbd22", "triangle"),
    ("floor", "flop floor (this machine's rate)", "#000000", "ring"),
]


def points(rust: dict[str, Any], python: dict[str, Any]) -> dict[str, list[tuple[int, float, float]]]:
    out: dict[str, list[tuple[int, float, float]]] = {k: [] for k, *_ in SERIES}
    for size in rust["sizes"]:
        for m in size["methods"]:
            out[m["method"]].append((size["links"], m["seconds"], m["error"]))
        out["floor"].append((size["links"], size["floor_seconds"], 2.0**-53))
    for row in python["rows"]:
        if row["route"] in out and row["seconds"] is not None:
            out[row["route"]].append((row["links"], row["seconds"], row["error"]))
    return out


def svg(data: dict[str, list[tuple[int, float, float]]]) -> str:
    xs = [t for pts in data.values() for _, t, _ in pts]
    x0 = math.floor(math.log10(min(xs)))
    x1 = math.ceil(math.log10(max(xs)))
    y0, y1 = math.log10(EXACT_LEVEL), -11
    pw, ph = WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM

    def px(t: float) -> float:
        return LEFT + (math.log10(t) - x0) / (x1 - x0) * pw

    def py(e: float) -> float:
        e = max(e, EXACT_LEVEL)
        v = min(max(math.log10(e), y0), y1)
        return TOP + (y1 - v) / (y1 - y0) * ph

    s = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT + PANEL2}" viewBox="0 0 {WIDTH} {HEIGHT + PANEL2}" font-family="Helvetica, Arial, sans-serif" font-size="12">',
        f'<rect width="{WIDTH}" height="{HEIGHT + PANEL2}" fill="white"/>',
        f'<text x="{LEFT}" y="24" font-size="15" font-weight="bold">Time per scenario against relative error: inverse dynamics of planetary chains, 4 to 30 links</text>',
        f'<text x="{LEFT}" y="40" fill="#555">one point per method and train size (small labels: links); error = largest normwise relative error of speeds, accelerations, multipliers, input torque vs exact rationals</text>',
    ]
    for k in range(x0, x1 + 1):
        x = px(10.0**k)
        s.append(f'<line x1="{x:.1f}" y1="{TOP}" x2="{x:.1f}" y2="{TOP + ph}" stroke="#e5e5e5"/>')
        label = {-9: "1 ns", -8: "10 ns", -7: "100 ns", -6: "1 µs", -5: "10 µs", -4: "100 µs", -3: "1 ms", -2: "10 ms", -1: "100 ms", 0: "1 s", 1: "10 s"}.get(k, f"1e{k} s")
        s.append(f'<text x="{x:.1f}" y="{TOP + ph + 18}" text-anchor="middle">{label}</text>')
    for k in range(int(y0), y1 + 1):
        y = py(10.0**k)
        s.append(f'<line x1="{LEFT}" y1="{y:.1f}" x2="{LEFT + pw}" y2="{y:.1f}" stroke="#e5e5e5"/>')
        label = "exact (0)" if k == int(y0) else f"1e{k}"
        s.append(f'<text x="{LEFT - 8}" y="{y + 4:.1f}" text-anchor="end">{label}</text>')
    s.append(f'<rect x="{LEFT}" y="{TOP}" width="{pw}" height="{ph}" fill="none" stroke="#333"/>')
    s.append(f'<text x="{LEFT + pw / 2}" y="{HEIGHT - 22}" text-anchor="middle" font-size="13">time per scenario (log scale)</text>')
    s.append(f'<text transform="translate(22 {TOP + ph / 2}) rotate(-90)" text-anchor="middle" font-size="13">relative error (log scale)</text>')

    def marker(kind: str, x: float, y: float, colour: str) -> str:
        if kind == "circle":
            return f'<circle cx="{x:.1f}" cy="{y:.1f}" r="5" fill="{colour}"/>'
        if kind == "square":
            return f'<rect x="{x - 4.5:.1f}" y="{y - 4.5:.1f}" width="9" height="9" fill="{colour}"/>'
        if kind == "diamond":
            return f'<path d="M{x:.1f} {y - 6:.1f} L{x + 6:.1f} {y:.1f} L{x:.1f} {y + 6:.1f} L{x - 6:.1f} {y:.1f} Z" fill="{colour}"/>'
        if kind == "triangle":
            return f'<path d="M{x:.1f} {y - 6:.1f} L{x + 6:.1f} {y + 5:.1f} L{x - 6:.1f} {y + 5:.1f} Z" fill="{colour}"/>'
        return f'<circle cx="{x:.1f}" cy="{y:.1f}" r="5" fill="none" stroke="{colour}" stroke-width="1.5"/>'

    for key, label, colour, kind in SERIES:
        pts = sorted(data.get(key, []))
        if not pts:
            continue
        path = " ".join(f"{'M' if i == 0 else 'L'}{px(t):.1f} {py(e):.1f}" for i, (_, t, e) in enumerate(pts))
        s.append(f'<path d="{path}" fill="none" stroke="{colour}" stroke-width="1" opacity="0.6"/>')
        for links, t, e in pts:
            s.append(marker(kind, px(t), py(e), colour))
            if key in ("egt LU", "floor", "sympy", "numpy", "sympy-subs"):
                s.append(f'<text x="{px(t) + 6:.1f}" y="{py(e) - 6:.1f}" font-size="9" fill="{colour}">{links}</text>')
    # Panel B: the same times against the number of links.
    top2 = HEIGHT + 40
    ph2 = PANEL2 - 100
    ts = [t for pts in data.values() for _, t, _ in pts]
    t0, t1 = math.floor(math.log10(min(ts))), math.ceil(math.log10(max(ts)))
    lmax = max(links for pts in data.values() for links, _, _ in pts)

    def qx(links: float) -> float:
        return LEFT + links / (lmax + 2) * pw

    def qy(t: float) -> float:
        return top2 + (t1 - math.log10(t)) / (t1 - t0) * ph2

    s.append(f'<text x="{LEFT}" y="{top2 - 14}" font-size="15" font-weight="bold">Time per scenario against train size (same runs)</text>')
    for k in range(t0, t1 + 1):
        y = qy(10.0**k)
        s.append(f'<line x1="{LEFT}" y1="{y:.1f}" x2="{LEFT + pw}" y2="{y:.1f}" stroke="#e5e5e5"/>')
        label = {-9: "1 ns", -8: "10 ns", -7: "100 ns", -6: "1 µs", -5: "10 µs", -4: "100 µs", -3: "1 ms", -2: "10 ms", -1: "100 ms", 0: "1 s"}.get(k, f"1e{k} s")
        s.append(f'<text x="{LEFT - 8}" y="{y + 4:.1f}" text-anchor="end">{label}</text>')
    for links in range(0, lmax + 1, 5):
        x = qx(links)
        s.append(f'<line x1="{x:.1f}" y1="{top2}" x2="{x:.1f}" y2="{top2 + ph2}" stroke="#e5e5e5"/>')
        s.append(f'<text x="{x:.1f}" y="{top2 + ph2 + 18}" text-anchor="middle">{links}</text>')
    s.append(f'<rect x="{LEFT}" y="{top2}" width="{pw}" height="{ph2}" fill="none" stroke="#333"/>')
    s.append(f'<text x="{LEFT + pw / 2}" y="{top2 + ph2 + 40}" text-anchor="middle" font-size="13">links in the train</text>')
    s.append(f'<text transform="translate(22 {top2 + ph2 / 2}) rotate(-90)" text-anchor="middle" font-size="13">time per scenario (log scale)</text>')
    for key, label, colour, kind in SERIES:
        pts = sorted(data.get(key, []))
        if not pts:
            continue
        path = " ".join(f"{'M' if i == 0 else 'L'}{qx(n):.1f} {qy(t):.1f}" for i, (n, t, _) in enumerate(pts))
        s.append(f'<path d="{path}" fill="none" stroke="{colour}" stroke-width="1.2" opacity="0.8"/>')
        for n, t, _ in pts:
            s.append(marker(kind, qx(n), qy(t), colour))

    ly = TOP + 8
    for key, label, colour, kind in SERIES:
        if not data.get(key):
            continue
        s.append(marker(kind, WIDTH - RIGHT + 22, ly, colour))
        s.append(f'<text x="{WIDTH - RIGHT + 34}" y="{ly + 4}">{label}</text>')
        ly += 22
    s.append("</svg>")
    return "\n".join(s) + "\n"


def fmt_time(t: float | None) -> str:
    if t is None:
        return "–"
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("µs", 1e-6), ("ns", 1e-9)):
        if t >= scale:
            return f"{t / scale:.3g} {unit}"
    return f"{t * 1e9:.2g} ns"


def fmt_ratio(a: float | None, b: float | None) -> str:
    if a is None or b is None:
        return "–"
    r = a / b
    if r < 0.095:
        return f"{r:.2g}×"
    return f"{r:,.0f}×" if r >= 10 else f"{r:.1f}×"


def summary(rust: dict[str, Any], python: dict[str, Any], interpreted: dict[str, Any] | None) -> str:
    """The compact table of docs/performance.md: one scenario, the like-for-like batch kernel (compiled and, from a
    second run with EGT_JIT=0, interpreted), NumPy and SymPy batched, and SymPy's time over egt's."""

    def rust_time(run: dict[str, Any] | None, links: int, method: str) -> float | None:
        for size in (run or {}).get("sizes", []):
            if size["links"] == links:
                for m in size["methods"]:
                    if m["method"] == method:
                        return float(m["seconds"])
        return None

    def py_time(route: str, links: int) -> float | None:
        for r in python["rows"]:
            if r["route"] == route and r["links"] == links and r["seconds"] is not None:
                return float(r["seconds"])
        return None

    lines = [
        f"Host: flop rate {rust['flop_rate'] / 1e9:.1f} GFLOP/s on one core (a 384 × 384 matrix product); "
        f"NumPy {python['numpy']}, SymPy {python['sympy']}.",
        "",
        "| links | egt, one scenario | egt columns, their outputs (compiled, `jit`) | the same, interpreted (default build) "
        "| NumPy batched | SymPy CSE batched | SymPy CSE / egt compiled | SymPy CSE / egt interpreted |",
        "|---|---|---|---|---|---|---|---|",
    ]
    budget = {r["links"] for r in python["rows"] if r["route"] == "sympy-budget"}
    for size in rust["sizes"]:
        links = size["links"]
        compiled = rust_time(rust, links, "egt columns, their outputs")
        interp = rust_time(interpreted, links, "egt columns, their outputs")
        sympy = py_time("sympy-cse-batch", links)
        sympy_cell = fmt_time(sympy) if sympy is not None else (
            "(no derivation in 60 s)" if budget and links >= min(budget) else "–")
        lines.append(
            f"| {links} | {fmt_time(rust_time(rust, links, 'egt LU'))} | {fmt_time(compiled)} | {fmt_time(interp)} "
            f"| {fmt_time(py_time('numpy-batch', links))} | {sympy_cell} "
            f"| {fmt_ratio(sympy, compiled)} | {fmt_ratio(sympy, interp)} |"
        )
    return "\n".join(lines) + "\n"


def replace_section(path: str, marker: str, text: str) -> None:
    with open(path, encoding="utf-8") as fh:
        doc = fh.read()
    pattern = re.compile(rf"(<!-- {marker}:begin -->\n).*?(<!-- {marker}:end -->)", re.S)
    if not pattern.search(doc):
        raise SystemExit(f"{path}: no <!-- {marker}:begin/end --> markers")
    doc = pattern.sub(lambda m: m.group(1) + text + m.group(2), doc)
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(doc)


def main() -> None:
    out_dir = sys.argv[1] if len(sys.argv) > 1 else "target/speed_accuracy"
    chart = sys.argv[2] if len(sys.argv) > 2 else "docs/img/speed_accuracy.svg"
    with open(f"{out_dir}/rust.json", encoding="utf-8") as fh:
        rust = json.load(fh)
    with open(f"{out_dir}/python.json", encoding="utf-8") as fh:
        python = json.load(fh)
    data = points(rust, python)
    interpreted = None
    try:
        with open(f"{out_dir}/interpreted/rust.json", encoding="utf-8") as fh:
            interpreted = json.load(fh)
    except FileNotFoundError:
        print(f"{out_dir}/interpreted/rust.json: missing, so no interpreted column", file=sys.stderr)
    with open(chart, "w", encoding="utf-8") as fh:
        fh.write(svg(data))
    print(f"wrote {chart}", file=sys.stderr)
    if len(sys.argv) > 3:
        replace_section(sys.argv[3], "speed-accuracy", summary(rust, python, interpreted))
        print(f"updated {sys.argv[3]}", file=sys.stderr)
    if len(sys.argv) > 4:
        with open(f"{out_dir}/accuracy.md", encoding="utf-8") as fh:
            replace_section(sys.argv[4], "sweeps", fh.read())
        print(f"updated {sys.argv[4]}", file=sys.stderr)


if __name__ == "__main__":
    main()
