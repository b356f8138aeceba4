//! The references a cell's images are scored against ([`References`]): the windowed
//! brute-force reference, shaded as the cell shades (its radius cut-off, its shadows: the
//! implementation check), the infinite-range reference (every light at every pixel with the
//! infinite-range falloff, unshadowed: what the cut-off costs) and, where the cell renders it
//! (`Config::shadowed_truth`), the shadowed infinite-range reference (the same with a shadow ray
//! to every light that adds radiance: the light as it arrives). Both infinite-range references
//! are cached in the run folder ([`crate::reference_cache`]).

use manylights_gpu::{GpuContext, GpuError, GpuScene};
use manylights_scene::Camera;
use manylights_shade::infinite::infinite_image;
use manylights_shade::{HdrImage, InfiniteReference, ReferenceFrame, ReferenceRenderer, Shadows};

use crate::LabError;
use crate::experiment::Config;
use crate::renderers::ReferenceFrames;

/// The reference renderers of a cell with accuracy: the brute-force renderer and the
/// infinite-range pass unshadowed, and shadowed where the cell casts shadows or renders the
/// shadowed infinite-range reference.
pub(crate) struct ReferenceSet {
    plain: ReferenceRenderer,
    infinite: InfiniteReference,
    shadowed: Option<(ReferenceRenderer, InfiniteReference)>,
    /// Whether the windowed reference casts shadows (the cell's `shadows`).
    windowed_shadows: Shadows,
}

impl ReferenceSet {
    /// The renderers `c` needs over `scene` (whose BVH is built where shadows are wanted).
    pub(crate) fn new(ctx: &GpuContext, scene: &GpuScene, c: &Config) -> Result<Self, GpuError> {
        // With accuracy a cell with shadows renders the shadowed truth too.
        let shadowed = c.shadowed_truth();
        Ok(Self {
            plain: ReferenceRenderer::with_samples(ctx, scene, c.msaa)?,
            infinite: InfiniteReference::new(ctx, scene),
            shadowed: shadowed
                .then(|| -> Result<_, GpuError> {
                    Ok((
                        ReferenceRenderer::with_samples(ctx, scene, c.msaa)?.with_shadows(
                            ctx,
                            scene,
                            Shadows::Exact,
                        ),
                        InfiniteReference::new(ctx, scene).with_shadows(ctx, scene, Shadows::Exact),
                    ))
                })
                .transpose()?,
            windowed_shadows: c.shadows.truth(),
        })
    }

    /// The brute-force renderer and infinite-range pass shading with `shadows`.
    fn pair(&self, shadows: Shadows) -> (&ReferenceRenderer, &InfiniteReference) {
        match (&self.shadowed, shadows.casts()) {
            (Some((rr, inf)), true) => (rr, inf),
            _ => (&self.plain, &self.infinite),
        }
    }

    /// Whether the set renders the shadowed infinite-range reference.
    pub(crate) fn has_shadowed(&self) -> bool {
        self.shadowed.is_some()
    }
}

/// The references of a cell: its renderers, where the infinite-range images may be cached (the
/// run folder and the scene's fingerprint; none for moving lights), the run's windowed frames.
pub(crate) struct References<'a> {
    pub(crate) set: &'a ReferenceSet,
    pub(crate) cache: Option<(&'a std::path::Path, u64)>,
    /// The run's brute-force reference frames, which the cells of one view share (none for
    /// moving lights).
    pub(crate) frames: Option<&'a ReferenceFrames>,
    /// The scene of the lights as they are, where the cell shades others in their place (the
    /// lighting grid hierarchy's): the infinite-range references are theirs.
    pub(crate) lights_as_they_are: Option<&'a GpuScene>,
}

impl References<'_> {
    /// The brute-force reference frame of the view, shaded as the cell shades, from the run's
    /// kept frames where a cell of the same view rendered it.
    pub(crate) fn windowed(
        &self,
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        c: &Config,
        cam: &Camera,
    ) -> Result<ReferenceFrame, GpuError> {
        let (w, h) = c.resolution;
        let (rr, _) = self.set.pair(self.set.windowed_shadows);
        let render = || rr.render(ctx, gpu_scene, w, h);
        match self.frames {
            Some(kept) => kept.get_or(ReferenceFrames::key(c, cam).as_deref(), render),
            None => render(),
        }
    }

    /// The infinite-range image of the view shaded with `shadows`, from the cache where it
    /// holds it under the same key, and whether it did; `windowed`, the view's windowed
    /// reference frame where rendered, gives the surfaces.
    pub(crate) fn infinite(
        &self,
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        (cam, size): (&Camera, (u32, u32)),
        windowed: Option<&ReferenceFrame>,
        shadows: Shadows,
    ) -> Result<(HdrImage, bool), LabError> {
        use crate::reference_cache as cache;
        let (rr, inf) = self.set.pair(shadows);
        let key = self.cache.map(|(dir, scene)| {
            let key = cache::ReferenceKey::with_shadows(scene, cam, size, rr.samples(), shadows);
            (dir, key)
        });
        if let Some((dir, key)) = &key {
            if let Some(img) = cache::load(dir, key) {
                return Ok((img, true));
            }
        }
        let img = match self.lights_as_they_are {
            Some(scene) => {
                scene.set_view(ctx, cam, size.0, size.1, 0);
                infinite_image(ctx, (rr, inf), scene, cam, size, windowed)
            }
            None => infinite_image(ctx, (rr, inf), gpu_scene, cam, size, windowed),
        }?;
        if let Some((dir, key)) = &key {
            cache::save(dir, key, &img)?;
        }
        Ok((img, false))
    }
}
