//! Issue 12: one row per class of bad input, run through the `egt` binary as a
//! user would: the exit code and the words the message must contain. No row
//! may exit 0, print a non-finite number or take more than an instant.

use crate::util::egt;

/// A bad input: a spec (or none), the arguments, the exit code and the words.
struct Row {
    name: &'static str,
    spec: Option<&'static str>,
    args: &'static [&'static str],
    exit: i32,
    words: &'static [&'static str],
}

const SIMPLE: &str = "examples/simple_planetary.toml";

const ROWS: &[Row] = &[
    Row {
        name: "three-element pair in TOML",
        spec: Some(
            "frame = \"f\"\nlinks = [{ name = \"a\" }, { name = \"b\" }]\nrevolutes = [{ links = [\"f\", \"a\", \"b\"], level = \"a\" }]\n",
        ),
        args: &["check"],
        exit: 2,
        words: &["revolutes[0].links", "exactly two"],
    },
    Row {
        name: "three tooth counts",
        spec: Some(
            "frame = \"1\"\nadjacency = \"1-2:a 2-3:b 1-4:a\"\n[[gears]]\nlinks = [\"1\", \"3\"]\nteeth = [20, 30, 40]\nmesh = \"external\"\n",
        ),
        args: &["check"],
        exit: 2,
        words: &["gears[0].teeth", "exactly two"],
    },
    Row {
        name: "two fraction bars",
        spec: None,
        args: &["kinematics", SIMPLE, "--input", "sun=1/3/4"],
        exit: 2,
        words: &["1/3/4", "not a number"],
    },
    Row {
        name: "huge positive exponent",
        spec: None,
        args: &["kinematics", SIMPLE, "--input", "sun=1e1000000"],
        exit: 2,
        words: &["exponent", "1000"],
    },
    Row {
        name: "huge negative exponent",
        spec: None,
        args: &["kinematics", SIMPLE, "--input", "sun=1e-1000000"],
        exit: 2,
        words: &["exponent", "1000"],
    },
    Row {
        name: "huge exponent in a spec speed",
        spec: Some(
            "frame = \"ring\"\n[[planetary]]\nname = \"P\"\nsun = \"sun\"\nring = \"ring\"\ncarrier = \"c\"\nteeth = { sun = 30, ring = 72 }\n[analysis]\nspeeds = { sun = \"1e999999\" }\n",
        ),
        args: &["kinematics"],
        exit: 2,
        words: &["analysis.speeds.sun", "exponent"],
    },
    Row {
        name: "huge exponent in an adjacency ratio",
        spec: Some("frame = \"1\"\nadjacency = \"1-2:a 2-3:b 1-4:a 1-3:G=1e999999 3-4:G=-3/2\"\n"),
        args: &["check"],
        exit: 2,
        words: &["1-3:G=1e999999", "exponent"],
    },
    Row {
        name: "ratio beyond double range",
        spec: Some("frame = \"1\"\nadjacency = \"1-2:a 2-3:b 1-4:a 1-3:G=1e400 3-4:G=-3/2\"\n"),
        args: &["check"],
        exit: 2,
        words: &["1e400", "double precision"],
    },
    Row {
        name: "undeclared frame",
        spec: Some("frame = \"99\"\nadjacency = \"1-2:a 2-3:b 1-4:a 1-3:G=-2 3-4:G=-3/2\"\n"),
        args: &["check"],
        exit: 2,
        words: &["frame", "`99`"],
    },
    Row {
        name: "tooth count past the limit",
        spec: Some(
            "frame = \"ring\"\n[[planetary]]\nname = \"P\"\nsun = \"sun\"\nring = \"ring\"\ncarrier = \"c\"\nteeth = { sun = 4294967296, ring = 72, planet = 21 }\n",
        ),
        args: &["check"],
        exit: 2,
        words: &["teeth", "1 to 1000000", "4294967296"],
    },
    Row {
        name: "overflowing inertia",
        spec: Some(
            "frame = \"1\"\nadjacency = \"1-2:a 2-3:b 1-4:a 1-3:G=-2 3-4:G=-3/2\"\nlinks = [{ name = \"2\", inertia = 1e308 }, { name = \"4\", inertia = 1e308 }]\n[analysis]\ntorques = { \"4\" = -1e308 }\naccelerations = { \"4\" = 1e308 }\ndriving = [\"2\"]\n",
        ),
        args: &["dynamics"],
        exit: 1,
        words: &["not finite", "overflow"],
    },
    Row {
        name: "missing file",
        spec: None,
        args: &["check", "examples/no_such_file.toml"],
        exit: 1,
        words: &["no_such_file.toml"],
    },
    Row {
        name: "JSON with a byte-order mark is read",
        spec: None,
        args: &["check", "--spec-format", "json"],
        exit: 0,
        words: &["valid geared kinematic chain"],
    },
];

