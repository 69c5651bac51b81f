#!/usr/bin/env bash
# Seed the fuzz corpora from examples/: whole specs for `spec`, the adjacency
# strings of the specs that use one for `adjacency`, number forms for
# `input_value`, and a few trains (family, size, seed bytes) for `program`.
# The corpora grow under fuzz/corpus/ (not committed).
set -euo pipefail
cd "$(dirname "$0")"
mkdir -p corpus/spec corpus/adjacency corpus/input_value corpus/program
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
