"""egt.atlas: the enumerated gear-train graphs load back as trains."""

from pathlib import Path

import pytest

import egt
from conftest import EXAMPLES


def test_every_member_loads_as_a_train_with_the_requested_dof() -> None:
    members = egt.atlas(5, dof=1, level="displacement")
    assert members
    for m in members:
        train = egt.loads(f'frame = "1"\nadjacency = "{m["adjacency"]}"\n', format="toml")
        assert train.dof == 1
    assert len({m["code"] for m in members}) == len(members)


def test_rotation_members_sum_to_the_displacement_count() -> None:
    r = egt.atlas(6)
    d = egt.atlas(6, level="displacement")
    assert sum(m["displacement_graphs"] for m in r) == len(d)


def test_bad_requests_raise_egt_errors() -> None:
    with pytest.raises(egt.EgtError, match="level"):
        egt.atlas(5, level="other")
    with pytest.raises(egt.EgtError, match="links"):
        egt.atlas(2)


def test_six_link_counts_equal_the_published_atlas() -> None:
    # Yang & Ding, ASME J. Mech. Des. 141(4):043301 (2019): 27 r-graphs, 81 d-graphs.
    assert len(egt.atlas(6)) == 27
    assert len(egt.atlas(6, level="displacement")) == 81


def test_coaxial_triples_count_the_three_link_subsets_of_each_axis() -> None:
    from math import comb

    for m in egt.atlas(6, level="displacement"):
        turning = [p for p in m["adjacency"].split() if not p.endswith(":G")]
        per_axis: dict[str, int] = {}
        for p in turning:
            level = p.split(":")[1]
            per_axis[level] = per_axis.get(level, 0) + 1
        # a level's pairs form a tree: pairs + 1 links on that axis
        assert m["coaxial_triples"] == sum(comb(k + 1, 3) for k in per_axis.values())


def test_a_train_names_its_atlas_member() -> None:
    train = egt.Train.from_file(EXAMPLES / "fig5_example62.toml")
    m = train.atlas_member("displacement")
    assert m["links"] == 6 and m["dof"] == 2
    assert m["code"] in {x["code"] for x in egt.atlas(6, dof=2, level="displacement")}
    with pytest.raises(egt.EgtError, match="case"):
        egt.Train.from_file(EXAMPLES / "ford_c4_simpson.toml").atlas_member()


def test_the_kinematic_sense_of_fractionation_is_stricter_for_two_dof() -> None:
    layout = {m["code"] for m in egt.atlas(6, dof=2, level="displacement")}
    kinematic = {m["code"] for m in egt.atlas(6, dof=2, level="displacement", fractionation="kinematic")}
    assert kinematic < layout and len(kinematic) == 3
    with pytest.raises(egt.EgtError, match="fractionation"):
        egt.atlas(6, fractionation="other")


def test_the_ten_link_atlas_file_holds_a_recounted_part() -> None:
    """Issue 46: data/atlas10_dof1_displacement.txt.gz is the ten-link
    one-DOF atlas (docs/atlas.md: 903 812 displacement graphs, the sha256 of
    its text pinned there); a part recounted now is in it, line for line."""
    import gzip
    import hashlib

    path = Path(__file__).resolve().parents[3] / "data" / "atlas10_dof1_displacement.txt.gz"
    text = gzip.decompress(path.read_bytes())
    assert hashlib.sha256(text).hexdigest() == "66440f7db01e166cb7387a2195a8afae5ad8e7d046c91e8fc1b623227a3b889f"
    lines = text.decode().splitlines()
    assert len(lines) == len(set(lines)) == 903_812
    part = egt.atlas(10, level="displacement", part=(7, 400), search="levels")
    assert len(part) == 9455
    assert {m["adjacency"] for m in part} <= set(lines)
    # each line reads back as a ten-link train with eight gear pairs
    assert all(line.count(":G") == 8 for line in lines[::10_000])
