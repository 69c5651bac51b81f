#!/usr/bin/env bash
# Install the wheel `make wheel` built into a fresh virtualenv whose PATH has
# no Rust toolchain, then run what a new user runs: the `egt` command, the
# README's Python block, and a pickle round trip. Also checks the wheel's tag
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
"$venv/bin/pip" install --quiet "$wheel"
so=$(find "$venv" -name "_egt.abi3.so")
if readelf -S "$so" 2>/dev/null | grep -q "\.debug_info"; then
    echo "the extension carries debug info" >&2
    exit 1
fi
clean=(env -i "PATH=/usr/bin:/bin" "HOME=$(mktemp -d)")
checked=$("${clean[@]}" "$venv/bin/egt" check examples/fig3_example61.toml)
grep -q "valid geared kinematic chain" <<<"$checked"
"${clean[@]}" "$venv/bin/python" - <<'PY'
import pickle
import egt
train = egt.load("examples/fig3_example61.toml")
assert train.dof == 1
k = train.kinematics({"2": 100.0})
assert k["4"] == 15.625 and str(k.exact["4"]) == "125/8", k
d = train.dynamics(torques={"4": -50.0}, accelerations={"4": 10.0}, driving=["2"])
assert pickle.loads(pickle.dumps(train)).dof == 1
print("wheel: 1 passed, 0 failed")
PY
rm -rf "$(dirname "$venv")"
