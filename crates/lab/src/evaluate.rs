//! What a camera pose of an experiment cell measures: [`evaluate`] renders one frame of the
//! backend and measures it on the GPU (the list metrics from the exact per-pixel oracle, on
//! every `exact_stride`-th pixel; lights per pixel; naive forward's metrics, every light at
//! every pixel; steady-state culling, shading and geometry at the first pose), then
//! [`PoseEval::score`] with `accuracy` the image error against the reference and the
//! infinite-range reference.

use manylights_cull::ListPass as _;
use manylights_cull::metrics::{ListMetrics, from_gpu_counts};
use manylights_cull::{CullSettings, Strategy};
use manylights_gpu::hierarchy::GpuHierarchy;
use manylights_gpu::layout::GpuFrame;
use manylights_gpu::timing::{Category, PassTiming};
use manylights_gpu::{GpuContext, GpuScene};
use manylights_scene::Camera;
use manylights_shade::accuracy::{ImageError, compare, compare_adapted};
use manylights_shade::{Backend, HdrImage, Renderer, ShadeOutput, Shadows};

use crate::LabError;
use crate::experiment::Config;
use crate::references::References;
use crate::runner::stage;
use crate::steady::{
    PassMedian, Repeated, SteadyCull, ThenBuild, steady_build, steady_cull, steady_cull_shade,
    steady_geometry,
};

/// What one camera pose measured.
pub(crate) struct PoseEval {
    pub(crate) metrics: Option<ListMetrics>,
    pub(crate) per_pixel: Vec<u32>,
    pub(crate) lights_per_pixel_mean: f64,
    /// Covered pixels (samples with MSAA where the exact oracle counted them).
    pub(crate) covered: u64,
    pub(crate) color: HdrImage,
    pub(crate) reference: Option<HdrImage>,
    /// The infinite-range reference (with accuracy).
    pub(crate) infinite: Option<HdrImage>,
    /// Whether it came from the run folder's cache.
    pub(crate) infinite_cached: Option<bool>,
    /// The shadowed infinite-range reference (with accuracy, `Config::shadowed_truth`).
    pub(crate) shadowed: Option<HdrImage>,
    /// Whether it came from the run folder's cache.
    pub(crate) shadowed_cached: Option<bool>,
    /// Where it is an estimate, its standard error in mean FLIP (`shadowed_reference_se`).
    pub(crate) shadowed_se: Option<f64>,
    pub(crate) acc: Option<ImageError>,
    pub(crate) acc_inf: Option<ImageError>,
    pub(crate) acc_shadowed: Option<ImageError>,
    /// The shadow rays the frame casts (with shadows; counted in a frame of its own).
    pub(crate) rays: Option<u64>,
    /// The lights the frame's shading walks, summed over its pixels (the first pose; counted
    /// in a frame of its own).
    pub(crate) walked: Option<u64>,
    pub(crate) list_bytes: u64,
    pub(crate) gbuffer_bytes: u64,
    pub(crate) msaa_target_bytes: u64,
    pub(crate) dropped: u64,
    /// (Bin, light) pairs culling by visibility dropped.
    pub(crate) occluded: u64,
    pub(crate) nonfinite: u64,
    pub(crate) tile_masks: Option<bool>,
    /// Steady-state culling (run median, span), ms, where it was timed.
    pub(crate) steady: Option<(f64, Option<f64>)>,
    /// The same with the shading pass after each run (run median, span), ms.
    pub(crate) steady_frame: Option<(f64, Option<f64>)>,
    /// With shadows, the same runs' median with the shading pass of the renderer without
    /// them, ms.
    pub(crate) steady_frame_unshadowed: Option<f64>,
    /// With a hierarchy, the same runs' median with its build after each shading pass, ms.
    pub(crate) steady_frame_built: Option<f64>,
    /// The frame's geometry back to back (run median), ms.
    pub(crate) steady_geometry: Option<f64>,
    /// Each pass of the geometry's and of culling and shading's back-to-back runs: its
    /// median, ms.
    pub(crate) steady_passes: Vec<PassMedian>,
}

