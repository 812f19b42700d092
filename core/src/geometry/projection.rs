//! Projections of boxes onto planes: the silhouettes PAH measures and the analyzer overlaps.

use glam::{Vec2, Vec3};

use super::{clip_convex, Aabb, ConvexPolygon, Frame, MAX_POLY};

/// Corner `i` of a box: the upper bound on x when `i & 1`, on y when `i & 2`, on z when `i & 4`.
#[inline]
pub fn box_corner(b: &Aabb, i: usize) -> Vec3 {
    Vec3::new(
        if i & 1 == 0 { b.min.x } else { b.max.x },
        if i & 2 == 0 { b.min.y } else { b.max.y },
        if i & 4 == 0 { b.min.z } else { b.max.z },
    )
}

/// The orthographic silhouette of `b` on the plane spanned by the orthonormal `right` and `up`:
/// the hull of the eight projected corners, in `(right, up)` coordinates.
pub fn orthographic_silhouette(b: &Aabb, right: Vec3, up: Vec3) -> ConvexPolygon {
    let corners: [Vec2; 8] = core::array::from_fn(|i| {
        let p = box_corner(b, i);
        Vec2::new(p.dot(right), p.dot(up))
    });
    ConvexPolygon::hull(&corners)
}

/// The nearest depth [`perspective_silhouette`] projects, relative to the box's largest
/// eye-relative coordinate: `2^-20`.
pub const MIN_RELATIVE_DEPTH: f32 = 1.0 / (1u32 << 20) as f32;

/// The perspective silhouette, on the image plane `z = 1` of `frame` with its eye at `eye`, of the
/// part of `b` at least `near >= 0` in front of the eye. The silhouette of a convex body from a
/// point in front of it is the hull of its projected vertices: the box's corners beyond the near
/// plane and the points where its 12 edges cross it, at most 14 points.
///
/// The cut is at least [`MIN_RELATIVE_DEPTH`] times the box's largest eye-relative coordinate
/// from the eye, so no projected point lies farther than `1 / MIN_RELATIVE_DEPTH` from the axis
/// and the hull's arithmetic stays far from overflow however small `near` is (0 included). The
/// floor follows the box, not the frustum's depth (a floor from `far` would cut away small scenes
/// near the eye of a deep frustum), and changes the silhouette only when the eye lies within that
/// fraction of the box's size from the box.
pub fn perspective_silhouette(b: &Aabb, eye: Vec3, frame: &Frame, near: f32) -> ConvexPolygon {
    let local: [Vec3; 8] = core::array::from_fn(|i| frame.to_local(box_corner(b, i) - eye));
    let reach = local
        .iter()
        .fold(0.0f32, |m, p| m.max(p.abs().max_element()));
    let near = near.max(MIN_RELATIVE_DEPTH * reach).max(f32::MIN_POSITIVE);
    let mut pts = [Vec2::ZERO; MAX_POLY];
    let mut n = 0;
    let project = |p: Vec3| Vec2::new(p.x / p.z, p.y / p.z);
    for p in &local {
        if p.z >= near {
            pts[n] = project(*p);
            n += 1;
        }
    }
    if n < 8 {
        // Edges join corners differing in one bit; those crossing the near plane contribute
        // their crossing point (at most 6 of them for a plane cutting a box).
        for i in 0..8usize {
            for bit in [1usize, 2, 4] {
                let j = i | bit;
                if j == i {
                    continue;
                }
                let (a, c) = (local[i], local[j]);
                if (a.z < near) != (c.z < near) && n < MAX_POLY {
                    let t = (near - a.z) / (c.z - a.z);
                    let mut q = a + (c - a) * t;
                    q.z = near;
                    pts[n] = project(q);
                    n += 1;
                }
            }
        }
    }
    ConvexPolygon::hull(&pts[..n])
}

