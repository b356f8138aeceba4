//! The camera and its conventions.
//!
//! Conventions, used by every pass and every oracle:
//! - World space is right-handed with +Y up.
//! - View space: the camera sits at the origin looking down -Z, +X right, +Y up
//!   (`view_from_world` is a right-handed look-at).
//! - Clip space follows WebGPU: NDC x and y in [-1, 1] with +Y up, depth z in [0, 1] with the
//!   near plane at 0 and the far plane at 1. Reversed-Z is **not** used; the far plane is finite.
//! - Framebuffer pixels have their origin at the top-left; the centre of pixel (px, py) is at
//!   NDC `((px + 0.5) / w * 2 - 1, 1 - (py + 0.5) / h * 2)`.
//! - Matrices are named `a_from_b`, so that `clip_from_view * view_from_world = clip_from_world`
//!   reads right under multiplication.

use glam::camera::rh::{proj::directx, view::look_at_mat4};
use glam::{Mat4, Vec3};
use serde::{Deserialize, Serialize};

use crate::SceneError;

/// The projection of a camera.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Projection {
    /// A perspective projection.
    Perspective {
        /// Full vertical field of view, in degrees, in (0, 180).
        fov_y_deg: f32,
        /// Distance to the near plane, > 0.
        near: f32,
        /// Distance to the far plane, > near.
        far: f32,
    },
    /// An orthographic projection.
    Orthographic {
        /// Full height of the view volume in world units, > 0 (width follows the aspect ratio).
        height: f32,
        /// Distance to the near plane (may be 0 or negative), < far.
        near: f32,
        /// Distance to the far plane.
        far: f32,
    },
}

/// A camera: a pose and a projection.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Eye position in world space.
    pub position: Vec3,
    /// A point the camera looks at.
    pub target: Vec3,
    /// The approximate up direction (must not be parallel to the view direction).
    pub up: Vec3,
    /// The projection.
    pub projection: Projection,
}

impl Camera {
    /// A perspective camera looking from `position` at `target` with +Y up.
    pub fn perspective(position: Vec3, target: Vec3, fov_y_deg: f32, near: f32, far: f32) -> Self {
        Self {
            position,
            target,
            up: Vec3::Y,
            projection: Projection::Perspective {
                fov_y_deg,
                near,
                far,
            },
        }
    }

    /// Checks that the pose and projection are usable; errors name the field and value.
    pub fn validate(&self) -> Result<(), SceneError> {
        for (name, v) in [
            ("position", self.position),
            ("target", self.target),
            ("up", self.up),
        ] {
            if !v.is_finite() {
                return Err(SceneError::invalid(
                    format!("camera.{name}"),
                    format!("{v:?}"),
                    "finite coordinates",
                ));
            }
        }
        let forward = self.target - self.position;
        if forward.length_squared() < 1e-12 {
            return Err(SceneError::invalid(
                "camera.target",
                format!("{:?}", self.target),
                "a point different from camera.position",
            ));
        }
        if forward
            .normalize()
            .cross(self.up.normalize_or_zero())
            .length_squared()
            < 1e-10
        {
            return Err(SceneError::invalid(
                "camera.up",
                format!("{:?}", self.up),
                "a direction not parallel to the view direction",
            ));
        }
        match self.projection {
            Projection::Perspective {
                fov_y_deg,
                near,
                far,
            } => {
                if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) {
                    return Err(SceneError::invalid(
                        "camera.fov_y_deg",
                        fov_y_deg,
                        "a value in (0, 180) degrees",
                    ));
                }
                if !(near > 0.0 && near.is_finite()) {
                    return Err(SceneError::invalid(
                        "camera.near",
                        near,
                        "a finite value > 0",
                    ));
                }
                if !(far > near && far.is_finite()) {
                    return Err(SceneError::invalid(
                        "camera.far",
                        far,
                        format!("a finite value > near ({near})"),
                    ));
                }
            }
            Projection::Orthographic { height, near, far } => {
                if !(height > 0.0 && height.is_finite()) {
                    return Err(SceneError::invalid(
                        "camera.height",
                        height,
                        "a finite value > 0",
                    ));
                }
                if !(near.is_finite() && far.is_finite() && far > near) {
                    return Err(SceneError::invalid(
                        "camera.far",
                        far,
                        format!("a finite value > near ({near})"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Right-handed look-at: world to view space (camera looking down -Z).
    pub fn view_from_world(&self) -> Mat4 {
        look_at_mat4(self.position, self.target, self.up)
    }

    /// View to clip space for a target of the given aspect ratio (width / height), depth in [0, 1].
    pub fn clip_from_view(&self, aspect: f32) -> Mat4 {
        match self.projection {
            Projection::Perspective {
                fov_y_deg,
                near,
                far,
            } => {
                // glam's `directx` constructors give WebGPU's clip space: NDC z in [0, 1], +Y up.
                directx::perspective(fov_y_deg.to_radians(), aspect, near, far)
            }
            Projection::Orthographic { height, near, far } => {
                let h = height * 0.5;
                let w = h * aspect;
                directx::orthographic(-w, w, -h, h, near, far)
            }
        }
    }

    /// World to clip space.
    pub fn clip_from_world(&self, aspect: f32) -> Mat4 {
        self.clip_from_view(aspect) * self.view_from_world()
    }

    /// `(near, far)` distances of the projection.
    pub fn near_far(&self) -> (f32, f32) {
        match self.projection {
            Projection::Perspective { near, far, .. }
            | Projection::Orthographic { near, far, .. } => (near, far),
        }
    }

    /// Whether the projection is orthographic.
    pub fn is_orthographic(&self) -> bool {
        matches!(self.projection, Projection::Orthographic { .. })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perspective_depth_range_is_zero_to_one() {
        let cam = Camera::perspective(Vec3::ZERO, -Vec3::Z, 60.0, 0.5, 100.0);
        let m = cam.clip_from_world(1.0);
        let near = m.project_point3(Vec3::new(0.0, 0.0, -0.5));
        let far = m.project_point3(Vec3::new(0.0, 0.0, -100.0));
        assert!(near.z.abs() < 1e-6, "near maps to {}", near.z);
        assert!((far.z - 1.0).abs() < 1e-6, "far maps to {}", far.z);
    }

    #[test]
    fn bad_cameras_are_rejected() {
        let mut cam = Camera::perspective(Vec3::ZERO, -Vec3::Z, 60.0, 0.5, 100.0);
        cam.projection = Projection::Perspective {
            fov_y_deg: 200.0,
            near: 0.5,
            far: 100.0,
        };
        assert!(
            cam.validate()
                .unwrap_err()
                .to_string()
                .contains("fov_y_deg")
        );
        let cam = Camera {
            up: Vec3::Z,
            ..Camera::perspective(Vec3::ZERO, -Vec3::Z, 60.0, 0.5, 1.0)
        };
        assert!(
            cam.validate()
                .unwrap_err()
                .to_string()
                .contains("camera.up")
        );
    }
}
