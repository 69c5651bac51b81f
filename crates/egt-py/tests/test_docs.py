"""Every ```python block of docs/python.md runs on its own (from the
repository root, each in a fresh namespace), as a reader pastes it."""

from __future__ import annotations

import os
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
DOC = ROOT / "docs" / "python.md"


def test_python_blocks_of_the_guide_run(capsys: pytest.CaptureFixture[str]) -> None:
    import sympy  # noqa: F401  (a dev requirement: missing, the test fails)
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(), flags=re.S)
    assert len(blocks) >= 5
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        for block in blocks:
            exec(compile(block, str(DOC), "exec"), {})
    finally:
        os.chdir(cwd)
