"""The `egt` command line from Python: ``python -m egt check spec.toml``, and
the ``egt`` console script the wheel installs. It is the same Rust CLI as the
``egt`` binary (compiled into the extension), with the same exit codes."""

from __future__ import annotations

import os
import sys

from . import _fmu
from ._egt import cli


def main() -> None:
    """Run ``egt`` with the process's arguments and exit with its code."""
    # `egt fmu` looks for its library beside the running executable, which is
    # Python here: point it at the wheel's unless the caller chose one.
    library = _fmu.bundled()
    if library is not None:
        os.environ.setdefault("EGT_FMU_LIBRARY", str(library))
    sys.stdout.flush()
    raise SystemExit(cli(sys.argv[1:]))


if __name__ == "__main__":
    main()
