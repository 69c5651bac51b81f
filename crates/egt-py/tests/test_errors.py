"""Every error family reaches Python as its own exception class, carrying the
offending names; a Rust panic is an egt.InternalError, never a crash."""

from __future__ import annotations

import pytest

import egt
from conftest import FIG3


def _with_ratios(tau1: str, tau2: str) -> str:
    return FIG3.replace(
        'teeth = [30, 20]\nmesh = "external"\nmodule = 2.0e-3', f"ratio = {tau1}"
    ).replace('teeth = [18, 32]\nmesh = "external"\nmodule = 2.0e-3', f"ratio = {tau2}")


def test_hierarchy() -> None:
    assert issubclass(egt.EgtError, Exception)
    assert issubclass(egt.SpecSyntaxError, egt.SpecError)
    for cls in (egt.SpecError, egt.TopologyError, egt.AnalysisError, egt.TransmissionError, egt.InternalError):
        assert issubclass(cls, egt.EgtError)
    for cls in (
        egt.InputError,
        egt.UnderdeterminedError,
        egt.InconsistentError,
        egt.SingularError,
        egt.IllConditionedError,
        egt.MissingDataError,
    ):
        assert issubclass(cls, egt.AnalysisError)


def test_every_exception_class_has_its_attributes() -> None:
    # Class-level defaults: every attribute exists even where unused.
    assert egt.EgtError.kind is None and egt.EgtError.names is None
    assert egt.SpecSyntaxError.line is None and egt.SpecSyntaxError.path is None
    assert egt.IllConditionedError.condition is None


def test_toml_syntax_error_has_source_line_column_path() -> None:
    text = 'frame = "f"\n[[gears]]\nlinks = ["a", "b"]\nteeth = [30, "x"]\n'
    with pytest.raises(egt.SpecSyntaxError) as info:
        egt.loads(text, source="t.toml")
    e = info.value
    assert (e.source, e.line, e.kind) == ("t.toml", 4, "syntax")
    assert e.column is not None and e.column > 1
    assert e.path == "gears[0].teeth[1]"
    assert "t.toml:4:" in str(e)


def test_json_syntax_error_has_line() -> None:
    with pytest.raises(egt.SpecSyntaxError) as info:
        egt.loads('{\n "frame": "f",\n "links": [ }\n', format="json")
    assert info.value.line == 3
    with pytest.raises(egt.SpecSyntaxError) as info2:
        egt.loads('{"frame": "f", ', format="json")
    assert info2.value.path is None and info2.value.names == ()


def test_file_name_is_the_source(tmp_path) -> None:  # type: ignore[no-untyped-def]
    p = tmp_path / "bad.toml"
    p.write_text("frame = 1\n")
    with pytest.raises(egt.SpecSyntaxError) as info:
        egt.load(p)
    assert info.value.source == str(p)
    assert info.value.line == 1


def test_unknown_field_is_a_syntax_error() -> None:
    with pytest.raises(egt.SpecSyntaxError, match="inertai"):
        egt.loads('frame = "f"\n[[links]]\nname = "a"\ninertai = 1.0\n')


def test_unknown_link_names_it_and_suggests(fig3: egt.Train) -> None:
    spec = 'frame = "housing"\n[[planetary]]\nname = "P"\nsun = "sun"\nring = "housing"\ncarrier = "carrier"\nteeth = { sun = 30, ring = 72 }\n'
    train = egt.loads(spec)
    with pytest.raises(egt.SpecError) as info:
        train.kinematics({"sunn": 1.0})
    e = info.value
    assert not isinstance(e, egt.SpecSyntaxError)
    assert (e.kind, e.names, e.suggestion) == ("unknown_link", ("sunn",), "sun")
    assert e.path is not None and "sunn" in e.path


def test_invalid_teeth_is_a_spec_error_with_value() -> None:
    with pytest.raises(egt.SpecError) as info:
        egt.loads(FIG3.replace("teeth = [30, 20]", "teeth = [0, 20]"))
    assert info.value.kind == "invalid_teeth"
    assert info.value.value == 0
    assert info.value.path == "gears[0].teeth[0]"


def test_non_finite_input_speed(fig3: egt.Train) -> None:
    with pytest.raises(egt.SpecError) as info:
        fig3.kinematics({"2": float("nan")})
    assert info.value.kind == "non_finite"


def test_topology_error_names_the_pair() -> None:
    # Circuit 5-6 with 6 at level a (Table 2 as printed) has no transfer vertex.
    spec = """
frame = "1"
[[revolutes]]
links = ["1", "3"]
level = "b"
[[revolutes]]
links = ["3", "5"]
level = "c"
[[revolutes]]
links = ["1", "4"]
level = "b"
[[revolutes]]
links = ["1", "6"]
level = "a"
[[gears]]
name = "G2"
links = ["5", "4"]
ratio = -1.5
[[gears]]
name = "G3"
links = ["5", "6"]
ratio = 3.5
"""
    spec = spec + "\n".join(f'[[links]]\nname = "{n}"' for n in "3456") + "\n"
    with pytest.raises(egt.TopologyError) as info:
        egt.loads(spec)
    e = info.value
    assert e.kind == "no_transfer_vertex"
    assert e.pairs == ("G3",)
    assert "G3" in e.names
    assert set(e.levels or ()) == {"a", "b", "c"}


def test_wrong_input_count(fig3: egt.Train) -> None:
    with pytest.raises(egt.InputError) as info:
        fig3.kinematics({"3": 1.0, "4": 2.0})
    e = info.value
    assert (e.kind, e.dof, e.given, e.what) == ("wrong_input_count", 1, 2, "input speeds")


