"""egt-fmu's shared library, which the wheel carries beside this file: what
`Train.export_fmu` and the wheel's `egt fmu` put in each unit unless
``EGT_FMU_LIBRARY`` names another (docs/fmu.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

BUNDLED = Path(__file__).with_name("libegt_fmu.so")


def bundled() -> Optional[Path]:
    """The wheel's library, or None where the package has none (a build
    without `make wheel`, e.g. ``maturin develop``)."""
    return BUNDLED if BUNDLED.is_file() else None
