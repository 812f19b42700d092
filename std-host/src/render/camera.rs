//! A pinhole camera: `--eye`, `--look-at`, `--up` and a vertical field of view, or a default that
//! frames the scene's bounds.

use rdbvh_core::geometry::{Aabb, Ray};
use rdbvh_core::Vec3;

use super::direction::{in_range, unit};
use super::RenderError;

/// The default vertical field of view, in degrees.
pub const DEFAULT_FOV_DEG: f32 = 50.0;

/// A pinhole camera over a `width x height` image; pixel `(0, 0)` is the top left.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    eye: Vec3,
    forward: Vec3,
    /// `right` and `up` are the image plane's half-extents at unit distance: unit vectors scaled
    /// by the tangents of the half fields of view.
    right: Vec3,
    up: Vec3,
    /// The unit right vector and the vertical tangent, to make the camera at another size.
    unit_right: Vec3,
    tan_y: f32,
    width: f32,
    height: f32,
}

impl Camera {
    /// A camera at `eye` looking at `look_at`, `up` giving the image's up direction, with a
    /// vertical field of view of `fov_deg` degrees in (0, 180).
    pub fn new(
        eye: Vec3,
        look_at: Vec3,
        up: Vec3,
        fov_deg: f32,
        width: u32,
        height: u32,
    ) -> Result<Self, RenderError> {
        let bad = |why: String| Err(RenderError::Camera(why));
        for (name, v) in [("--eye", eye), ("--look-at", look_at), ("--up", up)] {
            if !v.is_finite() {
                return bad(format!("{name} must be finite, got {v}"));
            }
        }
        check_fov(fov_deg)?;
        if width == 0 || height == 0 {
            return bad(format!(
                "the image must not be empty, got {width} x {height}"
            ));
        }
        let view = look_at - eye;
        if !view.is_finite() {
            return bad(format!(
                "--eye {eye} and --look-at {look_at} are too far apart for single precision"
            ));
        }
        let forward = unit(view);
        if forward == Vec3::ZERO {
            return bad("--eye and --look-at must differ".to_string());
        }
        let right = unit(forward.cross(in_range(up)));
        if right == Vec3::ZERO {
            return bad(format!(
                "--up {up} must not be zero or parallel to the viewing direction"
            ));
        }
        let tan_y = (fov_deg.to_radians() * 0.5).tan();
        Ok(Self::from_basis(eye, forward, right, tan_y, width, height))
    }

    /// The camera at `eye` looking along the unit `forward`, with the unit `right` at right
    /// angles to it and a vertical half field of view of tangent `tan_y`.
    fn from_basis(
        eye: Vec3,
        forward: Vec3,
        right: Vec3,
        tan_y: f32,
        width: u32,
        height: u32,
    ) -> Self {
        let image_up = right.cross(forward);
        let tan_x = tan_y * width as f32 / height as f32;
        Self {
            eye,
            forward,
            right: right * tan_x,
            up: image_up * tan_y,
            unit_right: right,
            tan_y,
            width: width as f32,
            height: height as f32,
        }
    }

    /// The same camera over a `width x height` image (not empty): bit for bit what
    /// [`Camera::new`] makes from this one's arguments at that size. The pilot frame's camera.
    pub fn resized(&self, width: u32, height: u32) -> Self {
        Self::from_basis(
            self.eye,
            self.forward,
            self.unit_right,
            self.tan_y,
            width.max(1),
            height.max(1),
        )
    }

    /// The cone every ray of [`Camera::ray`] leaves the eye in: its unit axis (the viewing
    /// direction) and its half-angle in radians, the angle to the image's corners, widened by
    /// 1 % so that rounding leaves no ray outside. At least 1e-6 (a field of view so narrow that
    /// its tangent rounds to zero still has a cone) and at most a right angle.
    pub fn view_cone(&self) -> (Vec3, f32) {
        let corner = (self.right + self.up).length().atan();
        (
            self.forward,
            (corner * 1.01).clamp(1e-6, core::f32::consts::FRAC_PI_2),
        )
    }

