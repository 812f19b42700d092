//! The `rdbvh` command: see `rdbvh --help`, or run it with no arguments for the demo.

use std::process::ExitCode;

fn main() -> ExitCode {
    rdbvh::cli::main_with_args(std::env::args_os())
}