/// What one pose of a cell is rendered and measured with.
pub(crate) struct Pose<'a> {
    pub(crate) ctx: &'a GpuContext,
    pub(crate) renderer: &'a Renderer,
    /// With shadows, the renderer of the same frame without them (`gpu_ms_shadow`).
    pub(crate) unshadowed: Option<&'a Renderer>,
    pub(crate) gpu_scene: &'a GpuScene,
    /// The cell's configuration.
    pub(crate) c: &'a Config,
    pub(crate) cam: &'a Camera,
    /// Culling's settings for the camera.
    pub(crate) settings: &'a CullSettings,
    /// The pose's name in the log.
    pub(crate) name: &'a str,
    /// The lighting grid hierarchy built before the frame, where the cell has one.
    pub(crate) hierarchy: Option<&'a GpuHierarchy>,
}

/// Renders the pose once and measures it on the GPU: list metrics from the exact oracle and
/// lights per pixel; with `count_walked`, the lights its shading walks, in a frame of their own;
/// with `steady_runs`, culling, shading and the geometry back to back over that many runs; with
/// `export`, the pose's data exported there. Its accuracy is [`PoseEval::score`]'s.
pub(crate) fn evaluate(
    p: &Pose<'_>,
    count_walked: bool,
    steady_runs: Option<u32>,
    export: Option<&std::path::Path>,
) -> Result<PoseEval, LabError> {
    let Pose {
        ctx,
        renderer,
        gpu_scene,
        c,
        cam,
        settings,
        name: pose,
        ..
    } = *p;
    let light_count = u64::from(gpu_scene.light_count);
    let (w, h) = c.resolution;
    gpu_scene.set_view(ctx, cam, w, h, 0);
    let render = || renderer.render(ctx, gpu_scene, c.backend, &c.strategy, settings, (w, h));
    let walked = match count_walked {
        true => Some(stage(pose, "lights walked counted", || {
            gpu_scene.count_lights_walked(ctx, (cam, w, h), || render().map(|_| ()))
        })?),
        false => None,
    };
    let rays = match c.shadows.casts() {
        true => Some(stage(pose, "shadow rays counted", || {
            gpu_scene.count_rays(ctx, (cam, w, h), || render().map(|_| ()))
        })?),
        false => None,
    };
    let o = stage(pose, "rendered", render)?;
    let frame = GpuFrame::new(cam, w, h, gpu_scene.light_count);
    let covered = o.color.data.iter().filter(|p| p[3] > 0.0).count() as u64;
    let mut metrics: Option<ListMetrics> = None;
    let (mut list_bytes, mut dropped, mut occluded) = (0, 0, 0);
    let mut tile_masks = None;
    let mut steady = None;
    let mut steady_frame = None;
    let mut steady_frame_unshadowed = None;
    let mut steady_frame_built = None;
    let mut steady_passes = Vec::new();
    let per_pixel: Vec<u32> = match &o.lists {
        Some(lists) => {
            list_bytes = lists.list_bytes();
            tile_masks = Some(lists.used_tile_masks());
            dropped = u64::from(lists.dropped);
            occluded = u64::from(lists.occluded);
            if c.exact_stride > 0 {
                let bins = stage(pose, "list lengths read back", || lists.bin_lengths(ctx))?;
                let counts = stage(pose, "exact oracle", || {
                    renderer.culler.exact_counts_with(
                        ctx,
                        gpu_scene,
                        &o.depth,
                        lists,
                        frame.clip_from_world.inverse(),
                        c.exact_stride,
                        c.occlusion
                            || (c.shadowed_exact()
                                && manylights_cull::per_pixel::shadowed_exact_fits(
                                    ctx,
                                    gpu_scene.light_count,
                                )),
                    )
                })?;
                metrics = Some(from_gpu_counts(&counts, &bins));
            }
            if let (Some(runs), Some(t)) = (steady_runs, &o.timings) {
                let timed = steady_lists(p, &o, t, runs)?;
                (steady, steady_frame) = (timed.cull, timed.frame);
                steady_frame_unshadowed = timed.frame_unshadowed;
                steady_frame_built = timed.frame_built;
                steady_passes.extend(timed.passes);
            }
            if let Some(dir) = export {
                stage(pose, "exported", || {
                    let run = crate::export::RunToExport {
                        ctx,
                        culler: &renderer.culler,
                        scene: gpu_scene,
                        depth: &o.depth,
                        lists,
                        frame: &frame,
                        strategy: c.strategy.name(),
                    };
                    crate::export::export_run(&run, dir)
                })?;
            }
            stage(pose, "lights per pixel", || {
                renderer
                    .culler
                    .lights_per_pixel(ctx, gpu_scene, &o.depth, lists)
            })?
        }
        None => {
            if c.exact_stride > 0 {
                metrics = Some(stage(pose, "exact oracle", || {
                    naive_metrics(p, (&o.depth, &o.cull_depth), &frame)
                })?);
            }
            o.color
                .data
                .iter()
                .map(|p| if p[3] > 0.0 { light_count as u32 } else { 0 })
                .collect()
        }
    };
    let steady_geometry = match (steady_runs, &o.timings) {
        (Some(runs), Some(timings)) => {
            steady_geometry_after(p, &o, timings, runs, &mut steady_passes)?
        }
        _ => None,
    };
    Ok(PoseEval {
        metrics,
        lights_per_pixel_mean: per_pixel.iter().map(|&n| f64::from(n)).sum::<f64>()
            / covered.max(1) as f64,
        covered,
        per_pixel,
        nonfinite: o.color.non_finite_count() as u64,
        color: o.color,
        reference: None,
        infinite: None,
        infinite_cached: None,
        shadowed: None,
        shadowed_cached: None,
        shadowed_se: None,
        acc: None,
        acc_inf: None,
        acc_shadowed: None,
        rays,
        walked,
        list_bytes,
        gbuffer_bytes: o.gbuffer_bytes,
        msaa_target_bytes: o.msaa_target_bytes,
        dropped,
        occluded,
        tile_masks,
        steady,
        steady_frame,
        steady_frame_unshadowed,
        steady_frame_built,
        steady_geometry,
        steady_passes,
    })
}

