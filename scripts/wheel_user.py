"""What a new user does with the wheel, run by scripts/test_wheel.sh in a
clean virtualenv (no Rust on PATH, the wheel and its extras from pip):
the README's Python block and every block of docs/python.md as written, each
in a fresh namespace; the 8HP shift chart and a train's lever diagram drawn
with matplotlib, and the notebook views; a train pickled into a process pool;
a result's to_dict() equal to the `egt` command's JSON."""

from __future__ import annotations

import json
import pathlib
import pickle
import re
import subprocess
import sys
import tempfile
from concurrent.futures import ProcessPoolExecutor

import matplotlib

matplotlib.use("Agg")

import egt  # noqa: E402


def blocks(path: str) -> list[str]:
    found = re.findall(r"```python\n(.*?)```", pathlib.Path(path).read_text(), flags=re.S)
    assert found, f"no python blocks in {path}"
    return found


def output_speed(train: egt.Train) -> float:
    return train.kinematics({"2": 100.0})["4"]


def main() -> None:
    ran = 0
    for path in ("README.md", "docs/python.md"):
        for code in blocks(path):
            exec(compile(code, path, "exec"), {"__name__": "__doc_block__"})
            ran += 1

    out = pathlib.Path(tempfile.mkdtemp())
    zf = egt.load("examples/zf_8hp70.toml")
    table = zf.shift_table()
    ax = table.plot("ladder")
    ax.figure.savefig(out / "8hp_ladder.png")
    assert len(ax.lines) >= len(table.gears)
    ax = egt.load("examples/fig3_example61.toml").speed_ladder()
    ax.figure.savefig(out / "fig3_ladder.png")
    assert "<table>" in table._repr_html_() and "<" in zf._repr_html_()

    fig3 = egt.load("examples/fig3_example61.toml")
    assert pickle.loads(pickle.dumps(fig3)).dof == 1
    with ProcessPoolExecutor(2) as pool:
        speeds = list(pool.map(output_speed, [fig3] * 4))
    assert speeds == [15.625] * 4, speeds

    cmd = pathlib.Path(sys.executable).parent / "egt"
    cli = subprocess.run(
        [str(cmd), "kinematics", "examples/fig3_example61.toml", "--input", "2=100", "--format", "json"],
        capture_output=True, text=True, check=True,
    )
    assert json.loads(cli.stdout) == fig3.kinematics({"2": 100}).to_dict()
    print(f"wheel: {ran} documented blocks ran; plots, notebook views, process pool and CLI document checked")


if __name__ == "__main__":
    main()
