"""Sorts the atlas candidates that egt rejects by their minimal rigid
sub-chains (issue 46). Some k >= 3 links are a rigid sub-chain when they hold
k - 1 or more gear pairs whose gears and carrier are all among them; then
Gruebler-Kutzbach (paper eq. 1) leaves them no motion relative to each other.
A rigid sub-chain is minimal when no smaller rigid sub-chain is inside it.

The input is the output of the ignored test `candidates_with_reasons`
(`reason<TAB>rcode<TAB>adjacency`). Each rejected rotation graph is keyed by
the set of (links, gear pairs, carriers) of its minimal rigid sub-chains.
The output has one line per key: how many rotation graphs and displacement
graphs have it, and, for groups of three or fewer, one example.

Usage: python scripts/atlas_rigid.py CANDS
"""

import sys
from collections import defaultdict

from atlas_iso import carrier, levels_of, parse


def rigid(gears, links):
    """Gear pairs (i, j, k) inside the link set `links` (a bit mask)."""
    return [x for x in gears if all(links >> v & 1 for v in x)]


def is_rigid(gears, links):
    k = bin(links).count("1")
    return k >= 3 and len(rigid(gears, links)) >= k - 1


def kinds(n, gears):
    """(links, gear pairs, carriers) of every minimal rigid sub-chain."""
    out = set()
    for s in range(1, 1 << n):
        if not is_rigid(gears, s):
            continue
        if any(t & s == t and is_rigid(gears, t) for t in range(1, s)):
            continue
        inside = rigid(gears, s)
        out.add((bin(s).count("1"), len(inside), len({c for _, _, c in inside})))
    return tuple(sorted(out))


def main():
    groups = defaultdict(list)
    with open(sys.argv[1]) as f:
        for row in f:
            reason, rcode, adjacency = row.rstrip("\n").split("\t")
            if reason != "member":
                groups[rcode].append(adjacency)
    stat = defaultdict(lambda: [0, 0])
    example = {}
    for ds in groups.values():
        n, bearings, gear_edges = parse(ds[0])
        levels = levels_of(n, bearings)
        gears = [(i, j, carrier(levels, i, j)) for i, j in gear_edges]
        key = kinds(n, gears)
        stat[key][0] += 1
        stat[key][1] += len(ds)
        example.setdefault(key, ds[0])
    for key, (r, d) in sorted(stat.items(), key=lambda x: x[1][0]):
        print(f"{key}: {r} rotation / {d} displacement", example[key] if r <= 3 else "")


if __name__ == "__main__":
    main()
