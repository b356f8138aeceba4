//! Procedural scenes: deterministic functions of a few parameters.
//!
//! - `atrium`: a two-storey colonnade around a courtyard with arches and hanging cloth, in
//!   roughly Sponza's proportions (about 28 x 16 m in plan, 13 m high by default).
//! - `pillars`: thin pillars in front of a far wall, so that almost every screen tile holds a
//!   depth discontinuity (the case 2.5D culling exists for).
//! - `topdown`: a flat ground seen from straight above (little depth variance).
//! - `city`: a grid of boxes of varied height on a ground plane.
//!
//! Every scene comes with a default camera and the volume its lights are generated in. Surfaces
//! are two-sided in the renderers (the shading normal is turned towards the viewer), so winding
//! does not matter here.

use std::collections::BTreeMap;
use std::f32::consts::PI;

use glam::Vec3;
use rand::{RngExt, SeedableRng};
use serde::{Deserialize, Serialize};

use crate::{Aabb, Camera, Material, Primitive, Scene, SceneError};

/// The procedural scene names, as accepted by [`ProceduralScene::from_name`].
pub const NAMES: [&str; 4] = ["atrium", "pillars", "topdown", "city"];

/// Parameters of `atrium`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AtriumParams {
    /// Arches along each long side, 1..=64.
    pub bays: u32,
    /// Storeys of arcades, 1..=8.
    pub storeys: u32,
    /// Whether cloth hangs from the upper galleries.
    pub cloth: bool,
}

impl Default for AtriumParams {
    fn default() -> Self {
        Self {
            bays: 7,
            storeys: 2,
            cloth: true,
        }
    }
}

/// Parameters of `pillars`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PillarsParams {
    /// Number of pillars in the row, 1..=4096.
    pub count: u32,
    /// Width of each (square) pillar in metres, > 0.
    pub width: f32,
    /// Distance from the pillar row to the far wall in metres, > 0.
    pub gap: f32,
}

impl Default for PillarsParams {
    fn default() -> Self {
        Self {
            count: 64,
            width: 0.12,
            gap: 20.0,
        }
    }
}

/// Parameters of `topdown`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TopdownParams {
    /// Side of the square ground in metres, > 0.
    pub size: f32,
    /// Quads along each side of the ground grid, 1..=1024.
    pub subdivisions: u32,
}

impl Default for TopdownParams {
    fn default() -> Self {
        Self {
            size: 40.0,
            subdivisions: 32,
        }
    }
}

/// Parameters of `city`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CityParams {
    /// Blocks along each side, 1..=256.
    pub blocks: u32,
    /// Seed of the building heights.
    pub seed: u64,
    /// Tallest building in metres, > 0.
    pub max_height: f32,
}

impl Default for CityParams {
    fn default() -> Self {
        Self {
            blocks: 8,
            seed: 1,
            max_height: 24.0,
        }
    }
}

/// A procedural scene and its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum ProceduralScene {
    /// See [`AtriumParams`].
    Atrium(AtriumParams),
    /// See [`PillarsParams`].
    Pillars(PillarsParams),
    /// See [`TopdownParams`].
    Topdown(TopdownParams),
    /// See [`CityParams`].
    City(CityParams),
}

impl ProceduralScene {
    /// The scene of that name with default parameters.
    pub fn from_name(name: &str) -> Result<Self, SceneError> {
        Ok(match name {
            "atrium" => Self::Atrium(AtriumParams::default()),
            "pillars" => Self::Pillars(PillarsParams::default()),
            "topdown" => Self::Topdown(TopdownParams::default()),
            "city" => Self::City(CityParams::default()),
            _ => {
                return Err(SceneError::UnknownScene {
                    name: name.to_owned(),
                    accepted: NAMES.join(", "),
                });
            }
        })
    }

