//! Reading area files: TOML text to checked influence areas, every problem a typed error with a
//! line.

use std::collections::BTreeMap;
use std::fs;
use std::path::Path;

use rdbvh_core::influence::{AreaError, InfluenceArea, PlaneArea, PointArea};
use rdbvh_core::Vec3;
use serde::Deserialize;
use toml::{Spanned, Value};

use super::{AreaEntry, AreaFile, AreaKind, AreasError, AreasErrorKind, TableKind};

/// Keys of `experiments.toml` entries that describe the experiment, not the area: allowed, kept
/// in [`AreaEntry`], and without effect on the area.
pub const IGNORED_KEYS: [&str; 4] = ["scene", "file", "orientation", "thesis_test"];

/// One table, each value with its place in the text.
type RawTable = BTreeMap<String, Spanned<Value>>;

/// The parts of the file that matter; everything else (`scene_dir`, `[settings]`) is ignored.
#[derive(Deserialize)]
struct RawFile {
    area: Option<Vec<Spanned<RawTable>>>,
    config: Option<Vec<Spanned<RawTable>>>,
}

/// Reads and checks the area file at `path`.
pub fn read_areas(path: &Path) -> Result<AreaFile, AreasError> {
    let fail = |line, e| AreasError {
        path: path.to_path_buf(),
        line,
        entry: None,
        kind: AreasErrorKind::Io(e),
    };
    let bytes = fs::read(path).map_err(|e| fail(None, e))?;
    let text = crate::text_lines::utf8_text(bytes).map_err(|at| {
        let why = format!("not UTF-8 text: byte {} is not UTF-8", at.byte);
        fail(
            Some(at.line),
            std::io::Error::new(std::io::ErrorKind::InvalidData, why),
        )
    })?;
    parse_areas(&text, path)
}