    /// The default camera: on the `+z` side of `bounds`, looking along `-z` at their centre, `y`
    /// up, far enough that the box's `+z` face fills the view with a 5 % margin. It frames an
    /// object, or a room that is open toward `+z` like the Cornell box; a closed room needs a
    /// camera inside it.
    pub fn framing(
        bounds: Aabb,
        fov_deg: f32,
        width: u32,
        height: u32,
    ) -> Result<Self, RenderError> {
        check_fov(fov_deg)?;
        let centre = bounds.center();
        let half = (bounds.max - bounds.min) * 0.5;
        let tan_y = (fov_deg.to_radians() * 0.5).tan();
        let aspect = width as f32 / height.max(1) as f32;
        let fit = (half.y / tan_y).max(half.x / (tan_y * aspect)) * 1.05;
        // A scene flat in x and y still needs the eye off its face: by a tenth of its depth. A
        // single point at the world origin, by one unit. Every other distance is relative to
        // the scene, whatever its scale.
        let distance = fit
            .max(0.1 * half.max_element())
            .max(1e-3 * centre.abs().max_element());
        let distance = if distance > 0.0 { distance } else { 1.0 };
        let eye = Vec3::new(centre.x, centre.y, bounds.max.z + distance);
        if !eye.is_finite() || eye == centre {
            return Err(RenderError::Camera(format!(
                "the default camera cannot frame the scene's bounds {} to {} in single \
                 precision (its eye would be at {eye}); give --eye and --look-at",
                bounds.min, bounds.max
            )));
        }
        Self::new(eye, centre, Vec3::Y, fov_deg, width, height)
    }

    /// The camera's position.
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// The ray through the image point `(x, y)`, in pixels from the top left. Its direction is
    /// not normalised: hit distances are in units of it, as for every ray in rdbvh.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let sx = 2.0 * x / self.width - 1.0;
        let sy = 1.0 - 2.0 * y / self.height;
        let dir = self.forward + self.right * sx + self.up * sy;
        // The eye is finite and `dir` has a unit component along `forward`: never an error.
        Ray::new(self.eye, dir).unwrap_or_else(|_| unreachable!("checked camera"))
    }
}