/// The perspective silhouette of the part of `b` at depths `depth = (near, far)` in front of the
/// eye (`0 <= near`: where the rays start and stop), clipped to the light's window `[-tan, tan]`
/// on the image plane `z = 1`. Projecting first and clipping the hull is exact to rounding while
/// the box lies before the far plane and the projected points stay within [`PRECISE_SPAN`]
/// windows of the axis (as they do unless the box comes close to the eye's plane beside the
/// eye); otherwise the box is clipped in 3D first ([`perspective_window_silhouette`], several
/// times the work, so only then).
pub fn windowed_silhouette(
    b: &Aabb,
    eye: Vec3,
    frame: &Frame,
    depth: (f32, f32),
    tan: Vec2,
) -> ConvexPolygon {
    let (near, far) = depth;
    // A box that every ray meets (the root's box, with the light inside or a narrow light
    // pointing at it) covers the whole window.
    let window = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    if covers_window(b, eye, frame, depth, tan) {
        return ConvexPolygon::hull(&window.map(|(x, y)| Vec2::new(x * tan.x, y * tan.y)));
    }
    // Rays stop at the far plane: a box reaching past it is cut there, in 3D.
    let (c, h) = (b.center() - eye, b.extent() * 0.5);
    let deepest = c.dot(frame.forward) + h.dot(frame.forward.abs());
    if deepest > far {
        return perspective_window_silhouette(b, eye, frame, depth, tan);
    }
    let hull = perspective_silhouette(b, eye, frame, near);
    let span = PRECISE_SPAN * tan.max_element();
    let precise = hull.points().iter().all(|p| p.abs().max_element() <= span);
    let hull = if precise {
        hull
    } else {
        perspective_window_silhouette(b, eye, frame, depth, tan)
    };
    hull.clip_to_rect(-tan, tan)
}

/// True when the rays from the eye through the window's four corners all meet `b` at a depth
/// between `near` and `far`: the part of a box between the two planes is convex, so its
/// silhouette is, and holding the corners it holds the whole window. Slab tests in 3D and in
/// f64, where the corner directions keep the window's width beside `forward` (1e-10 of it for a
/// light of 1e-8 degrees). Clipping the projected hull to such a window cannot decide this: the
/// hull's f32 vertices place its edges only to about 6e-8, far coarser than the window.
fn covers_window(b: &Aabb, eye: Vec3, frame: &Frame, depth: (f32, f32), tan: Vec2) -> bool {
    let wide = |v: Vec3| [v.x, v.y, v.z].map(f64::from);
    let (right, up, forward, eye) = (
        wide(frame.right),
        wide(frame.up),
        wide(frame.forward),
        wide(eye),
    );
    let (lo, hi) = (wide(b.min), wide(b.max));
    let (tx, ty) = (f64::from(tan.x), f64::from(tan.y));
    [(-tx, -ty), (tx, -ty), (tx, ty), (-tx, ty)]
        .into_iter()
        .all(|(x, y)| {
            // The corner ray `eye + t d` is at depth `t`: `d . forward = 1`.
            let (mut enter, mut leave) = (f64::from(depth.0), f64::from(depth.1));
            for k in 0..3 {
                let d = forward[k] + x * right[k] + y * up[k];
                if d == 0.0 {
                    if eye[k] < lo[k] || eye[k] > hi[k] {
                        return false;
                    }
                    continue;
                }
                let (a, c) = ((lo[k] - eye[k]) / d, (hi[k] - eye[k]) / d);
                enter = enter.max(a.min(c));
                leave = leave.min(a.max(c));
            }
            enter <= leave
        })
}

/// How far from the axis, in windows, projected points may lie for [`windowed_silhouette`] to
/// clip after projecting: the clip's rounding is then bounded by about `4096 * 2^-24` (2.4e-4)
/// of the window. Boxes past it are rare (they reach the eye's plane beside the eye), and the 3D
/// clip costs several hull clips.
pub const PRECISE_SPAN: f32 = 4096.0;

/// The perspective silhouette of the part of `b` at depths `depth = (near, far)` in front of the
/// eye (`0 <= near`) and inside the pyramid of half-angle tangents `tan` (the light's window), on
/// the image plane `z = 1`: the box is clipped in 3D before anything is projected. Each of its six
/// faces is clipped (Sutherland-Hodgman) by the near and far planes and the pyramid's four side
/// planes; the clipped faces' vertices are the clipped solid's, and all of them project into the
/// window, so no projected point is large whatever `near` is (0 included). Projecting first and
/// clipping the hull to the window instead loses the window's precision to the long edges of
/// points near the eye plane (a few 1e-4 of the measure with `near` 0).
pub fn perspective_window_silhouette(
    b: &Aabb,
    eye: Vec3,
    frame: &Frame,
    depth: (f32, f32),
    tan: Vec2,
) -> ConvexPolygon {
    let (near, far) = depth;
    let local: [Vec3; 8] = core::array::from_fn(|i| frame.to_local(box_corner(b, i) - eye));
    // Signed distance to plane `k` of the six, positive inside.
    let plane = |k: usize, p: Vec3| match k {
        0 => p.z - near,
        1 => far - p.z,
        2 => tan.x * p.z - p.x,
        3 => tan.x * p.z + p.x,
        4 => tan.y * p.z - p.y,
        _ => tan.y * p.z + p.y,
    };
    // Every point lies inside the window: two closer than a millionth of it are one vertex.
    let mut hull = HullPoints::new(1e-6 * tan.max_element());
    clipped_box_vertices(&local, 6, plane, |p| {
        // The apex itself (near 0) projects nowhere, and the rest of the clipped solid already
        // spans every direction it holds.
        if p.z > 0.0 {
            hull.push(Vec2::new(p.x / p.z, p.y / p.z));
        }
    });
    hull.hull()
}

