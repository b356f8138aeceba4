//! Stochastic light culling and stochastic shadows in a run: a cell whose radius rule is
//! `Stochastic` draws its generated lights' ranges before every frame
//! (`manylights_gpu::stochastic`, timed with the frame as `lights.stochastic`); a cell with
//! `shadows: Stochastic` sets the frame its shadow rays draw by
//! (`manylights_gpu::GpuScene::set_shadow_frame`). Either's noise is measured honestly over
//! seeds ([`measure`]; a cell with both takes its culling's `seeds` and `accumulate`):
//!
//! - each seed `s` of `seeds` renders `K` frames (`accumulate`, 1 without), frames `s K` to
//!   `s K + K - 1`, each with fresh draws, and averages them into one image, as a renderer that
//!   accumulates temporally shows it;
//! - error: each seed's image against the infinite-range reference (mean FLIP at the adapted
//!   exposure, RMSE, energy error), averaged over the seeds: what a single image costs; and
//!   where the cell renders it, against the shadowed infinite-range reference alike;
//! - bias: each lit pixel's mean over the seeds less the reference (the shadowed infinite-range
//!   reference where the cell casts shadows, the infinite-range one otherwise; so are noise and
//!   flicker below), as the root mean square over
//!   lit pixels with the part the noise contributes taken out (`mean((m - R)^2) - mean(s^2) / M`
//!   for M seeds, an unbiased estimate of the mean squared bias, floored at 0), relative to the
//!   mean reference luminance: zero within its own noise for an unbiased method, where the
//!   energy error (a mean over pixels, so the same for the seeds' mean as for each seed's image)
//!   could hide a bias that changes sign across the image;
//! - noise: the standard deviation across seeds of each lit pixel's luminance, as the root mean
//!   square over lit pixels, relative to their mean reference luminance;
//! - flicker: the mean absolute change of luminance from one seed's image to the next, relative
//!   to the mean reference luminance (the largest such change, `temporal_flicker`, saturates
//!   for any noisy method).

use manylights_gpu::stochastic::StochasticRanges;
use manylights_gpu::timing::PassTiming;
use manylights_gpu::{GpuContext, GpuScene, ShadowFrames};
use manylights_scene::{RadiusRule, Scene};
use manylights_shade::HdrImage;
use manylights_shade::accuracy::{LIT_FRACTION, compare_adapted, luminance};
use manylights_shade::image_out::ImageSum;

use crate::LabError;
use crate::evaluate::Pose;
use crate::experiment::Config;

/// The stochastic ranges and shadow frames of a cell.
pub(crate) struct Draws {
    ranges: Option<StochasticRanges>,
    /// With stochastic shadows, the shaded scene's shadow frame.
    shadow_frames: Option<ShadowFrames>,
    /// Frames averaged into one image (1: none).
    pub(crate) accumulate: u32,
    /// Seeds measured.
    pub(crate) seeds: u32,
}

impl Draws {
    /// The draws of `scene` (uploaded as `gpu_scene`, the scene shaded), whose lights from
    /// `first` on are the generated ones; `None` where neither the radius rule nor the shadows
    /// are stochastic.
    pub(crate) fn new(
        ctx: &GpuContext,
        c: &Config,
        gpu_scene: &GpuScene,
        scene: &Scene,
        first: usize,
    ) -> Result<Option<Self>, LabError> {
        let shadow_frames = c.shadows.rays().map(|_| gpu_scene.shadow_frames());
        let (Some(params), RadiusRule::Stochastic {
            accumulate, seeds, ..
        }) = (c.lights.stochastic(scene), c.lights.radius)
        else {
            return Ok(match c.shadows {
                manylights_shade::Shadows::Stochastic {
                    accumulate, seeds, ..
                } => Some(Self {
                    ranges: None,
                    shadow_frames,
                    accumulate: accumulate.max(1),
                    seeds,
                }),
                _ => None,
            });
        };
        let count = (scene.lights.len() - first) as u32;
        let strata = manylights_scene::stochastic::strata(&scene.lights[first..]);
        let ranges = StochasticRanges::new(ctx, gpu_scene, first as u32, count, &params, &strata)?;
        Ok(Some(Self {
            ranges: Some(ranges),
            shadow_frames,
            accumulate: accumulate.max(1),
            seeds,
        }))
    }

    /// Draws the ranges of frame `frame` and sets it as the shadow frame; the ranges' pass's
    /// time where timed.
    pub(crate) fn draw(
        &self,
        ctx: &GpuContext,
        frame: u32,
    ) -> Result<Option<Vec<PassTiming>>, LabError> {
        if let Some(s) = &self.shadow_frames {
            s.set(ctx, frame);
        }
        match &self.ranges {
            Some(r) => r.draw(ctx, frame).map_err(LabError::from),
            None => Ok(None),
        }
    }
}

