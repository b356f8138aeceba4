//! What a frame is rendered as: the shading backend ([`Backend`]), the lit image's format
//! ([`HdrFormat`]), and the formats and bytes of the buffers a deferred backend's raster pass
//! writes.

use serde::{Deserialize, Serialize};

use crate::HdrImage;

pub(crate) const GB_NORMAL_DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub(crate) const GB_MATERIAL: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
pub(crate) const GB_POSITION: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// The visibility buffer's triangle ids.
pub(crate) const VISIBILITY_ID: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// G-buffer bytes per pixel: normal and view depth (16), material index (4), depth (4).
pub const GBUFFER_BYTES_PER_PIXEL: u64 = 24;
/// Visibility buffer bytes per pixel (a sample with MSAA): triangle id (4), depth (4).
pub const VISIBILITY_BYTES_PER_PIXEL: u64 = 8;
/// What the visibility buffer's lighting fetches of a triangle: three u32 indices and three
/// 28-byte vertices (`GpuVertex`).
pub const VISIBILITY_TRIANGLE_BYTES: u64 = 3 * 4 + 3 * 28;

/// A shading backend.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Backend {
    /// Forward+: depth prepass, culling, forward shading over the lists.
    Forward,
    /// Deferred: G-buffer, culling, a compute lighting pass over the lists; the position is
    /// rebuilt from the G-buffer's view depth and the pixel centre.
    Deferred,
    /// Deferred with the interpolated world position stored in the G-buffer (16 bytes more a
    /// pixel): agrees with forward shading to rounding on any GPU. Comparing it with `deferred`
    /// measures what rebuilding the position costs.
    DeferredStoredPosition,
    /// Every light at every fragment, no culling (baseline).
    NaiveForward,
    /// The visibility buffer (Burns and Hunt 2013): a raster pass writes depth and each
    /// pixel's triangle id, culling reads that depth, and deferred's lighting passes fetch each
    /// pixel's triangle and interpolate its position, normal and material at the pixel
    /// (`VISIBILITY` in shaders/render/deferred.wgsl). Needs `PRIMITIVE_INDEX`.
    Visibility,
}

impl Backend {
    /// The backend's name (result column value).
    pub fn name(&self) -> &'static str {
        match self {
            Self::Forward => "forward",
            Self::Deferred => "deferred",
            Self::DeferredStoredPosition => "deferred_stored_position",
            Self::NaiveForward => "naive_forward",
            Self::Visibility => "visibility",
        }
    }

    /// Every backend.
    pub const ALL: [Backend; 5] = [
        Self::Forward,
        Self::Deferred,
        Self::DeferredStoredPosition,
        Self::NaiveForward,
        Self::Visibility,
    ];

    /// The bytes a pixel of an opaque frame moves between its raster pass and its shading
    /// (written, read), with `samples` samples a pixel and a lit image of `hdr`: the depth and
    /// surface buffers the raster pass writes and the shading reads, and the lit image it
    /// writes (with MSAA the multisampled colour target and the resolved image). The visibility
    /// buffer also reads a triangle a distinct id (its three indices and three vertices, 96
    /// bytes; counted once a pixel, as at one sample, or where a pixel's samples share one
    /// triangle). Lists, the scene's lights, glass and lookup bounds are not counted
    /// (`list_bytes`, `msaa_target_bytes` have them). A model of what the passes must move,
    /// not a measurement.
    pub fn bytes_per_pixel(self, samples: u32, hdr: HdrFormat) -> (u64, u64) {
        let s = u64::from(samples);
        let colour = hdr.texel_bytes();
        // Forward's colour target a sample, and its resolve into the image.
        let raster_colour = s * colour + if samples > 1 { colour } else { 0 };
        let surfaces = s * self.surface_bytes_per_sample();
        match self {
            // Depth in the prepass; the shading pass tests it and writes colour.
            Self::Forward | Self::NaiveForward => (s * 4 + raster_colour, s * 4),
            Self::Deferred | Self::DeferredStoredPosition => (surfaces + colour, surfaces),
            Self::Visibility => (surfaces + colour, surfaces + VISIBILITY_TRIANGLE_BYTES),
        }
    }

    /// Bytes a sample of the buffer of surfaces its raster pass writes, depth included: the
    /// G-buffer's ([`GBUFFER_BYTES_PER_PIXEL`], 16 more with the stored position), the
    /// visibility buffer's ([`VISIBILITY_BYTES_PER_PIXEL`]); 0 for the forward backends.
    pub fn surface_bytes_per_sample(self) -> u64 {
        match self {
            Self::Deferred => GBUFFER_BYTES_PER_PIXEL,
            Self::DeferredStoredPosition => GBUFFER_BYTES_PER_PIXEL + 16,
            Self::Visibility => VISIBILITY_BYTES_PER_PIXEL,
            Self::Forward | Self::NaiveForward => 0,
        }
    }

    /// Whether its shading is a compute pass over a buffer of the frame's surfaces (a
    /// G-buffer or a visibility buffer) rather than a raster pass.
    pub fn lights_in_compute(self) -> bool {
        matches!(
            self,
            Self::Deferred | Self::DeferredStoredPosition | Self::Visibility
        )
    }
}

