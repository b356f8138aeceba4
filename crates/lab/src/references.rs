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
                        match c.shadowed_reference_rays {
                            Some(rays) => {
                                InfiniteReference::new(ctx, scene).with_estimate(ctx, scene, rays)
                            }
                            None => InfiniteReference::new(ctx, scene).with_shadows(
                                ctx,
                                scene,
                                Shadows::Exact,
                            ),
                        },
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
    /// holds it under the same key, whether it did, and where the shadowed one is an estimate
    /// (`Config::shadowed_reference_rays`) its standard error in mean FLIP; `windowed`, the
    /// view's windowed reference frame where rendered, gives the surfaces.
    pub(crate) fn infinite(
        &self,
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        view: (&Camera, (u32, u32)),
        windowed: Option<&ReferenceFrame>,
        shadows: Shadows,
    ) -> Result<(HdrImage, bool, Option<f64>), LabError> {
        let (_, inf) = self.set.pair(shadows);
        if shadows.casts() && inf.estimate_rays() > 0 {
            return self.estimated(ctx, gpu_scene, view, windowed);
        }
        let (img, cached) = self.infinite_part(ctx, gpu_scene, view, windowed, shadows, None)?;
        Ok((img, cached, None))
    }

    /// The shadowed infinite-range reference as the mean of [`ESTIMATES`] unbiased estimates
    /// (`InfiniteReference::estimate`, each seeded apart), cached as the means of its two
    /// halves, and its standard error: half the mean FLIP between the halves (their difference
    /// has twice the standard deviation of the mean of all).
    fn estimated(
        &self,
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        view: (&Camera, (u32, u32)),
        windowed: Option<&ReferenceFrame>,
    ) -> Result<(HdrImage, bool, Option<f64>), LabError> {
        let (a, cached_a) =
            self.infinite_part(ctx, gpu_scene, view, windowed, Shadows::Exact, Some(0))?;
        let (b, cached_b) =
            self.infinite_part(ctx, gpu_scene, view, windowed, Shadows::Exact, Some(1))?;
        let se = manylights_shade::accuracy::compare_adapted(&a, &b).flip_mean / 2.0;
        Ok((mean_of(&[&a, &b]), cached_a && cached_b, Some(se)))
    }

    /// The infinite-range image with `shadows`, or with `half` = Some(h) the mean of the
    /// shadowed estimate's h-th half, from the cache where it holds it.
    fn infinite_part(
        &self,
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        (cam, size): (&Camera, (u32, u32)),
        windowed: Option<&ReferenceFrame>,
        shadows: Shadows,
        half: Option<u32>,
    ) -> Result<(HdrImage, bool), LabError> {
        use crate::reference_cache as cache;
        let (rr, inf) = self.set.pair(shadows);
        let key = self.cache.map(|(dir, scene)| {
            let key = cache::ReferenceKey::with_shadows(scene, cam, size, rr.samples(), shadows);
            let key = match half {
                Some(h) => key.with_estimate(inf.estimate_rays(), h),
                None => key,
            };
            (dir, key)
        });
        if let Some((dir, key)) = &key {
            if let Some(img) = cache::load(dir, key) {
                return Ok((img, true));
            }
        }
        let img = match half {
            Some(h) => {
                let (unshadowed, _) =
                    self.infinite_part(ctx, gpu_scene, (cam, size), windowed, Shadows::Off, None)?;
                let scene = match self.lights_as_they_are {
                    Some(scene) => {
                        scene.set_view(ctx, cam, size.0, size.1, 0);
                        scene
                    }
                    None => gpu_scene,
                };
                let rendered;
                let surfaces = match windowed {
                    Some(w) => w,
                    None => {
                        rendered = rr.surfaces(ctx, scene, size.0, size.1)?;
                        &rendered
                    }
                };
                let runs = (0..ESTIMATES / 2)
                    .map(|k| inf.estimate(ctx, scene, surfaces, &unshadowed, h * ESTIMATES / 2 + k))
                    .collect::<Result<Vec<_>, _>>()?;
                mean_of(&runs.iter().collect::<Vec<_>>())
            }
            None => match self.lights_as_they_are {
                Some(scene) => {
                    scene.set_view(ctx, cam, size.0, size.1, 0);
                    infinite_image(ctx, (rr, inf), scene, cam, size, windowed)
                }
                None => infinite_image(ctx, (rr, inf), gpu_scene, cam, size, windowed),
            }?,
        };
        if let Some((dir, key)) = &key {
            cache::save(dir, key, &img)?;
        }
        Ok((img, false))
    }
}

/// Independent estimates the shadowed infinite-range reference averages where it is estimated
/// (`Config::shadowed_reference_rays`): two halves of two, whose difference gives its standard
/// error.
pub(crate) const ESTIMATES: u32 = 4;

/// The texel-wise mean of images of one size (alpha: the first's).
fn mean_of(images: &[&HdrImage]) -> HdrImage {
    let n = images.len() as f32;
    let mut out = images[0].clone();
    for (k, t) in out.data.iter_mut().enumerate() {
        for c in 0..3 {
            t[c] = images.iter().map(|i| i.data[k][c]).sum::<f32>() / n;
        }
    }
    out
}
