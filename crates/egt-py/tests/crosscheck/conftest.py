"""Counts what the randomized cross-check suite compared, and prints the
counts at the end of the run (how many trains of each shape, and how many
results of each kind agreed with the independent reference)."""

from __future__ import annotations

from collections import Counter
from typing import Any

import pytest

CHECKED: Counter[str] = Counter()


@pytest.fixture
def checked() -> Counter[str]:
    return CHECKED


def pytest_terminal_summary(terminalreporter: Any) -> None:
    if not CHECKED:
        return
    terminalreporter.write_sep("-", "cross-check: cases compared with the independent references")
    for key in sorted(CHECKED):
        terminalreporter.write_line(f"{key}: {CHECKED[key]}")
