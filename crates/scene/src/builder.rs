//! What the procedural scenes are built with: a mesh builder of quads, cuboids, parametric
//! surfaces, columns and arches, accumulating triangles per material; the shared materials; and
//! the checks of scene parameters.

use std::collections::BTreeMap;
use std::f32::consts::PI;

use glam::Vec3;

use crate::{Material, Primitive, SceneError};

pub(crate) fn check_u32(field: &str, v: u32, lo: u32, hi: u32) -> Result<(), SceneError> {
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

pub(crate) fn check_pos(field: &str, v: f32) -> Result<(), SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(field, v, "a finite value > 0"))
    }
}

/// Accumulates triangles per material.
#[derive(Default)]
pub(crate) struct MeshBuilder {
    by_material: BTreeMap<u32, Primitive>,
}

impl MeshBuilder {
    pub(crate) fn prim(&mut self, material: u32) -> &mut Primitive {
        self.by_material
            .entry(material)
            .or_insert_with(|| Primitive {
                material,
                ..Primitive::default()
            })
    }

    /// A parallelogram `corner, corner + u, corner + u + v, corner + v`, normal `u x v`.
    pub(crate) fn quad(&mut self, material: u32, corner: Vec3, u: Vec3, v: Vec3) {
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
    pub(crate) fn cuboid(&mut self, material: u32, min: Vec3, max: Vec3) {
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
    pub(crate) fn surface(
        &mut self,
        material: u32,
        nu: u32,
        nv: u32,
        f: impl Fn(f32, f32) -> Vec3,
    ) {
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
    pub(crate) fn column(
        &mut self,
        material: u32,
        base: Vec3,
        radius: f32,
        height: f32,
        segments: u32,
    ) {
        self.surface(material, segments, 1, |u, v| {
            let a = u * 2.0 * PI;
            base + Vec3::new(radius * a.cos(), height * v, radius * a.sin())
        });
    }

    /// A semicircular arch in the XY plane (spanning along X), centred at `center`, extruded
    /// along Z by `depth`: intrados, extrados and both faces.
    pub(crate) fn arch(
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

    pub(crate) fn finish(self) -> Vec<Primitive> {
        self.by_material.into_values().collect()
    }
}

pub(crate) const STONE: u32 = 0;
pub(crate) const FLOOR: u32 = 1;
/// Glass panes (transparent: opacity 0.3, a faint blue-green tint).
pub(crate) const GLASS: u32 = 5;

pub(crate) fn base_materials() -> Vec<Material> {
    vec![
        Material::new(Vec3::new(0.72, 0.66, 0.56), 0.1), // stone
        Material::new(Vec3::new(0.45, 0.42, 0.38), 0.3), // floor
        Material::new(Vec3::new(0.70, 0.12, 0.10), 0.0), // red cloth
        Material::new(Vec3::new(0.12, 0.45, 0.16), 0.0), // green cloth
        Material::new(Vec3::new(0.14, 0.20, 0.60), 0.0), // blue cloth
        Material::transparent(Vec3::new(0.80, 0.90, 0.88), 0.8, 0.3), // glass
    ]
}