    /// The scene's name.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Atrium(_) => "atrium",
            Self::Pillars(_) => "pillars",
            Self::Topdown(_) => "topdown",
            Self::City(_) => "city",
        }
    }

    /// Builds the geometry, materials, default camera and light volume (no lights).
    pub fn build(&self) -> Result<Scene, SceneError> {
        match self {
            Self::Atrium(p) => atrium(p),
            Self::Pillars(p) => pillars(p),
            Self::Topdown(p) => topdown(p),
            Self::City(p) => city(p),
        }
    }
}

fn check_u32(field: &str, v: u32, lo: u32, hi: u32) -> Result<(), SceneError> {
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(SceneError::invalid(
            field,
            v,
            format!("an integer in {lo}..={hi}"),
        ))
    }
}

fn check_pos(field: &str, v: f32) -> Result<(), SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(field, v, "a finite value > 0"))
    }
}

/// Accumulates triangles per material.
#[derive(Default)]
struct MeshBuilder {
    by_material: BTreeMap<u32, Primitive>,
}

impl MeshBuilder {
    fn prim(&mut self, material: u32) -> &mut Primitive {
        self.by_material
            .entry(material)
            .or_insert_with(|| Primitive {
                material,
                ..Primitive::default()
            })
    }

    /// A parallelogram `corner, corner + u, corner + u + v, corner + v`, normal `u x v`.
    fn quad(&mut self, material: u32, corner: Vec3, u: Vec3, v: Vec3) {
        let n = u.cross(v).normalize();
        let p = self.prim(material);
        let base = p.positions.len() as u32;
        p.positions
            .extend([corner, corner + u, corner + u + v, corner + v]);
        p.normals.extend([n; 4]);
        p.indices
            .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }

    /// An axis-aligned box with outward faces.
    fn cuboid(&mut self, material: u32, min: Vec3, max: Vec3) {
        let e = max - min;
        let (x, y, z) = (Vec3::X * e.x, Vec3::Y * e.y, Vec3::Z * e.z);
        self.quad(material, min, z, y); // -X
        self.quad(material, min + x, y, z); // +X
        self.quad(material, min, x, z); // -Y
        self.quad(material, min + y, z, x); // +Y
        self.quad(material, min, y, x); // -Z
        self.quad(material, min + z, x, y); // +Z
    }

    /// A parametric surface sampled on an (nu+1) x (nv+1) grid; normals from averaged faces.
    fn surface(&mut self, material: u32, nu: u32, nv: u32, f: impl Fn(f32, f32) -> Vec3) {
        let p = self.prim(material);
        let base = p.positions.len() as u32;
        let stride = nu + 1;
        let mut normals = vec![Vec3::ZERO; ((nu + 1) * (nv + 1)) as usize];
        let mut positions = Vec::with_capacity(normals.len());
        for j in 0..=nv {
            for i in 0..=nu {
                positions.push(f(i as f32 / nu as f32, j as f32 / nv as f32));
            }
        }
        for j in 0..nv {
            for i in 0..nu {
                let (a, b, c, d) = (
                    j * stride + i,
                    j * stride + i + 1,
                    (j + 1) * stride + i + 1,
                    (j + 1) * stride + i,
                );
                let fnorm = (positions[c as usize] - positions[a as usize])
                    .cross(positions[d as usize] - positions[b as usize]);
                for k in [a, b, c, d] {
                    normals[k as usize] += fnorm;
                }
                p.indices
                    .extend([base + a, base + b, base + c, base + a, base + c, base + d]);
            }
        }
        p.positions.extend(positions);
        p.normals
            .extend(normals.into_iter().map(|n| n.normalize_or(Vec3::Y)));
    }

    /// A vertical cylinder side (no caps).
    fn column(&mut self, material: u32, base: Vec3, radius: f32, height: f32, segments: u32) {
        self.surface(material, segments, 1, |u, v| {
            let a = u * 2.0 * PI;
            base + Vec3::new(radius * a.cos(), height * v, radius * a.sin())
        });
    }

