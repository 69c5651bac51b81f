"""The one-DOF atlas against a second generator and a second canonical form
that share no code with egt (issue 46): scripts/atlas_gen.py builds the
candidates from hypertrees of axis levels (not from bearing trees),
scripts/atlas_iso.py keys graphs by nauty's certificate (not egt's canon.rs),
and the validity rule here is the rigid-sub-chain count of docs/atlas.md (not
`egt check`). At 3-8 links, both levels, the members must be the same
isomorphism classes as `egt.atlas`'s, each once, in the published numbers."""

import sys
from pathlib import Path

import pytest

import egt

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "scripts"))

from atlas_gen import graphs_of, hypertrees  # noqa: E402
from atlas_iso import key, nauty_key  # noqa: E402

# Yang & Ding, ASME J. Mech. Des. 141(4) 043301 (2019): rotation / displacement
# graphs, called confirmed at 6-8 links.
PUBLISHED = {6: (27, 81), 7: (152, 647), 8: (1070, 6360)}


def rigid(n, gears):
    """Whether some k >= 3 links hold k - 1 gear pairs whose two gears and
    carrier are all among them (eq. 1 leaves them no relative motion)."""
    masks = [(1 << i) | (1 << j) | (1 << k) for i, j, k in gears]
    for s in range(1, 1 << n):
        k = bin(s).count("1")
        if k >= 3 and sum(m & s == m for m in masks) >= k - 1:
            return True
    return False


def independent_atlas(n):
    """(rotation keys, displacement keys) of the members by the generator,
    nauty and the rigid-sub-chain rule."""
    rot, disp = set(), set()
    for levels in hypertrees(n):
        for chosen in graphs_of(n, n - 2, levels):
            gears = [(i, j, k) for i, j, k, *_ in chosen]
            if rigid(n, gears):
                continue
            gear_edges = [(i, j) for i, j, _ in gears]
            turning = sorted({tuple(sorted(e)) for i, j, k in gears for e in ((i, k), (j, k))})
            disp.add(nauty_key(n, [gear_edges, levels]))
            rot.add(nauty_key(n, [gear_edges, turning]))
    return rot, disp


@pytest.mark.parametrize("n", [3, 4, 5, 6, 7, 8])
def test_two_generators_two_canonical_forms_agree(n):
    rot, disp = independent_atlas(n)
    for level, theirs in (("rotation", rot), ("displacement", disp)):
        lines = [m["adjacency"] for m in egt.atlas(n, 1, level)]
        ours = [key(line, level) for line in lines]
        # each member once: no two of egt's lines are isomorphic by nauty
        assert len(set(ours)) == len(ours), level
        assert set(ours) == theirs, level
    if n in PUBLISHED:
        assert (len(rot), len(disp)) == PUBLISHED[n]


def test_the_rule_and_the_key_can_fail():
    """The rigid rule rejects the redundant gear triangle on one carrier, and
    nauty's key is blind to link names but not to the structure."""
    # three gears meshing in a loop on one carrier: 4 links, 3 gear pairs
    assert rigid(4, [(0, 1, 3), (1, 2, 3), (0, 2, 3)])
    assert not rigid(4, [(0, 1, 3), (1, 2, 3)])
    simple = key("1-4:a 2-4:a 3-4:b 1-3:G 2-3:G", "displacement")
    # the same set with links renamed 4 -> 1 -> 2 -> 3 -> 4
    assert key("2-1:a 3-1:a 4-1:b 2-4:G 3-4:G", "displacement") == simple
    # sun and ring on different axes of the carrier: another member
    assert key("1-4:a 2-4:c 3-4:b 1-3:G 2-3:G", "displacement") != simple
