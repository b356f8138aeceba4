//! Moving lights: where each light is at a frame, deterministic from the light's index and the
//! frame index alone, so that a GPU animation pass and a host upload put every light in the
//! same place (up to `sin`/`cos` rounding). The WGSL twin is `shaders/lights/motion.wgsl`
//! (`manylights_gpu::motion` runs it); this is its oracle.
//!
//! Time is the frame index over a nominal clock of [`MOTION_FPS`] frames a second. Every light
//! moves about its home position (where it was generated) on a path of size `a` = half its
//! radius of influence, and is at home at frame 0:
//!
//! ```text
//! Orbit(speed): a circle in the horizontal plane through home,
//!     offset = a (cos(p + w t) - cos p, 0, sin(p + w t) - sin p),      w = speed / a
//! Noise(speed): a smooth pseudo-random wander, one sine per axis,
//!     offset_k = a (sin(f_k w t + p_k) - sin p_k),   f_k in [0.5, 1.5)
//! Glide { speed, extent }: a circle of radius e = extent through home in the plane of the
//!     surface the light was placed on (its anchor normal n, with the tangents t, b of
//!     `tangents(n)`), so that the light keeps its distance from that plane,
//!     offset = e ((cos(p + w t) - cos p) t + (sin(p + w t) - sin p) b),  w = speed / e
//! ```
//!
//! with `speed` in world units per second along the path, and the phases `p` and frequency
//! factors `f_k` hashed from the light's index (PCG). Spot axes, radii and colours do not
//! change. The anchor normals come from the generator (`LightSpec::anchors`: the surface's
//! normal for `OnSurfaces` and `Fixtures`, up for the volume generators, where a glide is a
//! horizontal circle); only `Glide` reads them.

use std::f32::consts::TAU;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::SceneError;

/// Frames per second of the clock that turns a frame index into time.
pub const MOTION_FPS: f32 = 60.0;

/// How lights move from frame to frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum Motion {
    /// Lights stay where they were generated.
    #[default]
    Static,
    /// Each light circles its home position in the horizontal plane at this speed (world units
    /// per second).
    Orbit(f32),
    /// Each light wanders smoothly about its home position at about this speed (world units
    /// per second).
    Noise(f32),
    /// Each light circles its home position in the plane of the surface it was placed on, at
    /// `speed` (world units per second) on a circle of radius `extent` (world units), so lights
    /// placed on surfaces stay at their distance from them.
    Glide {
        /// World units per second along the circle.
        speed: f32,
        /// The circle's radius, world units (> 0).
        extent: f32,
    },
}

/// [`Motion`]'s kind as the GPU pass reads it.
pub const MOTION_STATIC: u32 = 0;
/// See [`MOTION_STATIC`].
pub const MOTION_ORBIT: u32 = 1;
/// See [`MOTION_STATIC`].
pub const MOTION_NOISE: u32 = 2;
/// See [`MOTION_STATIC`].
pub const MOTION_GLIDE: u32 = 3;

impl Motion {
    /// Whether lights move.
    pub fn is_static(&self) -> bool {
        matches!(self, Self::Static) || self.speed() == 0.0
    }

    /// The speed (0 for `Static`).
    pub fn speed(&self) -> f32 {
        match *self {
            Self::Static => 0.0,
            Self::Orbit(s) | Self::Noise(s) | Self::Glide { speed: s, .. } => s,
        }
    }

    /// The radius of a glide's circle (0 for the other motions).
    pub fn extent(&self) -> f32 {
        match *self {
            Self::Glide { extent, .. } => extent,
            _ => 0.0,
        }
    }

    /// Whether the motion reads the lights' anchor normals (`Glide`).
    pub fn uses_anchors(&self) -> bool {
        matches!(self, Self::Glide { .. }) && !self.is_static()
    }

    /// The kind as the GPU pass reads it ([`MOTION_STATIC`], ...).
    pub fn kind(&self) -> u32 {
        match self {
            Self::Static => MOTION_STATIC,
            Self::Orbit(_) => MOTION_ORBIT,
            Self::Noise(_) => MOTION_NOISE,
            Self::Glide { .. } => MOTION_GLIDE,
        }
    }

