//! The `rdbvh` command line: `build` and `trace` over OBJ files or built-in scenes, optionally
//! with influence areas (local BVHs, the scene structure), and a self-checking demo when run with
//! no arguments.
//!
//! Output contracts are measured from outside (scripts parse `build --json` and the CSV files), so
//! they are kept stable: see each command's documentation. Every failure is one line on standard
//! error, `error: ...`, and a non-zero exit status: 2 for a bad command line, 1 for anything else.

mod analyze;
mod answers;
mod areas;
mod build;
mod builder;
mod demo;
mod error;
mod experiment;
mod help;
mod inputs;
mod rays;
mod render;
mod structure;
mod trace;
mod words;

pub use analyze::{AnalyzeArgs, NODE_COLUMNS};
pub use answers::Answers;
pub use build::{BuildArgs, BuildReport};
pub use builder::{chooser_name, BuilderArgs, BuilderKind, BuiltBvh, PresetArg};
pub use error::CliError;
pub use experiment::ExperimentArgs;
pub use rays::{parse_rays, read_rays, write_rays, RaysError, OPTIONAL_COLUMNS, REQUIRED_COLUMNS};
pub use render::{RenderArgs, RenderReport};
pub use structure::{trace_structure, StructureTrace, DEFAULT_LOCAL_PRESET};
pub use trace::{trace, LookupKind, TraceArgs};

use std::ffi::OsString;
use std::io::{self, Write};
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Ray-distribution-aware BVHs: build and trace over OBJ scenes.
#[derive(Parser, Debug)]
#[command(name = "rdbvh", version, after_help = help::top())]
pub struct Cli {
    /// What to do; none runs the demo.
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Build a BVH (over the scene, or over the triangles of an influence area) and report
    /// nodes, leaves, depth, SAH and PAH cost, memory and build speed.
    #[command(after_help = help::build())]
    Build(BuildArgs),
    /// Trace rays from a CSV file and write the closest (or any) hit of each to a CSV file, with
    /// one BVH or through the scene structure of influence areas.
    #[command(after_help = help::trace())]
    Trace(TraceArgs),
    /// Run an experiment file (the thesis's experiments.toml): results.csv, report.md, charts.
    Experiment(ExperimentArgs),
    /// Build over each influence area of a scene and print every analyzer metric.
    Analyze(AnalyzeArgs),
    /// Path trace a scene with next event estimation (point, spot, quad and emissive lights),
    /// write a PNG, and report what its shadow rays cost through the structure chosen.
    #[command(after_help = help::render())]
    Render(RenderArgs),
}

/// Runs the command line `args` (the first item is the program name) and returns the exit
/// status. Never panics on user input: every failure is one `error: ...` line on standard error.
pub fn main_with_args<I, T>(args: I) -> ExitCode
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => return usage_error(&e),
    };
    let stdout = io::stdout();
    let mut out = stdout.lock();
    let result = match &cli.command {
        None => demo::run(&mut out),
        Some(Command::Build(args)) => build::run(args, &mut out),
        Some(Command::Trace(args)) => match &args.areas {
            Some(areas) => structure::run(args, areas, &mut io::stderr()),
            None => trace::run(args, &mut io::stderr()),
        },
        Some(Command::Experiment(args)) => experiment::run(args, &mut out),
        Some(Command::Analyze(args)) => analyze::run(args, &mut out),
        Some(Command::Render(args)) => render::run(args, &mut out),
    };
    let result = result.and_then(|()| out.flush().map_err(CliError::Stdout));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // A closed pipe (`rdbvh build x | head -1`) is the reader's choice, not a failure.
        Err(CliError::Stdout(e)) if e.kind() == io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(e @ CliError::Usage(_)) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Prints help and version as clap does; squeezes a usage error into one line, since scripts
/// and users read the first line of standard error.
fn usage_error(e: &clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    match e.kind() {
        ErrorKind::DisplayHelp
        | ErrorKind::DisplayVersion
        | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            // Printing help can only fail on a closed stream, where there is no one to tell.
            let _ = e.print();
            ExitCode::from(if e.use_stderr() { 2 } else { 0 })
        }
        _ => {
            eprintln!("{}", one_line(&e.render().to_string()));
            ExitCode::from(2)
        }
    }
}

/// clap's message without its usage block, on one line.
fn one_line(message: &str) -> String {
    let body = message.split("\nUsage:").next().unwrap_or(message);
    let mut line = body
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("For more information"))
        .collect::<Vec<_>>()
        .join(" ");
    if !line.starts_with("error:") {
        line = format!("error: {line}");
    }
    format!("{line} (see rdbvh --help)")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn usage_errors_are_one_line() {
        for args in [
            &["rdbvh", "build"][..],
            &["rdbvh", "build", "x.obj", "--bins", "1"],
            &["rdbvh", "build", "x.obj", "--builder", "median"],
            &["rdbvh", "trace", "x.obj"],
            &["rdbvh", "frobnicate"],
        ] {
            let e = Cli::try_parse_from(args).unwrap_err();
            let line = one_line(&e.render().to_string());
            assert!(line.starts_with("error: "), "{line}");
            assert!(!line.contains('\n'), "{line}");
        }
    }

    #[test]
    fn demo_passes() {
        let mut out = Vec::new();
        let image = std::env::temp_dir().join(format!("rdbvh-demo-{}.png", std::process::id()));
        demo::run_with(&mut out, &image).unwrap();
        assert!(image.is_file());
        let lights = image.with_file_name(format!("rdbvh-demo-{}-lights.toml", std::process::id()));
        assert!(lights.is_file(), "the demo's lights file beside its image");
        let text = String::from_utf8(out).unwrap();
        // Checked, so removed: a test run leaves nothing in the temporary directory.
        let _ = (std::fs::remove_file(&image), std::fs::remove_file(&lights));
        assert!(text.contains("agree with brute force"), "{text}");
    }
}