/// The orthographic silhouette, in `(right, up)` coordinates, of the part of `b` between the
/// planes `forward . p = 0` and `forward . p = depth` (a plane area's rays start on the first and
/// stop at the second, with `b` taken relative to the light's centre): the box's faces clipped to
/// the slab, projected, and their hull. For boxes inside the slab it is
/// [`orthographic_silhouette`]; for a box straddling either plane along an oblique `forward`,
/// the projection of the whole box is larger.
pub fn orthographic_slab_silhouette(b: &Aabb, frame: &Frame, depth: f32) -> ConvexPolygon {
    let corners: [Vec3; 8] = core::array::from_fn(|i| box_corner(b, i));
    let plane = |k: usize, p: Vec3| {
        let z = p.dot(frame.forward);
        if k == 0 {
            z
        } else {
            depth - z
        }
    };
    // Exact duplicates only: the points are not confined to a window that would bound the
    // error of merging near ones.
    let mut hull = HullPoints::new(0.0);
    clipped_box_vertices(&corners, 2, plane, |p| {
        hull.push(Vec2::new(p.dot(frame.right), p.dot(frame.up)));
    });
    hull.hull()
}

/// Calls `emit` with every vertex of each face of the box with corners `corners` (in
/// [`box_corner`]'s order) clipped (Sutherland-Hodgman) to the half-spaces `plane(k, p) >= 0`,
/// `k < planes`: the clipped faces' vertices are the clipped solid's, each found once per face
/// it lies on.
fn clipped_box_vertices(
    corners: &[Vec3; 8],
    planes: usize,
    plane: impl Fn(usize, Vec3) -> f32,
    mut emit: impl FnMut(Vec3),
) {
    for (axis, other) in [(1usize, [2usize, 4]), (2, [4, 1]), (4, [1, 2])] {
        for side in [0, axis] {
            // The face's corners in cyclic order.
            let [u, v] = other;
            let mut face = [Vec3::ZERO; FACE_CLIP_MAX];
            for (k, bits) in [0, u, u | v, v].into_iter().enumerate() {
                face[k] = corners[side | bits];
            }
            let mut len = 4;
            for k in 0..planes {
                let mut clipped = [Vec3::ZERO; FACE_CLIP_MAX];
                len = clip_convex(&face[..len], &mut clipped, |p| plane(k, p));
                face = clipped;
                if len == 0 {
                    break;
                }
            }
            face[..len].iter().copied().for_each(&mut emit);
        }
    }
}

/// Points gathered for a hull, without allocation: a point within `same` of one already held
/// (a vertex of a solid reached from another of its faces) is dropped, and when the points would
/// overflow the hull's input, the hull of those so far (a subset of them) takes their place.
struct HullPoints {
    pts: [Vec2; MAX_POLY],
    n: usize,
    same: f32,
}

impl HullPoints {
    fn new(same: f32) -> Self {
        Self {
            pts: [Vec2::ZERO; MAX_POLY],
            n: 0,
            same,
        }
    }

    fn push(&mut self, q: Vec2) {
        if self.pts[..self.n]
            .iter()
            .any(|&r| (q - r).abs().max_element() <= self.same)
        {
            return;
        }
        if self.n == MAX_POLY {
            let hull = ConvexPolygon::hull(&self.pts);
            self.n = hull.points().len();
            self.pts[..self.n].copy_from_slice(hull.points());
        }
        // A clipped box's silhouette has at most one vertex per face of the solid (eleven), so
        // a hull of distinct points always leaves room.
        if self.n < MAX_POLY {
            self.pts[self.n] = q;
            self.n += 1;
        }
    }

    fn hull(&self) -> ConvexPolygon {
        ConvexPolygon::hull(&self.pts[..self.n])
    }
}

/// The most vertices a box face has while it is clipped ([`clipped_box_vertices`]): four, plus
/// one per clipping plane (six at most).
const FACE_CLIP_MAX: usize = 4 + 6;
