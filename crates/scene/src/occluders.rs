//! Occluders for culling by visibility, in f64: the scene's large opaque convex polygons, and
//! a conservative test that one of them hides a light from every point of a cell.
//!
//! [`occluders`] takes the opaque triangles ([`crate::ray::opaque_triangles`]), merges each pair
//! that shares an edge, lies in one plane and forms a convex quadrilateral (a wall's two
//! triangles) into one polygon, and keeps the largest by area. [`hides`] says whether a polygon
//! hides a light from every point of the convex hull of a cell's corners: the set of points a
//! convex polygon hides from a point light (every segment from the light to them crossing the
//! polygon) is convex (the cone from the light through the polygon, beyond its plane), so it
//! holds the whole hull where it holds every corner. Each corner must lie beyond the plane and
//! its segment cross the polygon by at least `margin` from every edge, plus the lift of a shadow
//! ray's origin off its surface ([`crate::ray::shadow_origin`]): the segment from the lifted
//! origin crosses too. A crossing on the diagonal two merged triangles share is a crossing of
//! their union; the f64 ray oracle calls such segments undecided ([`crate::ray::Blocked`]).

use std::collections::HashMap;

use glam::{DVec3, Vec3};

use crate::ray::SHADOW_OFFSET;

/// A planar convex polygon, its corners in order around its normal.
#[derive(Clone, Debug, PartialEq)]
pub struct Occluder {
    /// Corners, 3 or 4, counter-clockwise about `normal`.
    pub corners: Vec<DVec3>,
    /// Unit normal.
    pub normal: DVec3,
    /// Area, m^2.
    pub area: f64,
}

impl Occluder {
    fn triangle(t: &[Vec3; 3]) -> Option<Self> {
        let c = t.map(Vec3::as_dvec3);
        let cross = (c[1] - c[0]).cross(c[2] - c[0]);
        let area = 0.5 * cross.length();
        (area > 0.0).then(|| Self {
            corners: c.to_vec(),
            normal: cross / (2.0 * area),
            area,
        })
    }

    /// Signed distance of `p` from the polygon's plane.
    fn plane_distance(&self, p: DVec3) -> f64 {
        self.normal.dot(p - self.corners[0])
    }

    /// The least distance of `x` (in the plane) inside the polygon's edges: negative outside.
    fn inside(&self, x: DVec3) -> f64 {
        let n = self.corners.len();
        (0..n)
            .map(|i| {
                let (a, b) = (self.corners[i], self.corners[(i + 1) % n]);
                let e = b - a;
                // Inward normal of edge a -> b in the plane.
                let inward = self.normal.cross(e).normalize();
                inward.dot(x - a)
            })
            .fold(f64::INFINITY, f64::min)
    }
}

/// The `max` largest opaque convex polygons of `triangles` with an area of at least
/// `min_area`: pairs of coplanar triangles sharing an edge merged where their quadrilateral is
/// convex, the others alone; largest first.
pub fn occluders(triangles: &[[Vec3; 3]], min_area: f64, max: usize) -> Vec<Occluder> {
    let key = |v: Vec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
    let mut edges: HashMap<([u32; 3], [u32; 3]), usize> = HashMap::new();
    let mut partner = vec![None; triangles.len()];
    for (i, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
            let e = if a < b { (a, b) } else { (b, a) };
            match edges.get(&e) {
                Some(&j) if partner[j].is_none() && partner[i].is_none() => {
                    if let Some(q) = merge(&triangles[j], t) {
                        partner[j] = Some((i, q.clone()));
                        partner[i] = Some((j, q));
                    }
                }
                Some(_) => {}
                None => {
                    edges.insert(e, i);
                }
            }
        }
    }
    let mut out = Vec::new();
    for (i, t) in triangles.iter().enumerate() {
        match &partner[i] {
            Some((j, q)) if *j > i => out.push(q.clone()),
            Some(_) => {}
            None => out.extend(Occluder::triangle(t)),
        }
    }
    out.retain(|o| o.area >= min_area);
    out.sort_by(|a, b| b.area.total_cmp(&a.area));
    out.truncate(max);
    out
}