/// What the first pose of a timed cell times after culling and shading (`timings`: its single
/// frame's passes): the frame's geometry back to back over `runs` runs (with culling and
/// shading, the frame in steady state; its passes put first in `steady_passes`).
fn steady_geometry_after(
    p: &Pose<'_>,
    o: &ShadeOutput,
    timings: &[PassTiming],
    runs: u32,
    steady_passes: &mut Vec<PassMedian>,
) -> Result<Option<f64>, LabError> {
    let Pose {
        ctx,
        renderer,
        gpu_scene,
        c,
        name: pose,
        ..
    } = *p;
    let passes = timings
        .iter()
        .filter(|p| p.category == Category::Prepass || c.backend == Backend::NaiveForward)
        .count() as u32;
    let geometry = stage(pose, "geometry timed back to back", || {
        steady_geometry(ctx, renderer, gpu_scene, o, passes, runs)
    })?
    .map(|s| {
        steady_passes.splice(0..0, s.passes.iter().cloned());
        s.total_ms
    });
    Ok(geometry)
}

/// The lighting grid hierarchy's build back to back over `runs` runs. Timed right after a
/// timed pose's [`evaluate`], before its [`PoseEval::score`], at the clock the frame's passes
/// ran at: timed after the host's accuracy work, the GPU's clock could fall so far that the
/// warm-up did not raise it (an H200 read two of seven million-light builds 2.5-2.7 times slow,
/// every pass alike). Every build of the same lights is the same hierarchy.
pub(crate) fn steady_hierarchy_build(
    ctx: &GpuContext,
    hier: &GpuHierarchy,
    runs: u32,
    pose: &str,
) -> Result<Option<SteadyCull>, LabError> {
    Ok(stage(pose, "hierarchy built back to back", || {
        steady_build(ctx, hier, hier.pass_count(), runs)
    })?)
}

impl PoseEval {
    /// The pose's image against the windowed reference (where the cell renders it), the
    /// infinite-range one and the shadowed infinite-range one (where the cell renders it).
    pub(crate) fn score(&mut self, p: &Pose<'_>, refs: &References<'_>) -> Result<(), LabError> {
        let a = against_references(p, refs, &self.color)?;
        self.reference = a.reference;
        self.infinite = a.infinite;
        self.infinite_cached = a.infinite_cached;
        self.shadowed = a.shadowed;
        self.shadowed_cached = a.shadowed_cached;
        self.shadowed_se = a.shadowed_se;
        self.acc = a.acc;
        self.acc_inf = a.acc_inf;
        self.acc_shadowed = a.acc_shadowed;
        Ok(())
    }
}

