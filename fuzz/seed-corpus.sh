#!/usr/bin/env bash
# Seed the fuzz corpora from examples/: whole specs for `spec`, the adjacency
# strings of the specs that use one for `adjacency`, and number forms for
# `input_value`. The corpora grow under fuzz/corpus/ (not committed).
set -euo pipefail
cd "$(dirname "$0")"
mkdir -p corpus/spec corpus/adjacency corpus/input_value
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
