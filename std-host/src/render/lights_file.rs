//! The lights file (`--lights FILE.toml`): point, spot and quad lights, each a `[[light]]` table
//! with a `kind`. Every error names the light (its index from 0 and its kind) and the field.
//!
//! ```toml
//! [[light]]
//! kind = "point"
//! position = [0.0, 1.9, 0.0]
//! intensity = [5.0, 5.0, 5.0]     # radiant intensity, RGB
//!
//! [[light]]
//! kind = "spot"
//! position = [0.0, 1.9, 0.0]
//! direction = [0.0, -1.0, 0.0]
//! angle_deg = 30.0                # the cone's half-angle, in (0, 90]
//! intensity = [5.0, 5.0, 5.0]
//!
//! [[light]]
//! kind = "quad"                   # one-sided: emits toward edge1 x edge2
//! corner = [-0.25, 1.98, -0.25]
//! edge1 = [0.5, 0.0, 0.0]
//! edge2 = [0.0, 0.0, 0.5]
//! radiance = [10.0, 10.0, 10.0]
//! ```

use std::path::Path;

use rdbvh_core::Vec3;
use toml::{Table, Value};

use super::direction::unit;
use super::{Light, RenderError};

/// The light kinds and the fields each one takes, all required.
const KINDS: [(&str, &[&str]); 3] = [
    ("point", &["position", "intensity"]),
    ("spot", &["position", "direction", "angle_deg", "intensity"]),
    ("quad", &["corner", "edge1", "edge2", "radiance"]),
];

/// Reads the lights of the file at `path`.
pub fn read_lights(path: &Path) -> Result<Vec<Light>, RenderError> {
    let text = std::fs::read_to_string(path).map_err(|source| RenderError::LightsFile {
        path: path.to_path_buf(),
        source,
    })?;
    parse_lights(&text, path)
}

/// Parses the lights file `text`; `path` names it in errors. A file without any `[[light]]` has
/// no lights, which is fine when the scene has emissive triangles.
pub fn parse_lights(text: &str, path: &Path) -> Result<Vec<Light>, RenderError> {
    let syntax = |reason: String| RenderError::LightsSyntax {
        path: path.to_path_buf(),
        reason,
    };
    let table: Table = text
        .parse()
        .map_err(|e: toml::de::Error| syntax(e.to_string().trim().replace('\n', " ")))?;
    let mut lights = Vec::new();
    for (key, value) in table {
        if key != "light" {
            return Err(syntax(format!(
                "unknown key `{key}`: a lights file has only [[light]] tables"
            )));
        }
        let Value::Array(items) = value else {
            return Err(syntax(
                "`light` must be an array of tables, [[light]]".into(),
            ));
        };
        for (index, item) in items.into_iter().enumerate() {
            let fail = |kind: Option<&str>, reason: String| RenderError::Light {
                path: path.to_path_buf(),
                index,
                kind: kind.map(str::to_string),
                reason,
            };
            let Value::Table(fields) = item else {
                return Err(fail(None, "must be a table, [[light]]".into()));
            };
            lights.push(parse_light(&fields).map_err(|(kind, reason)| fail(kind, reason))?);
        }
    }
    Ok(lights)
}