    /// A semicircular arch in the XY plane (spanning along X), centred at `center`, extruded
    /// along Z by `depth`: intrados, extrados and both faces.
    fn arch(
        &mut self,
        material: u32,
        center: Vec3,
        r_in: f32,
        r_out: f32,
        depth: f32,
        segments: u32,
    ) {
        let ring =
            |r: f32, u: f32, z: f32| center + Vec3::new(r * (PI * u).cos(), r * (PI * u).sin(), z);
        let h = depth * 0.5;
        self.surface(material, segments, 1, |u, v| ring(r_in, u, -h + depth * v));
        self.surface(material, segments, 1, |u, v| ring(r_out, u, -h + depth * v));
        self.surface(material, segments, 1, |u, v| {
            ring(r_in + (r_out - r_in) * v, u, -h)
        });
        self.surface(material, segments, 1, |u, v| {
            ring(r_in + (r_out - r_in) * v, u, h)
        });
    }

    fn finish(self) -> Vec<Primitive> {
        self.by_material.into_values().collect()
    }
}

const STONE: u32 = 0;
const FLOOR: u32 = 1;

fn base_materials() -> Vec<Material> {
    vec![
        Material::new(Vec3::new(0.72, 0.66, 0.56), 0.1), // stone
        Material::new(Vec3::new(0.45, 0.42, 0.38), 0.3), // floor
        Material::new(Vec3::new(0.70, 0.12, 0.10), 0.0), // red cloth
        Material::new(Vec3::new(0.12, 0.45, 0.16), 0.0), // green cloth
        Material::new(Vec3::new(0.14, 0.20, 0.60), 0.0), // blue cloth
    ]
}

/// Sponza-like atrium; see [`AtriumParams`].
pub fn atrium(params: &AtriumParams) -> Result<Scene, SceneError> {
    check_u32("scene.bays", params.bays, 1, 64)?;
    check_u32("scene.storeys", params.storeys, 1, 8)?;
    const BAY: f32 = 4.0; // column spacing
    const STOREY: f32 = 6.0;
    const COL_H: f32 = 3.5; // column shaft; the arch rises BAY/2 above it
    const COURT: f32 = 5.0; // half-width of the courtyard (column line)
    const OUTER: f32 = 8.0; // half-width to the outer walls
    let half_len = params.bays as f32 * BAY * 0.5;
    let height = params.storeys as f32 * STOREY + 1.0;
    let mut mb = MeshBuilder::default();
    mb.quad(
        FLOOR,
        Vec3::new(-half_len, 0.0, -OUTER),
        Vec3::Z * 2.0 * OUTER,
        Vec3::X * 2.0 * half_len,
    );
    for side in [-1.0f32, 1.0] {
        // Outer wall and end walls.
        let wall_z = side * OUTER;
        mb.cuboid(
            STONE,
            Vec3::new(-half_len, 0.0, wall_z.min(wall_z + side * 0.3)),
            Vec3::new(half_len, height, wall_z.max(wall_z + side * 0.3)),
        );
        let end_x = side * half_len;
        mb.cuboid(
            STONE,
            Vec3::new(end_x.min(end_x + side * 0.3), 0.0, -OUTER),
            Vec3::new(end_x.max(end_x + side * 0.3), height, OUTER),
        );
        for storey in 0..params.storeys {
            let y0 = storey as f32 * STOREY;
            let z = side * COURT;
            for i in 0..=params.bays {
                let x = -half_len + i as f32 * BAY;
                mb.column(STONE, Vec3::new(x, y0, z), 0.35, COL_H, 12);
            }
            for i in 0..params.bays {
                let x = -half_len + (i as f32 + 0.5) * BAY;
                mb.arch(
                    STONE,
                    Vec3::new(x, y0 + COL_H, z),
                    BAY * 0.5 - 0.35,
                    BAY * 0.5,
                    0.6,
                    16,
                );
            }
            // Lintel band above the arches and the gallery floor/roof slab behind it.
            let top = y0 + COL_H + BAY * 0.5;
            let (z0, z1) = (z - side * 0.3, z + side * 0.3);
            mb.cuboid(
                STONE,
                Vec3::new(-half_len, top, z0.min(z1)),
                Vec3::new(half_len, y0 + STOREY, z0.max(z1)),
            );
            let (s0, s1) = (z, wall_z);
            mb.cuboid(
                STONE,
                Vec3::new(-half_len, y0 + STOREY - 0.3, s0.min(s1)),
                Vec3::new(half_len, y0 + STOREY, s0.max(s1)),
            );
        }
        if params.cloth && params.storeys >= 2 {
            // Drapes hang in front of the first-floor gallery, every other bay.
            for i in (0..params.bays).step_by(2) {
                let x0 = -half_len + i as f32 * BAY + 0.6;
                let width = BAY - 1.2;
                let top = STOREY + 1.2;
                let material = 2 + (i / 2) % 3;
                let zc = side * (COURT - 0.5);
                mb.surface(material, 16, 16, |u, v| {
                    let sway = 0.18 * (u * 3.0 * PI).sin() * (0.3 + 0.7 * v);
                    Vec3::new(x0 + width * u, top - 5.0 * v, zc - side * sway)
                });
            }
        }
    }
    let camera = Camera::perspective(
        Vec3::new(half_len * 0.85, 2.5, 1.0),
        Vec3::new(-half_len, 4.0, -0.8),
        60.0,
        0.1,
        4.0 * half_len + 50.0,
    );
    Ok(Scene {
        name: "atrium".into(),
        primitives: mb.finish(),
        materials: base_materials(),
        lights: Vec::new(),
        camera,
        light_bounds: Aabb::new(
            Vec3::new(-half_len, 0.2, -OUTER),
            Vec3::new(half_len, height - 1.0, OUTER),
        ),
    })
}

