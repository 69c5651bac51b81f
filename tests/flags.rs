//! Issue 42: every flag of every subcommand, as `--help` lists it, run once
//! with a valid value on a bundled example, must succeed. The flags come from
//! the grammar itself (clap's command tree), so a flag added without a row
//! here fails the test; the `--torque-table` panic (a flag no test ran) is
//! the class this closes.

use clap::CommandFactory;

use crate::util::egt;

/// What a run starts from, before its flag.
#[derive(Clone, Copy)]
enum Base {
    /// Nothing (`egt enumerate`).
    Bare,
    /// A spec or search spec.
    Spec(&'static str),
    /// The 8HP70's 2-3 upshift of tests/shift_sim.rs (without its input
    /// torque: `--torque-table` replaces it; without its two ramps: `--ramp`
    /// gives them by element).
    Upshift { torque: bool, ramps: bool },
}

const FIG3: Base = Base::Spec("examples/fig3_example61.toml");
const FIG5: Base = Base::Spec("examples/fig5_stability.toml");
const COMPLIANT: Base = Base::Spec("examples/simple_planetary_compliant.toml");
const ZF: Base = Base::Spec("examples/zf_8hp70.toml");
const C4_SEARCH: Base = Base::Spec("examples/synth/ford_c4_simpson.toml");
const UP: Base = Base::Upshift {
    torque: true,
    ramps: true,
};

/// One run per flag: (command, flag, base, the arguments after the base).
/// `{tmp}` is a fresh directory for the files a flag reads or writes.
#[rustfmt::skip]
const RUNS: &[(&str, &str, Base, &[&str])] = &[
    ("check", "spec-format", FIG3, &["--spec-format", "toml"]),
    ("check", "format", FIG3, &["--format", "json"]),
    ("circuits", "spec-format", FIG3, &["--spec-format", "toml"]),
    ("circuits", "format", FIG3, &["--format", "json"]),
    ("kinematics", "spec-format", FIG3, &["--spec-format", "toml"]),
    ("kinematics", "format", FIG3, &["--format", "json"]),
    ("kinematics", "input", FIG3, &["--input", "2=100"]),
    ("dynamics", "spec-format", FIG3, &["--spec-format", "toml"]),
    ("dynamics", "format", FIG3, &["--format", "json"]),
    ("dynamics", "torque", FIG3, &["--torque", "2=10"]),
    ("dynamics", "accel", FIG3, &["--accel", "2=1"]),
    ("dynamics", "driving", FIG3, &["--driving", "2"]),
    ("dynamics", "forces", FIG3, &["--forces"]),
    ("dynamics", "reduce-to", FIG3, &["--reduce-to", "2"]),
    ("power", "spec-format", FIG3, &["--spec-format", "toml"]),
    ("power", "format", FIG3, &["--format", "json"]),
    ("power", "input", FIG3, &["--input", "2=100"]),
    ("power", "torque", FIG3, &["--torque", "2=10"]),
    ("power", "accel", FIG3, &["--accel", "2=1"]),
    ("power", "driving", FIG3, &["--driving", "2"]),
    ("power", "ideal", FIG3, &["--ideal"]),
    ("shift", "spec-format", ZF, &["--spec-format", "toml"]),
    ("shift", "format", ZF, &["--format", "json"]),
    ("shift", "state", ZF, &["--state", "1"]),
    ("shift", "plot", ZF, &["--plot", "{tmp}/ladder.svg"]),
    ("fmu", "spec-format", ZF, &["--spec-format", "toml", "-o", "{tmp}/a.fmu"]),
    ("fmu", "output", ZF, &["--output", "{tmp}/b.fmu"]),
    ("fmu", "model-identifier", ZF, &["-o", "{tmp}/c.fmu", "--model-identifier", "zf"]),
    ("fmu", "library", ZF, &["-o", "{tmp}/d.fmu", "--library", "{lib}"]),
    ("graph", "spec-format", FIG3, &["--spec-format", "toml"]),
    ("graph", "format", FIG3, &["--format", "json"]),
    ("graph", "svg", FIG3, &["--svg"]),
    ("stability", "spec-format", FIG5, &["--spec-format", "toml"]),
    ("stability", "format", FIG5, &["--format", "json"]),
    ("stability", "slope", FIG5, &["--slope", "2=0.01"]),
    ("stability", "coords", FIG5, &["--coords", "2,4"]),
    ("stability", "input", FIG5, &["--input", "2=300", "--input", "4=80"]),
    ("modes", "spec-format", COMPLIANT, &["--spec-format", "toml"]),
    ("modes", "format", COMPLIANT, &["--format", "json"]),
    ("modes", "state", COMPLIANT, &["--state", "low"]),
    ("modes", "campbell", COMPLIANT, &["--state", "low", "--campbell"]),
    ("modes", "speed", COMPLIANT, &["--state", "low", "--campbell", "--speed", "0:7000"]),
    ("modes", "plot", COMPLIANT, &["--state", "low", "--campbell", "--plot", "{tmp}/campbell.svg"]),
    ("modes", "static", COMPLIANT, &["--state", "low", "--static", "10"]),
    ("simulate", "spec-format", FIG5, &["--spec-format", "toml", "--t-end", "0.1"]),
    ("simulate", "format", FIG5, &["--format", "csv", "--t-end", "0.1"]),
    ("simulate", "slope", FIG5, &["--slope", "2=0.01", "--t-end", "0.1"]),
    ("simulate", "t-end", FIG5, &["--t-end", "0.1"]),
    ("simulate", "dt", FIG5, &["--dt", "0.01", "--t-end", "0.1"]),
    ("simulate", "method", FIG5, &["--method", "rk4", "--t-end", "0.1"]),
    ("simulate", "initial", FIG5, &["--initial", "2=330", "--initial", "4=80", "--t-end", "0.1"]),
    ("simulate", "every", FIG5, &["--every", "2", "--t-end", "0.1"]),
    ("simulate", "plot", FIG5, &["--plot", "{tmp}/sim.svg", "--t-end", "0.1"]),
    ("simulate", "reactions", FIG5, &["--reactions", "--t-end", "0.1"]),
    ("batch", "spec-format", FIG3, &["--spec-format", "toml", "--vary", "speed.2=1:2:3"]),
    ("batch", "specs", Base::Bare, &["--specs", "{tmp}/specs.txt"]),
    ("batch", "compute", FIG3, &["--compute", "kinematics", "--vary", "speed.2=1:2:3"]),
    ("batch", "set", FIG3, &["--set", "torque.2=5", "--vary", "speed.2=1:2:3"]),
    ("batch", "vary", FIG3, &["--vary", "speed.2=1:2:3"]),
    ("batch", "grid", FIG3, &["--grid", "speed.2=1:2:3", "--grid", "torque.2=1,2"]),
    ("batch", "rows", FIG3, &["--rows", "{tmp}/rows.jsonl"]),
    ("batch", "max-rows", FIG3, &["--grid", "speed.2=1:2:3", "--max-rows", "3"]),
    ("batch", "state", ZF, &["--state", "1", "--vary", "speed.input=1:2:3"]),
    ("batch", "output", FIG3, &["--vary", "speed.2=1:2:3", "--output", "csv"]),
    ("batch", "threads", FIG3, &["--vary", "speed.2=1:2:3", "--threads", "1"]),
    ("batch", "columns", FIG3, &["--vary", "speed.2=1:2:3", "--columns", "speed.3"]),
    ("batch", "list", FIG3, &["--list"]),
    ("batch", "progress", FIG3, &["--vary", "speed.2=1:2:3", "--progress"]),
    ("enumerate", "links", Base::Bare, &["--links", "5"]),
    ("enumerate", "identify", Base::Bare, &["--identify", "examples/fig3_example61.toml"]),
    ("enumerate", "dof", Base::Bare, &["--links", "5", "--dof", "1"]),
    ("enumerate", "level", Base::Bare, &["--links", "5", "--level", "displacement"]),
    ("enumerate", "jsonl", Base::Bare, &["--links", "5", "--jsonl"]),
    ("enumerate", "part", Base::Bare, &["--links", "6", "--part", "0/2"]),
    ("enumerate", "fractionation", Base::Bare, &["--links", "5", "--fractionation", "kinematic"]),
    ("enumerate", "count", Base::Bare, &["--links", "6", "--count"]),
    ("enumerate", "max-links", Base::Bare, &["--links", "5", "--max-links", "5"]),
    ("enumerate", "progress", Base::Bare, &["--links", "5", "--progress"]),
    ("enumerate", "search", Base::Bare, &["--links", "5", "--search", "levels"]),
    ("synth", "spec-format", C4_SEARCH, &["--spec-format", "toml"]),
    ("synth", "format", C4_SEARCH, &["--format", "json"]),
    ("synth", "top", C4_SEARCH, &["--top", "2"]),
    ("synth", "max-leaves", C4_SEARCH, &["--max-leaves", "1000"]),
    ("synth", "part", C4_SEARCH, &["--part", "0/2"]),
    ("synth", "write-specs", C4_SEARCH, &["--top", "2", "--write-specs", "{tmp}/c4"]),
    ("synth", "tables", C4_SEARCH, &["--top", "2", "--format", "json", "--tables"]),
    ("synth", "stream", C4_SEARCH, &["--top", "2", "--stream"]),
    ("synth", "progress", C4_SEARCH, &["--top", "2", "--progress"]),
    ("shift-sim", "spec-format", UP, &["--spec-format", "toml"]),
    ("shift-sim", "format", UP, &["--format", "csv"]),
    ("shift-sim", "shift", ZF, &["--shift", "2-3"]),
    ("shift-sim", "from", UP, &[]),
    ("shift-sim", "to", UP, &[]),
    ("shift-sim", "input-speed", UP, &[]),
    ("shift-sim", "input-torque", UP, &[]),
    ("shift-sim", "torque-table", Base::Upshift { torque: false, ramps: true }, &["--torque-table", "0:300,1000:250"]),
    ("shift-sim", "ramp", Base::Upshift { torque: true, ramps: false }, &["--ramp", "A=0.05:0.15:5000:0", "--ramp", "C=0.05:0.3:0:9000"]),
    ("shift-sim", "road-load", UP, &[]),
    ("shift-sim", "vehicle-inertia", UP, &[]),
    ("shift-sim", "output-shaft", UP, &["--output-shaft", "5000,1"]),
    ("shift-sim", "losses", UP, &["--losses"]),
    ("shift-sim", "mu", UP, &["--mu", "0.15,0.12"]),
    ("shift-sim", "mu-decay", UP, &["--mu-decay", "10"]),
    ("shift-sim", "off-going", UP, &[]),
    ("shift-sim", "on-coming", UP, &[]),
    ("shift-sim", "t-end", UP, &["--t-end", "1"]),
    ("shift-sim", "max-steps", UP, &["--max-steps", "100000"]),
    ("shift-sim", "rtol", UP, &["--rtol", "1e-8"]),
    ("shift-sim", "atol", UP, &["--atol", "1e-9"]),
    ("shift-sim", "method", UP, &["--method", "explicit"]),
    ("shift-sim", "plot", UP, &["--plot", "{tmp}/shift.svg"]),
];

impl Base {
    fn args(self) -> Vec<&'static str> {
        match self {
            Base::Bare => Vec::new(),
            Base::Spec(path) => vec![path],
            Base::Upshift { torque, ramps } => {
                let mut a = vec![
                    "examples/zf_8hp70.toml",
                    "--from",
                    "2",
                    "--to",
                    "3",
                    "--input-speed",
                    "250",
                    "--road-load",
                    "20,0.2,0.002",
                    "--vehicle-inertia",
                    "12",
                ];
                if ramps {
                    a.extend([
                        "--off-going",
                        "0.05:0.15:5000:0",
                        "--on-coming",
                        "0.05:0.3:0:9000",
                    ]);
                }
                if torque {
                    a.extend(["--input-torque", "300"]);
                }
                a
            }
        }
    }
}