/// What a pose measured against the references.
#[derive(Default)]
struct Accuracy {
    acc: Option<ImageError>,
    acc_inf: Option<ImageError>,
    acc_shadowed: Option<ImageError>,
    reference: Option<HdrImage>,
    infinite: Option<HdrImage>,
    infinite_cached: Option<bool>,
    shadowed: Option<HdrImage>,
    shadowed_cached: Option<bool>,
    shadowed_se: Option<f64>,
}

/// `color`, the pose's image, against the windowed reference (where the cell renders it) and the
/// infinite-range one.
fn against_references(
    p: &Pose<'_>,
    refs: &References<'_>,
    color: &HdrImage,
) -> Result<Accuracy, LabError> {
    let Pose {
        ctx,
        gpu_scene,
        c,
        cam,
        name: pose,
        ..
    } = *p;
    let mut out = Accuracy::default();
    let windowed = if c.cutoff_reference {
        let r = stage(pose, "reference rendered", || {
            refs.windowed(ctx, gpu_scene, c, cam)
        })?;
        out.acc = Some(compare(color, &r.color, 1.0));
        Some(r)
    } else {
        None
    };
    let view = (cam, c.resolution);
    let (ri, cached, _) = stage(pose, "infinite-range reference", || {
        refs.infinite(ctx, gpu_scene, view, windowed.as_ref(), Shadows::Off)
    })?;
    out.acc_inf = Some(compare_adapted(color, &ri));
    out.infinite = Some(ri);
    out.infinite_cached = Some(cached);
    if refs.set.has_shadowed() {
        let (rs, cached, se) = stage(pose, "shadowed infinite-range reference", || {
            refs.infinite(ctx, gpu_scene, view, windowed.as_ref(), Shadows::Exact)
        })?;
        out.shadowed_se = se;
        out.acc_shadowed = Some(compare_adapted(color, &rs));
        out.shadowed = Some(rs);
        out.shadowed_cached = Some(cached);
    }
    out.reference = windowed.map(|r| r.color);
    Ok(out)
}

/// Steady-state timings of a frame's lists.
struct SteadyLists {
    /// Culling back to back (run median, span), ms.
    cull: Option<(f64, Option<f64>)>,
    /// Culling and the shading pass after each run (run median, span), ms.
    frame: Option<(f64, Option<f64>)>,
    /// Each pass of culling and shading's runs: its median, ms.
    passes: Vec<PassMedian>,
    /// With shadows, culling and the shading pass without them (run median), ms.
    frame_unshadowed: Option<f64>,
    /// With a hierarchy, culling, shading and the build (run median), ms.
    frame_built: Option<f64>,
}

/// The lists of `o` (a frame whose single run timed `t`) culled again `runs` times back to
/// back, alone and with the shading pass that reads them: a frame's culling and what its lists
/// cost in shading.
fn steady_lists(
    p: &Pose<'_>,
    o: &ShadeOutput,
    t: &[PassTiming],
    runs: u32,
) -> Result<SteadyLists, LabError> {
    let Pose {
        ctx,
        renderer,
        gpu_scene,
        c,
        settings,
        name: pose,
        ..
    } = *p;
    let lists = o.lists.as_ref().expect("a frame with lists");
    let culler = &renderer.culler;
    let passes = t.iter().filter(|p| p.category == Category::Cull).count() as u32;
    let repeated = Repeated {
        ctx,
        culler,
        scene: gpu_scene,
        depth: &o.cull_depth,
        strategy: &c.strategy,
        settings,
        first: lists,
    };
    let timed = stage(pose, "culling timed back to back", || {
        steady_cull(&repeated, passes, runs)
    })?;
    let mut out = SteadyLists {
        cull: timed.map(|s| (s.total_ms, s.span_ms)),
        frame: None,
        passes: Vec::new(),
        frame_unshadowed: None,
        frame_built: None,
    };
    if let Some(mut pass) = renderer.shade_pass(ctx, gpu_scene, o) {
        let timed = stage(pose, "culling and shading timed back to back", || {
            steady_cull_shade(&repeated, passes + pass.passes(), runs, &mut pass)
        })?;
        if let Some(s) = &timed {
            out.passes = s.passes.clone();
        }
        out.frame = timed.map(|s| (s.total_ms, s.span_ms));
    }
    if let Some(mut pass) = p.unshadowed.and_then(|r| r.shade_pass(ctx, gpu_scene, o)) {
        let timed = stage(
            pose,
            "culling and unshadowed shading timed back to back",
            || steady_cull_shade(&repeated, passes + pass.passes(), runs, &mut pass),
        )?;
        out.frame_unshadowed = timed.map(|s| s.total_ms);
    }
    if let Some(hierarchy) = p.hierarchy
        && let Some(pass) = renderer.shade_pass(ctx, gpu_scene, o)
    {
        let mut built = ThenBuild { pass, hierarchy };
        let timed = stage(
            pose,
            "culling, shading and the hierarchy's build timed back to back",
            || steady_cull_shade(&repeated, passes + built.passes(), runs, &mut built),
        )?;
        out.frame_built = timed.map(|s| s.total_ms);
    }
    Ok(out)
}

