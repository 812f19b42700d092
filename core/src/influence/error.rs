//! Errors of influence-area construction.

use core::fmt;

/// Why an influence area could not be made. Each names the offending key as `experiments.toml`
/// spells it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AreaError {
    /// A value is NaN or infinite.
    NotFinite(&'static str),
    /// A length that must be positive is zero or negative.
    NotPositive(&'static str),
    /// A direction is the zero vector.
    ZeroDirection(&'static str),
    /// A field of view is not strictly between 0 and 180 degrees.
    FieldOfView(&'static str),
    /// `near` is negative or not below `far`.
    NearFar,
    /// The affinity tolerance is not within `[0, 180)` degrees.
    Tolerance,
    /// The area reaches farther than [`MAX_AREA_COORDINATE`] from the origin: products of its
    /// coordinates would overflow `f32`, and its planes would lose the box to rounding.
    TooLarge(&'static str),
    /// The light's window is too small for `f32` measures: its area (plane) or its image-plane
    /// area `4 tan_x tan_y` (point) is below [`MIN_WINDOW_MEASURE`].
    TooSmall(&'static str),
}

/// The smallest window measure an area may have, `2^-100` (about 7.9e-31): the measures of the
/// boxes inside it, down to `2^-24` of it, then stay normal `f32`s. Below it they round to
/// subnormals and zero, and every PAH cost over the window reads zero.
pub const MIN_WINDOW_MEASURE: f32 = 1.0 / (1u128 << 100) as f32;

/// [`AreaError::TooSmall`] (naming the smaller side's key) unless a window of half sides `a`
/// and `b` (half extents, or half-angle tangents) measures at least [`MIN_WINDOW_MEASURE`].
pub(crate) fn window_measurable(
    (a, a_key): (f32, &'static str),
    (b, b_key): (f32, &'static str),
) -> Result<(), AreaError> {
    if 4.0 * a * b >= MIN_WINDOW_MEASURE {
        return Ok(());
    }
    Err(AreaError::TooSmall(if a < b { a_key } else { b_key }))
}

/// How far from the origin an influence area may reach, per coordinate. Its plane offsets and
/// separating-axis projections multiply coordinates, and `1e18` squared stays well inside `f32`.
pub const MAX_AREA_COORDINATE: f32 = 1e18;

impl fmt::Display for AreaError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AreaError::NotFinite(key) => write!(f, "`{key}` must be finite (got NaN or infinity)"),
            AreaError::NotPositive(key) => write!(f, "`{key}` must be positive"),
            AreaError::ZeroDirection(key) => write!(f, "`{key}` must not be the zero vector"),
            AreaError::FieldOfView(key) => {
                write!(f, "`{key}` must be strictly between 0 and 180 degrees")
            }
            AreaError::NearFar => f.write_str("`near` must be >= 0 and below `far`"),
            AreaError::Tolerance => {
                f.write_str("the affinity tolerance must be within [0, 180) degrees")
            }
            AreaError::TooSmall(key) => write!(
                f,
                "`{key}` makes the light's window too small for f32 measures (its area must be \
                 at least 2^-100, about 7.9e-31)"
            ),
            AreaError::TooLarge(key) => write!(
                f,
                "`{key}` puts the area more than 1e18 units from the origin, beyond what f32 \
                 geometry can test"
            ),
        }
    }
}

impl core::error::Error for AreaError {}

/// Checks that every component is finite.
pub(crate) fn finite3(v: glam::Vec3, key: &'static str) -> Result<glam::Vec3, AreaError> {
    v.is_finite().then_some(v).ok_or(AreaError::NotFinite(key))
}

/// Checks that a length is finite and positive.
pub(crate) fn positive(x: f32, key: &'static str) -> Result<f32, AreaError> {
    if !x.is_finite() {
        return Err(AreaError::NotFinite(key));
    }
    (x > 0.0).then_some(x).ok_or(AreaError::NotPositive(key))
}

/// The cosine of an affinity tolerance in degrees.
pub(crate) fn cos_tolerance(deg: f32) -> Result<f32, AreaError> {
    if !(0.0..180.0).contains(&deg) {
        return Err(AreaError::Tolerance);
    }
    Ok(libm::cosf(deg.to_radians()))
}