/// A vertical field of view must be in (0, 180) degrees.
fn check_fov(fov_deg: f32) -> Result<(), RenderError> {
    if fov_deg > 0.0 && fov_deg < 180.0 {
        Ok(())
    } else {
        Err(RenderError::Camera(format!(
            "--fov must be in (0, 180) degrees, got {fov_deg}"
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_at_the_target() {
        let c = Camera::new(Vec3::ZERO, Vec3::new(0.0, 0.0, -5.0), Vec3::Y, 90.0, 4, 2).unwrap();
        let r = c.ray(2.0, 1.0);
        assert!((r.dir.normalize() - Vec3::NEG_Z).length() < 1e-6);
        // The top left corner: 45 degrees up, and twice as far right (aspect 2) at 90 degrees.
        let corner = c.ray(0.0, 0.0).dir;
        assert!(
            (corner - Vec3::new(-2.0, 1.0, -1.0)).length() < 1e-5,
            "{corner}"
        );
    }

    #[test]
    fn a_resized_camera_is_the_one_made_at_that_size_and_its_rays_stay_in_its_cone() {
        let (eye, at) = (Vec3::new(1.0, 2.0, 3.0), Vec3::new(-4.0, 2.5, 0.3));
        for (fov, w, h) in [
            (60.0, 512, 512),
            (75.0, 640, 360),
            (170.0, 3, 900),
            (1.0, 1, 1),
            (1e-45, 4, 4),
        ] {
            let big = Camera::new(eye, at, Vec3::Y, fov, w, h).unwrap();
            let (pw, ph) = ((w / 8).max(1), (h / 8).max(1));
            let small = Camera::new(eye, at, Vec3::Y, fov, pw, ph).unwrap();
            assert_eq!(big.resized(pw, ph), small, "{fov} {w} {h}");
            let (axis, half) = big.view_cone();
            assert!(half <= core::f32::consts::FRAC_PI_2);
            for (x, y) in [(0, 0), (w, 0), (0, h), (w, h), (w / 2, h / 3)] {
                let d = big.ray(x as f32, y as f32).dir.normalize();
                let angle = d.dot(axis).min(1.0).acos();
                assert!(angle < half, "{fov} {w} {h}: corner {x},{y}");
            }
        }
    }

    #[test]
    fn bad_cameras_are_refused_by_name() {
        let make = |eye, at, up, fov| Camera::new(eye, at, up, fov, 8, 8).unwrap_err().to_string();
        assert!(make(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 45.0).contains("--look-at"));
        assert!(make(Vec3::ZERO, Vec3::Y, Vec3::Y, 45.0).contains("--up"));
        assert!(make(Vec3::ZERO, Vec3::Z, Vec3::Y, 180.0).contains("--fov"));
        assert!(make(Vec3::ZERO, Vec3::Z, Vec3::Y, f32::NAN).contains("--fov"));
        assert!(make(Vec3::splat(f32::NAN), Vec3::Z, Vec3::Y, 45.0).contains("--eye"));
        let far = Vec3::splat(3e38);
        assert!(make(-far, far, Vec3::Y, 45.0).contains("too far apart"));
        // A long view still has a direction.
        let c = Camera::new(Vec3::ZERO, Vec3::new(0.0, 0.0, 1e30), Vec3::Y, 45.0, 8, 8).unwrap();
        assert_eq!(c.forward, Vec3::Z);
        // Huge and tiny vectors still have directions: only their directions matter.
        for s in [1e20, 1e-30, 1e-44] {
            let c = Camera::new(Vec3::ZERO, Vec3::Z * s, Vec3::Y * s, 45.0, 8, 8).unwrap();
            assert_eq!(c.forward, Vec3::Z, "{s}");
            assert!(c.right.normalize().abs_diff_eq(Vec3::NEG_X, 1e-6), "{s}");
        }
        // An up nearly along the view: its small perpendicular part gives the image's up.
        let c = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::new(0.0, 1e-25, 1.0), 45.0, 8, 8).unwrap();
        assert!(c.right.normalize().abs_diff_eq(Vec3::NEG_X, 1e-6));
    }

    #[test]
    fn framing_a_box_past_single_precision_is_refused() {
        let b = Aabb::new(Vec3::ZERO, Vec3::splat(3e38));
        let why = Camera::framing(b, 50.0, 8, 8).unwrap_err().to_string();
        assert!(
            why.contains("default camera") && why.contains("--eye"),
            "{why}"
        );
    }

    /// The default camera frames a scene of any size, however small, and a single point.
    #[test]
    fn framing_is_relative_to_the_scene() {
        for s in [1e-12, 1e-8, 1.0, 1e10] {
            let b = Aabb::new(Vec3::splat(-s), Vec3::splat(s));
            let c = Camera::framing(b, 50.0, 8, 8).unwrap();
            let d = c.eye().z / s;
            assert!(d > 2.0 && d < 4.0, "{s}: eye at {}", c.eye());
        }
        let point = Camera::framing(Aabb::new(Vec3::ZERO, Vec3::ZERO), 50.0, 8, 8).unwrap();
        assert_eq!(point.eye(), Vec3::Z);
    }

    #[test]
    fn framing_sees_the_whole_box() {
        let b = Aabb::new(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 1.0));
        let c = Camera::framing(b, 50.0, 64, 64).unwrap();
        assert!(c.eye().z > 1.0);
        // The rays through the image corners pass outside the box's front face.
        for (x, y) in [(0.0, 0.0), (64.0, 64.0)] {
            let r = c.ray(x, y);
            let t = (1.0 - r.origin.z) / r.dir.z;
            let p = r.at(t);
            assert!(p.x.abs() >= 1.0 && (p.y - 1.0).abs() >= 1.0, "{p}");
        }
    }
}
