"""`egt batch` end to end against the in-process rate of the same job,
measured in turns so that both see the same machine.

    python3 bench/batch_ratio.py [ROUNDS] [THREADS]

Issue 13's target: `egt batch` writing Parquet on 2 threads at no less than
70 % of the in-process batch rate. The in-process job is the divan benchmark
`driving_torque_column_set` of `crates/egt-core/benches/scenarios.rs`
(`egt batch`'s own: the 6-link planetary chain's driving torque for new
loads and ratios, column-major, on the batch pool); the command is `egt
batch --threads THREADS target/speed_accuracy/planetary_chain_6.toml --grid
torque.c2=-10:-100:10000 --grid ratio.P1/sun-planet=-0.5:-0.9:1000
--columns driving_torque.s1 --output parquet` (10^7 rows) to /dev/null.

Each round runs the benchmark once (200 samples) and then the command ten
times (started with `os.posix_spawn` and timed around it, as
`bench/alternate.py` does), and prints both rates, fastest and median, and
their ratios. The spec comes from the `speed_accuracy` example (`make chart`,
or `cargo run --release -p egt-core --example speed_accuracy --
target/speed_accuracy`); the binaries are built here first.
"""

import json
import os
import re
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SPEC = os.path.join(ROOT, "target", "speed_accuracy", "planetary_chain_6.toml")
ROWS = 10_000 * 1_000


def build() -> tuple[str, str]:
    """The release `egt` and the benchmark's executable."""
    subprocess.run(["cargo", "build", "-q", "--release", "-p", "egt-cli"], cwd=ROOT, check=True)
    out = subprocess.run(
        ["cargo", "bench", "-q", "-p", "egt-core", "--bench", "scenarios", "--no-run", "--message-format=json"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    bench = None
    for line in out.splitlines():
        message = json.loads(line)
        if message.get("reason") == "compiler-artifact" and message["target"]["name"] == "scenarios":
            bench = message.get("executable") or bench
    if bench is None:
        sys.exit("no executable for the `scenarios` benchmark")
    return os.path.join(ROOT, "target", "release", "egt"), bench


def in_process(bench: str) -> tuple[float, float]:
    """The benchmark's fastest and median rate, millions of rows a second."""
    out = subprocess.run(
        [bench, "--bench", "driving_torque_column_set", "--sample-count", "200"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    rates = [float(r) for r in re.findall(r"([0-9.]+) Mitem/s", out)]
    if len(rates) < 3:
        sys.exit(f"no rates in the benchmark's output:\n{out}")
    # divan's columns: fastest, slowest, median, mean.
    return rates[0], rates[2]


def end_to_end(egt: str, threads: int, runs: int = 10) -> tuple[float, float]:
    """`egt batch`'s fastest and median rate, millions of rows a second."""
    command = [
        egt,
        "batch",
        "--threads",
        str(threads),
        SPEC,
        "--grid",
        "torque.c2=-10:-100:10000",
        "--grid",
        "ratio.P1/sun-planet=-0.5:-0.9:1000",
        "--columns",
        "driving_torque.s1",
        "--output",
        "parquet",
    ]
    null = os.open(os.devnull, os.O_WRONLY)
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        pid = os.posix_spawn(egt, command, os.environ, file_actions=[(os.POSIX_SPAWN_DUP2, null, 1)])
        _, status = os.waitpid(pid, 0)
        times.append(time.perf_counter() - start)
        if status != 0:
            sys.exit(f"{' '.join(command)}: exit status {status}")
    os.close(null)
    return ROWS / min(times) / 1e6, ROWS / statistics.median(times) / 1e6


def main() -> int:
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    threads = int(sys.argv[2]) if len(sys.argv) > 2 else 2
    if not os.path.isfile(SPEC):
        sys.exit(f"{SPEC} is missing: run `make chart` (or the speed_accuracy example) first")
    egt, bench = build()
    print("round | in process, fastest / median | egt batch, fastest / median | ratio of fastest / of medians")
    for r in range(1, rounds + 1):
        (fast, median), (ours_fast, ours_median) = in_process(bench), end_to_end(egt, threads)
        print(
            f"{r} | {fast:.0f} / {median:.0f} M rows/s | {ours_fast:.0f} / {ours_median:.0f} M rows/s | "
            f"{100 * ours_fast / fast:.1f} / {100 * ours_median / median:.1f} %"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
