//! `egt batch`'s Parquet and Arrow files read back against its CSV, and
//! the block pipeline.

use arrow_array::{Array, Float64Array, RecordBatch, StringArray, UInt64Array};

use super::tests::batch_bytes as batch;

fn example(name: &str) -> String {
    format!("{}/../../examples/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The cells of a CSV line (quoted fields with doubled quotes).
fn cells(line: &str) -> Vec<String> {
    let (mut out, mut cur, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(std::mem::take(&mut cur)),
            c => cur.push(c),
        }
    }
    out.push(cur);
    out
}

/// Every cell of `batches` against the CSV of the same batch: numbers
/// bit for bit (the CSV's shortest round-trip decimals), empty cells as
/// nulls, texts equal.
fn assert_same_as_csv(batches: &[RecordBatch], csv: &str) {
    let mut lines = csv.lines();
    let header = cells(lines.next().unwrap_or_default());
    let schema = batches[0].schema();
    let names: Vec<&str> = schema.fields().iter().map(|f| f.name().as_str()).collect();
    assert_eq!(names, header);
    let rows: Vec<Vec<String>> = lines.map(cells).collect();
    let mut r = 0;
    for b in batches {
        for i in 0..b.num_rows() {
            let row = &rows[r];
            for (c, col) in b.columns().iter().enumerate() {
                let cell = &row[c];
                let what = format!("row {r} column {}", header[c]);
                if let Some(a) = col.as_any().downcast_ref::<Float64Array>() {
                    if cell.is_empty() {
                        assert!(a.is_null(i), "{what}: {} for an empty cell", a.value(i));
                    } else {
                        let v: f64 = cell.parse().unwrap_or_else(|e| panic!("{what}: {e}"));
                        assert!(a.is_valid(i), "{what}: null for {cell}");
                        assert_eq!(a.value(i).to_bits(), v.to_bits(), "{what}");
                    }
                } else if let Some(a) = col.as_any().downcast_ref::<StringArray>() {
                    let got = if a.is_null(i) { "" } else { a.value(i) };
                    assert_eq!(got, cell, "{what}");
                } else if let Some(a) = col.as_any().downcast_ref::<UInt64Array>() {
                    assert_eq!(a.value(i).to_string(), *cell, "{what}");
                } else {
                    panic!("{what}: unexpected type {:?}", col.data_type());
                }
            }
            r += 1;
        }
    }
    assert_eq!(r, rows.len(), "every CSV row is in the columnar file");
}

fn parquet_batches(bytes: Vec<u8>) -> Vec<RecordBatch> {
    let dir = std::env::temp_dir().join(format!("egt-columnar-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let path = dir.join(format!("{}.parquet", bytes.len()));
    std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("{e}"));
    let file = std::fs::File::open(&path).unwrap_or_else(|e| panic!("{e}"));
    let builder = parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder::try_new(file)
        .unwrap_or_else(|e| panic!("{e}"));
    // The row numbers are delta-encoded in every row group.
    for g in builder.metadata().row_groups() {
        let row = g.column(0);
        assert_eq!(row.column_path().string(), "row");
        let delta = parquet::basic::Encoding::DELTA_BINARY_PACKED;
        assert!(
            row.encodings().any(|e| e == delta),
            "row encodings {:?}",
            row.encodings().collect::<Vec<_>>()
        );
    }
    builder
        .build()
        .unwrap_or_else(|e| panic!("{e}"))
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("{e}"))
}

fn arrow_batches(bytes: Vec<u8>) -> Vec<RecordBatch> {
    arrow_ipc::reader::FileReader::try_new(std::io::Cursor::new(bytes), None)
        .unwrap_or_else(|e| panic!("{e}"))
        .collect::<Result<Vec<_>, _>>()
        .unwrap_or_else(|e| panic!("{e}"))
}

/// A grid's or a zip's columns filled in runs hold what row-by-row
/// setting gives, whatever the block's start and length.
#[test]
fn grids_and_zips_fill_blocks_as_row_by_row() {
    use super::design::{Layout, Rows};
    let grid = |axes: &[usize], zip: usize| Rows::Product {
        zipped: (0..zip.min(1) * 2)
            .map(|z| (10 + z, (0..zip).map(|v| (100 * z + v) as f64).collect()))
            .collect(),
        axes: (axes.iter().enumerate())
            .map(|(a, &n)| (2 * a, (0..n).map(|v| (1000 * (a + 1) + v) as f64).collect()))
            .collect(),
        count: axes.iter().product::<usize>() * zip.max(1),
    };
    for (axes, zip) in [
        (vec![1000, 1000], 0),
        (vec![3, 5, 7], 0),
        (vec![7], 4),
        (vec![], 9),
        (vec![2, 1, 3], 5),
    ] {
        let rows = grid(&axes, zip);
        for (start, len) in [(0, 1), (0, 64), (5, 17), (999, 1002), (13, 300)] {
            let len = len.min(rows.count().saturating_sub(start));
            let mut by_columns = vec![f64::NAN; 12 * len];
            let mut by_rows = vec![f64::NAN; 12 * len];
            assert!(rows.fill((start, len), &mut by_columns, Layout::Columns));
            assert!(rows.fill((start, len), &mut by_rows, Layout::Rows(12)));
            // The varied columns only, in reverse order of their index.
            let Rows::Product { zipped, axes, .. } = &rows else {
                unreachable!()
            };
            let mut set: Vec<usize> = zipped.iter().chain(axes).map(|z| z.0).collect();
            set.sort_unstable_by(|a, b| b.cmp(a));
            let mut slot = [None; 12];
            for (j, &c) in set.iter().enumerate() {
                slot[c] = Some(j);
            }
            let mut by_varied = vec![f64::NAN; set.len() * len];
            assert!(rows.fill((start, len), &mut by_varied, Layout::Varied(&slot)));
            for r in 0..len {
                let mut want = [f64::NAN; 12];
                rows.set(start + r, |c, v| want[c] = v)
                    .unwrap_or_else(|e| panic!("{e}"));
                for (c, w) in want.iter().enumerate() {
                    // (A column not varied is NaN in `want` and left out.)
                    let varied = slot[c].map_or(f64::NAN, |j| by_varied[j * len + r]);
                    for (got, layout) in [
                        (by_columns[c * len + r], "columns"),
                        (by_rows[r * 12 + c], "rows"),
                        (varied, "varied columns"),
                    ] {
                        assert!(
                            got.to_bits() == w.to_bits(),
                            "{axes:?} zip {zip} by {layout}: row {} column {c}: {got} against {w}",
                            start + r
                        );
                    }
                }
            }
        }
    }
    assert!(!Rows::Listed(super::rows::Listed::empty()).fill((0, 0), &mut [], Layout::Columns));
}

/// Blocks come back in order whatever order they finish in; the writer
/// solves blocks too, between its writes; an error of the writer stops
/// the helpers within the window.
#[test]
fn in_order_writes_blocks_in_order_and_stops_on_an_error() {
    use super::order::{AHEAD, Buffers, in_order};
    use std::sync::atomic::{AtomicUsize, Ordering};
    let all = 40;
    let solved = AtomicUsize::new(0);
    let solvers = std::sync::Mutex::new(std::collections::HashMap::new());
    let solve = |(b, i): (&mut Buffers, usize)| {
        b.params.push(i as f64);
        // Later blocks finish sooner.
        std::thread::sleep(std::time::Duration::from_micros(((all - i) * 50) as u64));
        solved.fetch_add(1, Ordering::SeqCst);
        let mut by = solvers.lock().unwrap_or_else(|e| e.into_inner());
        *by.entry(std::thread::current().id()).or_insert(0) += 1;
        i
    };
    let mut seen = Vec::new();
    let mut ahead = 0;
    in_order(all, AHEAD, 3, &solve, |i| {
        if i == 0 {
            // A slow writer: the helpers wait, the window ahead of it.
            std::thread::sleep(std::time::Duration::from_millis(30));
            ahead = solved.load(Ordering::SeqCst);
        }
        seen.push(i);
        Ok(())
    })
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(seen, (0..all).collect::<Vec<_>>());
    assert!(
        ahead <= AHEAD * 3,
        "{ahead} blocks solved before the first was written"
    );
    assert_eq!(solved.load(Ordering::SeqCst), all);
    // Three threads solved, the writer one of them (no thread only waits).
    let by = std::mem::take(&mut *solvers.lock().unwrap_or_else(|e| e.into_inner()));
    assert!(by.len() <= 3, "{} threads solved", by.len());
    assert!(
        by.get(&std::thread::current().id()).is_some_and(|&n| n > 0),
        "the writer solved no block: {by:?}"
    );
    solved.store(0, Ordering::SeqCst);
    let failed = in_order(all, AHEAD, 3, &solve, |i| {
        anyhow::ensure!(i < 5, "full disk at block {i}");
        Ok(())
    });
    let e = failed.err().map(|e| e.to_string());
    assert_eq!(e.as_deref(), Some("full disk at block 5"));
    // Block 5 and those before it, and at most the window's past them.
    let n = solved.load(Ordering::SeqCst);
    assert!(n > 5 && n <= 6 + AHEAD * 3, "{n} blocks solved");
}

/// A large train's rows are wide, so its blocks hold fewer rows: at most
/// `BLOCK_BYTES` of parameters and outputs at once (16 384 rows of a
/// 10 000-link chain would be 10 GB a thread). Here 2 500 rows of a
/// 1 502-link chain come out as Parquet row groups (one per block) of
/// `block_rows` rows, and each driving torque balances its load (the
/// alternating sets' speed ratio is 1).
#[test]
fn wide_rows_are_cut_into_short_blocks() {
    use super::{BLOCK, BLOCK_BYTES, COLUMNAR_BLOCK, block_rows};
    assert_eq!(block_rows(45, BLOCK), BLOCK);
    assert_eq!(block_rows(45, COLUMNAR_BLOCK), COLUMNAR_BLOCK);
    let w = 75_000;
    let r = block_rows(w, COLUMNAR_BLOCK);
    assert!(r < BLOCK && r * w * 8 <= BLOCK_BYTES && (r + 1) * w * 8 > BLOCK_BYTES);
    assert_eq!(block_rows(w, BLOCK), r);
    assert_eq!(block_rows(usize::MAX / 4, COLUMNAR_BLOCK), 1);

    let sets = 750;
    let mut spec = String::from("frame = \"case\"\n");
    for i in 1..=sets {
        let (sun, carrier) = if i % 2 == 1 {
            (format!("m{}", i - 1), format!("m{i}"))
        } else {
            (format!("m{i}"), format!("m{}", i - 1))
        };
        spec.push_str(&format!(
            "[[planetary]]\nname = \"P{i}\"\nsun = \"{sun}\"\nring = \"case\"\ncarrier = \"{carrier}\"\nteeth = {{ sun = 30, planet = 21, ring = 72 }}\n"
        ));
    }
    spec.push_str(&format!(
        "[analysis]\nspeeds = {{ m0 = 100.0 }}\ntorques = {{ m{sets} = -1.0 }}\ndriving = [\"m0\"]\n"
    ));
    let dir = std::env::temp_dir().join(format!("egt-wide-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let path = dir.join("chain.toml");
    std::fs::write(&path, spec).unwrap_or_else(|e| panic!("{e}"));
    let path = path.display().to_string();
    let grid = format!("torque.m{sets}=-1:-2:2500");
    let args = [
        path.as_str(),
        "--grid",
        grid.as_str(),
        "--columns",
        "driving_torque.m0",
        "--output",
        "parquet",
    ];
    let (bytes, r) = batch(&args);
    r.unwrap_or_else(|e| panic!("{e}"));
    // The row groups as written (the reader's batches have a size of their own).
    let file = dir.join("out.parquet");
    std::fs::write(&file, &bytes).unwrap_or_else(|e| panic!("{e}"));
    let meta = parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder::try_new(
        std::fs::File::open(&file).unwrap_or_else(|e| panic!("{e}")),
    )
    .unwrap_or_else(|e| panic!("{e}"))
    .metadata()
    .clone();
    let sizes: Vec<i64> = meta.row_groups().iter().map(|g| g.num_rows()).collect();
    assert_eq!(sizes.iter().sum::<i64>(), 2500);
    assert!(sizes.len() >= 3, "row groups {sizes:?}");
    assert!(sizes.iter().all(|&s| s <= sizes[0]), "row groups {sizes:?}");
    let groups = parquet_batches(bytes);
    for g in &groups {
        let column = |name: &str| {
            g.column_by_name(name)
                .and_then(|c| c.as_any().downcast_ref::<arrow_array::Float64Array>())
                .unwrap_or_else(|| panic!("no column {name}"))
                .clone()
        };
        let (load, driving) = (
            column(&format!("torque.m{sets}")),
            column("driving_torque.m0"),
        );
        for (t, d) in load.iter().zip(driving.iter()) {
            let (t, d) = (t.unwrap_or(f64::NAN), d.unwrap_or(f64::NAN));
            assert!(
                (d + t).abs() <= 1e-9 * t.abs(),
                "load {t}, driving torque {d}"
            );
        }
    }
}

/// Parquet and Arrow files hold the CSV's cells: a shift table (states,
/// a varied torque) and rows with bad values (errors, empty outputs).
#[test]
fn parquet_and_arrow_hold_the_csv_cells() {
    let zf = example("zf_8hp70.toml");
    let fig3 = example("fig3_example61.toml");
    let dir = std::env::temp_dir().join(format!("egt-columnar-rows-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let rows = dir.join("rows.jsonl");
    std::fs::write(
        &rows,
        "{\"torque.4\": -10}\nnot json\n{\"ratio.G1\": 0}\n{\"torque.4\": -20, \"accel.4\": 0}\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let rows = rows.display().to_string();
    let shift = [
        zf.as_str(),
        "--state",
        "all",
        "--set",
        "speed.input=200",
        "--grid",
        "torque.input=0:400:5",
    ];
    let bad = [fig3.as_str(), "--rows", rows.as_str()];
    let bad_some = [
        fig3.as_str(),
        "--rows",
        rows.as_str(),
        "--columns",
        "driving_torque.2",
    ];
    // Three blocks and a part (Parquet's and Arrow's; twelve and a part
    // of text): blocks are solved in parallel waves and must come out in
    // order.
    let n = 3 * super::COLUMNAR_BLOCK + 100;
    let grid = format!("torque.4=-10:-20:{n}");
    let long = [
        fig3.as_str(),
        "--grid",
        grid.as_str(),
        "--columns",
        "driving_torque.2",
    ];
    // Through the lock of Fig. 3 (tau_2 = 1 / tau_1): warned and refused
    // rows, with and without the conditions' columns.
    let lock = [fig3.as_str(), "--grid", "ratio.G2=-1.5000001:-1.4999999:21"];
    let lock_some = [
        fig3.as_str(),
        "--grid",
        "ratio.G2=-1.5000001:-1.4999999:21",
        "--columns",
        "force.G1,driving_torque.2",
    ];
    // One warned row among unwarned ones, column-major (the scan for a
    // warning reads four rows at a time: row 2 is in the first four,
    // and the last row, read alone, is not warned).
    let lock_one = [
        fig3.as_str(),
        "--vary",
        "ratio.G2=-1.4,-1.45,-1.5000001,-1.55,-1.6,-1.65,-1.7,-1.75,-1.8",
        "--columns",
        "driving_torque.2",
    ];
    // Column-major blocks of the varied columns only (a program, a
    // ratio varied): a zip and grid axes, a fixed value set; and every
    // gear state of the 8HP70. (One axis given twice is refused now.)
    let varied = [
        fig3.as_str(),
        "--vary",
        "ratio.G1=-2.1,-2.2,-2.3",
        "--grid",
        "ratio.G2=-1.2:-1.4:4",
        "--grid",
        "inertia.4=0.001:0.002:2",
        "--grid",
        "torque.4=-10:-20:3",
        "--set",
        "inertia.2=0.5",
        "--columns",
        "driving_torque.2,speed.3",
    ];
    // Two blocks of a grid whose first axis holds each value for 100
    // rows and whose last repeats after 100 (egt writes the Snappy
    // streams of both: repeats.rs).
    let repeats = [
        fig3.as_str(),
        "--grid",
        "torque.4=-10:-20:300",
        "--grid",
        "ratio.G2=-1.2:-1.4:100",
        "--columns",
        "driving_torque.2",
    ];
    let states = [
        zf.as_str(),
        "--state",
        "all",
        "--set",
        "speed.input=200",
        "--grid",
        "ratio.P1/sun-planet=-1.9:-2.1:3",
        "--grid",
        "torque.input=100:200:2",
        "--columns",
        "driving_torque.output",
    ];
    for (args, ok) in [
        (&varied[..], true),
        (&repeats[..], true),
        (&states[..], true),
        (&shift[..], true),
        (&bad[..], false),
        (&bad_some[..], false),
        (&long[..], true),
        (&lock[..], false),
        (&lock_some[..], false),
        (&lock_one[..], true),
    ] {
        let with = |fmt: &str| {
            let mut a = args.to_vec();
            a.extend(["--output", fmt]);
            let (bytes, r) = batch(&a);
            assert_eq!(r.is_ok(), ok, "{fmt}");
            bytes
        };
        let csv = String::from_utf8(with("csv")).unwrap_or_else(|e| panic!("{e}"));
        if args[1..3] == lock[1..3] || args == lock_one {
            assert!(csv.contains("ill-conditioned"), "no warning: {csv}");
        }
        // Rows in order: numbered 0, 1, ... and the grid's values in its order.
        let mut last = f64::INFINITY;
        for (r, line) in csv.lines().skip(1).enumerate() {
            let c = cells(line);
            assert_eq!(c[0], r.to_string(), "row numbers in order");
            if args == long {
                let t: f64 = c[1].parse().unwrap_or_else(|e| panic!("row {r}: {e}"));
                assert!(t < last, "row {r}: torque.4 {t} after {last}");
                last = t;
            }
        }
        let p = parquet_batches(with("parquet"));
        assert_same_as_csv(&p, &csv);
        let a = arrow_batches(with("arrow"));
        assert_same_as_csv(&a, &csv);
    }
}

/// A failed row's message stays in its row: a task's buffers reused
/// after a block with a failure hold none in the later blocks (one
/// thread, and two), as CSV and as Parquet.
#[test]
fn a_failed_row_leaves_no_message_in_later_blocks() {
    let fig3 = example("fig3_example61.toml");
    let n = 4 * super::COLUMNAR_BLOCK + 100;
    // Row 0 is Fig. 3's lock (tau_2 = -1.5), the others far from it.
    let grid = format!("ratio.G2=-1.5:-1.9:{n}");
    for threads in ["1", "2"] {
        let with = |fmt: &str| {
            let a = [
                fig3.as_str(),
                "--grid",
                grid.as_str(),
                "--columns",
                "driving_torque.2",
                "--threads",
                threads,
                "--output",
                fmt,
            ];
            let (bytes, r) = batch(&a);
            let e = r.err().map(|e| e.to_string()).unwrap_or_default();
            assert!(
                e.starts_with(&format!("1 of {n} scenarios failed")),
                "{threads} threads, {fmt}: {e}"
            );
            bytes
        };
        let csv = String::from_utf8(with("csv")).unwrap_or_else(|e| panic!("{e}"));
        let failed: Vec<String> = (csv.lines().skip(1))
            .map(cells)
            .filter(|c| c.last().is_some_and(|e| !e.is_empty()))
            .map(|c| c[0].clone())
            .collect();
        assert_eq!(failed, ["0"], "{threads} threads");
        assert_same_as_csv(&parquet_batches(with("parquet")), &csv);
    }
}

/// A Parquet file holds its design (`--set`, `--vary`, `--grid`) in its
/// key-value metadata, as JSON.
#[test]
fn parquet_metadata_holds_the_design() {
    let fig3 = example("fig3_example61.toml");
    let args = [
        fig3.as_str(),
        "--set",
        "inertia.2=0.5",
        "--grid",
        "torque.4=-10:-20:3",
        "--output",
        "parquet",
    ];
    let (bytes, r) = batch(&args);
    r.unwrap_or_else(|e| panic!("{e}"));
    let dir = std::env::temp_dir().join(format!("egt-design-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let path = dir.join("design.parquet");
    std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("{e}"));
    let file = std::fs::File::open(&path).unwrap_or_else(|e| panic!("{e}"));
    let builder = parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder::try_new(file)
        .unwrap_or_else(|e| panic!("{e}"));
    let kv = builder.metadata().file_metadata().key_value_metadata();
    let design = (kv.into_iter().flatten())
        .find(|kv| kv.key == "egt.design")
        .and_then(|kv| kv.value.clone())
        .unwrap_or_else(|| panic!("no egt.design in {kv:?}"));
    let design: serde_json::Value =
        serde_json::from_str(&design).unwrap_or_else(|e| panic!("{e}: {design}"));
    assert_eq!(
        design,
        serde_json::json!({
            "set": { "inertia.2": 0.5 },
            "vary": [],
            "grid": [{ "name": "torque.4", "values": [-10.0, -15.0, -20.0] }],
            "state": [],
        })
    );
}

#[test]
fn binary_output_to_a_terminal_is_refused_naming_the_flag() {
    use clap::Parser;
    let args = |extra: &[&str]| {
        let mut a = vec!["egt", "batch", "x.toml"];
        a.extend(extra);
        match crate::cli::Cli::try_parse_from(a).map(|c| c.command) {
            Ok(crate::cli::Command::Batch(b)) => b,
            other => panic!("{other:?}"),
        }
    };
    for f in ["parquet", "arrow"] {
        let r = super::refuse_binary_to_terminal(&args(&["--output", f]));
        let e = format!("{:#}", r.err().unwrap_or_else(|| panic!("{f} accepted")));
        assert!(e.contains("--output") && e.contains("terminal"), "{e}");
        assert!(super::refuse_binary_to_terminal(&args(&["--output", f, "--list"])).is_ok());
    }
    for f in ["csv", "jsonl"] {
        assert!(super::refuse_binary_to_terminal(&args(&["--output", f])).is_ok());
    }
}

#[test]
fn columnar_output_of_whole_spec_lines_holds_the_long_csv() {
    let json = super::tests::fig3_json();
    let dir = std::env::temp_dir().join(format!("egt-columnar-specs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let specs = dir.join("specs.jsonl");
    std::fs::write(&specs, format!("{json}\n{{\"frame\": 3}}\n{json}\n"))
        .unwrap_or_else(|e| panic!("{e}"));
    let specs = specs.display().to_string();
    let with = |fmt: &str| {
        let (bytes, r) = batch(&["--specs", &specs, "--output", fmt]);
        assert!(r.is_err(), "{fmt}: the broken line fails the batch");
        bytes
    };
    let csv = String::from_utf8(with("csv")).unwrap_or_else(|e| panic!("{e}"));
    let rows: Vec<Vec<String>> = csv.lines().skip(1).map(cells).collect();
    assert!(rows.iter().any(|r| r[2] == "error"), "{csv}");
    assert!(rows.len() > 10, "{csv}");
    for batches in [
        parquet_batches(with("parquet")),
        arrow_batches(with("arrow")),
    ] {
        let names: Vec<String> = batches[0]
            .schema()
            .fields()
            .iter()
            .map(|f| f.name().clone())
            .collect();
        assert_eq!(names, ["row", "name", "quantity", "value", "error"]);
        let mut r = 0;
        for b in &batches {
            let col = |c: usize| b.column(c).as_any();
            let row = col(0).downcast_ref::<UInt64Array>();
            let name = col(1).downcast_ref::<StringArray>();
            let quantity = col(2).downcast_ref::<StringArray>();
            let value = col(3).downcast_ref::<Float64Array>();
            let error = col(4).downcast_ref::<StringArray>();
            let (Some(row), Some(name), Some(quantity), Some(value), Some(error)) =
                (row, name, quantity, value, error)
            else {
                panic!("unexpected column types: {:?}", b.schema());
            };
            for i in 0..b.num_rows() {
                let csv = &rows[r];
                let what = format!("row {r}");
                assert_eq!(row.value(i).to_string(), csv[0], "{what}");
                assert_eq!(name.value(i), csv[1], "{what}");
                assert_eq!(quantity.value(i), csv[2], "{what}");
                if csv[2] == "error" {
                    assert!(value.is_null(i), "{what}");
                    assert_eq!(error.value(i), csv[3], "{what}");
                } else {
                    assert!(error.is_null(i), "{what}");
                    let v: f64 = csv[3].parse().unwrap_or_else(|e| panic!("{what}: {e}"));
                    assert_eq!(value.value(i).to_bits(), v.to_bits(), "{what}");
                }
                r += 1;
            }
        }
        assert_eq!(r, rows.len(), "every CSV row is in the columnar file");
    }
}
