//! The infinite-range reference, cached on disk in the run folder so that a sweep pays for it
//! once per view: every cell of the same scene geometry, lights (positions, colours,
//! intensities and cones; not their radii, which the infinite range ignores), camera,
//! resolution, sample count and shadows (the shadowed reference is a file of its own) shares one
//! file, `references/<hash>.bin`, whatever its strategy, backend or radius rule.
//!
//! A file holds its whole key (a line of JSON, [`ReferenceKey`]) before the image, and is used
//! only when that key equals the cell's: a hash collision, a file of another version of the
//! shading model ([`VERSION`]) or a truncated file is recomputed and rewritten, never used.
//! Files are written atomically. Moving lights are never cached (the lights differ from frame
//! to frame).

use std::hash::Hasher as _;
use std::path::{Path, PathBuf};

use manylights_scene::{Camera, LightKind, Scene};
use manylights_shade::{HdrImage, Shadows};

use crate::{LabError, write_atomic};

/// The version of what the reference computes; a change of the shading model or the reference
/// bumps it, so that files of earlier builds are recomputed.
pub const VERSION: u32 = 1;

const MAGIC: &[u8; 8] = b"MLREFINF";

/// FNV-1a, 64 bits: a hash that is the same on every machine and build (std's is not).
#[derive(Clone, Copy, Debug)]
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl std::hash::Hasher for Fnv {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 ^= u64::from(*b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// A fingerprint of everything of `scene` the infinite-range reference reads: its triangles
/// (positions, normals, materials), its materials, and its lights less their radii.
pub fn scene_fingerprint(scene: &Scene) -> u64 {
    let mut h = Fnv::default();
    let f = |h: &mut Fnv, x: f32| h.write_u32(x.to_bits());
    for p in &scene.primitives {
        h.write_u32(p.material);
        h.write_usize(p.positions.len());
        for (v, n) in p.positions.iter().zip(&p.normals) {
            for x in v.to_array().into_iter().chain(n.to_array()) {
                f(&mut h, x);
            }
        }
        for i in &p.indices {
            h.write_u32(*i);
        }
    }
    for m in &scene.materials {
        for x in m.base_color.to_array() {
            f(&mut h, x);
        }
        h.write_u32(m.brdf.model().id());
        for x in m.brdf.params().into_iter().chain(m.emissive.to_array()) {
            f(&mut h, x);
        }
        f(&mut h, m.opacity);
    }
    h.write_usize(scene.lights.len());
    for l in &scene.lights {
        for x in l.position.to_array().into_iter().chain(l.color.to_array()) {
            f(&mut h, x);
        }
        f(&mut h, l.intensity);
        if let LightKind::Spot {
            direction,
            inner_angle,
            outer_angle,
        } = l.kind
        {
            for x in direction.to_array() {
                f(&mut h, x);
            }
            f(&mut h, inner_angle);
            f(&mut h, outer_angle);
        }
    }
    h.finish()
}

/// What one cached reference is of.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReferenceKey(String);

impl ReferenceKey {
    /// The key of the reference of a scene with fingerprint `scene` ([`scene_fingerprint`])
    /// seen by `camera` at `width` x `height` with `samples` samples a pixel.
    pub fn new(scene: u64, camera: &Camera, size: (u32, u32), samples: u32) -> Self {
        Self::with_shadows(scene, camera, size, samples, Shadows::Off)
    }

    /// The key of the reference as [`ReferenceKey::new`]'s, shaded with `shadows` (`Off`: the
    /// same key as `new`'s).
    pub fn with_shadows(
        scene: u64,
        camera: &Camera,
        (width, height): (u32, u32),
        samples: u32,
        shadows: Shadows,
    ) -> Self {
        let mut json = serde_json::json!({
            "version": VERSION,
            "scene": format!("{scene:016x}"),
            "camera": camera,
            "resolution": [width, height],
            "samples": samples,
        });
        if shadows.casts() {
            json["shadows"] = shadows.name().into();
        }
        Self(json.to_string())
    }

    /// The key of half `half` (0 or 1) of the shadowed reference's estimate with `rays` rays a
    /// pixel (`Config::shadowed_reference_rays`): the mean of its estimates of that half.
    pub fn with_estimate(self, rays: u32, half: u32) -> Self {
        let mut json: serde_json::Value = serde_json::from_str(&self.0).expect("a key is JSON");
        json["estimate"] = serde_json::json!({
            "rays": rays,
            "half": half,
            "of": crate::references::ESTIMATES,
        });
        Self(json.to_string())
    }

    /// The file name: a hash of the key.
    pub fn file_name(&self) -> String {
        let mut h = Fnv::default();
        h.write(self.0.as_bytes());
        format!("{:016x}.bin", h.finish())
    }

    /// The key's text (one line of JSON).
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

/// The file of `key` under the run folder `dir`.
pub fn path(dir: &Path, key: &ReferenceKey) -> PathBuf {
    dir.join("references").join(key.file_name())
}

/// The cached image of `key`, or `None` (and why, logged) where there is none, or the file's
/// key differs, or it is malformed.
pub fn load(dir: &Path, key: &ReferenceKey) -> Option<HdrImage> {
    let path = path(dir, key);
    let bytes = std::fs::read(&path).ok()?;
    match parse(&bytes, key) {
        Ok(img) => Some(img),
        Err(why) => {
            tracing::warn!(path = %path.display(), "cached reference not used: {why}; recomputing");
            None
        }
    }
}

fn parse(bytes: &[u8], key: &ReferenceKey) -> Result<HdrImage, String> {
    let take = |at: usize, n: usize| bytes.get(at..at + n).ok_or("truncated");
    let u32_at = |at: usize| take(at, 4).map(|b| u32::from_le_bytes(b.try_into().expect("4")));
    if take(0, 8)? != MAGIC {
        return Err("not a reference file".into());
    }
    let len = u32_at(8)? as usize;
    let stored = take(12, len)?;
    if stored != key.0.as_bytes() {
        return Err(format!(
            "its key {} is not this cell's {}",
            String::from_utf8_lossy(stored),
            key.0
        ));
    }
    let (w, h) = (u32_at(12 + len)?, u32_at(16 + len)?);
    let data = &bytes[20 + len..];
    if data.len() != w as usize * h as usize * 16 {
        return Err(format!("{} bytes of texels for {w} x {h}", data.len()));
    }
    Ok(HdrImage::from_bytes(w, h, data))
}

/// Writes the image of `key` (atomically).
pub fn save(dir: &Path, key: &ReferenceKey, img: &HdrImage) -> Result<(), LabError> {
    let mut bytes = Vec::with_capacity(20 + key.0.len() + img.data.len() * 16);
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&(key.0.len() as u32).to_le_bytes());
    bytes.extend_from_slice(key.0.as_bytes());
    bytes.extend_from_slice(&img.width.to_le_bytes());
    bytes.extend_from_slice(&img.height.to_le_bytes());
    bytes.extend_from_slice(bytemuck::cast_slice(&img.data));
    write_atomic(&path(dir, key), &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(v: f32) -> HdrImage {
        HdrImage {
            width: 3,
            height: 2,
            data: vec![[v, 2.0 * v, 3.0 * v, 1.0]; 6],
        }
    }

    #[test]
    fn fnv_is_fnv_1a_64() {
        // The published test vectors; cell ids (cells.rs) hash with it too, so they must not
        // change.
        for (text, want) in [
            ("", 0xcbf2_9ce4_8422_2325u64),
            ("a", 0xaf63_dc4c_8601_ec8c),
            ("foobar", 0x8594_4171_f739_67e8),
        ] {
            let mut h = Fnv::default();
            h.write(text.as_bytes());
            assert_eq!(h.finish(), want, "{text:?}");
        }
    }

    #[test]
    fn a_file_is_used_only_under_its_own_key() {
        let dir = tempfile::tempdir().unwrap();
        let cam = Camera::perspective(
            glam::Vec3::new(0.0, 1.0, 5.0),
            glam::Vec3::ZERO,
            60.0,
            0.1,
            100.0,
        );
        let key = ReferenceKey::new(7, &cam, (3, 2), 1);
        assert_eq!(
            key,
            ReferenceKey::with_shadows(7, &cam, (3, 2), 1, Shadows::Off),
            "unshadowed keys are those of files written before shadows"
        );
        assert!(load(dir.path(), &key).is_none(), "nothing cached yet");
        save(dir.path(), &key, &image(0.5)).unwrap();
        assert_eq!(load(dir.path(), &key), Some(image(0.5)));
        for other in [
            ReferenceKey::new(8, &cam, (3, 2), 1),
            ReferenceKey::new(7, &cam, (3, 2), 4),
            ReferenceKey::with_shadows(7, &cam, (3, 2), 1, Shadows::Exact),
            ReferenceKey::new(
                7,
                &Camera {
                    position: glam::Vec3::new(0.0, 1.0, 5.5),
                    ..cam
                },
                (3, 2),
                1,
            ),
        ] {
            assert_ne!(other, key);
        }
        // A file at the key's path that holds another key (a collision) is not used.
        let other = ReferenceKey::new(9, &cam, (3, 2), 1);
        std::fs::copy(path(dir.path(), &key), path(dir.path(), &other)).unwrap();
        assert!(load(dir.path(), &other).is_none());
        // Nor a truncated one.
        let bytes = std::fs::read(path(dir.path(), &key)).unwrap();
        std::fs::write(path(dir.path(), &key), &bytes[..bytes.len() - 4]).unwrap();
        assert!(load(dir.path(), &key).is_none());
    }
}
