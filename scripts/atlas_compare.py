"""Compares egt's atlas with the independent generator scripts/atlas_gen.py,
by nauty keys only (scripts/atlas_iso.py), at the displacement and rotation
levels (issue 46).

Inputs:
- GEN: `atlas_gen.py N --print` output, one candidate class a line (before checks);
- CANDS: egt's candidates with why each is in or out (the ignored test
  `synthesis::tests::candidates_with_reasons`), `reason<TAB>rcode<TAB>adjacency`;
- ATLAS: `egt enumerate --links N --level displacement` output.

It reports whether the two candidate sets are the same classes, whether the
atlas is exactly egt's "member" candidates, and the rejected candidates
grouped by reason, as rotation / displacement counts, with rotation graphs
counted under a reason when none of their displacement graphs is a member.

Usage: python scripts/atlas_compare.py GEN CANDS ATLAS [REASON]
(with REASON, also prints that group's rotation graphs and their lines)
"""

import sys
from collections import Counter, defaultdict

from atlas_iso import key


def lines(path):
    with open(path) as f:
        return [x.rstrip("\n") for x in f if x.strip()]


def main():
    gen_path, cands_path, atlas_path = sys.argv[1:4]
    show = sys.argv[4] if len(sys.argv) > 4 else None
    gen = {key(x, "displacement"): x for x in lines(gen_path)}
    cands = {}
    for row in lines(cands_path):
        reason, _, adjacency = row.split("\t")
        k = key(adjacency, "displacement")
        assert k not in cands, f"egt lists a candidate twice: {adjacency}"
        cands[k] = (reason, adjacency)
    atlas = {key(x, "displacement") for x in lines(atlas_path)}
    print(f"independent generator: {len(gen)} displacement candidates")
    print(f"egt: {len(cands)} displacement candidates, {len(atlas)} in the atlas")
    only_gen = set(gen) - set(cands)
    only_egt = set(cands) - set(gen)
    print(f"only in the independent generator: {len(only_gen)}; only in egt: {len(only_egt)}")
    for k in list(only_gen)[:20]:
        print("  gen only:", gen[k])
    for k in list(only_egt)[:20]:
        print("  egt only:", cands[k][1])
    members = {k for k, (r, _) in cands.items() if r == "member"}
    print(f"atlas == egt's member candidates: {members == atlas}")
    # rotation graphs: which reasons reject all their displacement graphs
    by_rot = defaultdict(list)
    for k, (reason, adjacency) in cands.items():
        by_rot[key(adjacency, "rotation")].append((reason, adjacency))
    rot_members = sum(any(r == "member" for r, _ in ds) for ds in by_rot.values())
    print(f"rotation: {len(by_rot)} candidates, {rot_members} in the atlas")
    d_reasons = Counter(r for r, _ in cands.values())
    r_reasons = Counter()
    groups = defaultdict(list)
    for rk, ds in by_rot.items():
        reasons = {r for r, _ in ds}
        if "member" in reasons:
            continue
        label = "+".join(sorted(reasons))
        r_reasons[label] += 1
        groups[label].append(ds)
    print("displacement candidates by reason:", dict(d_reasons))
    print("rotation graphs out of the atlas, by the reasons of all their d-graphs:")
    for label, c in r_reasons.most_common():
        d = sum(len(ds) for ds in groups[label])
        print(f"  {label}: {c} rotation / {d} displacement")
    if show:
        for ds in groups[show]:
            print("rotation graph:")
            for r, a in ds:
                print(f"  {r}\t{a}")


if __name__ == "__main__":
    main()