fn run(row: &Row) -> (i32, String) {
    if row.name.contains("byte-order") {
        let bom =
            "\u{feff}{\"frame\": \"f\", \"adjacency\": \"f-2:a 2-3:b f-4:a f-3:G=-2 3-4:G=-3/2\"}";
        return run_with(row, bom);
    }
    match row.spec {
        Some(text) => run_with(row, text),
        None => run_args(row.args, None),
    }
}

#[test]
fn every_bad_input_class_is_refused_by_name() {
    for row in ROWS {
        let start = std::time::Instant::now();
        let (code, text) = run(row);
        assert_eq!(code, row.exit, "{}: exit {code}\n{text}", row.name);
        for w in row.words {
            assert!(text.contains(w), "{}: no `{w}` in\n{text}", row.name);
        }
        let words = text.split(|c: char| !c.is_alphanumeric());
        assert!(
            !words.into_iter().any(|w| w == "inf" || w == "NaN"),
            "{}: {text}",
            row.name
        );
        // Bounded work, not a timing target: the slow paths took seconds to minutes.
        assert!(
            start.elapsed().as_secs() < 20,
            "{}: {:?}",
            row.name,
            start.elapsed()
        );
    }
}

/// Resource bounds (issues 12, 13): a train too large for the dense matrices
/// of an analysis (stability) is refused by name, with the limit, before the
/// work starts (asserting the refusal, not a time), while its check,
/// kinematics and inverse dynamics, which are sparse, run; a transmission
/// with too many gear states is refused.
#[test]
fn resource_limits_are_refused_by_name() {
    // A chain of 749 simple planetary sets: 1500 links.
    let sets = 749;
    let mut spec = String::from("frame = \"case\"\n");
    for i in 1..=sets {
        spec.push_str(&format!(
            "[[planetary]]\nname = \"P{i}\"\nsun = \"m{}\"\nring = \"case\"\ncarrier = \"m{i}\"\nteeth = {{ sun = 30, planet = 21, ring = 72 }}\n",
            i - 1
        ));
    }
    spec.push_str("[analysis]\nspeeds = { m0 = 100.0 }\naccelerations = { m0 = 1.0 }\ntorques = { m749 = -1.0 }\ndriving = [\"m0\"]\n");
    spec.push_str(
        "[[analysis.curves]]\nlink = \"m0\"\ntorque = 10.0\nslope = -0.1\nspeed = 100.0\n",
    );
    for (args, exit) in [
        (&["check"][..], 0),
        (&["kinematics"][..], 0),
        (&["dynamics"][..], 0),
        (&["stability"][..], 1),
    ] {
        let row = Row {
            name: "huge train",
            spec: None,
            args,
            exit,
            words: &[],
        };
        let (code, text) = run_with(&row, &spec);
        assert_eq!(code, exit, "{args:?}: {text}");
        match args[0] {
            "check" => assert!(text.contains("links: 1500"), "{text}"),
            "kinematics" => assert!(text.contains("no exact speeds"), "{text}"),
            "dynamics" => assert!(text.contains("inverse dynamics (1 DOF)"), "{text}"),
            _ => assert!(
                text.contains("1500 links")
                    && text.contains("MiB")
                    && text.contains("at most 1024 links"),
                "{text}"
            ),
        }
    }

    // A spec file past the size limit is refused by its size, before it is
    // parsed (a sparse file: no disk is used).
    let path = std::env::temp_dir().join(format!("egt-huge-spec-{}.toml", std::process::id()));
    std::fs::File::create(&path)
        .and_then(|f| f.set_len((256 << 20) + 1))
        .unwrap_or_else(|e| panic!("{e}"));
    let (code, text) = run_args(&["check", &path.display().to_string()], None);
    std::fs::remove_file(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("at most 256 MiB"), "{text}");

    let states: Vec<String> = (0..300).map(|k| format!("\"s{k}\" = [\"A\"]")).collect();
    let spec = format!(
        "frame = \"ring\"\n[[planetary]]\nname = \"P\"\nsun = \"sun\"\nring = \"ring\"\ncarrier = \"c\"\nteeth = {{ sun = 30, ring = 72 }}\n\
         [[elements]]\nname = \"A\"\nkind = \"clutch\"\nlinks = [\"sun\", \"c\"]\n[transmission]\ninput = \"sun\"\noutput = \"c\"\n[transmission.states]\n{}\n",
        states.join("\n")
    );
    let row = Row {
        name: "many states",
        spec: None,
        args: &["shift"],
        exit: 2,
        words: &[],
    };
    let (code, text) = run_with(&row, &spec);
    assert_eq!(code, 2, "{text}");
    assert!(
        text.contains("transmission.states") && text.contains("256"),
        "{text}"
    );
}

