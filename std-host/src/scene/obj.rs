//! Wavefront OBJ loading with `tobj`, behind a line-level check that turns every bad face index
//! into an error naming the line.
//!
//! Why a check of our own before `tobj`: `tobj` 4 reports bad indices without a line number, and
//! its texture-coordinate and normal index arithmetic (`vt * 2 + 1`) overflows on out-of-range
//! relative indices, which panics in debug builds and reads the wrong element in release builds.
//! Checking every face index against the vertices defined before it makes those inputs a clear
//! [`SceneError::MissingVertex`] instead. The same pass skips polylines (`tobj` reads `l a b c` as a
//! triangle) and rejects MTL colour lines with fewer than three values (`tobj` panics on them).
//! When `tobj` rejects a `v`, `vt` or `vn` line, a second pass finds it, so a malformed number
//! is an error with its line too (only on that error path: parsing every number twice made loading
//! a third slower). Before either reads it, the text loses a UTF-8 byte-order mark (which `tobj`
//! would take as part of the first statement: the first vertex was silently dropped) and any
//! trailing `# comment` on a data line (`tobj` reads it as more numbers or indices).

use std::borrow::Cow;

use std::cell::RefCell;
use std::collections::HashSet;
use std::io::Read;
use std::path::{Path, PathBuf};

use rdbvh_core::geometry::{Aabb, Triangle};
use rdbvh_core::Vec3;

use super::error::{SceneError, SceneWarning, VertexKind};
use super::{Material, Scene, DEFAULT_DIFFUSE};

/// Where the material libraries named by `mtllib` come from.
#[derive(Clone, Copy, Debug)]
pub enum MaterialFiles<'a> {
    /// None: every `mtllib` gives a warning.
    None,
    /// Files relative to this folder (the OBJ's own folder, as every OBJ reader resolves them).
    Folder(&'a Path),
    /// In-memory libraries as `(name, text)` pairs, for tests and fuzzing.
    Memory(&'a [(&'a str, &'a str)]),
}

impl MaterialFiles<'_> {
    /// The library's displayed path and its text.
    fn read(&self, name: &Path) -> (PathBuf, Result<String, String>) {
        match self {
            MaterialFiles::None => (
                name.to_path_buf(),
                Err("no material files available".to_string()),
            ),
            MaterialFiles::Folder(dir) => {
                let path = dir.join(name);
                let text = std::fs::read_to_string(&path).map_err(|e| e.to_string());
                (path, text)
            }
            MaterialFiles::Memory(files) => (
                name.to_path_buf(),
                files
                    .iter()
                    .find(|(n, _)| Path::new(n) == name)
                    .map(|(_, text)| (*text).to_string())
                    .ok_or_else(|| "not found".to_string()),
            ),
        }
    }
}

/// The label used in messages for OBJ text that does not come from a file.
pub const MEMORY_LABEL: &str = "<memory>";

impl Scene {
    /// Loads an OBJ file and the material libraries beside it.
    ///
    /// Triangles come in file order: every model (`o`/`g`, and every material change inside one)
    /// in turn, polygons fanned from their first vertex. A missing or malformed material library is
    /// a [`SceneWarning`], not an error: it only loses material names and emissive flags, and many
    /// published OBJ files (several of the thesis scenes) name an `.mtl` that was never shipped.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let text = utf8_text(bytes, path)?;
        let dir = path.parent().unwrap_or(Path::new(""));
        let mut scene = Scene::from_obj_str_with(&text, path, MaterialFiles::Folder(dir))?;
        scene.name = path.file_name().map_or_else(
            || path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        Ok(scene)
    }

    /// Loads OBJ text from any reader; `label` names it in messages and `materials` resolves its
    /// `mtllib` lines.
    pub fn from_obj_reader(
        mut reader: impl Read,
        label: &Path,
        materials: MaterialFiles<'_>,
    ) -> Result<Scene, SceneError> {
        let mut bytes = Vec::new();
        reader
            .read_to_end(&mut bytes)
            .map_err(|source| SceneError::Io {
                path: label.to_path_buf(),
                source,
            })?;
        Scene::from_obj_str_with(&utf8_text(bytes, label)?, label, materials)
    }

