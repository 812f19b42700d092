//! Small convex polygons in fixed arrays: hulls of projected points, clipping to a rectangle,
//! planar area and the solid angle of an image-plane polygon. No allocation: they run inside the
//! builder's sweeps.

use glam::Vec2;

/// Most vertices a polygon here can hold: a clipped box silhouette has at most 14 hull points
/// (8 corners and 6 near-plane cuts), and clipping by a rectangle adds at most 4.
pub const MAX_POLY: usize = 20;

/// Clips the convex polygon `points` (in order, in the plane or in space) to the half-space
/// `inside(p) >= 0` (Sutherland-Hodgman), writing at most `out.len()` points into `out`; returns
/// how many it wrote.
pub(crate) fn clip_convex<P>(points: &[P], out: &mut [P], inside: impl Fn(P) -> f32) -> usize
where
    P: Copy
        + core::ops::Add<Output = P>
        + core::ops::Sub<Output = P>
        + core::ops::Mul<f32, Output = P>,
{
    let mut m = 0;
    for i in 0..points.len() {
        let (a, c) = (points[i], points[(i + 1) % points.len()]);
        let (da, dc) = (inside(a), inside(c));
        if da >= 0.0 && m < out.len() {
            out[m] = a;
            m += 1;
        }
        if (da >= 0.0) != (dc >= 0.0) && m < out.len() {
            out[m] = a + (c - a) * (da / (da - dc));
            m += 1;
        }
    }
    m
}

/// A convex polygon, counter-clockwise, in a fixed array.
#[derive(Clone, Copy, Debug)]
pub struct ConvexPolygon {
    points: [Vec2; MAX_POLY],
    len: usize,
}

impl ConvexPolygon {
    /// The convex hull of `points` (Andrew's monotone chain, counter-clockwise). At most
    /// [`MAX_POLY`] points are read.
    pub fn hull(points: &[Vec2]) -> Self {
        let mut sorted = [Vec2::ZERO; MAX_POLY];
        let n = points.len().min(MAX_POLY);
        sorted[..n].copy_from_slice(&points[..n]);
        let sorted = &mut sorted[..n];
        sorted.sort_unstable_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        let mut out = ConvexPolygon {
            points: [Vec2::ZERO; MAX_POLY],
            len: 0,
        };
        if n < 3 {
            return out;
        }
        let cross = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
        // Lower hull, then upper hull; `hull` holds up to 2n points transiently.
        let mut hull = [Vec2::ZERO; 2 * MAX_POLY];
        let mut k = 0;
        for &p in sorted.iter() {
            while k >= 2 && cross(hull[k - 2], hull[k - 1], p) <= 0.0 {
                k -= 1;
            }
            hull[k] = p;
            k += 1;
        }
        let lower = k + 1;
        for &p in sorted.iter().rev().skip(1) {
            while k >= lower && cross(hull[k - 2], hull[k - 1], p) <= 0.0 {
                k -= 1;
            }
            hull[k] = p;
            k += 1;
        }
        let len = (k - 1).min(MAX_POLY);
        out.points[..len].copy_from_slice(&hull[..len]);
        out.len = len;
        out
    }

    /// The vertices.
    pub fn points(&self) -> &[Vec2] {
        &self.points[..self.len]
    }

    /// Shoelace area (zero for fewer than three vertices), as a fan from the first vertex in
    /// f64, where differences of f32 coordinates are exact (about the origin in f32, a unit
    /// square 1e4 away would sum terms of 1e8 and keep none of its own area's bits).
    pub fn area(&self) -> f32 {
        let p = self.points();
        if p.len() < 3 {
            return 0.0;
        }
        let o = p[0];
        let from_o = |v: Vec2| {
            (
                f64::from(v.x) - f64::from(o.x),
                f64::from(v.y) - f64::from(o.y),
            )
        };
        let mut twice = 0.0f64;
        for w in p[1..].windows(2) {
            let ((ax, ay), (bx, by)) = (from_o(w[0]), from_o(w[1]));
            twice += ax * by - ay * bx;
        }
        (0.5 * twice.abs()) as f32
    }