/// [`run`] with `spec` on stdin (the spec argument is `-`).
fn run_with(row: &Row, spec: &str) -> (i32, String) {
    let mut args = row.args.to_vec();
    args.push("-");
    run_args(&args, Some(spec))
}

/// Run `egt args` from the workspace root: the exit code and both streams together.
fn run_args(args: &[&str], stdin: Option<&str>) -> (i32, String) {
    let r = egt(args, stdin);
    (r.code, r.stdout + &r.stderr)
}

/// Issue 42: `egt batch` designs are bounded and checked before any row is
/// solved. Each case failed on 5ff1b3c: a panic ("capacity overflow") or a
/// machine's memory taken, a grid of 10^20 rows clamped and run, an uneven
/// zip exiting 1, and a parameter given twice or `--rows` with a grid
/// silently losing one of them.
#[test]
fn batch_designs_are_bounded_and_given_once() {
    let fig3 = "examples/fig3_example61.toml";
    let cases: &[(&[&str], i32, &[&str])] = &[
        (
            &["--vary", "speed.2=0:1:18446744073709551615"],
            2,
            &["COUNT", "--vary"],
        ),
        (
            &["--grid", "speed.2=0:1:1000000000000"],
            2,
            &["COUNT", "--grid"],
        ),
        (
            &[
                "--grid",
                "speed.2=0:1:100000",
                "--grid",
                "torque.4=0:1:100000",
                "--grid",
                "accel.4=0:1:100000",
            ],
            2,
            &["1000000000000000", "--max-rows"],
        ),
        (
            &["--vary", "speed.2=1,2,3", "--vary", "torque.4=1,2"],
            2,
            &["--vary", "equal lengths"],
        ),
        (
            &["--vary", "speed.2=1,2", "--grid", "speed.2=3,4"],
            2,
            &["`speed.2` is given twice"],
        ),
        (
            &["--set", "torque.4=-5", "--grid", "torque.4=3,4"],
            2,
            &["given twice"],
        ),
        (
            &["--rows", "-", "--grid", "torque.4=3,4"],
            2,
            &["--rows", "--grid"],
        ),
        (&["--vary", "speed.2=1,inf"], 2, &["not a finite number"]),
    ];
    for (extra, exit, words) in cases {
        let mut args = vec!["batch", fig3];
        args.extend_from_slice(extra);
        let (code, text) = run_args(&args, Some(""));
        assert_eq!(code, *exit, "{extra:?}: {text}");
        for w in *words {
            assert!(text.contains(w), "{extra:?}: `{w}` not in {text}");
        }
        assert!(!text.contains("panicked"), "{extra:?}: {text}");
    }
    // The budget is a flag: a design under it runs.
    let (code, text) = run_args(
        &[
            "batch",
            fig3,
            "--grid",
            "torque.4=0:1:3",
            "--grid",
            "speed.2=1:2:2",
            "--max-rows",
            "6",
        ],
        None,
    );
    assert_eq!(code, 0, "{text}");
    assert_eq!(text.lines().count(), 6, "{text}");
    let (code, text) = run_args(
        &[
            "batch",
            fig3,
            "--grid",
            "torque.4=0:1:3",
            "--grid",
            "speed.2=1:2:2",
            "--max-rows",
            "5",
        ],
        None,
    );
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("6 scenarios"), "{text}");
}

