"""Gear states of a transmission and the shift table."""

from __future__ import annotations

import json
from fractions import Fraction

import pytest

import egt
from conftest import EXAMPLES

TWO_SPEED = """
frame = "case"
[[planetary]]
name = "P"
sun = "sun"
ring = "ring"
carrier = "carrier"
teeth = { sun = 30, ring = 72 }
[[elements]]
name = "B"
kind = "brake"
links = ["ring"]
[[elements]]
name = "C"
kind = "clutch"
links = ["sun", "carrier"]
[transmission]
input = "sun"
output = "carrier"
states = { low = ["B"], direct = ["C"] }
"""


def test_shift_table_of_a_two_speed() -> None:
    train = egt.loads(TWO_SPEED)
    table = train.shift_table()
    assert (table.input, table.output) == ("sun", "carrier")
    low, direct = table.gears
    assert low.state == "low" and low.engaged == ("B",)
    assert low.ratio_exact == Fraction(17, 5)  # 1 + 72/30
    assert direct.ratio_exact == 1
    # The brake holds the ring against z_r/z_s of the input torque.
    assert low.elements[0].element == "B"
    assert low.elements[0].torque == pytest.approx(72 / 30)
    assert low.speeds["carrier"] == pytest.approx(5 / 17)
    assert table.forward == (True, True)
    assert table.steps[0].exact == Fraction(17, 5)
    assert table.spread is not None and table.spread.lowest == "low"
    (shift,) = table.shifts
    assert (shift.source, shift.target, shift.off, shift.on, shift.single_swap) == ("low", "direct", ("B",), ("C",), True)
    assert table["direct"].ratio == 1.0
    assert train.gear("low").ratio == pytest.approx(3.4)
    json.dumps(table.to_dict())


def test_ford_c4_ratios() -> None:
    table = egt.load(EXAMPLES / "ford_c4_simpson.toml").shift_table()
    ratios = {g.state: g.ratio for g in table.gears}
    assert ratios["1"] == pytest.approx(2.46, abs=0.01)
    assert ratios["2"] == pytest.approx(1.46, abs=0.01)
    assert ratios["3"] == pytest.approx(1.0)
    assert ratios["R"] == pytest.approx(-2.18, abs=0.01)


def test_transmission_errors(fig3: egt.Train) -> None:
    train = egt.loads(TWO_SPEED)
    with pytest.raises(egt.TransmissionError) as info:
        train.gear("Low")
    e = info.value
    assert (e.kind, e.state, e.suggestion) == ("unknown_state", "Low", "low")
    with pytest.raises(egt.TransmissionError) as info2:
        fig3.shift_table()
    assert info2.value.kind == "no_states"
    # A state that leaves two DOF names the free links.
    spec = TWO_SPEED.replace('states = { low = ["B"], direct = ["C"] }', 'states = { low = ["B"], neutral = [] }')
    with pytest.raises(egt.TransmissionError) as info3:
        egt.loads(spec).shift_table()
    assert info3.value.kind == "underconstrained" and info3.value.state == "neutral"


def test_shift_table_to_pandas() -> None:
    import pandas  # noqa: F401  (a dev requirement: missing, the test fails)
    df = egt.loads(TWO_SPEED).shift_table().to_pandas()
    assert list(df.index) == ["low", "direct"]


def test_batch_over_a_gear_state() -> None:
    train = egt.loads(TWO_SPEED)
    plan = train.batch("dynamics", gear_state="low")
    assert "lambda.B" in plan.outputs
    res = plan.evaluate({"speed.sun": [100.0, 200.0], "torque.sun": 10.0, "accel.sun": 0.0})
    assert res.ok.all()
    assert res.driving == ("carrier",)  # the output's torque is solved
    assert res["speed.carrier"] == pytest.approx([100 * 5 / 17, 200 * 5 / 17])
    # Static: the output holds the input torque times the ratio 17/5.
    assert res.driving_torque("carrier")[0] == pytest.approx(-10.0 * 17 / 5)
    assert res["lambda.B"][0] != 0.0
    with pytest.raises(egt.TransmissionError):
        train.batch("dynamics", gear_state="top")
