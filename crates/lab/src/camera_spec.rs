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
    /// A walkthrough of the scene from its own camera ([`Walkthrough`]): a path made at the
    /// scene's camera, measured and checked as a `Path` is.
    Walkthrough(Walkthrough),
}

/// A walk from the scene's own camera towards the point it looks at, panning: pose k of `poses`
/// stands `toward * k / (poses - 1)` of the way from the eye to that point (pose 0 is the
/// scene's camera), its view turned about the up axis by `pan_deg * sin(2 pi k / poses)`
/// degrees, with the scene camera's projection. The line from a scene's camera to what it
/// looks at crosses the room the camera shows, so the walk stays in it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Walkthrough {
    /// Poses, at least 2.
    pub poses: u32,
    /// How far towards the point looked at the last pose stands, a fraction in [0, 1).
    pub toward: f32,
    /// The widest turn of the view, degrees, in [0, 90].
    pub pan_deg: f32,
}

impl Default for Walkthrough {
    fn default() -> Self {
        Self {
            poses: 6,
            toward: 0.5,
            pan_deg: 30.0,
        }
    }
}

impl Walkthrough {
    /// An error naming the field and value where one is outside what is accepted.
    pub fn validate(&self) -> Result<(), String> {
        if self.poses < 2 {
            return Err(format!(
                "camera Walkthrough(poses: {}): at least 2 poses",
                self.poses
            ));
        }
        if !(0.0..1.0).contains(&self.toward) {
            return Err(format!(
                "camera Walkthrough(toward: {}): a fraction of the way in [0, 1)",
                self.toward
            ));
        }
        if !(0.0..=90.0).contains(&self.pan_deg) {
            return Err(format!(
                "camera Walkthrough(pan_deg: {}): degrees in [0, 90]",
                self.pan_deg
            ));
        }
        Ok(())
    }

    /// The walk's cameras from the scene's camera `start`.
    pub fn cameras(&self, start: &Camera) -> Vec<Camera> {
        let to_target = start.target - start.position;
        let up = start.up.normalize_or(glam::Vec3::Y);
        (0..self.poses)
            .map(|k| {
                let t = self.toward * k as f32 / (self.poses - 1) as f32;
                let position = start.position + to_target * t;
                let angle = (self.pan_deg.to_radians())
                    * (std::f32::consts::TAU * k as f32 / self.poses as f32).sin();
                let look = glam::Quat::from_axis_angle(up, angle) * (start.target - position);
                Camera {
                    position,
                    target: position + look,
                    ..*start
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::Walkthrough;
    use manylights_scene::Camera;

    #[test]
    fn a_walkthrough_starts_at_the_scene_camera_and_walks_towards_its_target() {
        let start = Camera::perspective(
            glam::Vec3::new(0.0, 1.5, 10.0),
            glam::Vec3::new(0.0, 1.5, 0.0),
            60.0,
            0.1,
            100.0,
        );
        let w = Walkthrough {
            poses: 5,
            toward: 0.4,
            pan_deg: 30.0,
        };
        let cams = w.cameras(&start);
        assert_eq!(cams.len(), 5);
        assert_eq!(cams[0], start, "pose 0 is the scene's camera");
        for (k, c) in cams.iter().enumerate() {
            // On the line from the eye to the target, 4 m of its 10 at the last pose.
            let z = 10.0 - 4.0 * k as f32 / 4.0;
            assert!(
                (c.position - glam::Vec3::new(0.0, 1.5, z)).length() < 1e-5,
                "{k}"
            );
            assert_eq!(c.projection, start.projection);
            // The view turned about +Y by 30 degrees times sin(2 pi k / 5), level.
            let d = (c.target - c.position).normalize();
            let want = 30f32.to_radians() * (std::f32::consts::TAU * k as f32 / 5.0).sin();
            assert!((d.x.atan2(-d.z) + want).abs() < 1e-4, "{k}: {d}");
            assert!(d.y.abs() < 1e-6, "{k}: {d}");
            c.validate().unwrap();
        }
        for (bad, what) in [
            (Walkthrough { poses: 1, ..w }, "poses: 1"),
            (Walkthrough { toward: 1.0, ..w }, "toward: 1"),
            (
                Walkthrough {
                    pan_deg: 120.0,
                    ..w
                },
                "pan_deg: 120",
            ),
        ] {
            let e = bad.validate().unwrap_err();
            assert!(e.contains(what), "{e}");
        }
    }
}