/// Issue 42: the atlas and the parts of a search refuse by name what they
/// cannot do, before any work: on 5ff1b3c `--links 12` ran without end, a
/// DOF of 2^64 - 1 wrapped into an empty atlas with exit 0, and a malformed
/// `--part` exited 1.
#[test]
fn atlas_budgets_and_parts_are_usage_errors() {
    let cases: &[(&[&str], i32, &[&str])] = &[
        (
            &["enumerate", "--links", "12", "--count"],
            2,
            &["--max-links 12", "budget"],
        ),
        (
            &["enumerate", "--links", "6", "--dof", "18446744073709551615"],
            2,
            &["dof", "between 1 and 4"],
        ),
        (
            &["enumerate", "--links", "6", "--part", "x"],
            2,
            &["--part", "`x`"],
        ),
        (
            &["enumerate", "--links", "6", "--part", "1/k"],
            2,
            &["--part", "K"],
        ),
        (
            &["synth", "examples/synth/zf_8hp70.toml", "--part", "0:4"],
            2,
            &["--part"],
        ),
        (
            &["enumerate", "--links", "7", "--count", "--max-links", "7"],
            0,
            &["152"],
        ),
    ];
    for (args, exit, words) in cases {
        let (code, text) = run_args(args, None);
        assert_eq!(code, *exit, "{args:?}: {text}");
        for w in *words {
            assert!(text.contains(w), "{args:?}: `{w}` not in {text}");
        }
    }
}

/// Issue 42: a batch row whose results overflow is a failed row (exit 1,
/// `non_finite_result` in its error cell), as `egt dynamics` refuses the
/// same input; it used to be written as blank cells with exit 0.
#[test]
fn batch_rows_that_overflow_fail_as_the_single_command_does() {
    let spec = std::fs::read_to_string(crate::util::root().join("examples/fig3_example61.toml"))
        .expect("fig3")
        .replacen("inertia = 2.0e-3", "inertia = 1e308", 1);
    let single = egt(&["dynamics", "-", "--spec-format", "toml"], Some(&spec));
    assert_eq!(single.code, 1, "{}", single.stderr);
    assert!(single.stderr.contains("overflow"), "{}", single.stderr);
    let r = egt(
        &[
            "batch",
            "examples/fig3_example61.toml",
            "--set",
            "inertia.2=1e308",
            "--vary",
            "accel.4=1e308,1",
            "--output",
            "csv",
        ],
        None,
    );
    assert_eq!(r.code, 1, "{}", r.stderr);
    let lines: Vec<&str> = r.stdout.lines().collect();
    assert_eq!(lines.len(), 3, "{}", r.stdout);
    for line in &lines[1..] {
        assert!(
            line.ends_with("a result overflowed: the inputs exceed the range of double precision"),
            "{line}"
        );
    }
}