/// Thin pillars in front of a far wall; see [`PillarsParams`].
pub fn pillars(params: &PillarsParams) -> Result<Scene, SceneError> {
    check_u32("scene.count", params.count, 1, 4096)?;
    check_pos("scene.width", params.width)?;
    check_pos("scene.gap", params.gap)?;
    const ROW_Z: f32 = -5.0;
    const ROW_HALF: f32 = 8.0;
    const HEIGHT: f32 = 6.0;
    let wall_z = ROW_Z - params.gap;
    let mut mb = MeshBuilder::default();
    let extent = 2.0 * (10.0 - wall_z);
    mb.quad(
        FLOOR,
        Vec3::new(-extent, 0.0, wall_z),
        Vec3::Z * (10.0 - wall_z),
        Vec3::X * 2.0 * extent,
    );
    mb.quad(
        STONE,
        Vec3::new(-extent, 0.0, wall_z),
        Vec3::X * 2.0 * extent,
        Vec3::Y * extent,
    );
    let spacing = if params.count > 1 {
        2.0 * ROW_HALF / (params.count - 1) as f32
    } else {
        0.0
    };
    let hw = params.width * 0.5;
    for i in 0..params.count {
        let x = if params.count > 1 {
            -ROW_HALF + i as f32 * spacing
        } else {
            0.0
        };
        mb.cuboid(
            STONE,
            Vec3::new(x - hw, 0.0, ROW_Z - hw),
            Vec3::new(x + hw, HEIGHT, ROW_Z + hw),
        );
    }
    let camera = Camera::perspective(
        Vec3::new(0.0, 3.0, 5.0),
        Vec3::new(0.0, 3.0, -10.0),
        60.0,
        0.1,
        20.0 - 2.0 * wall_z,
    );
    Ok(Scene {
        name: "pillars".into(),
        primitives: mb.finish(),
        materials: base_materials(),
        lights: Vec::new(),
        camera,
        light_bounds: Aabb::new(Vec3::new(-12.0, 0.2, wall_z), Vec3::new(12.0, 8.0, 4.0)),
    })
}

