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
//! ```
//!
//! with `speed` in world units per second along the path, and the phases `p` and frequency
//! factors `f_k` hashed from the light's index (PCG). Spot axes, radii and colours do not
//! change.

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
}

/// [`Motion`]'s kind as the GPU pass reads it.
pub const MOTION_STATIC: u32 = 0;
/// See [`MOTION_STATIC`].
pub const MOTION_ORBIT: u32 = 1;
/// See [`MOTION_STATIC`].
pub const MOTION_NOISE: u32 = 2;

impl Motion {
    /// Whether lights move.
    pub fn is_static(&self) -> bool {
        matches!(self, Self::Static) || self.speed() == 0.0
    }

    /// The speed (0 for `Static`).
    pub fn speed(&self) -> f32 {
        match *self {
            Self::Static => 0.0,
            Self::Orbit(s) | Self::Noise(s) => s,
        }
    }

    /// The kind as the GPU pass reads it ([`MOTION_STATIC`], ...).
    pub fn kind(&self) -> u32 {
        match self {
            Self::Static => MOTION_STATIC,
            Self::Orbit(_) => MOTION_ORBIT,
            Self::Noise(_) => MOTION_NOISE,
        }
    }

    /// Checks the speed; the error names the field and what is accepted.
    pub fn validate(&self) -> Result<(), SceneError> {
        let s = self.speed();
        if s.is_finite() && s >= 0.0 {
            Ok(())
        } else {
            Err(SceneError::invalid(
                "lights.motion",
                format!("{self:?}"),
                "Static, Orbit(speed) or Noise(speed) with a finite speed >= 0 (world units per second)",
            ))
        }
    }

    /// The label of results (`orbit2`, `noise0.5`, `static`).
    pub fn label(&self) -> String {
        match *self {
            Self::Static => "static".into(),
            Self::Orbit(s) => format!("orbit{s}"),
            Self::Noise(s) => format!("noise{s}"),
        }
    }

    /// Where the light of index `index`, at `home` with radius of influence `radius`, is at
    /// frame `frame`.
    pub fn position(&self, index: u32, home: Vec3, radius: f32, frame: u32) -> Vec3 {
        home + self.offset(index, radius, frame_time(frame))
    }

    /// The offset from home at time `t` seconds (see the module docs).
    fn offset(&self, index: u32, radius: f32, t: f32) -> Vec3 {
        let a = 0.5 * radius;
        if self.is_static() || a <= 0.0 {
            return Vec3::ZERO;
        }
        let w = self.speed() / a;
        match self {
            Self::Static => Vec3::ZERO,
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

    #[test]
    fn bad_speeds_are_rejected_with_the_field() {
        for m in [Motion::Orbit(-1.0), Motion::Noise(f32::NAN)] {
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
