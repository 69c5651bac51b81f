#!/usr/bin/env python3
"""Check the layering of the workspace: egt-core's layers, the CLI's
commands, and the bindings.

1. No module of egt-core imports a layer above its own.
2. No command of egt-cli (`commands/X.rs`, `commands/X/...`) imports another
   command or `cli.rs`: `cli.rs` owns the grammar and the dispatch, the
   commands share only `args`, `input`, `report`, `svg`, `interrupt` and
   `progress`.
3. The Python bindings (egt-py) use the CLI only through `egt_cli::run` (the
   wheel's `egt` command); the documents they return come from egt-views.
4. egt-views (the JSON documents) depends on egt-core only.
5. egt-fmu (the FMI boundary) depends on egt-core only, and its `unsafe`
   is in `ffi.rs` alone.
6. The Python package's modules import each other without a cycle at run
   time (imports under `if TYPE_CHECKING:` are for annotations only).

The layers of `crates/egt-core/src`, bottom to top (ARCHITECTURE.md):

    error -> numerics -> spec -> model -> solve -> analysis -> motion -> top
                                                       (batch, design, synthesis)

Every `crate::...` path in non-test code is resolved to the module it names
(names re-exported at the crate root are looked up in lib.rs) and compared with
the layer of the file that writes it. Doc comments are not imports and are
skipped; so are `#[cfg(test)]` modules, which may build whole trains.

Exit 0 when every reference runs down or sideways, 1 with a list otherwise.
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SRC = ROOT / "crates" / "egt-core" / "src"
CLI = ROOT / "crates" / "egt-cli" / "src"
PY = ROOT / "crates" / "egt-py" / "src"
VIEWS = ROOT / "crates" / "egt-views" / "src"
FMU = ROOT / "crates" / "egt-fmu" / "src"
PYPKG = ROOT / "crates" / "egt-py" / "python" / "egt"

LAYERS = {
    "error": 0,
    "numerics": 1,
    "spec": 2,
    "model": 3,
    "solve": 4,
    "analysis": 5,
    "motion": 6,
    "batch": 7,
    "design": 7,
    "synthesis": 7,
    "accuracy": 7,
    "families": 7,
}


def layer_of_file(path: Path) -> tuple[str, int] | None:
    top = path.relative_to(SRC).parts[0].removesuffix(".rs")
    if top == "lib":
        return None
    if top not in LAYERS:
        raise SystemExit(f"layers.py: {path} is in no layer; add `{top}` to LAYERS")
    return top, LAYERS[top]


def root_exports(lib: str) -> dict[str, str]:
    """Name re-exported at the crate root -> the top module it comes from."""
    exports: dict[str, str] = {}
    for m in re.finditer(r"pub use (\w+)::([^;]*);", lib):
        module, rest = m.group(1), m.group(2)
        for name in re.findall(r"\b([A-Za-z_]\w*)\b", rest):
            exports.setdefault(name, module)
    return exports


def code_lines(text: str):
    """(line number, code) of non-comment lines outside #[cfg(test)] modules."""
    in_test = False
    depth = 0
    for n, line in enumerate(text.splitlines(), 1):
        stripped = line.strip()
        if stripped.startswith("//"):
            continue
        if not in_test and stripped.startswith("#[cfg(test)]"):
            in_test, depth = True, 0
            continue
        if in_test:
            depth += line.count("{") - line.count("}")
            if depth <= 0 and "}" in line:
                in_test = False
            continue
        yield n, line


def cli_problems() -> list[str]:
    """Commands that import another command or the grammar (`cli.rs`)."""
    commands_dir = CLI / "commands"
    names = {p.stem for p in commands_dir.iterdir() if p.suffix == ".rs" and p.stem != "mod"}
    names |= {p.name for p in commands_dir.iterdir() if p.is_dir()}
    bad = []
    for path in sorted(commands_dir.rglob("*.rs")):
        if path.name == "tests.rs" or path.name.endswith("_tests.rs"):
            continue  # test modules may parse whole command lines
        rel = path.relative_to(commands_dir)
        own = rel.parts[0].removesuffix(".rs")
        depth = len(rel.parts) - 1  # 0 for commands/X.rs, 1 for commands/X/Y.rs
        for n, line in code_lines(path.read_text()):
            where = f"egt-cli/src/commands/{rel}:{n}"
            if re.search(r"\bcrate::cli\b", line):
                bad.append(f"{where}: a command imports cli.rs: {line.strip()}")
            for m in re.finditer(r"\bcrate::commands::(\w+)", line):
                if m.group(1) != own:
                    bad.append(f"{where}: command `{own}` imports command `{m.group(1)}`")
            up = r"\bsuper::" + r"super::" * depth + r"(\w+)"
            for m in re.finditer(up, line):
                if m.group(1) in names and m.group(1) != own:
                    bad.append(f"{where}: command `{own}` imports command `{m.group(1)}`")
    return bad


