//! Whether two paths name one file: the check that keeps every command from writing over its own
//! inputs, whatever name the output is given.

use std::path::Path;

/// Whether `a` and `b` name one existing file: the same device and inode where the platform has
/// them (which catches hard links and symbolic links), the same canonical path elsewhere. A path
/// that does not exist is no file, so it is the same as none.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        match (a.canonicalize(), b.canonicalize()) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        }
    }
}

/// The first of `inputs` that is the same file as `output`, if any.
pub fn input_named_by<'a>(
    output: &Path,
    inputs: impl IntoIterator<Item = &'a Path>,
) -> Option<&'a Path> {
    inputs.into_iter().find(|input| same_file(output, input))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_and_spellings_of_one_file_are_the_same_file() {
        let dir = std::env::temp_dir().join(format!("rdbvh-same-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("a.txt");
        std::fs::write(&file, "x").unwrap();
        let other = dir.join("b.txt");
        std::fs::write(&other, "x").unwrap();
        let hard = dir.join("hard.txt");
        let _ = std::fs::remove_file(&hard);
        std::fs::hard_link(&file, &hard).unwrap();
        let dotted = dir.join(".").join("a.txt");
        assert!(same_file(&file, &dotted));
        assert!(same_file(&file, &hard));
        assert!(!same_file(&file, &other), "equal contents are not one file");
        assert!(!same_file(&file, &dir.join("missing.txt")));
        assert_eq!(
            input_named_by(&hard, [other.as_path(), file.as_path()]),
            Some(file.as_path())
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
