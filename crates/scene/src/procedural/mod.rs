//! Procedural scenes: deterministic functions of a few parameters.
//!
//! - `atrium`: a two-storey colonnade around a courtyard with arches and hanging cloth, in
//!   roughly Sponza's proportions (about 28 x 16 m in plan, 13 m high by default).
//! - `pillars`: thin pillars in front of a far wall, so that almost every screen tile holds a
//!   depth discontinuity (the case 2.5D culling exists for).
//! - `topdown`: a flat ground seen from straight above (little depth variance).
//! - `city`: a grid of boxes of varied height on a ground plane.
//! - `cis5650`: a hall of Sponza's extents (x -15 to 14.5, y 0 to 11.5, z -9.5 to 8.8 m) with
//!   two rows of pillars and galleries behind them; its camera at (-7, 2, 0) looks along +X
//!   (45 degrees vertical field of view, near 0.1, far 1000) and its lights fill the box
//!   (-10, 0, -5) to (10, 8, 5): the setting of the University of Pennsylvania CIS 5650
//!   WebGPU project, with lights of radius 2.
//!
//! Every scene comes with a default camera and the volume its lights are generated in. Surfaces
//! are two-sided in the renderers (the shading normal is turned towards the viewer), so winding
//! does not matter here.

use std::f32::consts::PI;

use glam::Vec3;
use rand::{RngExt, SeedableRng};
use serde::{Deserialize, Serialize};

use crate::builder::{FLOOR, GLASS, MeshBuilder, STONE, base_materials, check_pos, check_u32};
use crate::{Aabb, Camera, Scene, SceneError};

mod cis5650;
pub use cis5650::cis5650;

/// The procedural scene names, as accepted by [`ProceduralScene::from_name`].
pub const NAMES: [&str; 5] = ["atrium", "pillars", "topdown", "city", "cis5650"];

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
    /// Whether the upper galleries have glass railings (transparent surfaces).
    pub glass: bool,
}

impl Default for AtriumParams {
    fn default() -> Self {
        Self {
            bays: 7,
            storeys: 2,
            cloth: true,
            glass: false,
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
    /// Whether a glass pane stands 1 m in front of the far wall (a transparent surface with
    /// lights between it and the wall).
    pub glass: bool,
    /// Distance from the pillar row to the far wall in metres, > 0.
    pub gap: f32,
}

impl Default for PillarsParams {
    fn default() -> Self {
        Self {
            count: 64,
            width: 0.12,
            gap: 20.0,
            glass: false,
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

/// Parameters of `cis5650`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Cis5650Params {
    /// Pillars in each of the two rows, 1..=64.
    pub pillars: u32,
    /// Whether galleries (a slab at 6 m between each row and its wall) stand behind the rows.
    pub galleries: bool,
    /// Whether glass sheets (transparent surfaces) hang before each row of pillars.
    pub glass: bool,
}

impl Default for Cis5650Params {
    fn default() -> Self {
        Self {
            pillars: 9,
            galleries: true,
            glass: false,
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
    /// See [`Cis5650Params`].
    Cis5650(Cis5650Params),
}

impl ProceduralScene {
    /// The scene of that name with default parameters.
    pub fn from_name(name: &str) -> Result<Self, SceneError> {
        Ok(match name {
            "atrium" => Self::Atrium(AtriumParams::default()),
            "pillars" => Self::Pillars(PillarsParams::default()),
            "topdown" => Self::Topdown(TopdownParams::default()),
            "city" => Self::City(CityParams::default()),
            "cis5650" => Self::Cis5650(Cis5650Params::default()),
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
            Self::Cis5650(_) => "cis5650",
        }
    }

    /// Builds the geometry, materials, default camera and light volume (no lights).
    pub fn build(&self) -> Result<Scene, SceneError> {
        match self {
            Self::Atrium(p) => atrium(p),
            Self::Pillars(p) => pillars(p),
            Self::Topdown(p) => topdown(p),
            Self::City(p) => city(p),
            Self::Cis5650(p) => cis5650(p),
        }
    }
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
        if params.glass {
            // A glass railing 1.1 m high along each upper gallery, on the court side.
            for storey in 1..params.storeys {
                mb.quad(
                    GLASS,
                    Vec3::new(-half_len, storey as f32 * STOREY, side * (COURT - 0.35)),
                    Vec3::X * 2.0 * half_len,
                    Vec3::Y * 1.1,
                );
            }
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
    if params.glass {
        mb.quad(
            GLASS,
            Vec3::new(-10.0, 0.5, wall_z + 1.0),
            Vec3::X * 20.0,
            Vec3::Y * 7.5,
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
            e.contains("sponza") && e.contains("atrium, pillars, topdown, city, cis5650"),
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
        let e = cis5650(&Cis5650Params {
            pillars: 65,
            ..Cis5650Params::default()
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("scene.pillars = 65"), "{e}");
    }

    #[test]
    fn cis5650_is_the_course_setting() {
        let s = ProceduralScene::from_name("cis5650")
            .unwrap()
            .build()
            .unwrap();
        assert_eq!(s.light_bounds.min, Vec3::new(-10.0, 0.0, -5.0));
        assert_eq!(s.light_bounds.max, Vec3::new(10.0, 8.0, 5.0));
        assert_eq!(s.camera.position, Vec3::new(-7.0, 2.0, 0.0));
        assert_eq!(
            (s.camera.target - s.camera.position).normalize(),
            Vec3::X,
            "looks along +X"
        );
        assert_eq!(s.camera.near_far(), (0.1, 1000.0));
        // The hall spans Sponza's extents; the lights' box lies inside it, clear of the pillars.
        let b = s.bounds();
        assert!(b.min.x <= -15.0 && b.max.x >= 14.5 && b.min.z <= -9.5 && b.max.z >= 8.8);
        assert!((b.max.y - 11.5).abs() < 1e-4, "height {}", b.max.y);
    }
}