    /// Loads OBJ text with no material libraries (each `mtllib` gives a warning).
    pub fn from_obj_str(text: &str) -> Result<Scene, SceneError> {
        Scene::from_obj_str_with(text, Path::new(MEMORY_LABEL), MaterialFiles::None)
    }

    /// Loads OBJ text; `label` names it in messages and `materials` resolves its `mtllib` lines.
    pub fn from_obj_str_with(
        text: &str,
        label: &Path,
        materials: MaterialFiles<'_>,
    ) -> Result<Scene, SceneError> {
        let text = normalized(text);
        let check = check_obj(&text, label)?;
        let text = if check.has_polylines {
            Cow::Owned(sanitized(&text, false))
        } else {
            text
        };

        let warnings = RefCell::new(Vec::new());
        let read_files = RefCell::new(Vec::new());
        let options = tobj::LoadOptions {
            triangulate: true,
            ignore_points: true,
            ignore_lines: true,
            ..Default::default()
        };
        let load = |text: &str| {
            tobj::load_obj_buf(&mut text.as_bytes(), &options, |name| {
                load_mtl(name, materials, &warnings, &read_files)
            })
        };
        let loaded = match load(&text) {
            // Colours on some positions and not on others: `tobj` fails on the faces. They are
            // unused here, so they go and the text loads again.
            Err(tobj::LoadError::FaceColorOutOfBounds) => {
                warnings.borrow_mut().clear();
                read_files.borrow_mut().clear();
                load(&sanitized(&text, true))
            }
            other => other,
        };
        let (models, loaded) = loaded.map_err(|e| {
            use tobj::LoadError as E;
            // Name the line `tobj` rejected, when it was a vertex line.
            let vertex = matches!(
                e,
                E::PositionParseError
                    | E::ScalingByZeroError
                    | E::ColorParseError
                    | E::TexcoordParseError
                    | E::NormalParseError
            );
            let (line, reason) = match vertex.then(|| vertex_line_error(&text)).flatten() {
                Some((line, reason)) => (Some(line), reason),
                None => (None, e.to_string()),
            };
            SceneError::Malformed {
                path: label.to_path_buf(),
                line,
                reason,
            }
        })?;
        let mut warnings = warnings.into_inner();
        // A failed library was already reported; `tobj` only returns its error when no library
        // loaded at all.
        let tobj_materials = loaded.unwrap_or_default();

        let materials: Vec<Material> = tobj_materials
            .iter()
            .map(|m| Material {
                name: m.name.clone(),
                diffuse: m.diffuse.unwrap_or(DEFAULT_DIFFUSE),
                emission: m.emissive.unwrap_or([0.0; 3]),
            })
            .collect();
        if warnings.is_empty() {
            let defined: HashSet<&str> = materials.iter().map(|m| m.name.as_str()).collect();
            warnings.extend(
                check
                    .used_materials
                    .iter()
                    .filter(|name| !defined.contains(name.as_str()))
                    .map(|name| SceneWarning::UnknownMaterial { name: name.clone() }),
            );
        }
        if check.skipped > 0 {
            warnings.push(SceneWarning::SkippedNonSurfaces {
                count: check.skipped,
            });
        }

        let mut triangles = Vec::new();
        let mut material = Vec::new();
        for model in &models {
            let mesh = &model.mesh;
            let id = mesh
                .material_id
                .filter(|&m| m < materials.len())
                .map_or(u32::MAX, |m| m as u32);
            for face in mesh.indices.chunks_exact(3) {
                let mut corners = [Vec3::ZERO; 3];
                for (corner, &index) in corners.iter_mut().zip(face) {
                    let i = index as usize * 3;
                    let p = mesh
                        .positions
                        .get(i..i + 3)
                        .ok_or_else(|| SceneError::Malformed {
                            path: label.to_path_buf(),
                            line: None,
                            reason: format!("tobj produced out-of-range vertex index {index}"),
                        })?;
                    *corner = Vec3::new(p[0], p[1], p[2]);
                }
                triangles.push(Triangle::new(corners[0], corners[1], corners[2]));
                material.push(id);
            }
        }
        if triangles.is_empty() {
            return Err(SceneError::NoTriangles {
                path: label.to_path_buf(),
            });
        }
        check_finite(&triangles, &text, label)?;

        let emissive = material
            .iter()
            .map(|&m| materials.get(m as usize).is_some_and(Material::is_emissive))
            .collect();
        let bounds = triangles
            .iter()
            .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
        warnings.extend(SceneWarning::precision(&bounds));
        Ok(Scene {
            name: label.display().to_string(),
            triangles,
            material,
            emissive,
            materials,
            bounds,
            warnings,
            material_files: read_files.into_inner(),
            view: None,
        })
    }
}

