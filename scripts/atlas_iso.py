"""An isomorphism key for egt's atlas graphs from nauty (pynauty), sharing no
code with egt's canon.rs; run as a script, it checks that no two lines of an
`egt enumerate` output are isomorphic (issue 46).

A line is egt's adjacency form: a bearing tree with axis letters, then gear
pairs (`1-4:a 2-4:a 3-4:b 1-3:G 2-3:G`). The graph is rebuilt from it here,
not from egt's internals:

- a level is a connected set of links joined by bearings of one letter;
- the carrier of gear pair i-j is the one link k that shares one level with i
  and another level with j (the levels form a tree, so k is unique);
- the rotation graph is links, gear edges i-j and turning edges i-k, j-k;
- the displacement graph is links, gear edges and the levels as sets of links
  (the carriers and legs follow from them, so nothing is lost).

Edge colours become vertex colours, as nauty expects: every edge is
subdivided by a vertex of its kind (gear or turning), and a level is a vertex
joined to its links. The key is nauty's certificate with the colour-class
sizes.

Usage: egt enumerate --links 8 --level rotation | python scripts/atlas_iso.py rotation
"""

import sys
from collections import defaultdict

import pynauty


def parse(line):
    """(n, bearings [(a, b, letter)], gears [(a, b)]) with links 0-based."""
    bearings, gears = [], []
    links = set()
    for tok in line.split():
        pair, kind = tok.split(":")
        a, b = (int(x) - 1 for x in pair.split("-"))
        links.update((a, b))
        if kind == "G":
            gears.append((a, b))
        else:
            bearings.append((a, b, kind))
    return max(links) + 1, bearings, gears


def levels_of(n, bearings):
    """The levels as frozensets of links: components of same-letter bearings."""
    parent = list(range(len(bearings)))

    def root(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for e, (a, b, la) in enumerate(bearings):
        for f in range(e):
            c, d, lb = bearings[f]
            if la == lb and {a, b} & {c, d}:
                parent[root(e)] = root(f)
    groups = defaultdict(set)
    for e, (a, b, _) in enumerate(bearings):
        groups[root(e)].update((a, b))
    return [frozenset(s) for s in groups.values()]


def carrier(levels, i, j):
    """The link sharing one level with i and another with j."""
    found = {
        k
        for la in levels
        if i in la and j not in la
        for lb in levels
        if j in lb and i not in lb and la != lb
        for k in la & lb
        if k not in (i, j)
    }
    if len(found) != 1:
        raise ValueError(f"gear pair {i + 1}-{j + 1}: carriers {sorted(found)}")
    return found.pop()


def legs(n, bearings, gears):
    """The turning edges of the rotation graph, and the levels."""
    levels = levels_of(n, bearings)
    turning = set()
    for i, j in gears:
        k = carrier(levels, i, j)
        turning.add((min(i, k), max(i, k)))
        turning.add((min(j, k), max(j, k)))
    return sorted(turning), levels


def nauty_key(n, groups):
    """Certificate of a vertex-coloured graph: links 0..n-1, then for each
    colour class in `groups` a vertex per item joined to the item's links."""
    adj = defaultdict(list)
    colouring = [set(range(n))]
    v = n
    sizes = [n]
    for items in groups:
        cls = set()
        for item in items:
            for a in item:
                adj[v].append(a)
            cls.add(v)
            v += 1
        colouring.append(cls)
        sizes.append(len(items))
    g = pynauty.Graph(v, adjacency_dict=dict(adj), vertex_coloring=colouring)
    return tuple(sizes), pynauty.certificate(g)


def key(line, level):
    """The isomorphism key of one adjacency line at `level`."""
    n, bearings, gears = parse(line)
    turning, levels = legs(n, bearings, gears)
    if level == "rotation":
        return nauty_key(n, [gears, turning])
    return nauty_key(n, [gears, [sorted(s) for s in levels]])


def main():
    level = sys.argv[1]
    seen = {}
    dupes = 0
    count = 0
    for line in sys.stdin:
        line = line.strip()
        if not line:
            continue
        count += 1
        k = key(line, level)
        if k in seen:
            dupes += 1
            print(f"isomorphic: {seen[k]}  ==  {line}")
        else:
            seen[k] = line
    print(f"{count} lines, {len(seen)} nauty classes, {dupes} duplicates")
    sys.exit(1 if dupes else 0)


if __name__ == "__main__":
    main()