    /// Checks the speed; the error names the field and what is accepted.
    pub fn validate(&self) -> Result<(), SceneError> {
        let s = self.speed();
        let e = self.extent();
        let extent_ok = !matches!(self, Self::Glide { .. }) || (e.is_finite() && e > 0.0);
        if s.is_finite() && s >= 0.0 && extent_ok {
            Ok(())
        } else {
            Err(SceneError::invalid(
                "lights.motion",
                format!("{self:?}"),
                "Static, Orbit(speed), Noise(speed) or Glide(speed: s, extent: e) with a finite speed >= 0 \
                 (world units per second) and a glide's finite extent > 0 (world units)",
            ))
        }
    }

    /// The label of results (`orbit2`, `noise0.5`, `static`).
    pub fn label(&self) -> String {
        match *self {
            Self::Static => "static".into(),
            Self::Orbit(s) => format!("orbit{s}"),
            Self::Noise(s) => format!("noise{s}"),
            Self::Glide { speed, extent } => format!("glide{speed}x{extent}"),
        }
    }

    /// Where the light of index `index`, at `home` with radius of influence `radius`, is at
    /// frame `frame`, its anchor normal up (see [`Motion::position_on`]).
    pub fn position(&self, index: u32, home: Vec3, radius: f32, frame: u32) -> Vec3 {
        self.position_on(index, home, radius, Vec3::Y, frame)
    }

    /// [`Motion::position`] for a light whose anchor normal (the normal of the surface it was
    /// placed on, unit length) is `anchor`; only `Glide` reads it.
    pub fn position_on(
        &self,
        index: u32,
        home: Vec3,
        radius: f32,
        anchor: Vec3,
        frame: u32,
    ) -> Vec3 {
        home + self.offset(index, radius, anchor, frame_time(frame))
    }

    /// The offset from home at time `t` seconds (see the module docs).
    fn offset(&self, index: u32, radius: f32, anchor: Vec3, t: f32) -> Vec3 {
        let a = match self {
            Self::Glide { extent, .. } => *extent,
            _ => 0.5 * radius,
        };
        if self.is_static() || a <= 0.0 {
            return Vec3::ZERO;
        }
        let w = self.speed() / a;
        match self {
            Self::Static => Vec3::ZERO,
            Self::Glide { .. } => {
                let (u, v) = tangents(anchor);
                let p = TAU * hash01(index, 0);
                let q = p + w * t;
                a * ((q.cos() - p.cos()) * u + (q.sin() - p.sin()) * v)
            }
            Self::Orbit(_) => {
                let p = TAU * hash01(index, 0);
                let q = p + w * t;
                a * Vec3::new(q.cos() - p.cos(), 0.0, q.sin() - p.sin())
            }
            Self::Noise(_) => {
                let axis = |k: u32| {
                    let f = 0.5 + hash01(index, 1 + k);
                    let p = TAU * hash01(index, 4 + k);
                    a * ((f * w * t + p).sin() - p.sin())
                };
                Vec3::new(axis(0), axis(1), axis(2))
            }
        }
    }
}