/// A flat ground seen from above; see [`TopdownParams`].
pub fn topdown(params: &TopdownParams) -> Result<Scene, SceneError> {
    check_pos("scene.size", params.size)?;
    check_u32("scene.subdivisions", params.subdivisions, 1, 1024)?;
    let h = params.size * 0.5;
    let mut mb = MeshBuilder::default();
    mb.surface(FLOOR, params.subdivisions, params.subdivisions, |u, v| {
        Vec3::new(-h + params.size * u, 0.0, h - params.size * v)
    });
    let mut camera = Camera::perspective(
        Vec3::new(0.0, params.size * 0.75, 0.0),
        Vec3::ZERO,
        60.0,
        0.1,
        params.size * 2.0,
    );
    camera.up = -Vec3::Z;
    Ok(Scene {
        name: "topdown".into(),
        primitives: mb.finish(),
        materials: base_materials(),
        lights: Vec::new(),
        camera,
        light_bounds: Aabb::new(Vec3::new(-h, 0.1, -h), Vec3::new(h, params.size * 0.075, h)),
    })
}

/// A grid of boxes of varied height; see [`CityParams`].
pub fn city(params: &CityParams) -> Result<Scene, SceneError> {
    check_u32("scene.blocks", params.blocks, 1, 256)?;
    check_pos("scene.max_height", params.max_height)?;
    const BLOCK: f32 = 10.0;
    const STREET: f32 = 4.0;
    let pitch = BLOCK + STREET;
    let half = params.blocks as f32 * pitch * 0.5;
    let mut rng = rand_pcg::Pcg64::seed_from_u64(params.seed);
    let mut mb = MeshBuilder::default();
    mb.quad(
        FLOOR,
        Vec3::new(-half, 0.0, -half),
        Vec3::Z * 2.0 * half,
        Vec3::X * 2.0 * half,
    );
    for j in 0..params.blocks {
        for i in 0..params.blocks {
            let x0 = -half + i as f32 * pitch + STREET * 0.5;
            let z0 = -half + j as f32 * pitch + STREET * 0.5;
            let hgt = params.max_height * rng.random_range(0.15f32..=1.0);
            mb.cuboid(
                STONE,
                Vec3::new(x0, 0.0, z0),
                Vec3::new(x0 + BLOCK, hgt, z0 + BLOCK),
            );
        }
    }
    let camera = Camera::perspective(
        Vec3::new(-half * 0.9, params.max_height * 1.6, half * 0.9),
        Vec3::new(half * 0.2, 0.0, -half * 0.2),
        60.0,
        0.5,
        half * 6.0 + params.max_height * 4.0,
    );
    Ok(Scene {
        name: "city".into(),
        primitives: mb.finish(),
        materials: base_materials(),
        lights: Vec::new(),
        camera,
        light_bounds: Aabb::new(
            Vec3::new(-half, 0.2, -half),
            Vec3::new(half, params.max_height, half),
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_scene_builds_valid_and_deterministic() {
        for name in NAMES {
            let s = ProceduralScene::from_name(name).unwrap();
            let a = s.build().unwrap();
            let b = s.build().unwrap();
            a.validate().unwrap();
            assert!(
                a.triangle_count() > 10,
                "{name}: {} triangles",
                a.triangle_count()
            );
            assert_eq!(a.primitives, b.primitives, "{name} is not deterministic");
        }
    }

    #[test]
    fn unknown_scene_lists_accepted_names() {
        let e = ProceduralScene::from_name("sponza")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("sponza") && e.contains("atrium, pillars, topdown, city"),
            "{e}"
        );
    }

    #[test]
    fn bad_parameters_are_rejected() {
        let e = atrium(&AtriumParams {
            bays: 0,
            ..AtriumParams::default()
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("scene.bays = 0"), "{e}");
        let e = pillars(&PillarsParams {
            width: f32::NAN,
            ..PillarsParams::default()
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("scene.width = NaN"), "{e}");
    }
}