/// Whether shading casts shadow rays (`shadows` of experiments, `--shadows` of the CLI).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Shadows {
    /// No shadow: every light shines through walls (the default, as every figure before).
    #[default]
    Off,
    /// A shadow ray for every (pixel, light) pair the shading evaluates with a nonzero
    /// contribution, from the surface point lifted along its shading normal to the light,
    /// through the scene's BVH of opaque triangles (`SHADOWS`, shaders/common/shading.wgsl), in
    /// the shading pass itself: forward's fragment shader, deferred's and the visibility
    /// buffer's lighting pass. The scene's BVH must be built (`GpuScene::build_bvh`).
    Exact,
    /// `rays` shadow rays a pixel to lights drawn from those the shading evaluates, in
    /// proportion to their unshadowed luminance, combined as the ratio estimator (`SHADOW_RAYS`,
    /// shaders/common/shading.wgsl; [`manylights_scene::shadow_estimate`]): the unshadowed sum
    /// times the drawn lights' shadowed over unshadowed share, per channel. Biased for finite
    /// `rays`, consistent as they grow. Each frame draws anew
    /// ([`manylights_gpu::GpuScene::set_shadow_frame`]).
    Stochastic {
        /// Rays a pixel, 1 to [`Shadows::MAX_RAYS`].
        rays: u32,
        /// Frames averaged into one image, each with its own draws, as a renderer accumulates
        /// temporally: 0 (the default) none, otherwise at least 2 (a cell that culls
        /// stochastically too takes its culling's).
        #[serde(default)]
        accumulate: u32,
        /// Independent draws measured for the noise and bias columns, >= 1 (default 4; a cell
        /// that culls stochastically too takes its culling's).
        #[serde(default = "four")]
        seeds: u32,
    },
}

fn four() -> u32 {
    4
}

impl Shadows {
    /// The most rays a pixel [`Shadows::Stochastic`] casts (`SHADOW_RAYS_MAX`,
    /// shaders/common/shading.wgsl).
    pub const MAX_RAYS: u32 = 16;

    /// Stochastic shadows of `rays` a pixel, one frame an image, four seeds.
    pub fn stochastic(rays: u32) -> Self {
        Self::Stochastic {
            rays,
            accumulate: 0,
            seeds: 4,
        }
    }

    /// Its name (`off`, `exact`, `stochastic`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Off => "off",
            Self::Exact => "exact",
            Self::Stochastic { .. } => "stochastic",
        }
    }

    /// Whether it casts shadow rays.
    pub fn casts(self) -> bool {
        self != Self::Off
    }

    /// The rays a pixel of stochastic shadows.
    pub fn rays(self) -> Option<u32> {
        match self {
            Self::Stochastic { rays, .. } => Some(rays),
            _ => None,
        }
    }

    /// What its references shade with: `Exact` where it casts rays (a reference traces every
    /// light's ray), else `Off`.
    pub fn truth(self) -> Self {
        if self.casts() { Self::Exact } else { Self::Off }
    }

    /// Checks its values: the error names the field (`shadows.rays`, ...), the value and what
    /// is accepted.
    pub fn validate(self) -> Result<(), String> {
        if let Self::Stochastic {
            rays,
            accumulate,
            seeds,
        } = self
        {
            if !(1..=Self::MAX_RAYS).contains(&rays) {
                return Err(format!(
                    "shadows.rays = {rays}: stochastic shadows cast 1 to {} rays a pixel",
                    Self::MAX_RAYS
                ));
            }
            if accumulate == 1 {
                return Err(
                    "shadows.accumulate = 1: 0 (no accumulation) or at least 2 frames".into(),
                );
            }
            if seeds == 0 {
                return Err("shadows.seeds = 0: at least 1 seed".into());
            }
        }
        Ok(())
    }

    /// The `SHADOWS` and `SHADOW_RAYS` overrides of shaders/common/shading.wgsl that shading
    /// with it is built with.
    pub fn constants(self) -> [(&'static str, f64); 2] {
        [
            ("SHADOWS", f64::from(u8::from(self.casts()))),
            ("SHADOW_RAYS", f64::from(self.rays().unwrap_or(0))),
        ]
    }

    /// An error naming `what` where it casts shadow rays and `scene` has no BVH to trace them
    /// through ([`manylights_gpu::GpuScene::build_bvh`]).
    pub fn check_scene(
        self,
        scene: &manylights_gpu::GpuScene,
        what: &str,
    ) -> Result<(), manylights_gpu::GpuError> {
        if self.casts() && !scene.has_bvh() {
            return Err(manylights_gpu::GpuError::Unsupported(format!(
                "{what} with shadows {}: the scene has no BVH of its opaque triangles to trace \
                 shadow rays through; build it after the upload (GpuScene::build_bvh)",
                self.name()
            )));
        }
        Ok(())
    }
}

