"""Issue 12: bad Python arguments raise egt.EgtError subclasses (that are also
the ValueError / TypeError / KeyError Python code expects) naming the
argument; exact numbers past the size limit and results that overflow are
refused, never returned as inf or NaN."""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Callable

import numpy as np
import pytest

import egt

SIMPLE = """
frame = "ring"
[[planetary]]
name = "P"
sun = "sun"
ring = "ring"
carrier = "carrier"
teeth = { sun = 30, ring = 72, planet = 21 }
[[links]]
name = "sun"
inertia = 1e-3
[[links]]
name = "carrier"
inertia = 2e-3
[analysis]
speeds = { sun = 100 }
torques = { carrier = -10 }
accelerations = { sun = 1 }
driving = ["sun"]
"""


@pytest.fixture
def train() -> egt.Train:
    return egt.loads(SIMPLE)


CASES: list[tuple[str, Callable[[egt.Train], Any], type, str]] = [
    ("huge int speed", lambda t: t.kinematics({"sun": 10**400}), ValueError, "speed of 'sun'"),
    ("huge Fraction speed", lambda t: t.kinematics({"sun": Fraction(10**5000, 3)}), ValueError, "speed of 'sun'"),
    ("huge exponent text", lambda t: t.kinematics({"sun": "1e999999"}), egt.EgtError, "exponent"),
    ("two fraction bars", lambda t: t.kinematics({"sun": "1/3/4"}), egt.EgtError, "not a number"),
    ("a list for inputs", lambda t: t.kinematics(["sun"]), TypeError, "inputs"),  # type: ignore[arg-type]
    ("a string for inputs", lambda t: t.kinematics("sun"), TypeError, "inputs"),  # type: ignore[arg-type]
    ("huge every", lambda t: t.simulate(0.1, every=10**30), ValueError, "every"),
    ("curve without torque", lambda t: t.stability(curves=[{"link": "sun"}]), KeyError, "torque"),
    ("non-numeric torque", lambda t: t.dynamics(torques={"carrier": "x"}), TypeError, "torques"),  # type: ignore[dict-item]
    ("infinite torque", lambda t: t.dynamics(torques={"carrier": float("inf")}), egt.SpecError, "finite"),
]


@pytest.mark.parametrize("name,call,python_type,words", CASES, ids=[c[0] for c in CASES])
def test_bad_arguments_raise_egt_errors(
    train: egt.Train, name: str, call: Callable[[egt.Train], Any], python_type: type, words: str
) -> None:
    with pytest.raises(egt.EgtError) as info:
        call(train)
    assert isinstance(info.value, python_type), (name, type(info.value))
    assert words in str(info.value), (name, str(info.value))


def test_unknown_batch_column_is_an_egt_key_error(train: egt.Train) -> None:
    plan = train.batch("dynamics")
    with pytest.raises(egt.EgtError) as info:
        plan.column("no.such.column")
    assert isinstance(info.value, KeyError) and "no.such.column" in str(info.value)


def test_overflowing_results_are_refused(train: egt.Train) -> None:
    big = egt.loads(SIMPLE.replace("inertia = 1e-3", "inertia = 1e308"))
    with pytest.raises(egt.NonFiniteError) as info:
        big.dynamics(accelerations={"sun": 1e308})
    assert "overflow" in str(info.value)


def test_threads_are_capped_not_spawned(train: egt.Train) -> None:
    plan = train.batch("kinematics")
    result = plan.run(plan.base, threads=10**6)
    assert len(result) == 1


def test_shape_and_keyword_errors_are_egt_errors(fig3: egt.Train) -> None:
    """Errors raised by the Python layer and by the bindings' argument checks
    are EgtErrors too (and still the ValueError/TypeError/KeyError Python expects)."""
    cases = [
        lambda: fig3.batch_kinematics({"2": 1.0}, teeth=np.ones((3, 2), dtype=int)),
        lambda: fig3.batch("kinematics").run(np.zeros((2, 99))),
        lambda: fig3.batch("nonsense"),
        lambda: fig3.simulate(0.1, method="euler"),
        lambda: egt.load("examples/zf_8hp70.toml").shift_table()["9"],
    ]
    for case in cases:
        with pytest.raises(egt.EgtError) as info:
            case()
        assert isinstance(info.value, (ValueError, TypeError, KeyError)), type(info.value)


def test_refused_rows_outside_the_matrix_are_argument_errors(train: egt.Train) -> None:
    """Issue 42: ``plan.run((params, refused))`` with a refused row that is not
    a row of the matrix raised NumPy's IndexError; it is an ArgumentError now,
    and a value that is not a RowError a TypeError."""
    plan = train.batch("dynamics")
    params, _ = plan.params()
    for bad in [{5: egt.RowError(5, "x", "y")}, {-1: egt.RowError(-1, "x", "y")}]:
        with pytest.raises(egt.ArgumentError, match="refused row"):
            plan.run((params, bad))
    with pytest.raises(TypeError, match="RowError"):
        plan.run((params, {0: "no"}))
    ok = plan.run((params, {0: egt.RowError(0, "invalid", "refused")}))
    assert not ok.ok[0]
