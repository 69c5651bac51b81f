#!/usr/bin/env bash
# Seed the fuzz corpora from examples/: whole specs for `spec`, the adjacency
# strings of the specs that use one for `adjacency`, number forms for
# `input_value`, and a few trains (family, size, seed bytes) for `program`.
# The corpora grow under fuzz/corpus/ (not committed).
set -euo pipefail
cd "$(dirname "$0")"
mkdir -p corpus/spec corpus/adjacency corpus/input_value corpus/program corpus/search_spec corpus/batch_args corpus/shift_sim_args
for f in ../examples/*.toml ../examples/*.json; do
    cp "$f" "corpus/spec/$(basename "$f")"
    # The adjacency string, when the spec has one (TOML `adjacency = "..."` or JSON).
    a=$(grep -oE '"?adjacency"? *[=:] *"[^"]*"' "$f" | head -n1 | sed -E 's/.*[=:] *"([^"]*)"/\1/' || true)
    if [ -n "$a" ]; then printf '%s' "$a" > "corpus/adjacency/$(basename "$f").txt"; fi
done
printf '%s' '1-2:a 2-3:b 1-4:a 1-3:G=-2/3 3-4:G=-16/9' > corpus/adjacency/fig3.txt
i=0
for v in 1 -3 2.5 1e-3 -162/77 0.1 1/2.5 +7E+2 1e1000 1/3/4 1e-1000000; do
    printf '%s' "$v" > "corpus/input_value/v$i"; i=$((i + 1))
done
# `program`: a chain of 1 and of 4 sets (odd first byte), a random train
# of 2 and of 3 sets (even), dynamics, every output, rows near the base.
for seed in '\x01\x01' '\x07\x01' '\x02\x00\x00\x00\x00\x00\x00\x00\x2a\x03\x01' '\x04\x00\x00\x00\x00\x00\x00\x01\x00\x05\x01'; do
    printf "$seed" > "corpus/program/$(printf "$seed" | od -An -tx1 | tr -d ' \n')"
done
# `search_spec`: the bundled search specs (the harness maps each `base` to
# its bundled train).
for f in ../examples/synth/*.toml; do
    cp "$f" "corpus/search_spec/$(basename "$f")"
done
# `batch_args`: one argument a line, after `egt batch fig3`.
i=0
for a in '--vary\nspeed.2=1:2:3' '--grid\nspeed.2=0:1:3\n--grid\ntorque.2=1,2' \
    '--set\ntorque.2=5\n--vary\nratio.G1=-2,-3\n--vary\ninertia.2=1,2' \
    '--compute\npower\n--vary\naccel.4=1:2:4\n--output\ncsv' \
    '--compute\nkinematics\n--grid\nspeed.2=1e308,-1e308\n--columns\nspeed.3'; do
    printf '%b' "$a" > "corpus/batch_args/a$i"; i=$((i + 1))
done
# `shift_sim_args`: one argument a line, after `egt shift-sim 8hp70`.
i=0
base='--from\n2\n--to\n3\n--input-speed\n250\n--off-going\n0.05:0.15:5000:0\n--on-coming\n0.05:0.3:0:9000'
for a in "$base\n--input-torque\n300\n--road-load\n20,0.2,0.002\n--vehicle-inertia\n12" \
    "$base\n--torque-table\n0:300,1000:250\n--t-end\n0.5\n--rtol\n1e-6\n--method\nimplicit" \
    "$base\n--input-torque\n-50\n--mu\n0.15,0.12\n--mu-decay\n10\n--format\ncsv"; do
    printf '%b' "$a" > "corpus/shift_sim_args/a$i"; i=$((i + 1))
done
