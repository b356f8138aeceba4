//! Geometry: triangle primitives in world space, one material index each (materials are in
//! [`crate::material`]).

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::{Camera, Light, Material, SceneError};

/// An indexed triangle list in world space with per-vertex normals and one material.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Primitive {
    /// Vertex positions, world space.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals, one per position.
    pub normals: Vec<Vec3>,
    /// Triangle list indices into `positions`.
    pub indices: Vec<u32>,
    /// Index into [`Scene::materials`].
    pub material: u32,
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    /// Minimum corner.
    pub min: Vec3,
    /// Maximum corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (min = +inf, max = -inf), the identity of [`Aabb::union_point`].
    pub const EMPTY: Self = Self {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    /// A box from its corners.
    pub const fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The box grown to hold `p`.
    pub fn union_point(self, p: Vec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Size along each axis.
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// Centre.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Whether min <= max on every axis.
    pub fn is_valid(&self) -> bool {
        self.min.cmple(self.max).all()
    }
}

/// A scene: geometry, materials, lights, a default camera and the volume lights are placed in.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Name (the procedural scene name or the glTF file stem).
    pub name: String,
    /// Triangle primitives.
    pub primitives: Vec<Primitive>,
    /// Materials indexed by [`Primitive::material`].
    pub materials: Vec<Material>,
    /// Lights.
    pub lights: Vec<Light>,
    /// The default camera for this scene.
    pub camera: Camera,
    /// The volume the light generators fill.
    pub light_bounds: Aabb,
}

impl Scene {
    /// Total number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.primitives.iter().map(|p| p.indices.len() / 3).sum()
    }

    /// Total number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.primitives.iter().map(|p| p.positions.len()).sum()
    }

    /// Bounds of all geometry.
    pub fn bounds(&self) -> Aabb {
        self.primitives
            .iter()
            .flat_map(|p| p.positions.iter())
            .fold(Aabb::EMPTY, |b, &p| b.union_point(p))
    }

    /// Gives the surfaces the material models `models` in turns
    /// ([`crate::material::assign_models`]); none changes nothing.
    pub fn assign_models(&mut self, models: &[crate::Model]) {
        if models.is_empty() {
            return;
        }
        let (primitives, materials) =
            crate::material::assign_models(&self.primitives, &self.materials, models);
        self.primitives = primitives;
        self.materials = materials;
    }

    /// Checks geometry, materials, lights and camera; the error names the first bad value.
    pub fn validate(&self) -> Result<(), SceneError> {
        if self.materials.is_empty() {
            return Err(SceneError::invalid(
                "materials",
                "[]",
                "at least one material",
            ));
        }
        for (i, m) in self.materials.iter().enumerate() {
            m.validate(&format!("materials[{i}]"))?;
        }
        for (i, p) in self.primitives.iter().enumerate() {
            if p.normals.len() != p.positions.len() {
                return Err(SceneError::invalid(
                    format!("primitives[{i}].normals"),
                    format!(
                        "{} normals for {} positions",
                        p.normals.len(),
                        p.positions.len()
                    ),
                    "one normal per position",
                ));
            }
            if p.indices.len() % 3 != 0 {
                return Err(SceneError::invalid(
                    format!("primitives[{i}].indices"),
                    p.indices.len(),
                    "a multiple of 3 (triangle list)",
                ));
            }
            if let Some(&bad) = p
                .indices
                .iter()
                .find(|&&ix| ix as usize >= p.positions.len())
            {
                return Err(SceneError::invalid(
                    format!("primitives[{i}].indices"),
                    bad,
                    format!("indices < vertex count {}", p.positions.len()),
                ));
            }
            if let Some(v) = p.positions.iter().find(|v| !v.is_finite()) {
                return Err(SceneError::invalid(
                    format!("primitives[{i}].positions"),
                    format!("{v:?}"),
                    "finite coordinates",
                ));
            }
            if let Some(v) = p.normals.iter().find(|v| !v.is_finite()) {
                return Err(SceneError::invalid(
                    format!("primitives[{i}].normals"),
                    format!("{v:?}"),
                    "finite coordinates",
                ));
            }
            if p.material as usize >= self.materials.len() {
                return Err(SceneError::invalid(
                    format!("primitives[{i}].material"),
                    p.material,
                    format!("an index < {}", self.materials.len()),
                ));
            }
        }
        for (i, l) in self.lights.iter().enumerate() {
            l.validate(i)?;
        }
        self.camera.validate()
    }
}
