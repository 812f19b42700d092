//! Everything the renderer can refuse: every message names the input at fault, so the command
//! line prints it as one `error: ...` line.

use std::fmt;
use std::path::PathBuf;

use rdbvh_core::builder::PresetError;
use rdbvh_core::light_buffer::LightSourceError;
use rdbvh_core::toplevel::TopLevelError;
use rdbvh_core::BuildError;

/// Why a render could not start or finish.
#[derive(Debug)]
pub enum RenderError {
    /// The lights file could not be read.
    LightsFile {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// The lights file is not valid TOML, or not the lights format.
    LightsSyntax {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the line when the TOML parser knows it.
        reason: String,
    },
    /// One light of the lights file is unusable: `light INDEX (KIND): FIELD ...`.
    Light {
        /// The file.
        path: PathBuf,
        /// The light's position in the file, from 0.
        index: usize,
        /// Its `kind`, when it has a valid one.
        kind: Option<String>,
        /// What is wrong, naming the field.
        reason: String,
    },
    /// A material the scene's triangles use has a colour the renderer cannot use.
    Material {
        /// The material's name.
        name: String,
        /// What is wrong, naming the MTL field.
        reason: String,
    },
    /// Neither the scene (emissive `Ke` materials) nor `--lights` gives a light.
    NoLights {
        /// The scene's name.
        scene: String,
        /// Its emissive triangles.
        emissive: usize,
        /// The lights file given, and how many lights it holds.
        from_file: Option<(String, usize)>,
    },
    /// The image's radiance is not finite: the lights are too bright for f32.
    RadianceOverflow,
    /// The camera cannot be made from the options given.
    Camera(String),
    /// The BVH or a light buffer could not be built.
    Build(BuildError),
    /// A light could not be made into a light buffer's source.
    LightSource(LightSourceError),
    /// A local BVH of the `thesis` structure could not be built.
    Thesis(TopLevelError),
    /// The replay of the frame's shadow rays disagreed with the frame: a bug, reported loudly.
    Replay(String),
    /// The image could not be encoded.
    Encode(String),
}

impl fmt::Display for RenderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RenderError::LightsFile { path, source } => {
                write!(f, "cannot read lights file {}: {source}", path.display())
            }
            RenderError::LightsSyntax { path, reason } => {
                write!(f, "lights file {}: {reason}", path.display())
            }
            RenderError::Light {
                path,
                index,
                kind,
                reason,
            } => match kind {
                Some(kind) => write!(f, "{}: light {index} ({kind}): {reason}", path.display()),
                None => write!(f, "{}: light {index}: {reason}", path.display()),
            },
            RenderError::Material { name, reason } => write!(f, "material `{name}`: {reason}"),
            RenderError::NoLights {
                scene,
                emissive: 0,
                from_file: None,
            } => write!(
                f,
                "{scene} has no light: no material emits (MTL `Ke`) and no --lights file was \
                 given"
            ),
            RenderError::NoLights {
                scene,
                emissive: 0,
                from_file: Some((file, 0)),
            } => write!(
                f,
                "{scene} has no light: no material emits (MTL `Ke`) and the lights file {file} \
                 holds no [[light]]"
            ),
            RenderError::NoLights {
                scene,
                emissive,
                from_file,
            } => {
                let given = from_file.as_ref().map_or(0, |(_, n)| *n);
                write!(
                    f,
                    "{scene} has no light of positive power: {emissive} emissive triangles \
                     (MTL `Ke`) and {given} lights from --lights, each emitting nothing in \
                     single precision (a triangle too small, a spot's `angle_deg` or a quad's \
                     area too small, or an emission that rounds to zero)"
                )
            }
            RenderError::RadianceOverflow => write!(
                f,
                "the image's radiance overflows single precision: a light's `intensity` or \
                 `radiance` (or an MTL `Ke`) is too large for this scene; no image was written"
            ),
            RenderError::Camera(why) => write!(f, "camera: {why}"),
            RenderError::Build(e) => write!(f, "BVH build failed: {e}"),
            RenderError::LightSource(e) => write!(f, "light buffer: {e}"),
            RenderError::Thesis(e) => write!(f, "thesis structure: {e}"),
            RenderError::Replay(what) => write!(f, "shadow ray replay disagrees: {what}"),
            RenderError::Encode(why) => write!(f, "cannot encode the PNG: {why}"),
        }
    }
}

impl std::error::Error for RenderError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            RenderError::LightsFile { source, .. } => Some(source),
            RenderError::LightSource(e) => Some(e),
            _ => None,
        }
    }
}

impl From<BuildError> for RenderError {
    fn from(e: BuildError) -> Self {
        RenderError::Build(e)
    }
}

/// The global BVH's preset needs no area, so a preset's error is its build's.
impl From<PresetError> for RenderError {
    fn from(e: PresetError) -> Self {
        match e {
            PresetError::Build(e) => RenderError::Build(e),
            PresetError::NeedsArea(_) => RenderError::Build(BuildError::InvalidConfig(
                "the global BVH's preset needs an influence area",
            )),
        }
    }
}

impl From<LightSourceError> for RenderError {
    fn from(e: LightSourceError) -> Self {
        RenderError::LightSource(e)
    }
}
