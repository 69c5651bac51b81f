"""egt.synth and egt.synth_distributed (issue 16): the 8HP's ratios from its
published figures, candidates whose exact ratios the shift table confirms,
and a Dask run on a 2-worker LocalCluster equal to the single-process run,
also when a worker dies mid-run."""

from __future__ import annotations

import os
from fractions import Fraction
from pathlib import Path

import pytest

import egt

ROOT = Path(__file__).resolve().parents[3]
ZF = ROOT / "examples" / "synth" / "zf_8hp70.toml"
C4 = ROOT / "examples" / "synth" / "ford_c4_simpson.toml"


def key(r: egt.SynthResult) -> list:
    return [(c.score, [(t.sun, t.ring, t.planet) for t in c.sets.values()]) for c in r.candidates]


def test_synth_finds_the_8hp_and_the_shift_table_confirms_it() -> None:
    r = egt.synth(ZF)
    best = r.candidates[0]
    assert [t.basic for t in best.sets.values()] == [Fraction(2), Fraction(2), Fraction(37, 23), Fraction(85, 23)]
    assert best.ratios["1"] == Fraction(108, 23)
    assert r.stats["tooth_space"] > 1e10
    # Rebuilt from the candidate's teeth, the train gives the same exact ratios.
    spec = (ROOT / "examples" / "zf_8hp70.toml").read_text()
    train = egt.loads(spec)
    table = train.shift_table()
    assert {g.state: g.ratio_exact for g in table.gears} == best.ratios
    df = r.to_pandas()
    assert list(df["P4.sun"]) == [t.sets["P4"].sun for t in r.candidates]
    assert "<table>" in r._repr_html_()


def test_synth_from_text_and_partitions() -> None:
    text = C4.read_text().replace('base = "../ford_c4_simpson.toml"', 'base = "examples/ford_c4_simpson.toml"')
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        whole = egt.synth(text, top=50)
    finally:
        os.chdir(cwd)
    parts = [egt.synth(C4, top=50, part=(i, 3)) for i in range(3)]
    merged = sorted((k for p in parts for k in key(p)), key=lambda x: (x[0], [(s, r) for s, r, _ in x[1]]))
    assert merged[: len(whole.candidates)] == key(whole)
    with pytest.raises(egt.SpecError, match="partition"):
        egt.synth(C4, part=(3, 3))


