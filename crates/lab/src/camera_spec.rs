//! An experiment's camera: the scene's own, one pose, or a short path of poses.

use manylights_scene::{Camera, Projection};
use serde::{Deserialize, Serialize};

/// A camera pose.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pose {
    /// Eye position.
    pub position: (f32, f32, f32),
    /// Point looked at.
    pub target: (f32, f32, f32),
    /// Up direction.
    #[serde(default = "up")]
    pub up: (f32, f32, f32),
    /// Vertical field of view in degrees (perspective).
    #[serde(default = "fov")]
    pub fov_y_deg: f32,
    /// Near plane distance.
    #[serde(default = "near")]
    pub near: f32,
    /// Far plane distance.
    #[serde(default = "far")]
    pub far: f32,
    /// With a value, an orthographic camera of this view height instead of a perspective one.
    #[serde(default)]
    pub orthographic_height: Option<f32>,
}

fn up() -> (f32, f32, f32) {
    (0.0, 1.0, 0.0)
}
fn fov() -> f32 {
    60.0
}
fn near() -> f32 {
    0.1
}
fn far() -> f32 {
    200.0
}

impl Pose {
    /// The camera.
    pub fn camera(&self) -> Camera {
        let v = |t: (f32, f32, f32)| glam::Vec3::new(t.0, t.1, t.2);
        let projection = match self.orthographic_height {
            Some(height) => Projection::Orthographic {
                height,
                near: self.near,
                far: self.far,
            },
            None => Projection::Perspective {
                fov_y_deg: self.fov_y_deg,
                near: self.near,
                far: self.far,
            },
        };
        Camera {
            position: v(self.position),
            target: v(self.target),
            up: v(self.up),
            projection,
        }
    }
}

/// The camera of an experiment.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum CameraSpec {
    /// The scene's own default camera.
    #[default]
    Default,
    /// One pose.
    Pose(Pose),
    /// A short path: measured frame k uses pose k modulo the path's length (accuracy and
    /// metrics use the first pose).
    Path(Vec<Pose>),
}
