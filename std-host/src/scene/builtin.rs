//! Scenes built into the binary, so the main job runs without downloading anything.

use super::{procedural, room, Scene, SceneError};

/// The prefix that selects a built-in scene wherever a scene path is expected.
pub const BUILTIN_PREFIX: &str = "builtin:";

/// Every built-in scene: its name (after `builtin:`) and what it is.
pub const BUILTIN_SCENES: &[(&str, &str)] = &[
    (
        "random100",
        "the thesis's Random100: 100 random triangles, std::mt19937 seed 1",
    ),
    (
        "random1000",
        "the thesis's Random1000: the next 1000 triangles of the same generator stream",
    ),
    (
        "room",
        "a closed room with an emissive ceiling light and three boxes",
    ),
];

/// The built-in scene `name`.
pub(super) fn builtin(name: &str) -> Result<Scene, SceneError> {
    match name {
        "random100" => Ok(procedural::random_scene(name, 0, 100)),
        "random1000" => Ok(procedural::random_scene(name, 100, 1000)),
        "room" => Ok(room::room()),
        _ => Err(SceneError::UnknownBuiltin {
            name: name.to_string(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_scene_opens() {
        for (name, _) in BUILTIN_SCENES {
            let s = Scene::open(&format!("{BUILTIN_PREFIX}{name}")).unwrap();
            assert_eq!(s.name, format!("{BUILTIN_PREFIX}{name}"));
            assert!(!s.is_empty());
            assert_eq!(s.material.len(), s.len());
            assert_eq!(s.emissive.len(), s.len());
        }
    }

    #[test]
    fn unknown_name_lists_the_known_ones() {
        let e = Scene::open("builtin:nope").unwrap_err();
        assert!(e.to_string().contains("builtin:room"), "{e}");
    }
}
