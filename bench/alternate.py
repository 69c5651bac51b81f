"""Time whole commands, alternating them, and print each one's best, median
and mean wall time.

    python3 bench/alternate.py N "CMD ARGS..." ["CMD ARGS..." ...]

Each command runs N times; run i of every command comes before run i + 1 of
any, so that a change in the host's load during the measurement falls on
all of them alike. Standard output goes to /dev/null, standard error is
kept for a failure. A command is split on spaces (no shell): give an
environment variable as `env NAME=VALUE CMD ...`.

Processes are started with `os.posix_spawn` and reaped with `os.waitpid`,
timed around both: no pipe, no shell, no Python `subprocess` bookkeeping,
so the figure is close to the process's own life (about 0.05 ms more than a
C program timing the same way, on the AMD EPYC host of docs/performance.md (history: git log -p -- docs/benchmarks.md)).
Used for `egt batch`'s end-to-end figures there.
"""

import os
import statistics
import sys
import time


def main() -> int:
    if len(sys.argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    runs = int(sys.argv[1])
    commands = [c.split() for c in sys.argv[2:]]
    for c in commands:
        if not os.path.isfile(c[0]) and "/" not in c[0]:
            c[0] = next(
                (
                    os.path.join(d, c[0])
                    for d in os.environ.get("PATH", "").split(os.pathsep)
                    if os.path.isfile(os.path.join(d, c[0]))
                ),
                c[0],
            )
    null = os.open(os.devnull, os.O_WRONLY)
    times = [[] for _ in commands]
    for _ in range(runs):
        for k, c in enumerate(commands):
            start = time.perf_counter()
            pid = os.posix_spawn(
                c[0], c, os.environ, file_actions=[(os.POSIX_SPAWN_DUP2, null, 1)]
            )
            _, status = os.waitpid(pid, 0)
            times[k].append(time.perf_counter() - start)
            if status != 0:
                print(f"{' '.join(c)}: exit status {status}", file=sys.stderr)
                return 1
    for c, t in zip(sys.argv[2:], times):
        print(
            f"best {min(t) * 1e3:8.2f}  median {statistics.median(t) * 1e3:8.2f}  "
            f"mean {statistics.fmean(t) * 1e3:8.2f} ms  {c}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
