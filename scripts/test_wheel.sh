#!/usr/bin/env bash
# Install the wheel `make wheel` built into a fresh virtualenv whose PATH has
# no Rust toolchain, then run what a new user runs: the `egt` command, and
# scripts/wheel_user.py (the README's Python block and every docs/python.md
# block as written, plots, a process pool). Also checks the wheel's tag
# (abi3, manylinux2014), that it is stripped and that it carries the licences.
set -euo pipefail
cd "$(dirname "$0")/.."
wheel=$(ls -t target/wheels/egt_gears-*-cp39-abi3-manylinux2014_x86_64*.whl | head -n 1)
echo "wheel: $wheel ($(du -h "$wheel" | cut -f1))"
listing=$(python3 -m zipfile -l "$wheel")
grep -q "licenses/LICENSE-APACHE" <<<"$listing"
grep -q "licenses/LICENSE-MIT" <<<"$listing"
venv=$(mktemp -d)/venv
python3 -m venv "$venv"
# The extras a reader of docs/python.md uses (SymPy, plots, pandas, units, Dask).
"$venv/bin/pip" install --quiet "$wheel[sympy,plot,pandas,pint,dask]"
so=$(find "$venv" -name "_egt.abi3.so")
if readelf -S "$so" 2>/dev/null | grep -q "\.debug_info"; then
    echo "the extension carries debug info" >&2
    exit 1
fi
clean=(env -i "PATH=/usr/bin:/bin" "HOME=$(mktemp -d)")
checked=$("${clean[@]}" "$venv/bin/egt" check examples/fig3_example61.toml)
grep -q "valid geared kinematic chain" <<<"$checked"
"${clean[@]}" "$venv/bin/python" scripts/wheel_user.py
rm -rf "$(dirname "$venv")"
