//! This workbench's cluster test on another program's grid (`score --cluster-on-grid`): the
//! lists a conservative cluster culler makes for exactly that grid's cells, so that a report can
//! set an engine's lists beside ours on the same cells and tell the grid's cost from the test's.
//!
//! A cell is the set of view points whose pixel (at a pixel centre) and view depth the grid
//! maps to it: four side planes through the eye (from the grid's screen mapping and the
//! frame's projection) and the slice's two depth planes (the first slice from the eye, the last
//! open-ended, as the lookup clamps). A light is listed in a cell unless its sphere, or for a
//! spot its cone capped at its range, lies wholly outside one of the six planes (the plane
//! test of `Clustered`, `outside_plane` in shaders/cull/common.wgsl), or its sphere misses the
//! box of the cell's frustum where the slice is bounded. In f64; conservative: no pixel of a
//! cell is reached by a light missing from its list (tested over random frames and grids).

use glam::{DMat4, DVec3, DVec4};

use super::grid::{Grid, ScreenMapping};
use super::{Frame, LightShape, Lists};

/// Relative slack on every comparison, far above f64's rounding of the frame's numbers.
const SLACK: f64 = 1e-7;

/// A light in view space.
struct ViewLight {
    center: DVec3,
    radius: f64,
    /// A spot's unit axis and the tangent of its outer half-angle.
    cone: Option<(DVec3, f64)>,
}

impl ViewLight {
    fn new(view_from_world: &DMat4, l: &LightShape) -> Self {
        let center = view_from_world.transform_point3(l.position.as_dvec3());
        let cone = l.cone.and_then(|(axis, cos)| {
            let cos = f64::from(cos);
            // Wider than a hemisphere the sphere is as tight as the cone.
            (cos > 0.0).then(|| {
                let axis = view_from_world
                    .transform_vector3(axis.as_dvec3())
                    .normalize();
                (axis, (1.0 - cos * cos).max(0.0).sqrt() / cos)
            })
        });
        Self {
            center,
            radius: f64::from(l.radius),
            cone,
        }
    }

    /// Whether the light lies wholly on the negative side of `plane` (`n . p + w`, `n` a unit
    /// normal): its sphere, and for a spot the cone from its apex to the disc at its range.
    fn outside(&self, plane: DVec4) -> bool {
        let n = plane.truncate();
        let slack = SLACK * (self.center.length() + self.radius + plane.w.abs());
        let dc = n.dot(self.center) + plane.w;
        if dc < -(self.radius + slack) {
            return true;
        }
        if let Some((axis, tan)) = self.cone {
            let base = n.dot(self.center + axis * self.radius) + plane.w;
            let perp = (n - n.dot(axis) * axis).length();
            return dc.max(base + self.radius * tan * perp) < -slack;
        }
        false
    }

    /// Whether the sphere meets the box `[lo, hi]`.
    fn meets_box(&self, lo: DVec3, hi: DVec3) -> bool {
        let d = self.center.clamp(lo, hi) - self.center;
        let r = self.radius * (1.0 + SLACK) + SLACK * self.center.length();
        d.length_squared() <= r * r
    }
}

/// The half-space `clip.k >= a clip.w` (`k` = 0 for x, 1 for y) in view space, as a unit
/// plane; `sign` -1 flips it to `clip.k <= a clip.w`.
fn side_plane(clip_from_view: &DMat4, k: usize, a: f64, sign: f64) -> DVec4 {
    let row = |i: usize| clip_from_view.row(i);
    let p = (row(k) - row(3) * a) * sign;
    p / p.truncate().length()
}

/// The NDC span of the pixel centres of column (`k` = 0) or row (`k` = 1) `i` of the grid,
/// low to high.
fn ndc_span(grid: &Grid, k: usize, i: u32) -> (f64, f64) {
    let size = f64::from(if k == 0 { grid.width } else { grid.height });
    let (u0, u1) = match grid.screen {
        ScreenMapping::Proportional => {
            let n = f64::from(grid.dims[k]);
            (f64::from(i) / n, f64::from(i + 1) / n)
        }
        ScreenMapping::Tiles { tile_size } => {
            let t = tile_size[k];
            let last = ((i + 1) * t).min(if k == 0 { grid.width } else { grid.height });
            (
                (f64::from(i * t) + 0.5) / size,
                (f64::from(last) - 0.5) / size,
            )
        }
    };
    if k == 0 {
        (u0 * 2.0 - 1.0, u1 * 2.0 - 1.0)
    } else {
        // Rows from the top: NDC y falls as the row rises.
        (1.0 - u1 * 2.0, 1.0 - u0 * 2.0)
    }
}