    /// The axis-aligned bounds `(min, max)` of the vertices.
    pub fn bounds(&self) -> (Vec2, Vec2) {
        self.points().iter().fold(
            (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        )
    }

    /// The polygon clipped to the rectangle `[lo, hi]` (Sutherland-Hodgman, one edge at a time).
    pub fn clip_to_rect(&self, lo: Vec2, hi: Vec2) -> Self {
        let mut poly = *self;
        // Each edge keeps points with `sign * p[axis] <= sign * bound`.
        for (axis, bound, sign) in [
            (0, hi.x, 1.0),
            (0, lo.x, -1.0),
            (1, hi.y, 1.0),
            (1, lo.y, -1.0),
        ] {
            poly = poly.clip_half(axis, bound, sign);
            if poly.len < 3 {
                break;
            }
        }
        poly
    }

    fn clip_half(&self, axis: usize, bound: f32, sign: f32) -> Self {
        let mut out = ConvexPolygon {
            points: [Vec2::ZERO; MAX_POLY],
            len: 0,
        };
        let p = self.points();
        let inside = |v: Vec2| sign * v[axis] <= sign * bound;
        for i in 0..p.len() {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            let (ia, ib) = (inside(a), inside(b));
            if ia && out.len < MAX_POLY {
                out.points[out.len] = a;
                out.len += 1;
            }
            if ia != ib && out.len < MAX_POLY {
                let t = (bound - a[axis]) / (b[axis] - a[axis]);
                let mut q = a + (b - a) * t;
                q[axis] = bound;
                out.points[out.len] = q;
                out.len += 1;
            }
        }
        out
    }

    /// The solid angle that this polygon, lying on the image plane `z = 1` of an eye at the
    /// origin, subtends: a fan of signed triangles from the eye's foot `(0, 0, 1)` to each edge,
    /// each by the formula of Van Oosterom and Strackee (1983),
    /// `tan(omega / 2) = a . (b x c) / (abc + (a . b) c + (a . c) b + (b . c) a)`.
    ///
    /// In f64, where products of f32 coordinates are exact, and from the foot, where `a . b = 1`:
    /// the denominator is then `(bc + b . c) + b + c`, and its one cancelling part, `bc + b . c`
    /// for `b` and `c` on opposite sides of the foot, is taken as `|b x c|^2 / (bc - b . c)`. A fan
    /// from a vertex, in f32, would cancel terms of `x^3` for vertices `x` windows out, which
    /// nearly flat windows reach.
    pub fn solid_angle_on_image_plane(&self) -> f32 {
        let p = self.points();
        if p.len() < 3 {
            return 0.0;
        }
        let mut total = 0.0f64;
        for (i, b) in p.iter().enumerate() {
            let c = p[(i + 1) % p.len()];
            let (xb, yb) = (f64::from(b.x), f64::from(b.y));
            let (xc, yc) = (f64::from(c.x), f64::from(c.y));
            let num = xb * yc - yb * xc;
            let lb = libm::sqrt(1.0 + xb * xb + yb * yb);
            let lc = libm::sqrt(1.0 + xc * xc + yc * yc);
            let dot = 1.0 + xb * xc + yb * yc;
            let bc_plus_dot = if dot >= 0.0 {
                lb * lc + dot
            } else {
                let (dx, dy) = (xc - xb, yc - yb);
                (dx * dx + dy * dy + num * num) / (lb * lc - dot)
            };
            total += 2.0 * libm::atan2(num, bc_plus_dot + lb + lc);
        }
        total.abs() as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_square_with_inner_points() {
        let pts = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.5, 0.5),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(0.2, 0.7),
        ];
        let h = ConvexPolygon::hull(&pts);
        assert_eq!(h.points().len(), 4);
        assert!((h.area() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn area_far_from_the_origin() {
        for offset in [0.0f32, 1e4, -3e5, 1e7] {
            let (x, y) = (offset, -offset / 2.0);
            let h = ConvexPolygon::hull(&[
                Vec2::new(x, y),
                Vec2::new(x + 1.0, y),
                Vec2::new(x + 1.0, y + 0.5),
                Vec2::new(x, y + 0.5),
            ]);
            assert_eq!(h.area(), 0.5, "at {offset}");
        }
    }

    #[test]
    fn clip_square_by_rect() {
        let h = ConvexPolygon::hull(&[
            Vec2::new(-1.0, -1.0),
            Vec2::new(1.0, -1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(-1.0, 1.0),
        ]);
        let c = h.clip_to_rect(Vec2::new(0.0, -0.5), Vec2::new(3.0, 0.5));
        assert!((c.area() - 1.0).abs() < 1e-6);
        let none = h.clip_to_rect(Vec2::new(2.0, 2.0), Vec2::new(3.0, 3.0));
        assert_eq!(none.area(), 0.0);
    }

    #[test]
    fn solid_angle_of_cube_face() {
        // A face of a cube seen from its centre covers 4 pi / 6.
        let h = ConvexPolygon::hull(&[
            Vec2::new(-1.0, -1.0),
            Vec2::new(1.0, -1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(-1.0, 1.0),
        ]);
        let expect = 4.0 * core::f32::consts::PI / 6.0;
        assert!((h.solid_angle_on_image_plane() - expect).abs() < 1e-5);
    }

    /// Rectangles `[x1, x2] x [y1, y2]` on the image plane against the closed form
    /// `sum +-atan(x y / sqrt(1 + x^2 + y^2))` over their corners, in f64: windows up to 179.999
    /// degrees wide, and small rectangles far from the foot, where the fan's signed triangles
    /// cancel.
    #[test]
    fn solid_angle_of_wide_and_far_rectangles() {
        let f = |x: f64, y: f64| libm::atan(x * y / libm::sqrt(1.0 + x * x + y * y));
        let tan = |deg: f64| libm::tan(deg.to_radians() / 2.0);
        let windows = [
            (179.999, 1.0),
            (179.99, 0.001),
            (179.98, 179.98),
            (90.0, 179.9),
        ]
        .map(|(fx, fy)| {
            let (tx, ty) = (tan(fx) as f32, tan(fy) as f32);
            (-tx, tx, -ty, ty)
        });
        let far = [(1000.0, 1001.0, 2000.0, 2000.5), (-3000.0, 2.0, 0.5, 0.75)];
        for (x1, x2, y1, y2) in windows.into_iter().chain(far) {
            let h = ConvexPolygon::hull(&[
                Vec2::new(x1, y1),
                Vec2::new(x2, y1),
                Vec2::new(x2, y2),
                Vec2::new(x1, y2),
            ]);
            let [x1, x2, y1, y2] = [x1, x2, y1, y2].map(f64::from);
            // The closed form differences atans of about 1.57 for the far rectangle: 1e-15 of
            // its own rounding.
            let expect = f(x2, y2) - f(x1, y2) - f(x2, y1) + f(x1, y1);
            let got = f64::from(h.solid_angle_on_image_plane());
            assert!(
                (got - expect).abs() <= 1e-6 * expect + 1e-15,
                "[{x1}, {x2}] x [{y1}, {y2}]: {got} against {expect}"
            );
        }
    }
}