def bindings_problems() -> list[str]:
    """Bindings that reach into the CLI beyond its entry point, and views
    that depend on a front end."""
    bad = []
    for path in sorted(PY.rglob("*.rs")):
        for n, line in code_lines(path.read_text()):
            for m in re.finditer(r"\begt_cli::(\w+)", line):
                if m.group(1) != "run":
                    bad.append(
                        f"egt-py/src/{path.relative_to(PY)}:{n}: the bindings use "
                        f"egt_cli::{m.group(1)} (only egt_cli::run is theirs)"
                    )
    for path in sorted(VIEWS.rglob("*.rs")):
        for n, line in code_lines(path.read_text()):
            if re.search(r"\b(egt_cli|egt_py|pyo3|clap)\b", line):
                bad.append(f"egt-views/src/{path.relative_to(VIEWS)}:{n}: depends on a front end")
    return bad


def fmu_problems() -> list[str]:
    """egt-fmu reaching past egt-core, or `unsafe` outside its ffi.rs."""
    bad = []
    for path in sorted(FMU.rglob("*.rs")):
        for n, line in code_lines(path.read_text()):
            where = f"egt-fmu/src/{path.relative_to(FMU)}:{n}"
            if re.search(r"\b(egt_cli|egt_py|egt_views|pyo3|clap)\b", line):
                bad.append(f"{where}: the FMI boundary depends on more than egt-core")
            if re.search(r"\bunsafe\b", line) and path.name != "ffi.rs":
                bad.append(f"{where}: `unsafe` outside ffi.rs")
    return bad


def python_cycles() -> list[str]:
    """Cycles among the package's modules through run-time imports
    (module level or inside functions; `if TYPE_CHECKING:` blocks aside)."""
    modules = {p.stem: p for p in PYPKG.glob("*.py")}
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for name, path in modules.items():
        tree = ast.parse(path.read_text())
        typing_only = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.If) and getattr(node.test, "id", None) == "TYPE_CHECKING":
                typing_only |= {id(n) for n in ast.walk(node)}
        for node in ast.walk(tree):
            if id(node) in typing_only or not isinstance(node, ast.ImportFrom) or node.level != 1:
                continue
            targets = [node.module] if node.module else [a.name for a in node.names]
            graph[name] |= {t for t in targets if t in modules}
    bad = []
    seen: set[str] = set()

    def visit(m: str, stack: list[str]) -> None:
        if m in stack:
            cycle = stack[stack.index(m):] + [m]
            key = " -> ".join(cycle)
            if frozenset(cycle) not in seen:
                seen.add(frozenset(cycle))
                bad.append(f"egt-py/python/egt: import cycle {key}")
            return
        for t in sorted(graph[m]):
            visit(t, stack + [m])

    for m in sorted(graph):
        visit(m, [])
    return bad


def main() -> int:
    exports = root_exports((SRC / "lib.rs").read_text())
    bad = []
    for path in sorted(SRC.rglob("*.rs")):
        own = layer_of_file(path)
        if own is None or path.name == "tests.rs":
            continue
        name, level = own
        for n, line in code_lines(path.read_text()):
            for m in re.finditer(r"\bcrate::(\w+)", line):
                target = m.group(1)
                top = target if target in LAYERS else exports.get(target)
                if top is None:
                    bad.append(f"{path.relative_to(SRC)}:{n}: unknown root name crate::{target}")
                elif LAYERS[top] > level:
                    bad.append(
                        f"{path.relative_to(SRC)}:{n}: layer `{name}` imports "
                        f"`{top}` above it: {line.strip()}"
                    )
    bad += cli_problems() + bindings_problems() + fmu_problems() + python_cycles()
    if bad:
        print("layers.py: imports that break the layering:", *bad, sep="\n  ")
        return 1
    print(
        "layers.py: ok: no module of egt-core imports a layer above its own; "
        "no command imports another or cli.rs; the bindings use only egt_cli::run; "
        "no import cycle in the Python package"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