/// One `[[light]]` table; the error carries the kind, when valid, and the reason.
fn parse_light(fields: &Table) -> Result<Light, (Option<&'static str>, String)> {
    let kind = match fields.get("kind") {
        None => return Err((None, "missing field `kind` (point, spot or quad)".into())),
        Some(Value::String(k)) => k.as_str(),
        Some(v) => return Err((None, format!("`kind` must be a string, got {v}"))),
    };
    let Some(&(kind, allowed)) = KINDS.iter().find(|(k, _)| *k == kind) else {
        return Err((
            None,
            format!("unknown kind `{kind}` (expected point, spot or quad)"),
        ));
    };
    let fail = |reason: String| (Some(kind), reason);
    if let Some(unknown) = fields
        .keys()
        .find(|k| *k != "kind" && !allowed.contains(&k.as_str()))
    {
        return Err(fail(format!(
            "unknown field `{unknown}` (a {kind} light takes {})",
            allowed.join(", ")
        )));
    }
    let vector = |name: &str| vec3(fields, name).map_err(fail);
    let colour = |name: &str| {
        let c = vector(name)?;
        if c.min_element() < 0.0 || c.max_element() <= 0.0 {
            return Err(fail(format!(
                "`{name}` must be non-negative with a positive component, got {}",
                show(c)
            )));
        }
        Ok(c)
    };
    match kind {
        "point" => Ok(Light::Point {
            position: vector("position")?,
            intensity: colour("intensity")?,
        }),
        "spot" => {
            let position = vector("position")?;
            let direction = vector("direction")?;
            if direction == Vec3::ZERO {
                return Err(fail("`direction` must not be the zero vector".into()));
            }
            let angle = number(fields, "angle_deg").map_err(fail)?;
            if !(angle > 0.0 && angle <= 90.0) {
                return Err(fail(format!("`angle_deg` must be in (0, 90], got {angle}")));
            }
            let half_angle = (angle as f32).to_radians().min(std::f32::consts::FRAC_PI_2);
            Ok(Light::Spot {
                position,
                direction: unit(direction),
                half_angle,
                cos_half_angle: half_angle.cos(),
                intensity: colour("intensity")?,
            })
        }
        _ => {
            let corner = vector("corner")?;
            let (edge1, edge2) = (vector("edge1")?, vector("edge2")?);
            // The sample weight takes `edge1 x edge2` in f32.
            if !edge1.cross(edge2).is_finite() {
                return Err(fail(format!(
                    "`edge1` {} and `edge2` {} span an area too large for single precision",
                    show(edge1),
                    show(edge2)
                )));
            }
            // In f64, where neither the area nor the lengths' squares overflow or underflow.
            let (e1, e2) = (edge1.as_dvec3(), edge2.as_dvec3());
            let area = e1.cross(e2).length();
            if !(area > 1e-6 * e1.length() * e2.length() && area > 0.0) {
                return Err(fail(format!(
                    "`edge1` {} and `edge2` {} span no area: the quad is degenerate",
                    show(edge1),
                    show(edge2)
                )));
            }
            Ok(Light::Quad {
                corner,
                edge1,
                edge2,
                radiance: colour("radiance")?,
            })
        }
    }
}

/// A finite number (integer or float) in field `name`.
fn number(fields: &Table, name: &str) -> Result<f64, String> {
    match fields.get(name) {
        None => Err(format!("missing field `{name}`")),
        Some(v) => scalar(v).ok_or_else(|| format!("`{name}` must be a finite number, got {v}")),
    }
}

/// Three finite numbers in field `name`, representable as `f32`.
fn vec3(fields: &Table, name: &str) -> Result<Vec3, String> {
    let bad = |v: &Value| format!("`{name}` must be three finite numbers [x, y, z], got {v}");
    let value = fields
        .get(name)
        .ok_or_else(|| format!("missing field `{name}`"))?;
    let Value::Array(items) = value else {
        return Err(bad(value));
    };
    let xs: Option<Vec<f32>> = items
        .iter()
        .map(|v| scalar(v).map(|x| x as f32).filter(|x| x.is_finite()))
        .collect();
    match xs.as_deref() {
        Some(&[x, y, z]) => Ok(Vec3::new(x, y, z)),
        _ => Err(bad(value)),
    }
}

/// A TOML integer or finite float as `f64`.
fn scalar(v: &Value) -> Option<f64> {
    match v {
        Value::Integer(i) => Some(*i as f64),
        Value::Float(x) if x.is_finite() => Some(*x),
        _ => None,
    }
}

