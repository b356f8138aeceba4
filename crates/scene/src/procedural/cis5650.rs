//! `cis5650`: the University of Pennsylvania CIS 5650 project's setting (see the module above).

use glam::Vec3;

use super::Cis5650Params;
use crate::builder::{FLOOR, GLASS, MeshBuilder, STONE, base_materials, check_u32};
use crate::{Aabb, Camera, Scene, SceneError};

/// The CIS 5650 hall; see [`Cis5650Params`].
pub fn cis5650(params: &Cis5650Params) -> Result<Scene, SceneError> {
    check_u32("scene.pillars", params.pillars, 1, 64)?;
    // Sponza's extents, as the course's setting gives them.
    let (min, max) = (Vec3::new(-15.0, 0.0, -9.5), Vec3::new(14.5, 11.5, 8.8));
    const WALL: f32 = 0.3;
    const ROW_Z: f32 = 6.0; // the pillar rows, just outside the lights' box (z within 5)
    const GALLERY_Y: f32 = 6.0;
    let mut mb = MeshBuilder::default();
    mb.quad(
        FLOOR,
        Vec3::new(min.x, 0.0, min.z),
        Vec3::Z * (max.z - min.z),
        Vec3::X * (max.x - min.x),
    );
    // The four walls, their inner faces on the hall's extents.
    mb.cuboid(
        STONE,
        Vec3::new(min.x - WALL, 0.0, min.z),
        Vec3::new(min.x, max.y, max.z),
    );
    mb.cuboid(
        STONE,
        Vec3::new(max.x, 0.0, min.z),
        Vec3::new(max.x + WALL, max.y, max.z),
    );
    mb.cuboid(
        STONE,
        Vec3::new(min.x, 0.0, min.z - WALL),
        Vec3::new(max.x, max.y, min.z),
    );
    mb.cuboid(
        STONE,
        Vec3::new(min.x, 0.0, max.z),
        Vec3::new(max.x, max.y, max.z + WALL),
    );
    let n = params.pillars;
    let (x0, x1) = (-12.0f32, 12.0f32);
    for (z, wall) in [(-ROW_Z, min.z), (ROW_Z, max.z)] {
        for i in 0..n {
            let x = if n == 1 {
                0.0
            } else {
                x0 + (x1 - x0) * i as f32 / (n - 1) as f32
            };
            mb.column(STONE, Vec3::new(x, 0.0, z), 0.45, max.y, 12);
        }
        if params.galleries {
            mb.cuboid(
                STONE,
                Vec3::new(min.x, GALLERY_Y - 0.3, z.min(wall)),
                Vec3::new(max.x, GALLERY_Y, z.max(wall)),
            );
        }
        if params.glass {
            let zg = z - z.signum() * 0.6;
            mb.quad(
                GLASS,
                Vec3::new(x0, 0.5, zg),
                Vec3::X * (x1 - x0),
                Vec3::Y * 3.5,
            );
        }
    }
    let camera = Camera::perspective(
        Vec3::new(-7.0, 2.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
        45.0,
        0.1,
        1000.0,
    );
    Ok(Scene {
        name: "cis5650".into(),
        primitives: mb.finish(),
        materials: base_materials(),
        lights: Vec::new(),
        camera,
        light_bounds: Aabb::new(Vec3::new(-10.0, 0.0, -5.0), Vec3::new(10.0, 8.0, 5.0)),
    })
}
