//! Lights placed on a scene's surfaces, as a designer lights a real interior, where a box of
//! uniform lights lands inside walls, furniture and other rooms: [`on_surfaces`] (area-weighted
//! points lifted along their surface's shading normal by a distance in a range) and
//! [`fixtures`] (hanging under downward-facing surfaces and mounted on walls). Each light comes
//! with the direction a spot of it aims along and the normal of its surface (its anchor).

use glam::Vec3;
use rand::RngExt;
use rand_pcg::Pcg64;

use crate::{Scene, SceneError};

/// A light's place, the direction a spot there aims along and its surface's shading normal
/// (both unit).
pub(crate) type Placed = (Vec3, Vec3, Vec3);

/// A triangle of the scene: its corners, their normals and its area.
struct Tri {
    p: [Vec3; 3],
    n: [Vec3; 3],
    area: f64,
}

impl Tri {
    /// The point at barycentrics (1 - u - v, u, v) and the shading normal there (the vertex
    /// normals interpolated; the face normal where they cancel).
    fn at(&self, u: f32, v: f32) -> (Vec3, Vec3) {
        let [a, b, c] = self.p;
        let face = (b - a).cross(c - a).normalize_or(Vec3::Y);
        let n = (self.n[0] * (1.0 - u - v) + self.n[1] * u + self.n[2] * v).normalize_or(face);
        (a + (b - a) * u + (c - a) * v, n)
    }

    /// Its mean shading normal.
    fn normal(&self) -> Vec3 {
        let [a, b, c] = self.p;
        (self.n[0] + self.n[1] + self.n[2]).normalize_or((b - a).cross(c - a).normalize_or(Vec3::Y))
    }
}

/// The scene's triangles of positive area that `keep` accepts by their mean shading normal.
fn triangles(scene: &Scene, keep: impl Fn(Vec3) -> bool) -> Vec<Tri> {
    let mut out = Vec::new();
    for p in &scene.primitives {
        for t in p.indices.chunks_exact(3) {
            let i = [t[0], t[1], t[2]].map(|i| i as usize);
            let tri = Tri {
                p: i.map(|k| p.positions[k]),
                n: i.map(|k| p.normals[k]),
                area: 0.0,
            };
            let [a, b, c] = tri.p;
            let area = 0.5 * f64::from((b - a).cross(c - a).length());
            if area > 0.0 && area.is_finite() && keep(tri.normal()) {
                out.push(Tri { area, ..tri });
            }
        }
    }
    out
}

/// `n` points on `tris`, area-weighted, each with its shading normal.
fn sample(tris: &[Tri], n: usize, rng: &mut Pcg64) -> Vec<(Vec3, Vec3)> {
    let mut cdf = Vec::with_capacity(tris.len());
    let mut total = 0.0f64;
    for t in tris {
        total += t.area;
        cdf.push(total);
    }
    (0..n)
        .map(|_| {
            let x = rng.random::<f64>() * total;
            let k = cdf.partition_point(|&c| c < x).min(tris.len() - 1);
            let (mut u, mut v) = (rng.random::<f32>(), rng.random::<f32>());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            tris[k].at(u, v)
        })
        .collect()
}

/// `n` lights on the scene's surfaces, area-weighted, each lifted along its shading normal by a
/// distance drawn uniformly in `[lo, hi]`; a spot aims along that normal.
pub(crate) fn on_surfaces(
    scene: &Scene,
    n: usize,
    (lo, hi): (f32, f32),
    rng: &mut Pcg64,
) -> Result<Vec<Placed>, SceneError> {
    let tris = triangles(scene, |_| true);
    if tris.is_empty() {
        return Err(SceneError::invalid(
            "lights.generator",
            "OnSurfaces",
            "a scene with at least one triangle of positive area",
        ));
    }
    Ok(sample(&tris, n, rng)
        .into_iter()
        .map(|(p, normal)| {
            let lift = lo + (hi - lo) * rng.random::<f32>();
            (p + normal * lift, normal, normal)
        })
        .collect())
}

/// `n` area-weighted points on every surface of the scene, each with its shading normal (none
/// where the scene has no triangle of positive area).
pub(crate) fn surface_points(scene: &Scene, n: usize, rng: &mut Pcg64) -> Vec<(Vec3, Vec3)> {
    let tris = triangles(scene, |_| true);
    if tris.is_empty() {
        return Vec::new();
    }
    sample(&tris, n, rng)
}

/// Below this `y` of a mean shading normal a surface faces down (a ceiling, a beam, a shelf's
/// underside): within 45 degrees of straight down.
const FACES_DOWN: f32 = -std::f32::consts::FRAC_1_SQRT_2;
/// A wall's mean shading normal is within 30 degrees of horizontal.
const WALL: f32 = 0.5;

/// `n` fixtures: `on_walls` of them (a fraction) mounted on walls, `drop` out from the wall,
/// spots aimed along the wall's normal tilted 30 degrees down; the rest hanging `drop` under
/// downward-facing surfaces, spots aimed straight down. Each kind area-weighted over its
/// surfaces; where the scene has none of one kind, all of them go to the other.
pub(crate) fn fixtures(
    scene: &Scene,
    n: usize,
    drop: f32,
    on_walls: f32,
    rng: &mut Pcg64,
) -> Result<Vec<Placed>, SceneError> {
    let ceilings = triangles(scene, |m| m.y < FACES_DOWN);
    let walls = triangles(scene, |m| m.y.abs() < WALL);
    let walls_n = match (ceilings.is_empty(), walls.is_empty()) {
        (true, true) => {
            return Err(SceneError::invalid(
                "lights.generator",
                "Fixtures",
                "a scene with downward-facing surfaces or walls (normals within 45 degrees of \
                 down, or 30 degrees of horizontal)",
            ));
        }
        (true, false) => n,
        (false, true) => 0,
        (false, false) => ((n as f32) * on_walls).round() as usize,
    };
    let mut out: Vec<Placed> = sample(&ceilings, n - walls_n, rng)
        .into_iter()
        .map(|(p, normal)| (p + normal * drop, Vec3::NEG_Y, normal))
        .collect();
    let down = 30f32.to_radians();
    out.extend(sample(&walls, walls_n, rng).into_iter().map(|(p, normal)| {
        let out_of_wall = Vec3::new(normal.x, 0.0, normal.z).normalize_or(normal);
        let aim = (out_of_wall * down.cos() - Vec3::Y * down.sin()).normalize();
        (p + normal * drop, aim, normal)
    }));
    Ok(out)
}
