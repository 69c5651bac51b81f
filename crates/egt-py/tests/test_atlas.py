"""egt.atlas: the enumerated gear-train graphs load back as trains."""

import pytest

import egt


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