def test_frame_as_input(fig3: egt.Train) -> None:
    with pytest.raises(egt.InputError) as info:
        fig3.kinematics({"1": 1.0})
    assert (info.value.kind, info.value.link, info.value.names) == ("frame_input", "1", ("1",))


def test_inconsistent_and_underdetermined_are_diagnosed_exactly() -> None:
    # tau_1 tau_2 = (-2/3)(-3/2) = 1: the output cannot drive the carrier.
    train = egt.loads(FIG3.replace("teeth = [18, 32]", "teeth = [18, 27]"))
    with pytest.raises(egt.InconsistentError) as info:
        train.kinematics({"4": 1.0})
    assert info.value.conflicting and all("circuit" in c for c in info.value.conflicting)
    with pytest.raises(egt.UnderdeterminedError) as info2:
        train.kinematics({"4": 0})
    assert info2.value.free == ("2", "3")
    assert info2.value.names == ("2", "3")


def test_singular_system() -> None:
    train = egt.loads(_with_ratios("-0.6666666666666666", "-1.5"))
    with pytest.raises(egt.SingularError) as info:
        train.kinematics({"4": 1.0})
    assert info.value.what == "the Willis system"
    assert info.value.detail


def test_ill_conditioned_system() -> None:
    train = egt.loads(_with_ratios('"-2/3"', "-1.500000000001"))
    with pytest.raises(egt.IllConditionedError) as info:
        train.kinematics({"4": 1.0})
    e = info.value
    assert e.condition is not None and e.threshold is not None
    assert e.condition > e.threshold
    assert e.what == "the Willis system"


def test_missing_data() -> None:
    # Without pitch radii the a-b offset of the planet's carrier is unknown (eq. 4).
    train = egt.loads(FIG3.replace("module = 2.0e-3\n", ""))
    with pytest.raises(egt.MissingDataError) as info:
        train.dynamics()
    e = info.value
    assert "offset" in (e.what or "") and "eq. 4" in (e.analysis or "") and e.hint
    # A static analysis does not need inertia data.
    assert train.dynamics(accelerations={"4": 0.0}).driving_torques["2"] != 0
    assert train.dynamics(inertia=False).driving_torques


def test_missing_ratio_is_missing_data() -> None:
    train = egt.loads(FIG3.replace('teeth = [18, 32]\nmesh = "external"\nmodule = 2.0e-3\n', ""))
    with pytest.raises(egt.MissingDataError) as info:
        train.kinematics({"2": 1.0})
    assert "G2" in (info.value.what or "")


def test_unknown_shift_element(fig3: egt.Train) -> None:
    with pytest.raises(egt.SpecError, match="unknown shift element"):
        fig3.dynamics(engaged=["X"])


def test_equivalent_inertia_needs_one_dof(fig5: egt.Train) -> None:
    with pytest.raises(egt.InputError) as info:
        fig5.equivalent_inertia("2")
    assert info.value.dof == 2


def test_a_panic_is_an_internal_error(fig3: egt.Train) -> None:
    with pytest.raises(egt.InternalError) as info:
        fig3._core._panic()
    assert info.value.kind == "panic"
    assert "deliberate panic" in str(info.value)
    # The interpreter and the train are still fine.
    assert fig3.kinematics({"2": 1.0})["2"] == 1.0


def test_errors_are_catchable_as_egt_error(fig3: egt.Train) -> None:
    with pytest.raises(egt.EgtError):
        fig3.kinematics({"nope": 1.0})


def _zigzag(sets: int) -> str:
    """A chain of simple planetary sets, every other one reversed (carrier in,
    sun out), so the speeds stay of order one: 2 + 2 * sets links."""
    out = ['frame = "case"']
    for i in range(1, sets + 1):
        prev, nxt = f"m{i - 1}", f"m{i}"
        sun, carrier = (prev, nxt) if i % 2 else (nxt, prev)
        out.append(
            f'[[planetary]]\nname = "P{i}"\nsun = "{sun}"\nring = "case"\ncarrier = "{carrier}"\n'
            "teeth = { sun = 30, planet = 21, ring = 72 }"
        )
    return "\n".join(out) + "\n"


def test_a_train_past_the_dense_limit_solves_its_kinematics_and_dynamics_and_refuses_dense_analyses() -> None:
    train = egt.loads(_zigzag(600))  # 1202 links
    k = train.kinematics({"m0": 1.0})
    # Sun in: the carrier turns at 30 / 102 of the sun; carrier in: the sun at 102 / 30.
    assert k["m1"] == pytest.approx(30 / 102, rel=1e-13)
    assert k["m600"] == pytest.approx(1.0, rel=1e-12)
    assert k.exact is None and any("no exact speeds" in w for w in k.warnings)
    assert train.willis_residual(k.speeds) < 1e-14
    # Inverse dynamics is sparse: the static, massless input torque is the
    # output load times the speed ratio, which is 1 over the 600 sets.
    d = train.dynamics(accelerations={"m0": 0.0}, torques={"m600": -1.0}, driving=["m0"])
    assert d.driving_torques["m0"] == pytest.approx(1.0, rel=1e-12)
    # The Willis Jacobian and the mass matrix's rows are dense: refused by name.
    with pytest.raises(egt.AnalysisError) as info:
        train.mass_matrix()
    assert info.value.kind == "too_large"
    with pytest.raises(egt.AnalysisError) as info:
        train.willis_jacobian()
    assert info.value.kind == "too_large"
    assert "1202 links" in str(info.value) and "at most 1024 links" in str(info.value)
