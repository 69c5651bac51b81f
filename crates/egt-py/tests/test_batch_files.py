"""`egt batch`'s Parquet files read by another implementation: Apache Arrow's
C++ reader (pyarrow) finds the CSV's cells in them, and row-group statistics
that agree with the values. parquet-rs writes the files, with egt's
settings (Snappy but for the solver's doubles, a grid's columns
dictionary-encoded, the row numbers delta-encoded, columns of nulls); the
Rust tests read them back with parquet-rs, these with a reader that shares
no code with it."""

from __future__ import annotations

import io
import math
import subprocess
import sys
from pathlib import Path

import pyarrow.csv as pa_csv  # a dev requirement: missing, the tests fail
import pyarrow.parquet as pq
import pytest

ROOT = Path(__file__).resolve().parents[3]

# Each case's arguments and exit code (1: some rows failed, each reported
# in its row).
CASES = {
    # Two row groups of 65 536 rows (the last shorter), every output; the
    # first ratio is Fig. 3's lock (tau_2 = 1 / tau_1), so the first row
    # group's outputs have nulls and the other none. The grid's columns are
    # dictionary-encoded (runs of 1 000 rows; a period of 1 000 rows).
    "grid": (["examples/fig3_example61.toml", "--grid", "torque.4=-10:-100:100", "--grid", "ratio.G2=-1.5:-2.5:1000"], 1),
    # Through the lock of Fig. 3: rows refused (nulls) and warned.
    "lock": (["examples/fig3_example61.toml", "--grid", "ratio.G2=-1.5000001:-1.4999999:21"], 1),
    # The shift table: a text column of states before the numbers.
    "states": (["examples/zf_8hp70.toml", "--state", "all", "--set", "speed.input=200", "--grid", "torque.input=0:400:5000"], 0),
}


def batch(case: str, output: str) -> bytes:
    args, code = CASES[case]
    r = subprocess.run(
        [sys.executable, "-m", "egt", "batch", *args, "--output", output], cwd=ROOT, capture_output=True
    )
    assert r.returncode == code, r.stderr.decode()
    return r.stdout


@pytest.mark.parametrize("case", sorted(CASES))
def test_parquet_read_by_arrow_cpp_holds_the_csv_cells(case: str) -> None:
    parquet = pq.ParquetFile(io.BytesIO(batch(case, "parquet")))
    table = parquet.read()
    csv = pa_csv.read_csv(
        io.BytesIO(batch(case, "csv")), convert_options=pa_csv.ConvertOptions(strings_can_be_null=True)
    )
    assert table.column_names == csv.column_names
    assert table.num_rows == csv.num_rows > 0
    for name in table.column_names:
        ours, theirs = table.column(name).to_pylist(), csv.column(name).to_pylist()
        for row, (a, b) in enumerate(zip(ours, theirs)):
            if a is None:
                assert b is None or b == "", (name, row, b)
            elif isinstance(a, float):
                assert isinstance(b, (int, float)) and (a == b or (math.isnan(a) and math.isnan(b))), (name, row, a, b)
            else:
                assert str(a) == str(b), (name, row, a, b)
    if case == "grid":
        assert parquet.metadata.num_row_groups == 2
    if case == "lock":
        assert table.column("error").null_count < table.num_rows
        assert table.column("warning").null_count < table.num_rows
    # Numbers were written, not only nulls.
    outputs = [n for n in table.column_names if n not in ("row", "state", "warning", "error")]
    assert all(table.column(n).null_count < table.num_rows for n in outputs)


@pytest.mark.parametrize("case", sorted(CASES))
def test_parquet_statistics_agree_with_the_values(case: str) -> None:
    """Every number column's null count, and the row numbers' min and max.
    A double's min and max are compared where pyarrow reads them: pyarrow 26
    does not, under the IEEE 754 total order parquet-rs 60 declares for
    every double column (parquet-rs computes them)."""
    parquet = pq.ParquetFile(io.BytesIO(batch(case, "parquet")))
    meta = parquet.metadata
    names = parquet.schema_arrow.names
    rows = doubles = 0
    for g in range(meta.num_row_groups):
        group = meta.row_group(g)
        for c in range(group.num_columns):
            chunk = group.column(c)
            if chunk.physical_type not in ("DOUBLE", "INT64"):
                continue
            values = parquet.read_row_group(g, columns=[names[c]]).column(0).to_pylist()
            present = [v for v in values if v is not None]
            stats = chunk.statistics
            assert stats is not None and stats.null_count == len(values) - len(present), (g, names[c])
            if chunk.physical_type == "INT64":
                assert stats.has_min_max and (stats.min, stats.max) == (min(present), max(present)), g
                rows += 1
            elif stats.has_min_max:
                assert (stats.min, stats.max) == (min(present), max(present)), (g, names[c])
            doubles += chunk.physical_type == "DOUBLE"
    assert rows == meta.num_row_groups and doubles >= meta.num_row_groups
