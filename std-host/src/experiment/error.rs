//! Why an experiment could not run.

use std::fmt;
use std::path::PathBuf;

/// Why an experiment (or an analysis) could not run. Each is one line.
#[derive(Debug)]
pub enum ExperimentError {
    /// A file could not be read or written.
    Io(PathBuf, String),
    /// A bad `[settings]` value or command-line override.
    Settings(String),
    /// A bad `[[config]]` entry.
    Areas(String),
    /// A scene could not be loaded.
    Scene(String),
    /// A build failed.
    Build(String),
    /// A CSV file could not be read or written.
    Csv(String),
    /// A chart could not be drawn.
    Plot(String),
}

impl fmt::Display for ExperimentError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ExperimentError::Io(p, e) => write!(f, "{}: {e}", p.display()),
            ExperimentError::Settings(m)
            | ExperimentError::Areas(m)
            | ExperimentError::Scene(m)
            | ExperimentError::Build(m)
            | ExperimentError::Csv(m) => f.write_str(m),
            ExperimentError::Plot(m) => write!(f, "chart: {m}"),
        }
    }
}

impl std::error::Error for ExperimentError {}