#[test]
fn every_flag_of_every_command_runs_with_a_valid_value() {
    let tmp = std::env::temp_dir().join(format!("egt-flags-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).expect("temp dir");
    let t = tmp.to_string_lossy().to_string();
    let lib = crate::fmu::library().to_string_lossy().to_string();
    let fig3 = egt_core::parse_spec(
        &std::fs::read_to_string(crate::util::root().join("examples/fig3_example61.toml"))
            .expect("fig3"),
        egt_core::Format::Toml,
        "fig3",
    )
    .expect("fig3 parses");
    let line = serde_json::to_string(&fig3).expect("a spec as JSON");
    std::fs::write(tmp.join("specs.txt"), format!("{line}\n")).expect("specs");
    std::fs::write(
        tmp.join("rows.jsonl"),
        "{\"speed.2\": 100}\n{\"speed.2\": 200}\n",
    )
    .expect("rows");
    // Completeness: every long flag of every subcommand has a run.
    let grammar = egt_cli::cli::Cli::command();
    let mut missing = Vec::new();
    for sub in grammar.get_subcommands() {
        for arg in sub.get_arguments() {
            let Some(long) = arg.get_long() else { continue };
            if long == "help" || long == "version" {
                continue;
            }
            if !RUNS
                .iter()
                .any(|(c, f, ..)| *c == sub.get_name() && *f == long)
            {
                missing.push(format!("{} --{long}", sub.get_name()));
            }
        }
    }
    assert!(missing.is_empty(), "flags with no run here: {missing:?}");
    let mut failed = Vec::new();
    for (command, flag, base, rest) in RUNS {
        let mut args = vec![command.to_string()];
        args.extend(
            base.args()
                .iter()
                .chain(*rest)
                .map(|a| a.replace("{tmp}", &t).replace("{lib}", &lib)),
        );
        let argv: Vec<&str> = args.iter().map(String::as_str).collect();
        let r = egt(&argv, None);
        if r.code != 0 || r.stderr.contains("panicked") {
            failed.push(format!(
                "{command} --{flag}: exit {}: {}",
                r.code,
                r.stderr.trim()
            ));
        }
    }
    std::fs::remove_dir_all(&tmp).ok();
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}