/// How the visibility backend finds each pixel's triangle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum VisibilityPass {
    /// A compute rasteriser (`crate::vis_compute`: a 64-bit depth-and-id key a pixel kept by
    /// atomic max), where it can: one sample a pixel, no transparent surfaces, and 64-bit atomic
    /// max on the device (`SHADER_INT64_ATOMIC_MIN_MAX`); elsewhere the raster pass. The
    /// default: 2-6x faster than the raster pass on the GPU machine (docs/BENCHMARKS.md).
    #[default]
    Compute,
    /// The raster pass (`shade.visibility`, `@builtin(primitive_index)`) always.
    Raster,
}

impl VisibilityPass {
    /// Its name (the `visibility_pass` of experiments and results).
    pub fn name(self) -> &'static str {
        match self {
            Self::Compute => "compute",
            Self::Raster => "raster",
        }
    }
}

/// The format of the lit (HDR) image a [`crate::Renderer`] shades into and reads back: 32-bit floats
/// (the default: the image as shading computed it), or 16-bit floats, as engines' HDR targets
/// commonly are (half the bytes the lighting pass writes; each channel rounded to 11
/// significant bits, to nearest or towards zero as Vulkan allows, a relative error of at most
/// 2^-10, and a channel past 65,504 becomes infinite, counted as a non-finite pixel in the
/// results). The reference renderers keep 32 bits,
/// so accuracy against them carries the rounding.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum HdrFormat {
    /// `Rgba32Float`.
    #[default]
    F32,
    /// `Rgba16Float`.
    F16,
}

impl HdrFormat {
    /// The texture format.
    pub fn texture_format(self) -> wgpu::TextureFormat {
        match self {
            Self::F32 => wgpu::TextureFormat::Rgba32Float,
            Self::F16 => wgpu::TextureFormat::Rgba16Float,
        }
    }

    /// Bytes a texel.
    pub fn texel_bytes(self) -> u64 {
        match self {
            Self::F32 => 16,
            Self::F16 => 8,
        }
    }

    /// Its name in experiment files' cell parameters: `f32` or `f16`.
    pub fn name(self) -> &'static str {
        match self {
            Self::F32 => "f32",
            Self::F16 => "f16",
        }
    }

    /// The image from tightly packed texels of this format, as f32.
    pub fn image(self, width: u32, height: u32, bytes: &[u8]) -> HdrImage {
        match self {
            Self::F32 => HdrImage::from_bytes(width, height, bytes),
            Self::F16 => HdrImage {
                width,
                height,
                data: bytes
                    .chunks_exact(8)
                    .map(|t| {
                        std::array::from_fn(|c| {
                            half::f16::from_le_bytes([t[2 * c], t[2 * c + 1]]).to_f32()
                        })
                    })
                    .collect(),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_a_pixel_follow_the_buffers() {
        let f32 = HdrFormat::F32;
        assert_eq!(Backend::Forward.bytes_per_pixel(1, f32), (20, 4));
        assert_eq!(Backend::Forward.bytes_per_pixel(4, f32), (16 + 64 + 16, 16));
        assert_eq!(Backend::Deferred.bytes_per_pixel(1, f32), (40, 24));
        assert_eq!(
            Backend::Deferred.bytes_per_pixel(4, HdrFormat::F16),
            (104, 96)
        );
        assert_eq!(
            Backend::DeferredStoredPosition.bytes_per_pixel(1, f32),
            (56, 40)
        );
        assert_eq!(Backend::Visibility.bytes_per_pixel(1, f32), (24, 104));
        assert_eq!(Backend::Visibility.bytes_per_pixel(4, f32), (48, 128));
        assert_eq!(
            VISIBILITY_TRIANGLE_BYTES,
            3 * 4 + 3 * std::mem::size_of::<manylights_gpu::layout::GpuVertex>() as u64
        );
    }
}
