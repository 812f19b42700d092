//! A command's inputs and outputs: the scene it opens, and the output paths it checks before any
//! work so that a run never writes over what it reads.

use std::io;
use std::path::Path;
use std::time::Instant;

use super::error::CliError;
use crate::scene::Scene;

/// Opens a scene (a path or `builtin:NAME`), prints its warnings to standard error, and returns
/// it with the seconds it took. Fails when `output` (checked by [`check_output`] already) is one
/// of the material libraries the scene read: those are inputs too, known only once read.
pub(super) fn load_scene(spec: &str, output: Option<&Path>) -> Result<(Scene, f64), CliError> {
    let start = Instant::now();
    let scene = Scene::open(spec)?;
    let seconds = start.elapsed().as_secs_f64();
    if let Some(output) = output {
        check_not_input(output, scene.material_files.iter().map(|p| p.as_path()))?;
    }
    for w in &scene.warnings {
        eprintln!("warning: {}: {w}", scene.name);
    }
    Ok((scene, seconds))
}

/// Fails early, before any work, when `path` cannot be an output file: it names a folder, its
/// folder does not exist, or it is one of the command's `inputs` (writing it would destroy the
/// input). Other failures, such as permissions, still show when it is written.
pub(super) fn check_output(path: &Path, inputs: &[&Path]) -> Result<(), CliError> {
    let fail = |why: &str| CliError::Write {
        path: path.to_path_buf(),
        source: io::Error::new(io::ErrorKind::NotFound, why.to_string()),
    };
    if path.is_dir() {
        return Err(fail("it is a folder"));
    }
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !folder.is_dir() {
        return Err(fail("its folder does not exist"));
    }
    check_not_input(path, inputs.iter().copied())
}

/// Fails when the output `path` is the same file as one of `inputs`: the same path, a symbolic
/// link to it, or a hard link to it.
fn check_not_input<'a>(
    path: &Path,
    inputs: impl IntoIterator<Item = &'a Path>,
) -> Result<(), CliError> {
    match crate::same_file::input_named_by(path, inputs) {
        Some(input) => Err(CliError::Write {
            path: path.to_path_buf(),
            source: io::Error::new(
                io::ErrorKind::AlreadyExists,
                format!(
                    "it is one of the command's input files ({})",
                    input.display()
                ),
            ),
        }),
        None => Ok(()),
    }
}
