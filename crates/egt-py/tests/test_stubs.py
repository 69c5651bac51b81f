"""The hand-written stub `egt/_egt.pyi` agrees with the built module
(mypy.stubtest), and the package type-checks under mypy --strict."""

from __future__ import annotations

import pathlib
import subprocess
import sys

import pytest

CRATE = pathlib.Path(__file__).resolve().parents[1]

import mypy  # noqa: F401  (a dev requirement: missing, the tests fail)


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", *args],
        cwd=CRATE,
        capture_output=True,
        text=True,
        timeout=600,
    )


def test_stubtest() -> None:
    r = _run(
        "mypy.stubtest",
        "egt",
        "--mypy-config-file",
        str(CRATE / "pyproject.toml"),
        "--allowlist",
        str(CRATE / "stubtest-allowlist.txt"),
    )
    assert r.returncode == 0, r.stdout + r.stderr


def test_mypy_strict() -> None:
    r = _run("mypy", "--config-file", str(CRATE / "pyproject.toml"))
    assert r.returncode == 0, r.stdout + r.stderr
