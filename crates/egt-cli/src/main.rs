//! The `egt` binary: the command line of `egt_cli::run` (with Ctrl-C
//! handled by the long commands), its exit code the process's.

use std::process::ExitCode;

// mimalloc keeps freed memory for reuse within each thread. `egt batch`
// builds and frees its Arrow columns and Parquet page buffers block after
// block; under glibc's malloc those buffers went back to the kernel and
// came back as page faults every block (docs/performance.md (history: git log -p -- docs/benchmarks.md), "Batch
// screening": 10^6 rows to Parquet 15-30 % faster).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> ExitCode {
    ExitCode::from(egt_cli::run_handling_ctrl_c(std::env::args_os()))
}
