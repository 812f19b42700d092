//! Everything a command can fail with. The binary prints one line, `error: <Display>`, and exits
//! non-zero, so every message must stand on its own and name the input at fault.

use std::fmt;
use std::io;
use std::path::PathBuf;

use rdbvh_core::builder::PresetError;
use rdbvh_core::toplevel::TopLevelError;
use rdbvh_core::BuildError;

use super::rays::RaysError;
use crate::areas::AreasError;
use crate::scene::SceneError;

/// Why a command failed.
#[derive(Debug)]
pub enum CliError {
    /// The scene could not be loaded.
    Scene(SceneError),
    /// The BVH build rejected its input or settings.
    Build(BuildError),
    /// The rays file is unusable.
    Rays(RaysError),
    /// The area file is unusable.
    Areas(AreasError),
    /// The scene structure (local BVHs, lookup, fallback BVH) could not be built.
    Structure(TopLevelError),
    /// The command line asks for something impossible that clap cannot see (a preset that needs
    /// an area without --areas): exit status 2, like clap's own usage errors.
    Usage(String),
    /// An output file could not be written.
    Write {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: io::Error,
    },
    /// Standard output could not be written.
    Stdout(io::Error),
    /// The demo found a BVH answer that differs from brute force: a bug, reported loudly.
    Mismatch(String),
    /// An experiment or analysis failed.
    Experiment(crate::experiment::ExperimentError),
    /// A render could not start or finish.
    Render(crate::render::RenderError),
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CliError::Scene(e) => e.fmt(f),
            CliError::Build(e) => write!(f, "BVH build failed: {e}"),
            CliError::Rays(e) => e.fmt(f),
            CliError::Areas(e) => e.fmt(f),
            CliError::Structure(e) => write!(f, "scene structure build failed: {e}"),
            CliError::Usage(why) => write!(f, "{why} (see rdbvh --help)"),
            CliError::Write { path, source } => {
                write!(f, "cannot write {}: {source}", path.display())
            }
            CliError::Stdout(e) => write!(f, "cannot write to standard output: {e}"),
            CliError::Mismatch(what) => write!(f, "BVH disagrees with brute force: {what}"),
            CliError::Experiment(e) => e.fmt(f),
            CliError::Render(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for CliError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            CliError::Scene(e) => Some(e),
            CliError::Rays(e) => Some(e),
            CliError::Areas(e) => Some(e),
            CliError::Write { source, .. } | CliError::Stdout(source) => Some(source),
            CliError::Build(_)
            | CliError::Structure(_)
            | CliError::Usage(_)
            | CliError::Mismatch(_) => None,
            CliError::Experiment(e) => Some(e),
            CliError::Render(e) => Some(e),
        }
    }
}

impl From<SceneError> for CliError {
    fn from(e: SceneError) -> Self {
        CliError::Scene(e)
    }
}

impl From<BuildError> for CliError {
    fn from(e: BuildError) -> Self {
        CliError::Build(e)
    }
}

impl From<RaysError> for CliError {
    fn from(e: RaysError) -> Self {
        CliError::Rays(e)
    }
}

impl From<AreasError> for CliError {
    fn from(e: AreasError) -> Self {
        CliError::Areas(e)
    }
}

impl From<TopLevelError> for CliError {
    fn from(e: TopLevelError) -> Self {
        CliError::Structure(e)
    }
}

impl From<PresetError> for CliError {
    fn from(e: PresetError) -> Self {
        match e {
            // Commands check this before loading anything; this is the backstop.
            PresetError::NeedsArea(p) => CliError::Usage(format!(
                "preset `{p}` uses PAH or SPFH, which need the rays' influence area: give \
                 --areas AREAS.toml"
            )),
            PresetError::Build(e) => CliError::Build(e),
        }
    }
}

impl From<crate::experiment::ExperimentError> for CliError {
    fn from(e: crate::experiment::ExperimentError) -> Self {
        CliError::Experiment(e)
    }
}

impl From<crate::render::RenderError> for CliError {
    fn from(e: crate::render::RenderError) -> Self {
        CliError::Render(e)
    }
}
