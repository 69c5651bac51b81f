"""Building trains (load, loads, from_dict) and reading their structure."""

from __future__ import annotations

import json
import pathlib
from fractions import Fraction

import pytest

import egt
from conftest import EXAMPLES, FIG3


def test_version_is_the_crate_version() -> None:
    cargo = pathlib.Path(__file__).resolve().parents[3] / "Cargo.toml"
    version = next(
        line.split("=")[1].strip().strip('"')
        for line in cargo.read_text().splitlines()
        if line.startswith("version")
    )
    assert egt.__version__ == version


def test_package_is_typed() -> None:
    pkg = pathlib.Path(egt.__file__).parent
    assert (pkg / "py.typed").exists()
    assert (pkg / "_egt.pyi").exists()


def test_all_names_exist() -> None:
    for name in egt.__all__:
        assert hasattr(egt, name), name


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.toml")) + sorted(EXAMPLES.glob("*.json")))
def test_every_example_loads(path: pathlib.Path) -> None:
    train = egt.load(path)
    assert train.dof >= 1
    assert len(train.circuits) == len(train.gears)
    assert train.check()


def test_load_accepts_str_and_pathlike(tmp_path: pathlib.Path) -> None:
    p = tmp_path / "fig3.toml"
    p.write_text(FIG3)
    assert egt.load(p).dof == egt.load(str(p)).dof == 1
    with pytest.raises(FileNotFoundError):
        egt.load(tmp_path / "missing.toml")


def test_json_spec_file_is_read_as_json(tmp_path: pathlib.Path) -> None:
    spec = {
        "frame": "housing",
        "planetary": [
            {"name": "P", "sun": "sun", "ring": "housing", "carrier": "carrier", "teeth": {"sun": 30, "ring": 72}}
        ],
    }
    p = tmp_path / "p.json"
    p.write_text(json.dumps(spec))
    assert egt.load(p).dof == 1
    assert egt.loads(json.dumps(spec), format="json").dof == 1
    assert egt.Train.from_dict(spec).dof == 1


def test_unknown_format_is_a_value_error() -> None:
    with pytest.raises(ValueError, match="format"):
        egt.loads(FIG3, format="yaml")


def test_from_dict_rejects_unserialisable_values() -> None:
    with pytest.raises(TypeError, match="JSON"):
        egt.Train.from_dict({"frame": object()})


def test_train_cannot_be_built_directly() -> None:
    with pytest.raises(TypeError):
        egt.Train("not a core")  # type: ignore[arg-type]


def test_structure_of_fig3(fig3: egt.Train) -> None:
    assert fig3.name == "Fig. 3"
    assert fig3.frame == "1"
    assert fig3.dof == 1
    assert fig3.link_names == ("1", "2", "3", "4")
    assert fig3.coordinates == ("2", "3", "4")
    assert set(fig3.levels) == {"a", "b"}
    links = {link.name: link for link in fig3.links}
    assert links["1"].frame and not links["2"].frame
    assert links["3"].copies == 3 and links["3"].mass == 0.12
    g1, g2 = fig3.gears
    assert (g1.name, g1.gear_i, g1.gear_j, g1.teeth, g1.mesh) == ("G1", "1", "3", (30, 20), "external")
    assert g1.ratio_exact == Fraction(-2, 3) and g1.ratio == pytest.approx(-2 / 3)
    assert g1.radii == pytest.approx((0.03, 0.02))
    assert g2.efficiency == 0.98
    assert json.dumps([g.to_dict() for g in fig3.gears])


def test_circuits_are_records_with_names(fig3: egt.Train) -> None:
    c1, c2 = fig3.circuits
    assert (c1.index, c1.gear, c1.gear_i, c1.gear_j, c1.carrier) == (1, "G1", "1", "3", "2")
    assert (c2.index, c2.gear, c2.gear_i, c2.gear_j, c2.carrier) == (2, "G2", "3", "4", "2")
    assert set(c1.levels) == {"a", "b"}
    assert c1.path[0] == "1" and c1.path[-1] == "3"
    assert c2.ratio_exact == Fraction(-16, 9)
    assert json.dumps([c.to_dict() for c in fig3.circuits])


def test_table_2_transfer_vertices(fig5: egt.Train) -> None:
    # Table 2 of the paper: (gear i, gear j, transfer vertex).
    rows = {(c.gear_i, c.gear_j, c.carrier) for c in fig5.circuits}
    assert rows == {("2", "3", "1"), ("5", "4", "3"), ("5", "6", "3")}
    assert fig5.dof == 2


def test_check_lists_the_passed_checks(fig3: egt.Train) -> None:
    checks = fig3.check()
    assert isinstance(checks, list) and all(isinstance(c, str) for c in checks)
    assert len(checks) >= 3


def test_planetary_shorthand_links(planetary: egt.Train) -> None:
    names = set(planetary.link_names)
    assert {"housing", "sun", "carrier", "P.planet"} <= names
    assert planetary.elements == {}


def test_repr(fig3: egt.Train) -> None:
    assert "Fig. 3" in repr(fig3) and "dof=1" in repr(fig3)


def test_shift_elements_are_listed() -> None:
    spec = FIG3 + '\n[[elements]]\nname = "B"\nkind = "brake"\nlinks = ["4"]\n'
    train = egt.loads(spec)
    assert train.elements == {"B": ("brake", ("4",))}
