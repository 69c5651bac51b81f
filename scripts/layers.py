#!/usr/bin/env python3
"""Check that no module of egt-core imports a layer above its own.

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

import re
import sys
from pathlib import Path

SRC = Path(__file__).resolve().parent.parent / "crates" / "egt-core" / "src"

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
    if bad:
        print("layers.py: imports that run up a layer:", *bad, sep="\n  ")
        return 1
    print(f"layers.py: ok, no module of egt-core imports a layer above its own")
    return 0


if __name__ == "__main__":
    sys.exit(main())
