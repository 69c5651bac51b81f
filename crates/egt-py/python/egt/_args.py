"""Argument checks of the Python layer, in one place: every bad Python
argument raises an :class:`egt.EgtError` that is also the ``ValueError`` or
``TypeError`` Python code expects, with the argument named."""

from __future__ import annotations

from numbers import Real
from typing import Any, Mapping

from ._egt import InputError


class ArgumentError(InputError, ValueError):
    """A Python argument with a bad value (too large, not finite, unknown key)."""


class ArgumentTypeError(InputError, TypeError):
    """A Python argument of the wrong type (a list where a mapping is expected, ...)."""


class ArgumentKeyError(ArgumentError, KeyError):
    """An unknown or missing key of a mapping argument."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


def number(value: Any, what: str) -> float:
    """``value`` as a float, or an :class:`ArgumentError` naming ``what`` when
    it is not a number or too large for one (an int or Fraction past about
    1.8e308). NaN and infinities pass: the core refuses them by field, as
    ``SpecError`` of kind ``non_finite``."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ArgumentTypeError(f"{what} must be a number, got {type(value).__name__}")
    try:
        return float(value)
    except OverflowError:
        # No repr of the value: a huge int or Fraction cannot even be printed.
        raise ArgumentError(f"{what} is beyond the range of double precision") from None


def count(value: Any, what: str, limit: int) -> int:
    """``value`` as a non-negative integer at most ``limit``."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise ArgumentTypeError(f"{what} must be an integer, got {type(value).__name__}")
    if value < 0 or value > limit:
        raise ArgumentError(f"{what} must be an integer from 0 to {limit}, got {value}")
    return value


def mapping(value: Any, what: str) -> Mapping[Any, Any]:
    """``value`` if it is a mapping, else an :class:`ArgumentTypeError` naming ``what``."""
    if not isinstance(value, Mapping):
        raise ArgumentTypeError(
            f"`{what}` must be a mapping of link names to values, got {type(value).__name__}"
        )
    return value
