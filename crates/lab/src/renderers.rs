//! The renderers of a run, kept from cell to cell: building one compiles every culling and
//! shading pipeline, most of a small cell's time (on lavapipe about 1.5 s of a tiny stability
//! cell's 2.3). A renderer's pipelines depend only on the sample count, the lit image's format,
//! whether the scene has transparent surfaces, its opaque surfaces' material models and whether
//! its lights are all windowed point lights: bind group layouts of equal entries are one layout
//! to wgpu, so a renderer serves every scene laid out alike.

use manylights_gpu::{GpuContext, GpuError, GpuScene};
use manylights_shade::{HdrFormat, Renderer};

/// What a renderer is built for: samples a pixel, glass, the opaque material models in order,
/// windowed point lights alone, stochastic ranges on them, the lit image's format.
type Key = (u32, bool, Vec<u32>, bool, bool, HdrFormat);

/// The renderers built so far in a run (the most recent [`Renderers::KEEP`]).
#[derive(Default)]
pub(crate) struct Renderers(Vec<(Key, Renderer)>);

impl Renderers {
    /// The most renderers kept: a sweep's cells rarely need more kinds.
    const KEEP: usize = 4;

    /// A renderer for `scene` at `samples` samples a pixel into a lit image of format `hdr`:
    /// one built before for a scene laid out alike, or a new one.
    pub fn get(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        samples: u32,
        hdr: HdrFormat,
    ) -> Result<&Renderer, GpuError> {
        let key = (
            samples,
            scene.has_transparent(),
            scene
                .opaque_models
                .iter()
                .map(|&(model, _)| model)
                .collect(),
            scene.point_lights(),
            scene.stochastic_points(),
            hdr,
        );
        let i = match self.0.iter().position(|(k, _)| *k == key) {
            Some(i) => i,
            None => {
                let renderer = Renderer::with_format(ctx, scene, samples, hdr)?;
                if self.0.len() == Self::KEEP {
                    self.0.remove(0);
                }
                self.0.push((key, renderer));
                self.0.len() - 1
            }
        };
        Ok(&self.0[i].1)
    }
}