/// The file's bytes as text, or an [`SceneError::Io`] (invalid data) naming the line and byte of
/// the first one that is not UTF-8 (the standard library's message names neither).
fn utf8_text(bytes: Vec<u8>, label: &Path) -> Result<String, SceneError> {
    crate::text_lines::utf8_text(bytes).map_err(|at| SceneError::Io {
        path: label.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, at.to_string()),
    })
}

/// Rejects the first triangle with a NaN or infinite coordinate, naming the line of its vertex
/// in `text`. Only vertices used by faces are checked: an unused bad vertex cannot reach a BVH.
fn check_finite(triangles: &[Triangle], text: &str, label: &Path) -> Result<(), SceneError> {
    for (triangle, t) in triangles.iter().enumerate() {
        for (corner, p) in [t.v0, t.v1, t.v2].into_iter().enumerate() {
            if !p.is_finite() {
                return Err(SceneError::NonFiniteVertex {
                    path: label.to_path_buf(),
                    line: position_line(text, p.to_array()),
                    triangle,
                    corner,
                    position: p.to_array(),
                });
            }
        }
    }
    Ok(())
}

/// The line (from 1) of the first `v` statement that reads as `position` (a NaN equal to any
/// NaN): found only for an error, since the loader keeps no line per vertex.
fn position_line(text: &str, position: [f32; 3]) -> Option<usize> {
    let same = |a: f32, b: f32| a == b || (a.is_nan() && b.is_nan());
    text.lines().enumerate().find_map(|(i, line)| {
        let mut words = line.split_whitespace();
        if words.next() != Some("v") {
            return None;
        }
        let read: Vec<f32> = words.take(3).map_while(|w| w.parse().ok()).collect();
        let found = read.len() == 3 && read.iter().zip(position).all(|(&a, b)| same(a, b));
        found.then_some(i + 1)
    })
}

/// What the line-level check found besides errors.
#[derive(Debug, Default)]
struct ObjCheck {
    /// `l` lines present (to be hidden from `tobj`).
    has_polylines: bool,
    /// Points, polylines and faces with fewer than 3 vertices.
    skipped: usize,
    /// Material names given to `usemtl`, first use first.
    used_materials: Vec<String>,
}

/// Statements whose words are all numbers or indices, so a `#` in them can only start a comment.
const DATA_STATEMENTS: [&str; 7] = ["v", "vt", "vn", "vp", "f", "l", "p"];

/// The text as the checks and `tobj` read it: without a leading UTF-8 byte-order mark, with CR
/// line ends made LF when the file has no LF at all, and with
/// a trailing `# comment` cut from every data line ([`DATA_STATEMENTS`]); other lines (names of
/// materials, groups, libraries) are kept whole. Borrowed when nothing changes, which only the
/// lines holding a `#` can tell.
fn normalized(text: &str) -> Cow<'_, str> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    // Classic Mac OS line ends (CR alone) read as one long line otherwise.
    if text.contains('\r') && !text.contains('\n') {
        return Cow::Owned(normalized(&text.replace('\r', "\n")).into_owned());
    }
    let is_data = |line: &str| {
        line.split_whitespace()
            .next()
            .is_some_and(|w| DATA_STATEMENTS.contains(&w))
    };
    let line_at = |at: usize| {
        let start = text[..at].rfind('\n').map_or(0, |i| i + 1);
        let end = text[at..].find('\n').map_or(text.len(), |i| at + i);
        &text[start..end]
    };
    if !text.match_indices('#').any(|(at, _)| is_data(line_at(at))) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        match line.find('#') {
            Some(at) if is_data(line) => out.push_str(&line[..at]),
            _ => out.push_str(line),
        }
        out.push('\n');
    }
    Cow::Owned(out)
}