/// `[x, y, z]`, as the file writes it.
fn show(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Vec<Light>, String> {
        parse_lights(text, Path::new("l.toml")).map_err(|e| e.to_string())
    }

    #[test]
    fn the_documented_example_parses() {
        let doc = include_str!("lights_file.rs");
        let example: String = doc
            .lines()
            .skip_while(|l| !l.starts_with("//! ```toml"))
            .skip(1)
            .take_while(|l| !l.starts_with("//! ```"))
            .map(|l| l.trim_start_matches("//!").trim_start().to_string() + "\n")
            .collect();
        let lights = parse(&example).unwrap();
        assert_eq!(lights.len(), 3);
        assert!(
            matches!(lights[1], Light::Spot { half_angle, .. } if (half_angle - 30f32.to_radians()).abs() < 1e-6)
        );
    }

    #[test]
    fn an_empty_file_has_no_lights() {
        assert_eq!(parse("").unwrap(), vec![]);
    }

    #[test]
    fn every_error_names_the_light_and_the_field() {
        let point = "[[light]]\nkind = \"point\"\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\n";
        for (text, expected) in [
            (
                "[[light]]\nkind = \"area\"\n",
                "light 0: unknown kind `area`",
            ),
            (
                "[[light]]\nposition = [0, 0, 0]\n",
                "light 0: missing field `kind`",
            ),
            (
                &format!("{point}[[light]]\nkind = \"point\"\nintensity = [1, 1, 1]\n"),
                "light 1 (point): missing field `position`",
            ),
            (
                "[[light]]\nkind = \"point\"\nposition = [nan, 0, 0]\nintensity = [1, 1, 1]\n",
                "`position` must be three finite numbers",
            ),
            (
                "[[light]]\nkind = \"point\"\nposition = [1e39, 0, 0]\nintensity = [1, 1, 1]\n",
                "`position` must be three finite numbers",
            ),
            (
                "[[light]]\nkind = \"point\"\nposition = [0, 0]\nintensity = [1, 1, 1]\n",
                "`position` must be three finite numbers",
            ),
            (
                "[[light]]\nkind = \"point\"\nposition = [0, 0, 0]\nintensity = [-1, 1, 1]\n",
                "light 0 (point): `intensity` must be non-negative",
            ),
            (
                "[[light]]\nkind = \"point\"\nposition = [0, 0, 0]\nintensity = [0, 0, 0]\n",
                "`intensity` must be non-negative with a positive component",
            ),
            (
                &format!("{point}colour = 3\n"),
                "light 0 (point): unknown field `colour`",
            ),
            (
                "[[light]]\nkind = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, 0, 0]\n\
                 angle_deg = 30\nintensity = [1, 1, 1]\n",
                "light 0 (spot): `direction` must not be the zero vector",
            ),
            (
                "[[light]]\nkind = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, -1, 0]\n\
                 angle_deg = 120\nintensity = [1, 1, 1]\n",
                "light 0 (spot): `angle_deg` must be in (0, 90], got 120",
            ),
            (
                "[[light]]\nkind = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, -1, 0]\n\
                 angle_deg = 0\nintensity = [1, 1, 1]\n",
                "`angle_deg` must be in (0, 90]",
            ),
            (
                "[[light]]\nkind = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, -1, 0]\n\
                 angle_deg = inf\nintensity = [1, 1, 1]\n",
                "`angle_deg` must be a finite number",
            ),
            (
                "[[light]]\nkind = \"quad\"\ncorner = [0, 0, 0]\nedge1 = [1, 0, 0]\n\
                 edge2 = [2, 0, 0]\nradiance = [1, 1, 1]\n",
                "light 0 (quad): `edge1` [1, 0, 0] and `edge2` [2, 0, 0] span no area",
            ),
            (
                "[[light]]\nkind = \"quad\"\ncorner = [0, 0, 0]\nedge1 = [0, 0, 0]\n\
                 edge2 = [1, 0, 0]\nradiance = [1, 1, 1]\n",
                "the quad is degenerate",
            ),
            (
                "[[light]]\nkind = \"quad\"\ncorner = [0, 0, 0]\nedge1 = [1e20, 0, 0]\n\
                 edge2 = [0, 1e20, 0]\nradiance = [1, 1, 1]\n",
                "span an area too large for single precision",
            ),
            ("[[lights]]\nkind = \"point\"\n", "unknown key `lights`"),
            ("light = 3\n", "`light` must be an array of tables"),
            ("[[light]\n", "l.toml"),
        ] {
            let e = parse(text).unwrap_err();
            assert!(e.contains(expected), "{text:?}: {e}");
            assert!(
                e.starts_with("l.toml") || e.starts_with("lights file l.toml"),
                "{e}"
            );
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn spot_angle_of_90_degrees_is_a_half_space() {
        let lights = parse(
            "[[light]]\nkind = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, 2, 0]\n\
             angle_deg = 90\nintensity = [1, 1, 1]\n",
        )
        .unwrap();
        let Light::Spot {
            direction,
            half_angle,
            ..
        } = lights[0]
        else {
            panic!()
        };
        assert_eq!(direction, Vec3::Y);
        assert!(half_angle <= std::f32::consts::FRAC_PI_2);
    }

    /// A spot's axis is a direction whatever its length: one whose square leaves f32's range
    /// once normalised to zero or to NaN, and the spot lit nothing.
    #[test]
    fn a_spot_axis_of_any_finite_length_is_a_direction() {
        for len in ["1e-30", "1e20", "3e38"] {
            let lights = parse(&format!(
                "[[light]]\nkind = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, -{len}, 0]\n\
                 angle_deg = 30\nintensity = [1, 1, 1]\n"
            ))
            .unwrap();
            let Light::Spot { direction, .. } = lights[0] else {
                panic!()
            };
            assert_eq!(direction, Vec3::NEG_Y, "{len}");
        }
    }
}
