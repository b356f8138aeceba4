//! Shadow rays in f64: whether the segment between two points meets one of a scene's opaque
//! triangles, by testing every triangle (Möller and Trumbore's test in f64). The oracle of the
//! GPU's BVH traversal (`manylights_gpu::bvh`).
//!
//! A segment from `from` to `to` is blocked by a triangle it crosses at a parameter `t` strictly
//! between 0 and 1 (a surface point's own triangle at `t = 0` and a light at `t = 1` do not count:
//! the caller lifts the origin off its surface), inside the triangle or on its edges. Glass and
//! other transparent surfaces cast no shadow, so only triangles of opaque materials count.
//!
//! A test in f32 cannot agree with f64 where a segment passes within rounding of a triangle's
//! edge, runs in its plane, or ends on it ([`MARGIN`], [`PARALLEL`]): [`segment`] says so (`Blocked::Ambiguous`), so that a
//! comparison skips such segments and checks every other one exactly.

use glam::{DVec3, Vec3};

use crate::Scene;

/// The margin, relative to the coordinates' magnitude, within which f32 rounding can move a
/// crossing across a triangle's edge or a segment's end (divided by the cosine of the segment's
/// angle to the triangle's normal: grazing segments round worse).
pub const MARGIN: f64 = 1e-5;
/// Below this cosine between a segment and a triangle's normal the segment runs in its plane.
pub const PARALLEL: f64 = 1e-6;

/// How far a shadow ray's origin is lifted off its surface along the shading normal, relative
/// to the point's magnitude (at least 1): [`shadow_origin`].
pub const SHADOW_OFFSET: f32 = 1e-3;

/// The origin of a shadow ray from surface point `p` of unit shading normal `n` (turned towards
/// the viewer), in f32 as the GPU computes it (`shadow_blocked` in shaders/common/shading.wgsl):
/// `p + n * SHADOW_OFFSET * max(1, |p|)`, `|p|` the largest coordinate's magnitude, so that the
/// ray leaves the surface's own triangle at any scale.
pub fn shadow_origin(p: Vec3, n: Vec3) -> Vec3 {
    p + n * (SHADOW_OFFSET * p.abs().max_element().max(1.0))
}

/// Whether a segment is blocked, as far as f64 decides against f32 rounding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blocked {
    /// Some triangle is crossed well inside, away from both ends.
    Yes,
    /// No triangle is crossed or comes near.
    No,
    /// None is crossed surely, and at least one is crossed or missed within the margins.
    Ambiguous,
}

/// The opaque triangles of `scene` in its order (primitive by primitive), each its three
/// corners.
pub fn opaque_triangles(scene: &Scene) -> Vec<[Vec3; 3]> {
    let mut out = Vec::new();
    for p in &scene.primitives {
        if scene.materials[p.material as usize].is_transparent() {
            continue;
        }
        for t in p.indices.chunks_exact(3) {
            out.push([0, 1, 2].map(|k| p.positions[t[k] as usize]));
        }
    }
    out
}

/// Whether the segment from `from` to `to` is blocked by one of `triangles` (see the module
/// docs).
pub fn segment(triangles: &[[Vec3; 3]], from: Vec3, to: Vec3) -> Blocked {
    let (o, d) = (from.as_dvec3(), (to - from).as_dvec3());
    let mut near = false;
    for tri in triangles {
        match crossing(tri, o, d) {
            Blocked::Yes => return Blocked::Yes,
            Blocked::Ambiguous => near = true,
            Blocked::No => {}
        }
    }
    if near {
        Blocked::Ambiguous
    } else {
        Blocked::No
    }
}

/// One triangle against the segment `o + t d`, `0 < t < 1`: surely crossed where the crossing
/// lies farther than the margin inside every edge and from both ends; undecided where it lies
/// within the margin of them, or where the segment runs nearly in the triangle's plane close by.
fn crossing(tri: &[Vec3; 3], o: DVec3, d: DVec3) -> Blocked {
    let v0 = tri[0].as_dvec3();
    let e1 = tri[1].as_dvec3() - v0;
    let e2 = tri[2].as_dvec3() - v0;
    let normal = e1.cross(e2);
    let (area2, len) = (normal.length(), d.length());
    if area2 == 0.0 || len == 0.0 {
        // A degenerate triangle or segment: f32 crosses none either (its determinant is 0).
        return Blocked::No;
    }
    let p = d.cross(e2);
    let det = e1.dot(p);
    let cos = det.abs() / (len * area2);
    let size = [o, o + d, v0]
        .iter()
        .map(|q| q.abs().max_element())
        .fold(len, f64::max);
    let m = MARGIN * size / cos.max(1e-3);
    if cos <= PARALLEL {
        let n = normal / area2;
        let plane = n.dot(o - v0).abs().min(n.dot(o + d - v0).abs());
        let reach = e1.length().max(e2.length()) + len;
        let close = (v0 - o).length() <= 2.0 * reach;
        return if close && plane <= 1e-3 * reach {
            Blocked::Ambiguous
        } else {
            Blocked::No
        };
    }
    let s = o - v0;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    let w = 1.0 - u - v;
    // Each weight times the height over its opposite edge: the distance from that edge.
    let inside = (u * area2 / e2.length())
        .min(v * area2 / e1.length())
        .min(w * area2 / (e2 - e1).length());
    let ends = (t * len).min((1.0 - t) * len);
    if inside > m && ends > m {
        Blocked::Yes
    } else if inside >= -m && ends > -m {
        Blocked::Ambiguous
    } else {
        Blocked::No
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRI: [Vec3; 3] = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];

    #[test]
    fn a_segment_through_a_triangle_is_blocked_and_one_beside_it_is_not() {
        let t = [TRI];
        let seg = |a: [f32; 3], b: [f32; 3]| segment(&t, Vec3::from(a), Vec3::from(b));
        assert_eq!(seg([0.2, 0.2, -1.0], [0.2, 0.2, 1.0]), Blocked::Yes);
        assert_eq!(
            seg([0.2, 0.2, 1.0], [0.2, 0.2, -1.0]),
            Blocked::Yes,
            "either side"
        );
        assert_eq!(seg([0.8, 0.8, -1.0], [0.8, 0.8, 1.0]), Blocked::No);
        // Stops short of the triangle, or starts beyond it.
        assert_eq!(seg([0.2, 0.2, -1.0], [0.2, 0.2, -0.1]), Blocked::No);
        assert_eq!(seg([0.2, 0.2, 0.1], [0.2, 0.2, 1.0]), Blocked::No);
        // Ends on it, or crosses its edge: undecided.
        assert_eq!(seg([0.2, 0.2, -1.0], [0.2, 0.2, 0.0]), Blocked::Ambiguous);
        assert_eq!(seg([0.5, 0.5, -1.0], [0.5, 0.5, 1.0]), Blocked::Ambiguous);
        // In its plane.
        assert_eq!(seg([-1.0, 0.2, 0.0], [2.0, 0.2, 0.0]), Blocked::Ambiguous);
        // Far from a triangle, nothing.
        assert_eq!(segment(&[], Vec3::ZERO, Vec3::ONE), Blocked::No);
    }
}