/// Checks a `v`, `vt` or `vn` line's numbers (`words`, after the statement) as `tobj` parses
/// them: `count` numbers first (x y z; u v; x y z), then for a position [`check_position_extras`].
fn check_numbers<'a>(
    mut words: impl Iterator<Item = &'a str>,
    count: usize,
    what: &str,
) -> Result<(), String> {
    let number = |w: &str, name: &str| {
        w.parse::<f32>()
            .map_err(|_| format!("{what}: {name} '{w}' is not a number"))
    };
    for k in 0..count {
        let Some(w) = words.next() else {
            return Err(format!("{what} needs {count} numbers, found {k}"));
        };
        number(w, "coordinate")?;
    }
    if what != "position" {
        return Ok(());
    }
    check_position_extras(&words.collect::<Vec<_>>())
}

/// Checks what follows a position's three coordinates: nothing, a weight `w` (`tobj` divides the
/// coordinates by it, so it must be finite and not zero: an infinite one silently moved the vertex
/// to the origin), or an RGB colour of three numbers (unused here, but `tobj` would skip a bad
/// one without a word).
fn check_position_extras(rest: &[&str]) -> Result<(), String> {
    let number = |w: &str, name: &str| {
        w.parse::<f32>()
            .map_err(|_| format!("position: {name} '{w}' is not a number"))
    };
    match rest {
        [] => Ok(()),
        [w] => {
            let w = number(w, "weight")?;
            if w == 0.0 || !w.is_finite() {
                return Err(format!(
                    "position: weight w is {w} (it must be finite and not 0)"
                ));
            }
            Ok(())
        }
        [r, g, b] => [r, g, b]
            .into_iter()
            .try_for_each(|c| number(c, "colour component").map(|_| ())),
        more => Err(format!(
            "position has {} numbers: expected 3, 4 (with a weight) or 6 (with a colour)",
            3 + more.len()
        )),
    }
}

/// The first `v`, `vt` or `vn` line whose numbers `tobj` would reject ([`check_numbers`]), with
/// its line number and why: run only after `tobj` failed, to name the line.
fn vertex_line_error(text: &str) -> Option<(usize, String)> {
    text.lines().enumerate().find_map(|(i, line)| {
        let mut words = line.split_whitespace();
        let (count, what) = match words.next() {
            Some("v") => (3, "position"),
            Some("vt") => (2, "texture coordinate"),
            Some("vn") => (3, "normal"),
            _ => return None,
        };
        check_numbers(words, count, what).err().map(|e| (i + 1, e))
    })
}