/// Checks the area file text `text`; `label` names it in errors.
pub fn parse_areas(text: &str, label: &Path) -> Result<AreaFile, AreasError> {
    let fail = |line: Option<usize>, kind| AreasError {
        path: label.to_path_buf(),
        line,
        entry: None,
        kind,
    };
    // A first pass as a plain table gives TOML's own syntax errors, and lets us say what is
    // wrong with `area`/`config` in our words before the typed pass.
    let plain: toml::Table = toml::from_str(text).map_err(|e| syntax(text, &e, label))?;
    for (key, table) in [("area", "[[area]]"), ("config", "[[config]]")] {
        if let Some(v) = plain.get(key) {
            let ok = v.as_array().is_some_and(|a| a.iter().all(Value::is_table));
            if !ok {
                return Err(fail(
                    None,
                    AreasErrorKind::Syntax(format!(
                        "`{key}` must be an array of tables: write each entry as {table}, \
                         not `{key} = ...` or [{key}]"
                    )),
                ));
            }
        }
    }
    let raw: RawFile = toml::from_str(text).map_err(|e| syntax(text, &e, label))?;
    let (tables, list) = match (raw.area, raw.config) {
        (Some(_), Some(_)) => return Err(fail(None, AreasErrorKind::BothTables)),
        (Some(a), None) => (TableKind::Area, a),
        (None, Some(c)) => (TableKind::Config, c),
        (None, None) => return Err(fail(None, AreasErrorKind::NoAreas)),
    };
    if list.is_empty() {
        return Err(fail(None, AreasErrorKind::NoAreas));
    }
    let entries = list
        .iter()
        .enumerate()
        .map(|(index, table)| {
            Entry {
                text,
                label,
                tables,
                index,
                table,
            }
            .parse()
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(AreaFile {
        path: label.to_path_buf(),
        tables,
        entries,
    })
}

/// A TOML error on one line: its message and the line its span starts on.
fn syntax(text: &str, e: &toml::de::Error, label: &Path) -> AreasError {
    AreasError {
        path: label.to_path_buf(),
        line: e.span().map(|s| line_at(text, s.start)),
        entry: None,
        kind: AreasErrorKind::Syntax(
            e.message()
                .lines()
                .map(str::trim)
                .filter(|l| !l.is_empty())
                .collect::<Vec<_>>()
                .join(" "),
        ),
    }
}

/// The 1-based line of byte `offset` of `text`.
fn line_at(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// One table being checked, with what its errors need.
struct Entry<'a> {
    text: &'a str,
    label: &'a Path,
    tables: TableKind,
    index: usize,
    table: &'a Spanned<RawTable>,
}

impl Entry<'_> {
    fn parse(&self) -> Result<AreaEntry, AreasError> {
        let kind = match self.table.get_ref().get("kind") {
            None => {
                return Err(self.error(
                    None,
                    AreasErrorKind::MissingKey {
                        key: "kind",
                        area_kind: None,
                    },
                ))
            }
            Some(v) => match v.get_ref().as_str() {
                Some("plane") => AreaKind::Plane,
                Some("point") => AreaKind::Point,
                Some(other) => {
                    return Err(self.error(Some(v), AreasErrorKind::UnknownKind(other.into())))
                }
                None => {
                    return Err(self.wrong_type("kind", v, "the string \"plane\" or \"point\""))
                }
            },
        };
        if let Some(&key) = kind
            .keys()
            .iter()
            .find(|k| !self.table.get_ref().contains_key(**k))
        {
            return Err(self.error(
                None,
                AreasErrorKind::MissingKey {
                    key,
                    area_kind: Some(kind),
                },
            ));
        }
        for (key, value) in self.table.get_ref() {
            let known = key == "kind"
                || kind.keys().contains(&key.as_str())
                || IGNORED_KEYS.contains(&key.as_str());
            if !known {
                return Err(self.error(
                    Some(value),
                    AreasErrorKind::UnknownKey {
                        key: key.clone(),
                        area_kind: kind,
                    },
                ));
            }
        }
        let [scene, file, orientation, thesis_test] = IGNORED_KEYS.map(|k| self.string(k));
        let area = match kind {
            AreaKind::Plane => PlaneArea::new(
                self.vec3("center")?,
                self.vec3("normal")?,
                self.number("half_width")?,
                self.number("half_height")?,
                self.number("depth")?,
            )
            .map(InfluenceArea::from),
            AreaKind::Point => PointArea::new(
                self.vec3("eye")?,
                self.vec3("direction")?,
                self.number("fov_x_deg")?,
                self.number("fov_y_deg")?,
                self.number("near")?,
                self.number("far")?,
            )
            .map(InfluenceArea::from),
        }
        .map_err(|e| {
            let value = area_error_key(&e).and_then(|k| self.table.get_ref().get(k));
            let kind = match value.and_then(|v| read_otherwise(self.text, v)) {
                Some((written, read)) => AreasErrorKind::InvalidAsRead {
                    error: e,
                    written,
                    read,
                },
                None => AreasErrorKind::Invalid(e),
            };
            self.error(value, kind)
        })?;
        Ok(AreaEntry {
            area,
            index: self.index,
            line: line_at(self.text, self.table.span().start),
            scene: scene?,
            file: file?,
            orientation: orientation?,
            thesis_test: thesis_test?,
        })
    }

    /// An error in this entry, on the line of `value` or else of the table.
    fn error(&self, value: Option<&Spanned<Value>>, kind: AreasErrorKind) -> AreasError {
        let start = value.map_or(self.table.span().start, |v| v.span().start);
        AreasError {
            path: self.label.to_path_buf(),
            line: Some(line_at(self.text, start)),
            entry: Some((self.tables, self.index)),
            kind,
        }
    }

    fn wrong_type(&self, key: &str, value: &Spanned<Value>, expected: &'static str) -> AreasError {
        self.error(
            Some(value),
            AreasErrorKind::WrongType {
                key: key.to_string(),
                expected,
                found: describe(value.get_ref()),
            },
        )
    }

    /// A required key; the caller has checked it is present.
    fn required(&self, key: &'static str) -> Result<&Spanned<Value>, AreasError> {
        self.table.get_ref().get(key).ok_or_else(|| {
            self.error(
                None,
                AreasErrorKind::MissingKey {
                    key,
                    area_kind: None,
                },
            )
        })
    }

    fn number(&self, key: &'static str) -> Result<f32, AreasError> {
        let value = self.required(key)?;
        as_f32(value.get_ref()).ok_or_else(|| self.wrong_type(key, value, "a number"))
    }

    fn vec3(&self, key: &'static str) -> Result<Vec3, AreasError> {
        let value = self.required(key)?;
        let xyz = value.get_ref().as_array().and_then(|a| match a.as_slice() {
            [x, y, z] => Some(Vec3::new(as_f32(x)?, as_f32(y)?, as_f32(z)?)),
            _ => None,
        });
        xyz.ok_or_else(|| self.wrong_type(key, value, "an array of 3 numbers"))
    }

    /// An optional string key.
    fn string(&self, key: &str) -> Result<Option<String>, AreasError> {
        match self.table.get_ref().get(key) {
            None => Ok(None),
            Some(v) => match v.get_ref().as_str() {
                Some(s) => Ok(Some(s.to_string())),
                None => Err(self.wrong_type(key, v, "a string")),
            },
        }
    }
}

/// A TOML integer or float as `f32` (huge values become infinite, which the area rejects).
fn as_f32(v: &Value) -> Option<f32> {
    match v {
        Value::Integer(i) => Some(*i as f32),
        Value::Float(f) => Some(*f as f32),
        _ => None,
    }
}

/// A number that single precision reads as another value than the file wrote, as `(written,
/// read)`: an invalid area's message then says so, since the written value may look valid.
fn read_otherwise(text: &str, value: &Spanned<Value>) -> Option<(String, f32)> {
    let read = as_f32(value.get_ref())?;
    let exact = match value.get_ref() {
        Value::Integer(i) => i.to_string(),
        Value::Float(f) => f.to_string(),
        _ => return None,
    };
    if read.to_string() == exact {
        return None;
    }
    let written = text.get(value.span())?.trim();
    Some((written.to_string(), read))
}

/// What a value is, for "must be X, not Y".
fn describe(v: &Value) -> String {
    match v {
        Value::String(s) => format!("the string \"{}\"", s.escape_debug()),
        Value::Array(a) if a.len() != 3 => format!("an array of {} values", a.len()),
        Value::Array(a) => match a.iter().find(|x| as_f32(x).is_none()) {
            Some(x) => format!("an array holding {}", describe(x)),
            None => "an array of 3 numbers".to_string(),
        },
        Value::Table(_) => "a table".to_string(),
        Value::Integer(i) => format!("the integer {i}"),
        other => format!("a {} ({other})", other.type_str()),
    }
}

/// The key an area error is about, to point at its line.
fn area_error_key(e: &AreaError) -> Option<&'static str> {
    match *e {
        AreaError::NotFinite(k)
        | AreaError::NotPositive(k)
        | AreaError::ZeroDirection(k)
        | AreaError::FieldOfView(k) => Some(k),
        AreaError::NearFar => Some("near"),
        AreaError::TooLarge(k) | AreaError::TooSmall(k) => Some(k),
        AreaError::Tolerance => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn label() -> PathBuf {
        PathBuf::from("areas.toml")
    }

    const PLANE: &str = "kind = \"plane\"\ncenter = [5.0, 5.0, -4.0]\nnormal = [0, 0, 1]\n\
                         half_width = 5.0\nhalf_height = 5\ndepth = 20.0\n";
    const POINT: &str = "kind = \"point\"\neye = [5.0, 12.0, 5.0]\ndirection = [0.0, -1.0, 0.1]\n\
                         fov_x_deg = 60.0\nfov_y_deg = 45\nnear = 1.0\nfar = 8.0\n";

    fn parse(text: &str) -> Result<AreaFile, AreasError> {
        parse_areas(text, &label())
    }

    /// The error of `text`, checking it is one line that names the file.
    fn error(text: &str) -> AreasError {
        let e = parse(text).expect_err(text);
        let s = e.to_string();
        assert!(s.starts_with("areas.toml"), "{s}");
        assert!(!s.contains('\n'), "{s}");
        e
    }

    #[test]
    fn both_kinds_in_order() {
        let file = parse(&format!("[[area]]\n{PLANE}\n[[area]]\n{POINT}")).unwrap();
        assert_eq!(file.tables, TableKind::Area);
        assert_eq!(file.entries.len(), 2);
        let InfluenceArea::Plane(p) = file.entries[0].area else {
            panic!("plane expected")
        };
        assert_eq!(p.center, Vec3::new(5.0, 5.0, -4.0));
        assert_eq!((p.half_width, p.half_height, p.depth), (5.0, 5.0, 20.0));
        let InfluenceArea::Point(q) = file.entries[1].area else {
            panic!("point expected")
        };
        assert_eq!((q.fov_x_deg, q.fov_y_deg), (60.0, 45.0));
        assert_eq!((file.entries[0].line, file.entries[1].line), (1, 9));
        assert_eq!(file.entries[1].index, 1);
        assert_eq!(file.areas().len(), 2);
    }

    #[test]
    fn experiment_keys_are_kept_and_do_not_change_the_area() {
        let plain = parse(&format!("[[area]]\n{PLANE}")).unwrap();
        let pasted = parse(&format!(
            "[[area]]\nscene = \"Random100\"\nfile = \"Random100.obj\"\n{PLANE}\
             orientation = \"parallel\"\nthesis_test = \"Random100_Plane_Parallel\"\n"
        ))
        .unwrap();
        assert_eq!(pasted.entries[0].area, plain.entries[0].area);
        assert_eq!(pasted.entries[0].file.as_deref(), Some("Random100.obj"));
        assert_eq!(pasted.entries[0].scene.as_deref(), Some("Random100"));
        assert_eq!(pasted.entries[0].orientation.as_deref(), Some("parallel"));
        assert_eq!(
            pasted.entries[0].thesis_test.as_deref(),
            Some("Random100_Plane_Parallel")
        );
    }

    #[test]
    fn config_tables_and_other_top_level_keys() {
        let text = format!(
            "scene_dir = \"x\"\n[settings]\nrays_per_config = 1000\n\n\
             [[config]]\nfile = \"Random100.obj\"\n{PLANE}\n\
             [[config]]\nfile = \"WoodScene.obj\"\n{POINT}\n\
             [[config]]\nscene = \"Crowd\"\n{PLANE}"
        );
        let file = parse(&text).unwrap();
        assert_eq!(file.tables, TableKind::Config);
        assert_eq!(file.entries.len(), 3);
        let wood = file.for_scene("/some/dir/WoodScene.obj").unwrap();
        assert_eq!(wood.len(), 1);
        assert_eq!(wood[0].index, 1);
        // A built-in scene matches its OBJ twin by stem, ignoring case.
        assert_eq!(file.for_scene("builtin:random100").unwrap()[0].index, 0);
        let e = file.for_scene("builtin:room").unwrap_err();
        let s = e.to_string();
        assert!(matches!(e.kind, AreasErrorKind::NoneForScene { .. }), "{s}");
        assert!(
            s.contains("builtin:room") && s.contains("Random100.obj, WoodScene.obj"),
            "{s}"
        );
        // [[area]] files apply to any scene.
        let areas = parse(&format!("[[area]]\nfile = \"Other.obj\"\n{PLANE}")).unwrap();
        assert_eq!(areas.for_scene("builtin:room").unwrap().len(), 1);
    }

    #[test]
    fn the_thesis_experiments_file_reads_whole() {
        let path = Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../shared/thesis/experiments.toml"
        ));
        let Ok(text) = fs::read_to_string(path) else {
            eprintln!("skipped: {} not found", path.display());
            return;
        };
        let file = parse_areas(&text, path).unwrap();
        assert_eq!(file.tables, TableKind::Config);
        assert_eq!(file.entries.len(), 64);
        assert_eq!(file.for_scene("WoodScene.obj").unwrap().len(), 8);
        let planes = file
            .entries
            .iter()
            .filter(|e| matches!(e.area, InfluenceArea::Plane(_)))
            .count();
        assert_eq!(planes, 32);
    }

    #[test]
    fn missing_keys_name_the_key_and_the_area() {
        for key in AreaKind::Plane.keys() {
            let body: String = PLANE
                .lines()
                .filter(|l| !l.starts_with(&format!("{key} ")))
                .map(|l| format!("{l}\n"))
                .collect();
            let e = error(&format!("[[area]]\n{PLANE}\n[[area]]\n{body}"));
            assert!(
                matches!(e.kind, AreasErrorKind::MissingKey { key: k, .. } if k == *key),
                "{e}"
            );
            let s = e.to_string();
            assert!(s.contains(&format!("area 1: missing key `{key}`")), "{s}");
            assert!(s.contains("line 9"), "{s}");
        }
        for key in AreaKind::Point.keys() {
            let body: String = POINT
                .lines()
                .filter(|l| !l.starts_with(&format!("{key} ")))
                .map(|l| format!("{l}\n"))
                .collect();
            let s = error(&format!("[[area]]\n{body}")).to_string();
            assert!(s.contains(&format!("area 0: missing key `{key}`")), "{s}");
            assert!(s.contains("a point area needs eye, direction"), "{s}");
        }
        let s = error("[[area]]\ncenter = [0, 0, 0]\n").to_string();
        assert!(s.contains("area 0: missing key `kind`"), "{s}");
        let s = error(&format!("[[config]]\n{}", &PLANE[15..])).to_string();
        assert!(s.contains("config 0: missing key `kind`"), "{s}");
    }

    #[test]
    fn wrong_types_name_the_key_and_the_line() {
        for (line, needle) in [
            (
                "kind = 3",
                "`kind` must be the string \"plane\" or \"point\", not the integer 3",
            ),
            (
                "depth = \"20\"",
                "`depth` must be a number, not the string \"20\"",
            ),
            ("depth = true", "`depth` must be a number, not a boolean"),
            (
                "center = [1, 2]",
                "`center` must be an array of 3 numbers, not an array of 2",
            ),
            (
                "center = 5",
                "`center` must be an array of 3 numbers, not the integer 5",
            ),
            (
                "normal = [0, \"a\", 1]",
                "`normal` must be an array of 3 numbers, not an array holding the string",
            ),
            (
                "half_width = [1, 2, 3]",
                "`half_width` must be a number, not an array",
            ),
            ("half_width = { x = 1 }", "not a table"),
            ("file = 3", "`file` must be a string"),
            ("thesis_test = [1]", "`thesis_test` must be a string"),
        ] {
            let key = line.split(' ').next().unwrap();
            let body: String = PLANE
                .lines()
                .filter(|l| !l.starts_with(&format!("{key} ")))
                .map(|l| format!("{l}\n"))
                .collect();
            let e = error(&format!("[[area]]\n{body}{line}\n"));
            let s = e.to_string();
            assert!(s.contains(needle), "{line}: {s}");
            assert!(s.contains("area 0: "), "{s}");
            // The offending value is on the file's last line.
            assert!(
                s.contains(&format!("line {}:", body.lines().count() + 2)),
                "{s}"
            );
        }
    }

    #[test]
    fn unknown_kinds_and_keys() {
        let s = error(&format!("[[area]]\n{}", PLANE.replace("plane", "sphere"))).to_string();
        assert!(s.contains("area 0: unknown kind \"sphere\""), "{s}");
        assert!(s.contains("line 2"), "{s}");
        let s = error(&format!("[[area]]\n{PLANE}radius = 3\n")).to_string();
        assert!(s.contains("unknown key `radius` for a plane area"), "{s}");
        // A point key in a plane area is a mistake worth naming.
        let s = error(&format!("[[area]]\n{PLANE}eye = [0, 0, 0]\n")).to_string();
        assert!(s.contains("unknown key `eye`"), "{s}");
        // Keys are case-sensitive, as in experiments.toml.
        let s = error(&format!(
            "[[area]]\n{}",
            PLANE.replace("\"plane\"", "\"Plane\"")
        ))
        .to_string();
        assert!(s.contains("unknown kind \"Plane\""), "{s}");
    }

    #[test]
    fn bad_values_use_the_core_message() {
        for (from, to, needle) in [
            (
                "depth = 20.0",
                "depth = 0",
                "area 0: `depth` must be positive",
            ),
            (
                "half_width = 5.0",
                "half_width = -1",
                "`half_width` must be positive",
            ),
            (
                "normal = [0, 0, 1]",
                "normal = [0, 0, 0]",
                "`normal` must not be the zero vector",
            ),
            ("depth = 20.0", "depth = nan", "`depth` must be finite"),
            (
                "center = [5.0, 5.0, -4.0]",
                "center = [inf, 0, 0]",
                "`center` must be finite",
            ),
            (
                "depth = 20.0",
                "depth = 1e300",
                "`depth` must be finite (got NaN or infinity); 1e300 reads as inf in single precision",
            ),
        ] {
            let text = format!("[[area]]\n{}", PLANE.replace(from, to));
            assert_ne!(text, format!("[[area]]\n{PLANE}"), "{from}");
            let e = error(&text);
            assert!(
                matches!(
                    e.kind,
                    AreasErrorKind::Invalid(_) | AreasErrorKind::InvalidAsRead { .. }
                ),
                "{e}"
            );
            let s = e.to_string();
            assert!(s.contains(needle), "{s}");
            let line = text.lines().position(|l| l == to).unwrap() + 1;
            assert!(s.contains(&format!("line {line}:")), "{s}");
        }
        for (from, to, needle) in [
            (
                "fov_x_deg = 60.0",
                "fov_x_deg = 180",
                "`fov_x_deg` must be strictly between 0 and 180 degrees",
            ),
            // Below 180 as written, 180 as read: the message says why it is refused.
            (
                "fov_x_deg = 60.0",
                "fov_x_deg = 179.99999999",
                "`fov_x_deg` must be strictly between 0 and 180 degrees; 179.99999999 reads as 180 \
                 in single precision",
            ),
            (
                "fov_y_deg = 45",
                "fov_y_deg = 0",
                "`fov_y_deg` must be strictly between",
            ),
            (
                "near = 1.0",
                "near = 9.0",
                "`near` must be >= 0 and below `far`",
            ),
            ("near = 1.0", "near = -1", "`near` must be >= 0"),
            (
                "direction = [0.0, -1.0, 0.1]",
                "direction = [0, 0, 0]",
                "zero vector",
            ),
        ] {
            let text = format!("[[area]]\n{}", POINT.replace(from, to));
            let s = error(&text).to_string();
            assert!(s.contains(needle), "{s}");
        }
    }

    #[test]
    fn file_level_errors() {
        let e = error("");
        assert!(matches!(e.kind, AreasErrorKind::NoAreas), "{e}");
        let e = error("area = []\n");
        assert!(matches!(e.kind, AreasErrorKind::NoAreas), "{e}");
        let e = error("[settings]\nx = 1\n");
        assert!(matches!(e.kind, AreasErrorKind::NoAreas), "{e}");
        let s = error(&format!("[area]\n{PLANE}")).to_string();
        assert!(s.contains("write each entry as [[area]]"), "{s}");
        let s = error("area = 5\n").to_string();
        assert!(s.contains("array of tables"), "{s}");
        let s = error(&format!("[[area]]\n{PLANE}\n[[config]]\n{PLANE}")).to_string();
        assert!(s.contains("both [[area]] and [[config]]"), "{s}");
        // TOML syntax errors keep the line and stay on one line.
        let e = error(&format!("[[area]]\n{PLANE}depth = = 3\n"));
        assert!(matches!(e.kind, AreasErrorKind::Syntax(_)), "{e}");
        assert_eq!(e.line, Some(8), "{e}");
        let e = error(&format!("[[area]]\n{PLANE}depth = 3\n"));
        assert!(
            matches!(e.kind, AreasErrorKind::Syntax(_)),
            "duplicate key: {e}"
        );
        let e = read_areas(Path::new("/nonexistent/areas.toml")).unwrap_err();
        assert!(matches!(e.kind, AreasErrorKind::Io(_)));
        let s = e.to_string();
        assert!(
            s.starts_with("/nonexistent/areas.toml: cannot read: "),
            "{s}"
        );
    }
}
