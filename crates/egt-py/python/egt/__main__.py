"""The `egt` command line from Python: ``python -m egt check spec.toml``, and
the ``egt`` console script the wheel installs. It is the same Rust CLI as the
``egt`` binary (compiled into the extension), with the same exit codes."""

from __future__ import annotations

import sys

from ._egt import cli


def main() -> None:
    """Run ``egt`` with the process's arguments and exit with its code."""
    sys.stdout.flush()
    raise SystemExit(cli(sys.argv[1:]))


if __name__ == "__main__":
    main()