/// Checks every face index against the positions, texture coordinates and normals defined before
/// the face (the OBJ rule, and what `tobj` resolves relative indices against), and every `usemtl`.
fn check_obj(text: &str, label: &Path) -> Result<ObjCheck, SceneError> {
    let malformed = |line: usize, reason: String| SceneError::Malformed {
        path: label.to_path_buf(),
        line: Some(line),
        reason,
    };
    let mut check = ObjCheck::default();
    let mut seen_materials = HashSet::new();
    // Positions, texture coordinates, normals defined so far.
    let mut defined = [0usize; 3];
    const KINDS: [VertexKind; 3] = [
        VertexKind::Position,
        VertexKind::TexCoord,
        VertexKind::Normal,
    ];
    for (i, line) in text.lines().enumerate() {
        let number = i + 1;
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                // The coordinates are `tobj`'s to check (a bad one names its line through
                // `vertex_line_error`); a weight or colour after them, rare, is checked here,
                // since `tobj` accepts some bad ones.
                // Most lines are `v x y z`: at most three separators, so no extras (counting
                // bytes costs a fraction of splitting words; `split_whitespace` decides the rest).
                let separators = line.bytes().filter(|&b| b == b' ' || b == b'\t').count();
                if separators > 3 {
                    let rest: Vec<&str> = words.by_ref().skip(3).collect();
                    if !rest.is_empty() {
                        check_position_extras(&rest).map_err(|e| malformed(number, e))?;
                    }
                }
                defined[0] += 1;
            }
            Some("vt") => defined[1] += 1,
            Some("vn") => defined[2] += 1,
            Some("l") => {
                check.has_polylines = true;
                check.skipped += 1;
            }
            Some("p") => check.skipped += 1,
            Some("usemtl") => {
                // Parsed as `tobj` does: everything after the first space.
                let name = line.split_once(' ').map_or("", |(_, n)| n.trim());
                if name.is_empty() {
                    return Err(malformed(number, "usemtl without a material name".into()));
                }
                if seen_materials.insert(name.to_string()) {
                    check.used_materials.push(name.to_string());
                }
            }
            Some("f") => {
                let mut vertices = 0;
                for vertex in words {
                    vertices += 1;
                    for (k, part) in vertex.split('/').enumerate() {
                        if part.is_empty() {
                            if k == 0 {
                                return Err(malformed(
                                    number,
                                    format!("face vertex '{vertex}' has no position index"),
                                ));
                            }
                            continue;
                        }
                        if k >= 3 {
                            return Err(malformed(
                                number,
                                format!("face vertex '{vertex}' has more than 3 indices"),
                            ));
                        }
                        let index: i64 = part.parse().map_err(|_| {
                            malformed(number, format!("cannot parse face index '{part}'"))
                        })?;
                        let n = defined[k];
                        // `i` names the i-th element, `-i` the i-th from the last one defined.
                        if index == 0 {
                            return Err(malformed(
                                number,
                                format!(
                                    "face vertex '{vertex}' has index 0: OBJ indices count from \
                                     1 (or back from -1, the last one defined)"
                                ),
                            ));
                        }
                        if index.unsigned_abs() > n as u64 {
                            return Err(SceneError::MissingVertex {
                                path: label.to_path_buf(),
                                line: number,
                                kind: KINDS[k],
                                index,
                                defined: n,
                            });
                        }
                    }
                }
                match vertices {
                    0 => return Err(malformed(number, "face with no vertices".into())),
                    1 | 2 => check.skipped += 1,
                    _ => {}
                }
            }
            _ => {}
        }
    }
    Ok(check)
}

/// The text as `tobj` should read it after the check: every `l` line blanked (kept as an empty
/// line so line numbers stay the same) and, with `no_colours`, every `v` line cut to its
/// coordinates and weight (for files where only some positions carry a colour).
fn sanitized(text: &str, no_colours: bool) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("l") => {}
            Some("v") if no_colours => {
                let numbers: Vec<&str> = words.collect();
                out.push('v');
                // 3 coordinates, or 3 and a weight; a colour's three numbers go.
                let keep = if numbers.len() == 4 { 4 } else { 3 };
                for n in numbers.iter().take(keep) {
                    out.push(' ');
                    out.push_str(n);
                }
            }
            _ => out.push_str(line),
        }
        out.push('\n');
    }
    out
}

