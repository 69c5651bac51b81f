"""Speed units at the edges: rpm in gives rpm out (the Willis equations are
homogeneous, so exact values survive), conversions agree with SI, pint
quantities are accepted, unknown units are refused."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

import egt


def test_rpm_in_rpm_out_exactly(fig3: egt.Train) -> None:
    si = fig3.kinematics({"2": 100.0})
    rpm = fig3.kinematics({"2": 100}, unit="rpm")
    assert rpm.unit == "rpm"
    # Same numbers: kinematics does not care about the unit, only the label does.
    np.testing.assert_array_equal(rpm.speeds, si.speeds)
    assert rpm.exact is not None and rpm.exact["2"] == Fraction(100)
    # 1000 rpm is 1000 pi/30 rad/s, and back.
    k = fig3.kinematics({"2": 1000}, unit="rpm")
    np.testing.assert_allclose(k.to("rad/s").speeds, fig3.kinematics({"2": 1000 * math.pi / 30}).speeds, rtol=1e-14)
    np.testing.assert_allclose(k.to("rad/s").to("rpm").speeds, k.speeds, rtol=1e-15)
    assert k.to("rad/s").exact is None
    assert k.to("rev/s").exact == {n: x / 60 for n, x in k.exact.items()}


def test_unknown_units_and_spec_speeds_are_refused(fig3: egt.Train) -> None:
    with pytest.raises(egt.ArgumentError, match="rpm"):
        fig3.kinematics({"2": 1.0}, unit="furlong/fortnight")
    with pytest.raises(egt.ArgumentError, match="rad/s"):
        fig3.kinematics(unit="rpm")


def test_pint_quantities(fig3: egt.Train) -> None:
    import pint

    ureg = pint.UnitRegistry()
    k = fig3.kinematics({"2": 1000 * ureg.revolution / ureg.minute})
    assert k.unit == "rad/s"
    np.testing.assert_allclose(k.speeds, fig3.kinematics({"2": 1000 * math.pi / 30}).speeds, rtol=1e-14)
    r = fig3.kinematics({"2": 2 * ureg.revolution / ureg.second}, unit="rpm")
    assert r["2"] == pytest.approx(120.0, rel=1e-14)
    with pytest.raises(egt.ArgumentError, match="angular speed"):
        fig3.kinematics({"2": 3 * ureg.meter})


def test_power_takes_rpm_and_answers_in_si(fig3: egt.Train) -> None:
    si = fig3.power({"2": 100 * math.pi / 30})
    rpm = fig3.power({"2": 100}, unit="rpm")
    assert rpm.input_power == pytest.approx(si.input_power, rel=1e-14)
    np.testing.assert_allclose(rpm.speeds.speeds, si.speeds.speeds, rtol=1e-14)
    assert rpm.speeds.unit == "rad/s"