/// What the seeds measured (see the module docs).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Noise {
    pub(crate) flip_mean: f64,
    pub(crate) rmse: f64,
    pub(crate) energy_error: f64,
    pub(crate) exposure: f64,
    /// None with one seed.
    pub(crate) bias: Option<f64>,
    /// None with one seed.
    pub(crate) noise: Option<f64>,
    /// None with one seed.
    pub(crate) flicker_mean: Option<f64>,
    /// Mean FLIP and energy error against the shadowed infinite-range reference, where given.
    pub(crate) shadowed: Option<(f64, f64)>,
}

/// Renders each seed's image of the cell at the pose and measures it against `reference` and
/// `shadowed`, the shadowed infinite-range reference where given (see the module docs).
pub(crate) fn measure(
    p: &Pose<'_>,
    draws: &Draws,
    (reference, shadowed): (&HdrImage, Option<&HdrImage>),
) -> Result<Noise, LabError> {
    let Pose {
        ctx,
        renderer,
        gpu_scene,
        c,
        cam,
        settings,
        ..
    } = *p;
    let (w, h) = c.resolution;
    let k = draws.accumulate;
    let mut images = Vec::with_capacity(draws.seeds as usize);
    for s in 0..draws.seeds {
        let mut sum = ImageSum::default();
        for j in 0..k {
            draws.draw(ctx, s * k + j)?;
            gpu_scene.set_view(ctx, cam, w, h, 0);
            let o = renderer.render(ctx, gpu_scene, c.backend, &c.strategy, settings, (w, h))?;
            sum.add(&o.color);
        }
        images.push(mean_over(&sum, reference)?);
    }
    let errors: Vec<_> = images
        .iter()
        .map(|i| compare_adapted(i, reference))
        .collect();
    let n = errors.len() as f64;
    let avg = |f: &dyn Fn(&manylights_shade::accuracy::ImageError) -> f64| {
        errors.iter().map(f).sum::<f64>() / n
    };
    let mut total = ImageSum::default();
    for i in &images {
        total.add(i);
    }
    let mean = mean_over(&total, reference)?;
    let truth = match shadowed {
        Some(s) if c.shadows.casts() => s,
        _ => reference,
    };
    let (bias, noise, flicker_mean) = spread(&images, &mean, truth);
    let shadowed = shadowed.map(|s| {
        let errors: Vec<_> = images.iter().map(|i| compare_adapted(i, s)).collect();
        let n = errors.len() as f64;
        (
            errors.iter().map(|e| e.flip_mean).sum::<f64>() / n,
            errors.iter().map(|e| e.energy_error).sum::<f64>() / n,
        )
    });
    Ok(Noise {
        flip_mean: avg(&|e| e.flip_mean),
        rmse: avg(&|e| e.rmse),
        energy_error: avg(&|e| e.energy_error),
        exposure: f64::from(errors[0].exposure),
        bias,
        noise,
        flicker_mean,
        shadowed,
    })
}

/// The mean of `sum`'s images with the reference's coverage in alpha.
fn mean_over(sum: &ImageSum, reference: &HdrImage) -> Result<HdrImage, LabError> {
    sum.mean_over(reference)
        .ok_or_else(|| LabError::refused("noise", "no image to average (0 seeds or frames)"))
}

/// The relative RMS bias (noise taken out) and standard deviation over lit pixels, and the
/// relative mean change from one image to the next (module docs); `None` for fewer than two
/// images.
fn spread(
    images: &[HdrImage],
    mean: &HdrImage,
    reference: &HdrImage,
) -> (Option<f64>, Option<f64>, Option<f64>) {
    if images.len() < 2 {
        return (None, None, None);
    }
    let covered: Vec<usize> = (0..reference.data.len())
        .filter(|&p| reference.data[p][3] > 0.0)
        .collect();
    let mean_ref = covered
        .iter()
        .map(|&p| luminance(reference.data[p]))
        .sum::<f64>()
        / covered.len().max(1) as f64;
    if mean_ref <= 0.0 {
        return (Some(0.0), Some(0.0), Some(0.0));
    }
    let m = images.len() as f64;
    let (mut var, mut sq, mut lit, mut lit_sum) = (0.0f64, 0.0f64, 0usize, 0.0f64);
    for &p in &covered {
        let r = luminance(reference.data[p]);
        if r <= 0.0 || r < LIT_FRACTION * mean_ref {
            continue;
        }
        let mu = luminance(mean.data[p]);
        var += images
            .iter()
            .map(|i| (luminance(i.data[p]) - mu).powi(2))
            .sum::<f64>()
            / (m - 1.0);
        sq += (mu - r).powi(2);
        lit += 1;
        lit_sum += r;
    }
    let lit_n = lit.max(1) as f64;
    let lit_mean = (lit_sum / lit_n).max(f64::MIN_POSITIVE);
    let noise = (var / lit_n).sqrt() / lit_mean;
    let bias = ((sq - var / m) / lit_n).max(0.0).sqrt() / lit_mean;
    let mut change = 0.0f64;
    for pair in images.windows(2) {
        change += covered
            .iter()
            .map(|&p| (luminance(pair[1].data[p]) - luminance(pair[0].data[p])).abs())
            .sum::<f64>()
            / covered.len().max(1) as f64;
    }
    let flicker = change / (m - 1.0) / mean_ref;
    (Some(bias), Some(noise), Some(flicker))
}