/// Two unit tangents of the unit normal `n`, orthogonal to it and to each other (Duff et al.
/// 2017, "Building an orthonormal basis, revisited"), as the WGSL twin builds them.
pub fn tangents(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// The time of frame `frame`, seconds, on the [`MOTION_FPS`] clock (as the GPU pass gets it).
pub fn frame_time(frame: u32) -> f32 {
    frame as f32 / MOTION_FPS
}

/// PCG's output hash (O'Neill; as in Jarzynski and Olano 2020), the same in WGSL.
pub fn pcg(v: u32) -> u32 {
    let s = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let w = ((s >> ((s >> 28) + 4)) ^ s).wrapping_mul(277_803_737);
    (w >> 22) ^ w
}

/// A number in [0, 1) hashed from a light's index and a salt (0 to 6), 24 bits, as in WGSL.
pub fn hash01(index: u32, salt: u32) -> f32 {
    (pcg(index.wrapping_mul(8).wrapping_add(salt)) >> 8) as f32 / 16_777_216.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_motion_starts_at_home_and_stays_within_its_radius() {
        for m in [Motion::Static, Motion::Orbit(2.0), Motion::Noise(3.0)] {
            for i in [0u32, 1, 77, 1 << 20] {
                let home = Vec3::new(1.0, 2.0, -3.0);
                assert_eq!(m.position(i, home, 2.0, 0), home, "{m:?} {i}");
                for f in [1u32, 10, 1000, 100_000] {
                    let d = m.position(i, home, 2.0, f) - home;
                    // An orbit's circle through home reaches 2a from it; each sine 2a.
                    assert!(d.length() <= 2.0 * 3f32.sqrt() + 1e-4, "{m:?} {i} {f}: {d}");
                }
            }
        }
    }

    #[test]
    fn lights_move_at_about_their_speed_and_apart() {
        let speed = 2.0;
        for m in [Motion::Orbit(speed), Motion::Noise(speed)] {
            let p0 = m.position(5, Vec3::ZERO, 4.0, 0);
            let p1 = m.position(5, Vec3::ZERO, 4.0, 1);
            let step = (p1 - p0).length() * MOTION_FPS;
            assert!(
                step > 0.2 * speed && step < 3.0 * speed,
                "{m:?}: {step} units/s"
            );
            // Lights of different indices are at different phases.
            let q1 = m.position(6, Vec3::ZERO, 4.0, 30);
            assert_ne!(m.position(5, Vec3::ZERO, 4.0, 30), q1, "{m:?}");
        }
        // An orbit keeps its height.
        assert_eq!(Motion::Orbit(1.0).position(3, Vec3::Y, 1.0, 17).y, 1.0);
    }

    /// A glide keeps its light in the plane through home across the anchor normal, within the
    /// circle's diameter of home, at its speed; with the anchor up it is a horizontal circle.
    #[test]
    fn a_glide_stays_in_its_surface_plane_at_its_speed() {
        let m = Motion::Glide {
            speed: 0.5,
            extent: 0.25,
        };
        let normals = [
            Vec3::Y,
            Vec3::NEG_Y,
            Vec3::X,
            Vec3::NEG_Z,
            Vec3::Z,
            Vec3::new(0.3, -0.8, 0.52).normalize(),
            Vec3::new(-1e-4, 0.0, -1.0).normalize(),
        ];
        for n in normals {
            let (u, v) = tangents(n);
            for (x, y) in [(u, v), (u, n), (v, n)] {
                assert!(x.dot(y).abs() < 1e-5, "{n}: {x} {y}");
            }
            assert!((u.length() - 1.0).abs() < 1e-5 && (v.length() - 1.0).abs() < 1e-5);
            let home = Vec3::new(1.0, 2.0, -3.0);
            for i in [0u32, 9, 1 << 20] {
                assert_eq!(m.position_on(i, home, 5.0, n, 0), home);
                for f in [1u32, 17, 400, 90_000] {
                    let d = m.position_on(i, home, 5.0, n, f) - home;
                    assert!(d.dot(n).abs() < 1e-5, "{n} {i} {f}: {d} leaves the plane");
                    assert!(d.length() <= 0.5 + 1e-5, "{n} {i} {f}: {d}");
                }
                let step = (m.position_on(i, home, 5.0, n, 1) - home).length() * MOTION_FPS;
                assert!((step - 0.5).abs() < 0.01, "{n}: {step} units/s");
            }
        }
        assert!(m.uses_anchors() && !Motion::Orbit(1.0).uses_anchors());
        assert!(
            !Motion::Glide {
                speed: 0.0,
                extent: 1.0
            }
            .uses_anchors()
        );
    }

    #[test]
    fn bad_speeds_are_rejected_with_the_field() {
        for m in [
            Motion::Orbit(-1.0),
            Motion::Noise(f32::NAN),
            Motion::Glide {
                speed: 1.0,
                extent: 0.0,
            },
            Motion::Glide {
                speed: -1.0,
                extent: 1.0,
            },
        ] {
            let e = m.validate().unwrap_err().to_string();
            assert!(e.contains("lights.motion"), "{e}");
        }
        Motion::Orbit(0.0).validate().unwrap();
        assert!(Motion::Orbit(0.0).is_static());
    }

    #[test]
    fn hashes_are_spread() {
        let n = 10_000;
        let mean: f32 = (0..n).map(|i| hash01(i, 3)).sum::<f32>() / n as f32;
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
        assert!((0..n).all(|i| (0.0..1.0).contains(&hash01(i, 0))));
    }
}