/// Loads one material library for `tobj`, turning every failure into a warning and a `tobj`
/// error (which `tobj` records and otherwise ignores).
fn load_mtl(
    name: &Path,
    files: MaterialFiles<'_>,
    warnings: &RefCell<Vec<SceneWarning>>,
    read_files: &RefCell<Vec<PathBuf>>,
) -> tobj::MTLLoadResult {
    let (path, text) = files.read(name);
    let text = match text {
        Ok(text) => {
            if let MaterialFiles::Folder(_) = files {
                read_files.borrow_mut().push(path.clone());
            }
            text
        }
        Err(reason) => {
            warnings
                .borrow_mut()
                .push(SceneWarning::MaterialLibraryUnreadable { path, reason });
            return Err(tobj::LoadError::OpenFileFailed);
        }
    };
    let malformed = |reason: String| {
        warnings
            .borrow_mut()
            .push(SceneWarning::MaterialLibraryMalformed {
                path: path.clone(),
                reason,
            });
    };
    // `tobj` unwraps the parse of these colours and panics with fewer than three values.
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if let Some(key @ ("Ka" | "Kd" | "Ks" | "Ke")) = words.next() {
            if words.count() < 3 {
                malformed(format!("line {}: {key} needs 3 values", i + 1));
                return Err(tobj::LoadError::MaterialParseError);
            }
        }
    }
    tobj::load_mtl_buf(&mut text.as_bytes()).inspect_err(|e| malformed(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

    fn err(text: &str) -> SceneError {
        Scene::from_obj_str(text).expect_err("should fail")
    }

    #[test]
    fn quad_is_two_triangles_in_fan_order() {
        let s = Scene::from_obj_str(QUAD).unwrap();
        assert_eq!(s.triangles.len(), 2);
        assert_eq!(s.triangles[0].v2, Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(s.triangles[1].v2, Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(s.material, [u32::MAX; 2]);
        assert_eq!(s.emissive, [false; 2]);
        assert!(s.warnings.is_empty());
        assert_eq!(s.bounds, Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
    }

    #[test]
    fn models_are_concatenated_in_file_order() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 5\no a\nf 1 2 4\no b\nf 1 2 3\ng c\nf 2 3 4\n";
        let s = Scene::from_obj_str(text).unwrap();
        assert_eq!(s.triangles.len(), 3);
        assert_eq!(s.triangles[0].v2.z, 5.0);
        assert_eq!(s.triangles[1].v2, Vec3::Y);
        assert_eq!(s.triangles[2].v0, Vec3::X);
    }

    #[test]
    fn relative_indices_resolve() {
        let s = Scene::from_obj_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n").unwrap();
        assert_eq!(s.triangles[0].v1, Vec3::X);
    }

    /// Found by black-box testing: a scene near 1e13 (or 1e-13) units loaded and built without
    /// a word, and every ray missed it. It still loads, with a warning.
    #[test]
    fn scenes_past_single_precision_range_load_with_a_warning() {
        let scaled = |s: f32| format!("v 0 0 {s}\nv {s} 0 {s}\nv 0 {s} {s}\nf 1 2 3\n");
        for (s, warned) in [(1e13, true), (5e-13, true), (1e11, false), (1e-9, false)] {
            let scene = Scene::from_obj_str(&scaled(s)).unwrap();
            let found = scene
                .warnings
                .iter()
                .any(|w| matches!(w, SceneWarning::OutsidePrecisionRange { .. }));
            assert_eq!(found, warned, "{s}: {:?}", scene.warnings);
        }
        let far = Scene::from_obj_str(&scaled(1e13)).unwrap();
        let shown = far.warnings[0].to_string();
        assert!(shown.starts_with("coordinates reach 1e13"), "{shown}");
    }

    #[test]
    fn index_zero_is_malformed_not_missing() {
        let e = err("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n").to_string();
        assert!(e.contains("line 4: face vertex '0' has index 0"), "{e}");
        let e = err("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/0 3/1\n").to_string();
        assert!(e.contains("line 5: face vertex '2/0' has index 0"), "{e}");
    }

    #[test]
    fn out_of_range_indices_are_errors_not_panics() {
        for (text, kind, index) in [
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
                VertexKind::Position,
                4,
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n",
                VertexKind::Position,
                -4,
            ),
            // A forward reference: vertex 3 is defined after the face.
            (
                "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n",
                VertexKind::Position,
                3,
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/-9\n",
                VertexKind::TexCoord,
                -9,
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//99999999999\n",
                VertexKind::Normal,
                99_999_999_999,
            ),
        ] {
            match err(text) {
                SceneError::MissingVertex {
                    kind: k,
                    index: i,
                    line,
                    ..
                } => {
                    assert_eq!((k, i), (kind, index), "{text:?}");
                    assert!(line >= 3);
                }
                e => panic!("{text:?}: unexpected {e}"),
            }
        }
    }

    #[test]
    fn malformed_faces_name_the_line() {
        for text in [
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1/1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf /1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf\n",
        ] {
            match err(text) {
                SceneError::Malformed { line: Some(l), .. } if l == text.lines().count() => {}
                e => panic!("{text:?}: unexpected {e}"),
            }
        }
    }

    #[test]
    fn malformed_vertex_lines_name_the_line() {
        for (text, says) in [
            ("v 0 0\n", "position needs 3 numbers, found 2"),
            ("v 0 x 0\n", "'x' is not a number"),
            ("v 0 0 0 0\n", "weight w is 0"),
            ("v 0 0 1 inf\n", "weight w is inf"),
            ("v 0 0 1 a b c\n", "colour component 'a'"),
            ("v 0 0 0 1 1\n", "has 5 numbers"),
            ("vt 0\n", "texture coordinate needs 2 numbers, found 1"),
            ("vn 0 0 abc\n", "normal: coordinate 'abc'"),
        ] {
            let text = format!("v 0 0 0\nv 1 0 0\n{text}v 0 1 0\nf 1 2 3\n");
            match err(&text) {
                SceneError::Malformed {
                    line: Some(3),
                    reason,
                    ..
                } if reason.contains(says) => {}
                e => panic!("{text:?}: unexpected {e}"),
            }
        }
        assert!(err("v 0 0\n").to_string().contains(MEMORY_LABEL));
        // What loads: a weight, a colour (on some vertices only: `tobj` fails on that, so the
        // colours go and the text loads again), a third texture coordinate.
        let s = Scene::from_obj_str("v 0 0 0 2\nv 1 0 0 0.5 0.5 0.5\nvt 0 0 0\nv 0 1 0\nf 1 2 3\n")
            .unwrap();
        assert_eq!(s.triangles[0].v1, Vec3::X);
    }

    #[test]
    fn a_byte_order_mark_and_trailing_comments_are_not_data() {
        // Found by black-box testing: a BOM glued to the first `v` made `tobj` skip that vertex,
        // so every face index silently shifted by one.
        let s = Scene::from_obj_str(&format!("\u{feff}{QUAD}")).unwrap();
        assert_eq!(s.triangles, Scene::from_obj_str(QUAD).unwrap().triangles);
        let s = Scene::from_obj_str(&QUAD.replace('\n', "\r")).unwrap();
        assert_eq!(s.triangles, Scene::from_obj_str(QUAD).unwrap().triangles);
        let commented = "v 0 0 0 # origin\nv 1 0 0\nv 0 1 0#tight\nusemtl a#b\nf 1 2 3 # one\n";
        let s = Scene::from_obj_str(commented).unwrap();
        assert_eq!(s.triangles[0].v2, Vec3::Y);
        // Names keep their `#`.
        assert!(
            s.warnings.iter().any(|w| w.to_string().contains("a#b")),
            "{:?}",
            s.warnings
        );
    }

    #[test]
    fn missing_vertex_messages_count_in_words() {
        let e = err("v 0 0 0\nf 1 1 2\n").to_string();
        assert!(e.contains("only 1 vertex is defined before it"), "{e}");
        let e = err("v 0 0 0\nv 0 0 0\nf 1 2 3\n").to_string();
        assert!(e.contains("only 2 vertices are defined before it"), "{e}");
    }

    #[test]
    fn no_faces_is_no_triangles() {
        assert!(matches!(err(""), SceneError::NoTriangles { .. }));
        assert!(matches!(
            err("v 0 0 0\n# nothing\n"),
            SceneError::NoTriangles { .. }
        ));
        // Points and lines are not triangles.
        assert!(matches!(
            err("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2 3\nf 1 2\np 1\n"),
            SceneError::NoTriangles { .. }
        ));
    }

    #[test]
    fn polylines_are_skipped_with_a_warning() {
        let s = Scene::from_obj_str(&format!("{QUAD}l 1 2 3\nf 1 2\n")).unwrap();
        assert_eq!(s.triangles.len(), 2);
        assert_eq!(s.warnings, [SceneWarning::SkippedNonSurfaces { count: 2 }]);
    }

    #[test]
    fn non_finite_vertices_name_triangle_and_corner() {
        for (bad, corner) in [("nan 0 0", 2), ("0 inf 0", 2), ("0 0 1e39", 2)] {
            let text = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nv {bad}\nf 1 2 3\nf 1 2 4\n");
            match err(&text) {
                SceneError::NonFiniteVertex {
                    triangle,
                    corner: c,
                    line,
                    ..
                } => assert_eq!((triangle, c, line), (1, corner, Some(4))),
                e => panic!("unexpected {e}"),
            }
        }
        // An unused bad vertex is harmless.
        assert!(Scene::from_obj_str("v nan 0 0\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 2 3 4\n").is_ok());
    }

    const MTL: &str = "newmtl white\nKd 1 1 1\nKe 0 0 0\nnewmtl lamp\nKe 17 12 4\n";
    const LIT: &str = "mtllib room.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl white\nf 1 2 3\n\
                       usemtl lamp\nf 3 2 1\nusemtl white\nf 1 3 2\n";

    #[test]
    fn materials_and_emission() {
        let files = [("room.mtl", MTL)];
        let s = Scene::from_obj_str_with(LIT, Path::new("room.obj"), MaterialFiles::Memory(&files))
            .unwrap();
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        let names: Vec<_> = s.materials.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["white", "lamp"]);
        assert_eq!(s.material, [0, 1, 0]);
        assert_eq!(s.emissive, [false, true, false]);
        assert_eq!(s.emissive_count(), 1);
    }

    #[test]
    fn missing_mtl_is_a_warning() {
        let s = Scene::from_obj_str(LIT).unwrap();
        assert_eq!(s.triangles.len(), 3);
        assert_eq!(s.material, [u32::MAX; 3]);
        assert_eq!(s.emissive_count(), 0);
        assert!(matches!(
            s.warnings[..],
            [SceneWarning::MaterialLibraryUnreadable { .. }]
        ));
    }

    #[test]
    fn malformed_mtl_is_a_warning_not_a_panic() {
        for mtl in [
            "newmtl lamp\nKe 1 1\n",
            "newmtl lamp\nKd a b c\n",
            "newmtl\n",
        ] {
            let files = [("room.mtl", mtl)];
            let s =
                Scene::from_obj_str_with(LIT, Path::new("x.obj"), MaterialFiles::Memory(&files))
                    .unwrap();
            assert_eq!(s.emissive_count(), 0);
            assert!(
                matches!(
                    s.warnings[..],
                    [SceneWarning::MaterialLibraryMalformed { .. }]
                ),
                "{mtl:?}: {:?}",
                s.warnings
            );
        }
    }

    #[test]
    fn unknown_material_is_a_warning() {
        let files = [("room.mtl", "newmtl white\nKd 1 1 1\n")];
        let s = Scene::from_obj_str_with(LIT, Path::new("x.obj"), MaterialFiles::Memory(&files))
            .unwrap();
        assert_eq!(s.material, [0, u32::MAX, 0]);
        assert_eq!(
            s.warnings,
            [SceneWarning::UnknownMaterial {
                name: "lamp".into()
            }]
        );
    }

    #[test]
    fn missing_file_is_an_io_error() {
        let e = Scene::load("/nonexistent/dir/scene.obj").unwrap_err();
        assert!(matches!(e, SceneError::Io { .. }));
        assert!(e.to_string().contains("/nonexistent/dir/scene.obj"), "{e}");
    }

    #[test]
    fn reader_rejects_non_utf8() {
        let e = Scene::from_obj_reader(
            &b"v 0 0 0\xff\n"[..],
            Path::new("x.obj"),
            MaterialFiles::None,
        )
        .unwrap_err();
        assert!(matches!(e, SceneError::Io { .. }), "{e}");
        assert!(e.to_string().contains("line 1 (byte 7)"), "{e}");
    }

    #[test]
    fn crlf_and_tabs() {
        let s = Scene::from_obj_str("v\t0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1\t2 3\r\n").unwrap();
        assert_eq!(s.triangles.len(), 1);
    }
}