/// The convex quadrilateral of two coplanar triangles sharing an edge, if they make one.
fn merge(a: &[Vec3; 3], b: &[Vec3; 3]) -> Option<Occluder> {
    let (ta, tb) = (Occluder::triangle(a)?, Occluder::triangle(b)?);
    if ta.normal.dot(tb.normal).abs() < 1.0 - 1e-9 {
        return None;
    }
    let scale = ta.corners.iter().map(|c| c.abs().max_element()).fold(1.0, f64::max);
    // The corner of b off the shared edge, in a's plane.
    let apex = tb
        .corners
        .iter()
        .copied()
        .find(|c| !ta.corners.iter().any(|d| d == c))?;
    if ta.plane_distance(apex).abs() > 1e-9 * scale {
        return None;
    }
    // Insert the apex between the shared edge's corners of a, in a's order.
    let n = 3;
    for i in 0..n {
        let (p, q) = (ta.corners[i], ta.corners[(i + 1) % n]);
        if tb.corners.contains(&p) && tb.corners.contains(&q) {
            let mut corners = Vec::with_capacity(4);
            for k in 0..n {
                corners.push(ta.corners[k]);
                if k == i {
                    corners.push(apex);
                }
            }
            let quad = Occluder {
                corners,
                normal: ta.normal,
                area: ta.area + tb.area,
            };
            // Convex: every corner turns the same way about the normal.
            let convex = (0..4).all(|k| {
                let (u, v, w) = (quad.corners[k], quad.corners[(k + 1) % 4], quad.corners[(k + 2) % 4]);
                (v - u).cross(w - v).dot(quad.normal) > 1e-12 * scale * scale
            });
            return convex.then_some(quad);
        }
    }
    None
}

/// Whether `o` hides the point light at `light` from every point of the convex hull of
/// `corners` (the shadow rays of those points, lifted off their surfaces, all crossing it),
/// with `margin` (metres) beyond its plane and inside its edges to spare for rounding.
pub fn hides(o: &Occluder, light: DVec3, corners: &[DVec3], margin: f64) -> bool {
    let sl = o.plane_distance(light);
    if sl.abs() <= margin {
        return false;
    }
    corners.iter().all(|&q| {
        let lift = f64::from(SHADOW_OFFSET) * q.abs().max_element().max(1.0);
        let spare = margin + lift;
        let sq = o.plane_distance(q);
        if sq * sl.signum() >= -spare {
            return false;
        }
        let x = light + (q - light) * (sl / (sl - sq));
        o.inside(x) > spare
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wall of two triangles merges into one quad; a cell behind it is hidden from a light in
    /// front, one half behind and half beside it is not, nor is a light on the cell's side.
    #[test]
    fn a_wall_hides_what_is_behind_it() {
        let (a, b, c, d) = (
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        );
        let o = occluders(&[[a, b, c], [a, c, d]], 0.0, 8);
        assert_eq!(o.len(), 1, "{o:?}");
        assert_eq!(o[0].corners.len(), 4);
        assert!((o[0].area - 4.0).abs() < 1e-12);
        let cell = |x: f64| {
            [0.0, 0.2].iter().flat_map(move |&dz| {
                [(-0.1, -0.1), (0.1, -0.1), (0.1, 0.1), (-0.1, 0.1)]
                    .map(|(u, v)| DVec3::new(x + u, v, -1.0 - dz))
            }).collect::<Vec<_>>()
        };
        let light = DVec3::new(0.0, 0.0, 1.0);
        assert!(hides(&o[0], light, &cell(0.0), 1e-6));
        assert!(!hides(&o[0], light, &cell(3.0), 1e-6), "beside the wall");
        assert!(!hides(&o[0], light, &cell(1.9), 1e-6), "half beside it");
        assert!(!hides(&o[0], DVec3::new(0.0, 0.0, -3.0), &cell(0.0), 1e-6), "same side");
        // A pair whose quadrilateral is not convex does not merge.
        let e = Vec3::new(2.0, 2.5, 0.0);
        let l = occluders(&[[a, b, c], [b, e, c]], 0.0, 8);
        assert_eq!(l.len(), 2, "{l:?}");
    }
}

/// A scene's occluders as culling by visibility takes them: the 64 largest opaque convex
/// polygons of at least 1e-3 of its lights' extent squared.
pub fn of_scene(scene: &crate::Scene) -> Vec<Occluder> {
    let extent = f64::from(scene.light_bounds.extent().max_element());
    occluders(&crate::ray::opaque_triangles(scene), extent * extent * 1e-3, 64)
}