/// The view-space corners' box of the cell whose side planes pass through NDC `xs` and `ys`,
/// between view depths `d0` and `d1` (finite); for a perspective or an orthographic camera.
fn cell_box(
    view_from_clip: &DMat4,
    xs: (f64, f64),
    ys: (f64, f64),
    d: (f64, f64),
) -> (DVec3, DVec3) {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for x in [xs.0, xs.1] {
        for y in [ys.0, ys.1] {
            // The line of NDC (x, y), through two of its points, at each view depth (-z).
            let p = view_from_clip.project_point3(DVec3::new(x, y, 0.25));
            let q = view_from_clip.project_point3(DVec3::new(x, y, 0.75));
            for depth in [d.0, d.1] {
                let t = (-depth - p.z) / (q.z - p.z);
                let c = p + (q - p) * t;
                lo = lo.min(c);
                hi = hi.max(c);
            }
        }
    }
    (lo, hi)
}

/// The lists this workbench's cluster test makes for `grid`'s cells over `frame`'s lights
/// (the scene's light indices, each cell's sorted), in the grid's cell order.
pub fn cluster_on_grid(frame: &Frame, grid: &Grid) -> Lists {
    let clip_from_view = frame.clip_from_world * frame.view_from_world.inverse();
    let view_from_clip = clip_from_view.inverse();
    let [nx, ny, nz] = grid.dims;
    let spans = |k: usize, n: u32| -> Vec<((f64, f64), DVec4, DVec4)> {
        (0..n)
            .map(|i| {
                let s = ndc_span(grid, k, i);
                (
                    s,
                    side_plane(&clip_from_view, k, s.0, 1.0),
                    side_plane(&clip_from_view, k, s.1, -1.0),
                )
            })
            .collect()
    };
    let (cols, rows) = (spans(0, nx), spans(1, ny));
    let slices: Vec<(f64, f64)> = (0..nz).map(|k| grid.slice_span(k)).collect();
    // Each bounded cell's frustum box, once for the grid (slice-major, rows, columns).
    let mut boxes: Vec<Option<(DVec3, DVec3)>> = Vec::with_capacity(grid.cells() as usize);
    for &(d0, d1) in &slices {
        for r in &rows {
            for c in &cols {
                boxes.push(
                    d1.is_finite()
                        .then(|| cell_box(&view_from_clip, c.0, r.0, (d0, d1))),
                );
            }
        }
    }
    let mut cells: Vec<Vec<u32>> = vec![Vec::new(); grid.cells() as usize];
    for (i, l) in frame.lights.iter().enumerate() {
        let l = ViewLight::new(&frame.view_from_world, l);
        let x_in: Vec<u32> = (0..nx)
            .filter(|&x| !l.outside(cols[x as usize].1) && !l.outside(cols[x as usize].2))
            .collect();
        let y_in: Vec<u32> = (0..ny)
            .filter(|&y| !l.outside(rows[y as usize].1) && !l.outside(rows[y as usize].2))
            .collect();
        for (z, &(d0, d1)) in (0u32..).zip(&slices) {
            // View depth d = -z: d >= d0 is (0, 0, -1) . p - d0 >= 0, d <= d1 the other side.
            if l.outside(DVec4::new(0.0, 0.0, -1.0, -d0))
                || (d1.is_finite() && l.outside(DVec4::new(0.0, 0.0, 1.0, d1)))
            {
                continue;
            }
            for &y in &y_in {
                for &x in &x_in {
                    let b = ((z * ny + y) * nx + x) as usize;
                    if boxes[b].is_some_and(|(lo, hi)| !l.meets_box(lo, hi)) {
                        continue;
                    }
                    let c = grid.index(u64::from(x), u64::from(y), u64::from(z));
                    cells[c as usize].push(i as u32);
                }
            }
        }
    }
    let mut offsets = Vec::with_capacity(cells.len() + 1);
    offsets.push(0u64);
    let mut indices = Vec::new();
    for c in cells {
        indices.extend(c);
        offsets.push(indices.len() as u64);
    }
    let mut grid = grid.clone();
    grid.source = format!("manylights cluster test on the grid of: {}", grid.source);
    grid.light_ids = None;
    Lists {
        grid,
        offsets,
        indices,
    }
}

