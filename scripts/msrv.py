"""Check the declared minimum Rust version (`rust-version` in Cargo.toml)
against every package in the lock file: no dependency may need a newer
compiler than the workspace declares. (Our own code is held to it by
clippy's `incompatible_msrv` lint, which reads the same field.)"""

import json
import subprocess
import sys


def version(v: str) -> tuple:
    return tuple(int(x) for x in v.split(".")[:3]) + (0,) * (3 - len(v.split(".")))


meta = json.loads(subprocess.run(
    ["cargo", "metadata", "--format-version", "1", "--locked"],
    check=True, capture_output=True, text=True).stdout)
ours = {p["name"]: p for p in meta["packages"] if p["id"] in meta["workspace_members"]}
declared = {p["rust_version"] for p in ours.values()}
if len(declared) != 1 or None in declared:
    sys.exit(f"msrv: workspace crates declare {declared}; expected one rust-version")
msrv = declared.pop()
newer = sorted((p["name"], p["rust_version"]) for p in meta["packages"]
               if p.get("rust_version") and version(p["rust_version"]) > version(msrv))
if newer:
    sys.exit(f"msrv: rust-version {msrv}, but these packages need more: {newer}")
print(f"msrv: rust-version {msrv} covers all {len(meta['packages'])} packages")