def test_bad_search_specs_are_spec_errors(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text(ZF.read_text().replace("P4 = {", "P9 = {").replace('base = "../zf_8hp70.toml"', f'base = "{ROOT / "examples" / "zf_8hp70.toml"}"'))
    with pytest.raises(egt.SpecError, match="sets.P9"):
        egt.synth(bad)
    with pytest.raises(egt.SpecSyntaxError):
        egt.synth("base = 3\n")


def test_synth_finds_the_6hp26_ravigneaux_teeth() -> None:
    r = egt.synth(ROOT / "examples" / "synth" / "zf_6hp26_lepelletier.toml")
    best = r.candidates[0]
    rv = best.sets["RV"]
    assert (best.sets["P1"].sun, best.sets["P1"].ring) == (37, 71)
    assert (rv.sun, rv.sun2, rv.ring) == (31, 38, 85)
    assert (rv.basic, rv.basic2) == (Fraction(85, 31), Fraction(85, 38))
    assert rv.planet2 is not None and rv.ring - rv.sun2 - 2 * rv.planet2 in (0, 1)
    # The real train's exact ratios are the candidate's.
    real = egt.load(str(ROOT / "examples" / "zf_6hp26_lepelletier.toml")).shift_table()
    assert {g.state: g.ratio_exact for g in real.gears} == best.ratios
    df = r.to_pandas()
    assert list(df["RV.sun2"]) == [c.sets["RV"].sun2 for c in r.candidates]


def test_synth_finds_a_stepped_planet() -> None:
    r = egt.synth(ROOT / "examples" / "synth" / "stepped_two_speed.toml")
    best = r.candidates[0]
    s = best.sets["S"]
    assert s.basic == Fraction(2263, 437) and s.planet2 is not None
    assert Fraction(s.ring * s.planet, s.sun * s.planet2) == s.basic
    assert s.sun + s.planet == s.ring - s.planet2
    # The bundled train (23/31/19/73) has the candidate's exact ratios.
    real = egt.load(str(ROOT / "examples" / "stepped_two_speed.toml")).shift_table()
    assert {g.state: g.ratio_exact for g in real.gears} == best.ratios
    assert list(r.to_pandas()["S.planet2"]) == [c.sets["S"].planet2 for c in r.candidates]
    # Statics and kinematics of the stepped planet in low (ring held, unit
    # sun torque and speed): the planet's ring wheel carries the sun mesh's
    # torque times planet / sun, and the planet turns at (1 - w_carrier)
    # sun / planet relative to its carrier.
    assert best.mesh_torque == pytest.approx(s.planet / s.sun, rel=1e-12)
    carrier = 1 / float(best.ratios["low"])
    assert best.planet_speed == pytest.approx((1 - carrier) * s.sun / s.planet, rel=1e-12)


def test_synth_with_free_element_positions_reports_the_layout() -> None:
    text = (ROOT / "examples" / "synth" / "zf_8hp70.toml").read_text()
    text = text.replace('base = "../zf_8hp70.toml"', f'base = "{ROOT / "examples" / "zf_8hp70.toml"}"')
    text = text.replace("[targets]", '[layout]\nD = "any"\nE = "any"\n\n[targets]')
    r = egt.synth(text)
    assert r.stats["layouts"] + r.stats["skipped_layouts"] == 28 * 28
    assert len(r.candidates) == 3
    for c in r.candidates:
        assert sorted(c.layout["D"]) == ["carrier3", "output"]
        assert [t.basic for t in c.sets.values()] == [Fraction(2), Fraction(2), Fraction(37, 23), Fraction(85, 23)]
    assert "layout.E" in r.to_pandas().columns
    # Each candidate's own train: its elements where the candidate puts them,
    # its exact ratios the candidate's.
    for c in r.candidates:
        t = c.train()
        assert sorted(t.elements["E"][1]) == sorted(c.layout["E"])
        assert {g.state: g.ratio_exact for g in t.shift_table().gears} == c.ratios


def test_bad_numbers_and_budgets_are_egt_errors(tmp_path: Path) -> None:
    """Issue 42 from Python: a NaN target, an efficiency above 1 and a broken
    base train are SpecErrors naming the field (no longer ``results: invalid
    type: null`` or a panic); a tolerance that prunes nothing is refused at
    the leaf budget; a negative partition or atlas size is an ArgumentError,
    not Python's OverflowError."""
    text = C4.read_text().replace('base = "../ford_c4_simpson.toml"', f'base = "{ROOT / "examples" / "ford_c4_simpson.toml"}"')
    with pytest.raises(egt.SpecError, match=r"targets\.ratios\.1"):
        egt.synth(text.replace('"1" = 2.46', '"1" = nan'))
    with pytest.raises(egt.SpecError, match=r"targets\.efficiency"):
        egt.synth(text.replace("[targets]", "[targets]\nefficiency = 1.5"))
    base = tmp_path / "base.toml"
    base.write_text((ROOT / "examples" / "ford_c4_simpson.toml").read_text().replace('links = ["input", "front_ring"]', "links = []"))
    with pytest.raises(egt.SpecError, match=r"base\.elements\[0\]\.links"):
        egt.synth(C4.read_text().replace('base = "../ford_c4_simpson.toml"', f'base = "{base}"'))
    with pytest.raises(egt.AnalysisError, match="max_leaves") as e:
        egt.synth("max_leaves = 20\n" + text.replace("tolerance = 0.005", "tolerance = 100"))
    assert e.value.kind == "budget"
    for bad in [(-1, 4), (0, 2**70)]:
        with pytest.raises(egt.ArgumentError, match="part"):
            egt.synth(C4, part=bad)
    for kwargs in [{"links": -1}, {"links": 7, "dof": 2**70}, {"links": 7, "part": (-1, 2)}]:
        with pytest.raises(egt.ArgumentError):
            egt.atlas(**kwargs)  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        egt.atlas(7.0)  # type: ignore[arg-type]