#[cfg(test)]
mod tests {
    use super::super::grid::{CellOrder, Slicing};
    use super::*;
    use glam::Vec3;

    /// A small generator (xorshift), so that the frames are the same on every run.
    struct Rng(u64);
    impl Rng {
        fn f(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, a: f64, b: f64) -> f64 {
            a + (b - a) * self.f()
        }
    }

    /// A frame of `w` x `h` pixels: a camera at the origin looking down -z (60 degrees, near
    /// 0.1, far 100), surfaces at random depths in blocks, some background, and `n` lights,
    /// points and spots, in and around the view.
    fn frame(r: &mut Rng, w: u32, h: u32, n: usize) -> Frame {
        let camera = manylights_scene::camera::Camera::perspective(
            Vec3::new(r.range(-1.0, 1.0) as f32, 1.0, 2.0),
            Vec3::new(r.range(-1.0, 1.0) as f32, 0.5, -10.0),
            60.0,
            0.1,
            100.0,
        );
        let view_from_world = camera.view_from_world().as_dmat4();
        let proj = if r.f() < 0.2 {
            let (hh, hw) = (12.0, 12.0 * w as f32 / h as f32);
            glam::camera::rh::proj::directx::orthographic(-hw, hw, -hh, hh, 0.1, 100.0)
        } else {
            camera.clip_from_view(w as f32 / h as f32)
        }
        .as_dmat4();
        let clip_from_world = proj * view_from_world;
        let mut depth = vec![1.0f32; (w * h) as usize];
        for by in 0..h.div_ceil(4) {
            for bx in 0..w.div_ceil(4) {
                let d = r.range(0.3, 40.0);
                let ndc = proj.project_point3(DVec3::new(0.0, 0.0, -d)).z as f32;
                let bg = r.f() < 0.1;
                for y in by * 4..(by * 4 + 4).min(h) {
                    for x in bx * 4..(bx * 4 + 4).min(w) {
                        // Depths vary inside a block, so cells see more than one plane.
                        let jitter = (r.f() as f32 - 0.5) * 1e-4;
                        depth[(y * w + x) as usize] =
                            if bg { 1.0 } else { (ndc + jitter).min(0.9999) };
                    }
                }
            }
        }
        let world_from_view = view_from_world.inverse();
        let lights = (0..n)
            .map(|_| {
                let d = r.range(0.05, 45.0);
                let p = DVec3::new(r.range(-0.8, 0.8) * d, r.range(-0.5, 0.5) * d, -d);
                let position = world_from_view.transform_point3(p).as_vec3();
                let radius = r.range(0.05, 6.0) as f32;
                let cone = (r.f() < 0.5).then(|| {
                    let a = Vec3::new(
                        r.range(-1.0, 1.0) as f32,
                        r.range(-1.0, 1.0) as f32,
                        r.range(-1.0, 1.0) as f32,
                    )
                    .normalize_or(Vec3::NEG_Z);
                    (a, r.range(-0.2, 0.99) as f32)
                });
                LightShape {
                    position,
                    radius,
                    cone,
                }
            })
            .collect();
        Frame {
            width: w,
            height: h,
            depth,
            clip_from_world,
            view_from_world,
            lights,
        }
    }

