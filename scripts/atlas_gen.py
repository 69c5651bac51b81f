"""A second generator of the atlas's displacement graphs, of a different kind
from egt's (issue 46): it starts from the axis levels, not from bearing
trees, and its isomorphism key is nauty's (scripts/atlas_iso.py), so it shares
no code with crates/egt-core/src/synthesis.

A displacement graph with N links is a hypertree of levels on the links (a
level is a set of coaxial links; levels meet in at most one link and form a
tree) with gear pairs i-j whose path in the hypertree crosses exactly two
levels, A holding i and B holding j, meeting in the carrier k; the legs i-k
(on A) and j-k (on B) are the turning edges. Every level's legs must join
all its links (otherwise it would be two levels). These are the candidates
*before* egt's checks (planarity, redundancy, fractionation).

The hypertrees come from networkx's free trees on N + L vertices, 2-coloured
into N links and L levels of two or more links each. For each, every choice
of N - 1 - F gear pairs is tried, and the graphs are de-duplicated by nauty.

Usage: python scripts/atlas_gen.py N [F] [--print]
prints the counts of candidate displacement and rotation classes; with
--print, one line per displacement class in egt's adjacency form (a bearing
tree per level, then the gear pairs).
"""

import sys
import time
import networkx as nx

from atlas_iso import nauty_key


def hypertrees(n):
    """Every hypertree on n links up to isomorphism, as lists of levels (tuples)."""
    for levels in range(1, n):
        for t in nx.nonisomorphic_trees(n + levels):
            side = nx.bipartite.color(t)
            zero = [v for v in t if side[v] == 0]
            one = [v for v in t if side[v] == 1]
            for links, lv in ((zero, one), (one, zero)):
                if len(links) != n or len(lv) != levels:
                    continue
                if any(t.degree(v) < 2 for v in lv):
                    continue
                name = {v: i for i, v in enumerate(links)}
                yield [tuple(sorted(name[u] for u in t[v])) for v in lv]
                break


def candidates(n, levels):
    """Gear pairs (i, j, k, A, B) allowed by the hypertree `levels`."""
    out = []
    for a, la in enumerate(levels):
        for b, lb in enumerate(levels):
            if a == b:
                continue
            common = set(la) & set(lb)
            if len(common) != 1:
                continue
            (k,) = common
            for i in la:
                for j in lb:
                    if i == k or j == k or i >= j:
                        continue
                    # i and j on no common level (they would be coaxial)
                    if any(i in lc and j in lc for lc in levels):
                        continue
                    out.append((i, j, k, a, b))
    return out


def connected(links, edges):
    """Whether `edges` join all of `links`."""
    links = list(links)
    seen = {links[0]}
    stack = [links[0]]
    while stack:
        u = stack.pop()
        for a, b in edges:
            for x, y in ((a, b), (b, a)):
                if x == u and y not in seen:
                    seen.add(y)
                    stack.append(y)
    return len(seen) == len(links)


def graphs_of(n, gears, levels):
    """All valid choices of `gears` gear pairs on the hypertree `levels`."""
    cands = candidates(n, levels)
    # the (link, level) incidences each gear pair's legs touch, as bits
    bit = {}
    for a, la in enumerate(levels):
        for x in la:
            bit[(x, a)] = 1 << len(bit)
    full = (1 << len(bit)) - 1
    inc = [bit[(i, a)] | bit[(k, a)] | bit[(j, b)] | bit[(k, b)] for i, j, k, a, b in cands]
    pick = []

    def rec(start, covered):
        left = gears - len(pick)
        if left == 0:
            if covered == full:
                yield list(pick)
            return
        # a gear pair touches at most four incidences
        if bin(full & ~covered).count("1") > 4 * left:
            return
        for p in range(start, len(cands) - left + 1):
            pick.append(p)
            yield from rec(p + 1, covered | inc[p])
            pick.pop()

    for chosen in rec(0, 0):
        per_level = [[] for _ in levels]
        for p in chosen:
            i, j, k, a, b = cands[p]
            per_level[a].append((i, k))
            per_level[b].append((j, k))
        if all(connected(la, per_level[a]) for a, la in enumerate(levels)):
            yield [cands[p] for p in chosen]


def adjacency(n, levels, chosen):
    """egt's adjacency form: a path of bearings per level, then the gear pairs."""
    letters = "abcdefghijklmnopqrstuvwxyz"
    parts = []
    for a, la in enumerate(levels):
        for x, y in zip(la, la[1:]):
            parts.append(f"{x + 1}-{y + 1}:{letters[a]}")
    parts += [f"{i + 1}-{j + 1}:G" for i, j, *_ in chosen]
    return " ".join(parts)


def main():
    n = int(sys.argv[1])
    dof = int(sys.argv[2]) if len(sys.argv) > 2 and sys.argv[2].isdigit() else 1
    show = "--print" in sys.argv
    gears = n - 1 - dof
    start = time.time()
    dclasses, rclasses = {}, set()
    trees = 0
    for levels in hypertrees(n):
        trees += 1
        for chosen in graphs_of(n, gears, levels):
            gear_edges = [(i, j) for i, j, *_ in chosen]
            turning = sorted(
                {tuple(sorted((i, k))) for i, j, k, *_ in chosen}
                | {tuple(sorted((j, k))) for i, j, k, *_ in chosen}
            )
            dk = nauty_key(n, [gear_edges, levels])
            if dk not in dclasses:
                dclasses[dk] = adjacency(n, levels, chosen)
                rclasses.add(nauty_key(n, [gear_edges, turning]))
    if show:
        for line in dclasses.values():
            print(line)
    print(
        f"{n} links, {dof} DOF: {trees} hypertrees, {len(dclasses)} displacement and "
        f"{len(rclasses)} rotation candidates in {time.time() - start:.1f} s",
        file=sys.stderr,
    )


if __name__ == "__main__":
    main()
