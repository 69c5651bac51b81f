"""Speed units: egt computes in SI (rad/s, N m, W); these convert at the edges.

``rad/s`` (the default), ``rpm``, ``rev/s`` and ``deg/s`` are accepted
wherever a method takes ``unit=``, and a pint ``Quantity`` of angular speed
(when pint is installed) is accepted as an input speed in any unit pint knows.
"""

from __future__ import annotations

import math
from typing import Any, Dict

from ._args import ArgumentError

RAD_PER_S: Dict[str, float] = {
    "rad/s": 1.0,
    "rpm": math.pi / 30.0,
    "rev/s": 2.0 * math.pi,
    "deg/s": math.pi / 180.0,
}
"""How many rad/s one of each unit is."""


def factor(unit: str) -> float:
    """rad/s per ``unit``; an unknown unit is refused, naming the known ones."""
    try:
        return RAD_PER_S[unit]
    except (KeyError, TypeError):
        raise ArgumentError(
            f"unknown speed unit {unit!r}: use one of {', '.join(RAD_PER_S)}"
        ) from None


def is_quantity(v: Any) -> bool:
    """Whether ``v`` looks like a pint Quantity (duck-typed: pint stays optional)."""
    return hasattr(v, "magnitude") and hasattr(v, "to") and hasattr(v, "units")


def quantity_in(v: Any, unit: str, what: str) -> float:
    """A pint Quantity's magnitude in ``unit`` (rad/s, rpm, ...), through
    rad/s and the one table of factors above."""
    k = factor(unit)
    try:
        return float(v.to("rad/s").magnitude) / k
    except Exception as e:  # pint's DimensionalityError and friends
        raise ArgumentError(f"{what}: {v!s} is not an angular speed ({e})") from None