    fn random_grid(r: &mut Rng, w: u32, h: u32) -> Grid {
        let order = if r.f() < 0.5 {
            CellOrder::XFastest
        } else {
            CellOrder::ZFastest
        };
        let (screen, dims_xy) = if r.f() < 0.5 {
            let t = [4 + (r.f() * 12.0) as u32, 4 + (r.f() * 12.0) as u32];
            (
                ScreenMapping::Tiles { tile_size: t },
                [w.div_ceil(t[0]), h.div_ceil(t[1])],
            )
        } else {
            (
                ScreenMapping::Proportional,
                [1 + (r.f() * 17.0) as u32, 1 + (r.f() * 9.0) as u32],
            )
        };
        let z = 2 + (r.f() * 23.0) as u32;
        let (near, far) = (r.range(0.1, 5.0), r.range(20.0, 60.0));
        let slicing = match (r.f() * 4.0) as u32 {
            0 => Slicing::Linear { near, far },
            1 => Slicing::Exponential { near, far },
            2 => Slicing::NearSlice { near, far },
            _ => Slicing::None,
        };
        let z = if slicing == Slicing::None { 1 } else { z };
        Grid {
            format: super::super::grid::FORMAT.into(),
            source: "random".into(),
            width: w,
            height: h,
            dims: [dims_xy[0], dims_xy[1], z],
            screen,
            slicing,
            order,
            light_ids: None,
        }
    }

    /// Over random frames and grids of every kind: no false negative, and the lists are far
    /// shorter than every light in every cell (the test culls).
    #[test]
    fn the_cluster_test_on_any_grid_misses_nothing() {
        let mut r = Rng(0x9e37_79b9_7f4a_7c15);
        let (mut evaluated, mut all) = (0u64, 0u64);
        for case in 0..60 {
            let (w, h) = (40 + (r.f() * 60.0) as u32, 24 + (r.f() * 40.0) as u32);
            let f = frame(&mut r, w, h, 60);
            let g = random_grid(&mut r, w, h);
            g.check(std::path::Path::new("grid.json"), w, h).unwrap();
            let lists = cluster_on_grid(&f, &g);
            let s = super::super::score(&f, &lists);
            assert_eq!(
                s.metrics.false_negatives, 0,
                "case {case}: {g:?}, first misses {:?}",
                s.first_misses
            );
            assert!(
                s.metrics.needed > 0,
                "case {case}: no light reaches a pixel"
            );
            evaluated += s.metrics.evaluated;
            all += s.metrics.covered_pixels * f.lights.len() as u64;
        }
        assert!(
            evaluated * 4 < all,
            "{evaluated} of {all}: the lists hardly cull"
        );
    }

    /// A light beside the view is in no cell; one at the middle of the view, 10 m away with a
    /// 1 m range, is in the middle columns and rows only, and only in the slices its depth
    /// range crosses.
    #[test]
    fn a_light_is_listed_where_it_is() {
        let view_from_world = DMat4::IDENTITY;
        let proj = manylights_scene::camera::Camera::perspective(
            Vec3::ZERO,
            Vec3::NEG_Z,
            90.0,
            0.1,
            100.0,
        )
        .clip_from_view(1.0)
        .as_dmat4();
        let light = |p: Vec3| LightShape {
            position: p,
            radius: 1.0,
            cone: None,
        };
        let f = Frame {
            width: 64,
            height: 64,
            depth: vec![0.5; 64 * 64],
            clip_from_world: proj * view_from_world,
            view_from_world,
            lights: vec![
                light(Vec3::new(40.0, 0.0, -10.0)),
                light(Vec3::new(0.0, 0.0, -10.0)),
            ],
        };
        let g = Grid {
            format: super::super::grid::FORMAT.into(),
            source: "test".into(),
            width: 64,
            height: 64,
            dims: [8, 8, 10],
            screen: ScreenMapping::Proportional,
            slicing: Slicing::Linear {
                near: 0.0,
                far: 20.0,
            },
            order: CellOrder::XFastest,
            light_ids: None,
        };
        let l = cluster_on_grid(&f, &g);
        let cells: Vec<u64> = (0..g.cells())
            .filter(|&c| l.offsets[c as usize + 1] > l.offsets[c as usize])
            .collect();
        assert!(
            l.indices.iter().all(|&i| i == 1),
            "the light beside the view is listed"
        );
        // 90 degrees over 8 columns: at 9-11 m the sphere spans x in [-1, 1]: columns 3 and 4;
        // depths 9 to 11 over 2-m slices: slices 4 and 5.
        let expect: Vec<u64> = [4u64, 5]
            .iter()
            .flat_map(|&z| {
                [3u64, 4]
                    .iter()
                    .flat_map(move |&y| [3u64, 4].map(|x| (z * 8 + y) * 8 + x))
            })
            .collect();
        let mut expect = expect;
        expect.sort_unstable();
        assert_eq!(cells, expect);
    }
}