/// Naive forward evaluates every light; the exact oracle (run over any conservative lists)
/// gives the lights needed.
pub(crate) fn naive_metrics(
    p: &Pose<'_>,
    (depth, cull_depth): (&wgpu::Texture, &wgpu::Texture),
    frame: &GpuFrame,
) -> Result<ListMetrics, LabError> {
    let Pose {
        ctx,
        renderer,
        gpu_scene,
        c,
        settings,
        ..
    } = *p;
    let (exact_stride, light_count) = (c.exact_stride, u64::from(gpu_scene.light_count));
    let mut timer = manylights_gpu::timing::GpuTimer::new(ctx, 32);
    let probe = Strategy::tiled_gather(16);
    let lists = renderer
        .culler
        .run(ctx, gpu_scene, cull_depth, &probe, settings, &mut timer)?;
    let counts = renderer.culler.exact_counts(
        ctx,
        gpu_scene,
        depth,
        &lists,
        frame.clip_from_world.inverse(),
        exact_stride,
    )?;
    // Covered samples (with MSAA a pixel's fourth word counts its covered samples).
    let sampled: u64 = counts.iter().map(|k| u64::from(k[3])).sum();
    let needed: u64 = counts.iter().map(|k| u64::from(k[1])).sum();
    Ok(ListMetrics {
        covered_pixels: sampled,
        // Not reported (the row's false_negatives is empty for naive forward: it has no lists).
        false_negatives: 0,
        evaluated: sampled * light_count,
        needed,
        false_positive_ratio: (needed > 0).then(|| (sampled * light_count) as f64 / needed as f64),
        lights_per_pixel_mean: light_count as f64,
        lights_needed_per_pixel_mean: if sampled > 0 {
            needed as f64 / sampled as f64
        } else {
            0.0
        },
        max_lights_per_bin: light_count as u32,
        histogram: Vec::new(),
        dropped_lights: 0,
    })
}

/// Temporal stability over consecutive poses (with accuracy and at least two poses):
/// the mean absolute frame-to-frame change of the image and of the reference (per RGB channel,
/// averaged over the pose pairs), and the flicker: the largest change of the image's error
/// against the reference from one pose to the next, `max |(I_t - I_t-1) - (R_t - R_t-1)|`,
/// relative to the reference's peak. Flicker caused by culling is zero for a conservative
/// method: its images differ from the reference by float rounding only.
pub(crate) fn temporal_stability(evals: &[PoseEval]) -> Option<(f64, f64, f64)> {
    if evals.len() < 2 || evals.iter().any(|e| e.reference.is_none()) {
        return None;
    }
    let (mut change, mut change_ref, mut flicker, mut peak) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut n = 0.0f64;
    for pair in evals.windows(2) {
        let (i0, i1) = (&pair[0].color.data, &pair[1].color.data);
        let r0 = &pair[0].reference.as_ref()?.data;
        let r1 = &pair[1].reference.as_ref()?.data;
        peak = peak.max(f64::from(pair[0].reference.as_ref()?.peak()));
        peak = peak.max(f64::from(pair[1].reference.as_ref()?.peak()));
        let (mut c, mut cr) = (0.0f64, 0.0f64);
        for p in 0..i0.len() {
            for k in 0..3 {
                let di = f64::from(i1[p][k]) - f64::from(i0[p][k]);
                let dr = f64::from(r1[p][k]) - f64::from(r0[p][k]);
                c += di.abs();
                cr += dr.abs();
                flicker = flicker.max((di - dr).abs());
            }
        }
        let m = (i0.len() * 3).max(1) as f64;
        change += c / m;
        change_ref += cr / m;
        n += 1.0;
    }
    Some((
        change / n,
        change_ref / n,
        if peak > 0.0 { flicker / peak } else { flicker },
    ))
}
