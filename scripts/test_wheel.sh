#!/usr/bin/env bash
# Install the wheel `make wheel` built into a fresh virtualenv whose PATH has
# no Rust toolchain, then run what a new user runs: the `egt` command, and
# scripts/wheel_user.py (the README's Python block and every docs/python.md
# block as written, plots, a process pool). Also checks the wheel's tag
# (abi3, manylinux2014), that it is stripped and that it carries the licences
# and egt-fmu's shared library (stripped, glibc 2.17 like the extension), which
# the wheel's `egt fmu` packages without EGT_FMU_LIBRARY.
set -euo pipefail
cd "$(dirname "$0")/.."
wheel=$(ls -t target/wheels/egt_gears-*-cp39-abi3-manylinux2014_x86_64*.whl | head -n 1)
echo "wheel: $wheel ($(du -h "$wheel" | cut -f1))"
listing=$(python3 -m zipfile -l "$wheel")
grep -q "licenses/LICENSE-APACHE" <<<"$listing"
grep -q "licenses/LICENSE-MIT" <<<"$listing"
grep -q "egt/libegt_fmu.so" <<<"$listing"
venv=$(mktemp -d)/venv
python3 -m venv "$venv"
# The extras a reader of docs/python.md uses (SymPy, plots, pandas, units, Dask).
"$venv/bin/pip" install --quiet "$wheel[sympy,plot,pandas,pint,dask]"
so=$(find "$venv" -name "_egt.abi3.so")
if readelf -S "$so" 2>/dev/null | grep -q "\.debug_info"; then
    echo "the extension carries debug info" >&2
    exit 1
fi
fmu_lib=$(dirname "$so")/libegt_fmu.so
if readelf -S "$fmu_lib" | grep -q "\.symtab"; then
    echo "egt-fmu's library is not stripped" >&2
    exit 1
fi
for lib in "$so" "$fmu_lib"; do
    # manylinux2014: no symbol from a glibc newer than 2.17
    newest=$(objdump -T "$lib" | grep -o "GLIBC_[0-9.]*" | sed "s/GLIBC_//" | sort -V | tail -n 1)
    if [ "$(printf '%s\n' "$newest" 2.17 | sort -V | tail -n 1)" != 2.17 ]; then
        echo "$lib needs glibc $newest (manylinux2014 allows 2.17)" >&2
        exit 1
    fi
done
clean=(env -i "PATH=/usr/bin:/bin" "HOME=$(mktemp -d)")
checked=$("${clean[@]}" "$venv/bin/egt" check examples/fig3_example61.toml)
grep -q "valid geared kinematic chain" <<<"$checked"
unit=$(dirname "$venv")/c4.fmu
made=$("${clean[@]}" "$venv/bin/egt" fmu examples/ford_c4_simpson.toml -o "$unit")
grep -q "egt/libegt_fmu.so" <<<"$made"
grep -q "binaries/linux64/c4.so" <<<"$(python3 -m zipfile -l "$unit")"
"${clean[@]}" "$venv/bin/python" scripts/wheel_user.py
rm -rf "$(dirname "$venv")"
