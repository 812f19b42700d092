//! Helpers shared by the end-to-end tests: running the binary, the shared scenes, scratch folders.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `rdbvh` binary with `args`.
pub fn rdbvh(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rdbvh"))
        .args(args)
        .output()
        .expect("the rdbvh binary runs")
}

/// Output bytes as text, for messages and parsing.
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The shared scenes beside the workspace, or `None` (with a note) when they are not checked out.
/// Under `CI=true` their absence is a failure, not a skip.
pub fn shared_scenes(test: &str) -> Option<PathBuf> {
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/scenes"));
    if dir.is_dir() {
        return Some(dir.to_path_buf());
    }
    assert!(
        std::env::var("CI").as_deref() != Ok("true"),
        "CI=true but {} is missing",
        dir.display()
    );
    eprintln!(
        "{test}: real scenes skipped: {} not found (check out ../shared beside the workspace)",
        dir.display()
    );
    None
}

/// A fresh scratch folder for one test, named after the test binary (`suite`) and the test.
pub fn scratch(suite: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rdbvh-{suite}-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
