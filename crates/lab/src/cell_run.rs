//! One cell of an experiment ([`run_cell`], called by [`crate::runner`]): its scene and lights,
//! its frames, their steady-state timing, the list metrics and accuracy at every pose, and the
//! row of results with the report's images.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use manylights_cull::{CullSettings, heatmap};
use manylights_gpu::hierarchy::GpuHierarchy;
use manylights_gpu::timing::{PassKind, PassTiming};
use manylights_gpu::{GpuContext, GpuScene};
use manylights_scene::gltf_import::{self, GltfOptions};
use manylights_scene::{Camera, Scene};
use manylights_shade::{Backend, InfiniteReference, ReferenceRenderer, Renderer};

use crate::dynamic::{Movers, hierarchy_plan};
use crate::evaluate::{PoseEval, References, evaluate, temporal_stability};
use crate::experiment::{CameraSpec, Cell, Config, Experiment, params_label};
use crate::noise::{Draws, Noise, measure};
use crate::renderers::{ReferenceFrames, Renderers};
use crate::results::{Row, percentiles};
use crate::runner::{category, now, stage};
use crate::{LabError, write_atomic};

/// The cell's scene with its generated lights after its own, and how many lights it has of
/// its own.
fn build_scene(c: &Config, base: &Path) -> Result<(Scene, usize), LabError> {
    let mut scene = match c.scene.procedural() {
        Some(p) => p.build().map_err(|e| LabError::Other(e.to_string()))?,
        None => {
            let crate::experiment::SceneSpec::Gltf(p) = &c.scene else {
                unreachable!("procedural handled")
            };
            let path: PathBuf = if Path::new(p).is_absolute() {
                p.into()
            } else {
                base.join(p)
            };
            let (scene, report) = gltf_import::load(&path, &GltfOptions::default())
                .map_err(|e| LabError::Other(e.to_string()))?;
            if report.unread_textures > 0 {
                tracing::warn!(
                    "{}: {} material textures are not read (their factors are)",
                    path.display(),
                    report.unread_textures
                );
            }
            scene
        }
    };
    scene.assign_models(&c.materials);
    let lights = c
        .lights
        .generate(&scene)
        .map_err(|e| LabError::Other(e.to_string()))?;
    let own = scene.lights.len();
    scene.lights.extend(lights);
    scene
        .validate()
        .map_err(|e| LabError::Other(e.to_string()))?;
    Ok((scene, own))
}

/// The material models of the scene's surfaces, by id, their names joined by `+`.
fn frame_models(scene: &Scene) -> String {
    let models: std::collections::BTreeSet<manylights_scene::Model> = scene
        .primitives
        .iter()
        .map(|p| scene.materials[p.material as usize].brdf.model())
        .collect();
    crate::cells::models_label(&models.into_iter().collect::<Vec<_>>())
}

/// The shading passes' steady-state time (`shade.*` but the G-buffer or visibility buffer) per light evaluated, ns;
/// none where they were not timed apart or nothing was evaluated.
fn ns_per_light_eval(passes: &[(String, f64)], evaluated: f64) -> Option<f64> {
    let ms: f64 = passes
        .iter()
        .filter(|(label, _)| label.starts_with("shade.") && !crate::runner::is_surfaces_pass(label))
        .map(|(_, ms)| ms)
        .sum();
    (ms > 0.0 && evaluated > 0.0).then(|| ms * 1e6 / evaluated)
}

/// A cell's scene on the GPU: the scene, the lights it shades, its camera poses.
struct CellScene {
    scene: Scene,
    /// How many lights the scene has of its own (before the generated ones).
    own_lights: usize,
    /// How many lights the cell shades: the scene's, or its hierarchy's in their place.
    shaded_lights: usize,
    poses: Vec<Camera>,
    gpu_scene: GpuScene,
    /// With a hierarchy and accuracy measured, the lights as they are, for the infinite-range
    /// reference.
    as_they_are: Option<GpuScene>,
    /// With `radius: Hierarchy`, its build, which fills `gpu_scene`'s lights each frame.
    hierarchy: Option<GpuHierarchy>,
}

impl CellScene {
    fn upload(ctx: &GpuContext, c: &Config, base: &Path, name: &str) -> Result<Self, LabError> {
        let other = |e: &dyn std::fmt::Display| LabError::Other(e.to_string());
        let (scene, own_lights) = stage(name, "scene built", || build_scene(c, base))?;
        let hier = stage(name, "hierarchy planned", || hierarchy_plan(c, &scene))?;
        let shaded = hier.as_ref().map_or(&scene, |(_, s)| s);
        let poses: Vec<Camera> = match &c.camera {
            CameraSpec::Default => vec![scene.camera],
            CameraSpec::Pose(p) => vec![p.camera()],
            CameraSpec::Path(ps) => ps.iter().map(|p| p.camera()).collect(),
        };
        let (w, h) = c.resolution;
        ctx.check_resolution(w, h).map_err(|e| other(&e))?;
        let gpu_scene = stage(name, "scene uploaded", || {
            GpuScene::upload(ctx, shaded, &poses[0], w, h)
        })
        .map_err(|e| other(&e))?;
        let as_they_are = match (&hier, c.accuracy) {
            (Some(_), true) => {
                Some(GpuScene::upload(ctx, &scene, &poses[0], w, h).map_err(|e| other(&e))?)
            }
            _ => None,
        };
        let shaded_lights = shaded.lights.len();
        let hierarchy = hier
            .map(|(plan, _)| GpuHierarchy::new(ctx, plan, &scene.lights, &gpu_scene))
            .transpose()
            .map_err(|e| other(&e))?;
        Ok(CellScene {
            shaded_lights,
            scene,
            own_lights,
            poses,
            gpu_scene,
            as_they_are,
            hierarchy,
        })
    }
}

/// A cell's measured frames as median and 10th and 90th percentile milliseconds: the whole,
/// each category and kind of pass, and each pass by label.
struct Timings {
    total: Option<(f64, f64, f64)>,
    cull: Option<(f64, f64, f64)>,
    shade: Option<(f64, f64, f64)>,
    prepass: Option<(f64, f64, f64)>,
    /// Where the update was timed (an upload's copy is not where the device cannot write
    /// timestamps between passes): never a made-up 0.
    light_update: Option<(f64, f64, f64)>,
    raster: Option<(f64, f64, f64)>,
    compute: Option<(f64, f64, f64)>,
    /// The lighting grid hierarchy's build (`lights.hierarchy.*`), where it ran and was timed.
    hierarchy: Option<(f64, f64, f64)>,
    passes: std::collections::BTreeMap<String, f64>,
}

impl Timings {
    /// Of `frames`, each a frame's passes; all `None` (and no passes) unless `timed`.
    fn of(frames: &[Vec<PassTiming>], timed: bool) -> Timings {
        let series = |pick: &dyn Fn(&PassTiming) -> bool| -> Vec<f64> {
            frames
                .iter()
                .map(|t| t.iter().filter(|p| pick(p)).map(|p| p.ms).sum())
                .collect()
        };
        let stats = |v: Vec<f64>| if timed { percentiles(&v) } else { None };
        let of_category = |name: &str| stats(series(&|p| category(&p.label) == name));
        let updates_timed = frames
            .iter()
            .any(|t| t.iter().any(|p| category(&p.label) == "light_update"));
        let mut passes = std::collections::BTreeMap::new();
        if timed {
            let labels: BTreeSet<String> = frames
                .iter()
                .flat_map(|t| t.iter().map(|p| p.label.clone()))
                .collect();
            for l in labels {
                if let Some((m, _, _)) = percentiles(&series(&|p| p.label == l)) {
                    passes.insert(l, m);
                }
            }
        }
        Timings {
            total: stats(series(&|_| true)),
            cull: of_category("cull"),
            shade: of_category("shade"),
            prepass: of_category("prepass"),
            light_update: if updates_timed {
                of_category("light_update")
            } else {
                None
            },
            raster: stats(series(&|p| p.kind == PassKind::Raster)),
            compute: stats(series(&|p| p.kind == PassKind::Compute)),
            hierarchy: frames
                .iter()
                .any(|t| t.iter().any(|p| p.label.starts_with("lights.hierarchy.")))
                .then(|| stats(series(&|p| p.label.starts_with("lights.hierarchy."))))
                .flatten(),
            passes,
        }
    }
}

pub(crate) fn run_cell(
    ctx: &GpuContext,
    exp: &Experiment,
    cell: &Cell,
    (base, out): (&Path, &Path),
    commit: &str,
    (renderers, kept_frames): (&mut Renderers, &ReferenceFrames),
) -> Result<Row, LabError> {
    let resolved = cell.config.at_limits(ctx);
    let c = &resolved;
    let id = cell.id();
    let other = |e: &dyn std::fmt::Display| LabError::Other(e.to_string());
    let name = cell.name.as_str();
    let CellScene {
        scene,
        own_lights,
        shaded_lights,
        poses,
        gpu_scene,
        as_they_are,
        hierarchy,
    } = CellScene::upload(ctx, c, base, name)?;
    let (w, h) = c.resolution;
    // Stochastic ranges first: they make the lights general, which the renderer is built for.
    let draws = Draws::new(ctx, c, &gpu_scene, &scene, own_lights)?;
    let renderer = stage(name, "pipelines built", || {
        renderers.get(ctx, &gpu_scene, c.msaa, c.hdr)
    })
    .map_err(|e| other(&format!("msaa = {}: {e}", c.msaa)))?;
    let settings = |cam: &Camera| CullSettings {
        slack: c.slack,
        capacity: c.capacity,
        mask_budget: c.mask_budget,
        tile_boxes: c.tile_boxes,
        ..CullSettings::for_camera(cam)
    };
    let mut movers = Movers::new(
        ctx,
        c,
        (&gpu_scene, &scene, own_lights),
        hierarchy,
        as_they_are.as_ref(),
    )?;
    let moving = movers.as_ref().is_some_and(Movers::moving);
    let sampled = matches!(
        c.lights.radius,
        manylights_scene::RadiusRule::Hierarchy {
            sample_from: Some(_),
            ..
        }
    );
    let Measured {
        frames,
        encode,
        uploads,
        timed,
    } = render_frames(
        ctx,
        c,
        name,
        &poses,
        (&gpu_scene, renderer),
        (draws.as_ref(), &mut movers),
        &settings,
    )?;
    // Metrics and accuracy at every pose (a path's poses are all checked), images at the first;
    // with moving lights, at every measured frame, the lights where that frame had them.
    let light_count = shaded_lights as u64;
    let reference = c
        .accuracy
        .then(|| ReferenceRenderer::with_samples(ctx, &gpu_scene, c.msaa))
        .transpose()
        .map_err(|e| other(&e))?;
    let infinite = c.accuracy.then(|| InfiniteReference::new(ctx, &gpu_scene));
    // The infinite-range reference is cached in the run folder, except for moving lights.
    let refs = match (&reference, &infinite) {
        (Some(rr), Some(inf)) => Some(References {
            rr,
            inf,
            cache: (!moving).then(|| (out, crate::reference_cache::scene_fingerprint(&scene))),
            // Kept frames hold one build's lights: not for lights that move. Sampled bands are
            // drawn for frame 0 before the checks (below), the same draws in every build.
            frames: (!moving).then_some(kept_frames),
            lights_as_they_are: as_they_are.as_ref(),
        }),
        _ => None,
    };
    let checks: Vec<(usize, Option<u32>)> = if moving {
        (c.warmup..c.warmup + c.frames)
            .map(|f| (f as usize % poses.len(), Some(f)))
            .collect()
    } else {
        (0..poses.len()).map(|k| (k, None)).collect()
    };
    if let (true, false, Some(m)) = (sampled, moving, &mut movers) {
        // Static lights with sampled bands: every check sees frame 0's draws (the timed frames
        // drew their own, as many as the steady-state warm-up took).
        m.update(ctx, 0)?;
    }
    let mut evals = Vec::with_capacity(checks.len());
    for (k, &(p, frame)) in checks.iter().enumerate() {
        let cam = &poses[p];
        let pose = match (frame, &mut movers) {
            (Some(f), Some(m)) => {
                m.update(ctx, f)?;
                format!("{name} frame {f} (pose {p})")
            }
            _ => format!("{name} pose {p}"),
        };
        if let Some(d) = &draws {
            // Each check sees the ranges of its frame (the first frame's where none moves).
            d.draw(ctx, frame.unwrap_or(0))?;
        }
        evals.push(evaluate(
            ctx,
            renderer,
            refs.as_ref(),
            &gpu_scene,
            c,
            cam,
            &settings(cam),
            &pose,
            // Steady-state culling at the first pose, over as many runs as measured frames.
            (k == 0 && timed).then_some(c.frames),
            (k == 0 && c.export)
                .then(|| out.join("cells").join(&id))
                .as_deref(),
        )?);
    }
    if let Some(m) = &movers {
        m.check(ctx)?;
    }
    let first = &evals[0];
    save_images(out, &id, &first.color, &first.per_pixel, w, h)?;
    // Stochastic cells: each seed's image against infinite range (static lights only).
    let noise: Option<Noise> = match (&draws, &first.infinite) {
        (Some(d), Some(inf)) if !moving => Some(stage(name, "seeds measured", || {
            measure(
                ctx,
                renderer,
                &gpu_scene,
                c,
                &poses[0],
                &settings(&poses[0]),
                d,
                inf,
            )
        })?),
        _ => None,
    };
    let temporal = temporal_stability(&evals);
    let worst = Worst::of(&evals, noise.as_ref());
    let (list_bytes, gbuffer_bytes) = (first.list_bytes, first.gbuffer_bytes);

    let Timings {
        total,
        cull,
        shade,
        prepass,
        light_update,
        raster,
        compute,
        hierarchy: hierarchy_ms,
        passes,
    } = Timings::of(&frames, timed);
    let med = |s: Option<(f64, f64, f64)>| s.map(|x| x.0);
    let p10 = |s: Option<(f64, f64, f64)>| s.map(|x| x.1);
    let p90 = |s: Option<(f64, f64, f64)>| s.map(|x| x.2);
    Ok(Row {
        experiment: exp.name.clone(),
        cell: cell.name.clone(),
        scene: c.scene.name(),
        lights: light_count,
        width: w,
        height: h,
        strategy: if c.backend == Backend::NaiveForward {
            "none".into()
        } else {
            c.strategy.name().into()
        },
        backend: c.backend.name().into(),
        params: params_label(c),
        gpu_ms_total: med(total),
        gpu_ms_cull: med(cull),
        gpu_ms_shade: med(shade),
        gpu_ms_prepass: med(prepass),
        cpu_ms_encode: percentiles(&encode).map_or(0.0, |x| x.0),
        false_negatives: worst.false_negatives,
        false_positive_ratio: worst.fp_ratio,
        lights_per_pixel_mean: worst.per_pixel_mean,
        max_lights_per_tile: worst.max_per_bin,
        dropped_lights: worst.dropped,
        list_bytes,
        gbuffer_bytes,
        msaa: c.msaa,
        transparent: gpu_scene.has_transparent(),
        passes_steady: first.steady_passes.iter().fold(
            std::collections::BTreeMap::new(),
            |mut m, (label, ms)| {
                *m.entry(label.clone()).or_insert(0.0) += ms;
                m
            },
        ),
        gpu_ms_geometry_steady: first.steady_geometry,
        gpu_ms_frame_steady: match (c.backend, first.steady_geometry, first.steady_frame) {
            (Backend::NaiveForward, g, _) => g,
            (_, Some(g), Some(f)) => Some(g + f.0),
            _ => None,
        },
        msaa_target_bytes: first.msaa_target_bytes,
        psnr_db: worst.psnr,
        flip_mean: worst.flip,
        max_abs_error: worst.max_abs,
        adapter: ctx.info.name.clone(),
        driver: format!("{} {}", ctx.info.driver, ctx.info.driver_info)
            .trim()
            .to_string(),
        commit: commit.to_string(),
        gpu_ms_total_p10: p10(total),
        gpu_ms_total_p90: p90(total),
        gpu_ms_cull_p10: p10(cull),
        gpu_ms_cull_p90: p90(cull),
        gpu_ms_shade_p10: p10(shade),
        gpu_ms_shade_p90: p90(shade),
        gpu_ms_prepass_p10: p10(prepass),
        gpu_ms_prepass_p90: p90(prepass),
        gpu_ms_raster: med(raster),
        gpu_ms_compute: med(compute),
        psnr_db_infinite: worst.psnr_inf,
        flip_mean_infinite: worst.flip_inf,
        max_abs_error_infinite: worst.max_abs_inf,
        exact_stride: c.exact_stride,
        frames: c.frames,
        nonfinite_pixels: worst.nonfinite,
        poses: checks.len() as u32,
        temporal_change: temporal.map(|t| t.0),
        temporal_change_reference: temporal.map(|t| t.1),
        temporal_flicker: temporal.map(|t| t.2),
        tile_masks: first.tile_masks,
        gpu_ms_cull_steady: first.steady.map(|s| s.0),
        gpu_ms_cull_span: first.steady.and_then(|s| s.1),
        gpu_ms_cull_shade: first.steady_frame.map(|s| s.0),
        gpu_ms_cull_shade_span: first.steady_frame.and_then(|s| s.1),
        radius_rule: c.lights.radius.kind().into(),
        exposure_infinite: worst.exposure_inf,
        rmse_infinite: worst.rmse_inf,
        energy_error_infinite: worst.energy_inf,
        seeds: draws.as_ref().map(|d| d.seeds),
        accumulate: draws.as_ref().map(|d| d.accumulate),
        bias_infinite: noise.and_then(|n| n.bias),
        noise_infinite: noise.and_then(|n| n.noise),
        temporal_flicker_mean: noise.and_then(|n| n.flicker_mean),
        reference_infinite_cached: first.infinite_cached,
        materials: frame_models(&scene),
        covered_pixels: Some(first.covered),
        gpu_ms_hierarchy: med(hierarchy_ms),
        scene_lights: (c.lights.radius.kind() == "hierarchy").then_some(scene.lights.len() as u64),
        bytes_written_per_pixel: Some(c.backend.bytes_per_pixel(c.msaa, c.hdr).0),
        bytes_read_per_pixel: Some(c.backend.bytes_per_pixel(c.msaa, c.hdr).1),
        ns_per_light_eval: ns_per_light_eval(
            &first.steady_passes,
            if c.backend == Backend::NaiveForward {
                light_count as f64
            } else {
                first.lights_per_pixel_mean
            } * first.covered as f64,
        ),
        lights_needed_per_pixel_mean: worst.needed_per_pixel_mean,
        gpu_ms_light_update: med(light_update),
        cpu_ms_upload: percentiles(&uploads).map(|x| x.0),
        passes,
        index: cell.index,
        id,
        finished_unix: now(),
    })
}

/// A cell's measured frames: each one's passes (the lights' move and draws first), the host's
/// encode times, the lights' upload times; `timed` false where the device has no timestamps.
struct Measured {
    frames: Vec<Vec<PassTiming>>,
    encode: Vec<f64>,
    uploads: Vec<f64>,
    timed: bool,
}

/// Renders a cell's warm-up and measured frames, a pose each in turn, as an application's
/// frames go: the lights moved (and the hierarchy built) first, stochastic ranges drawn, then
/// the frame.
fn render_frames(
    ctx: &GpuContext,
    c: &Config,
    name: &str,
    poses: &[Camera],
    (gpu_scene, renderer): (&GpuScene, &Renderer),
    (draws, movers): (Option<&Draws>, &mut Option<Movers>),
    settings: &dyn Fn(&Camera) -> CullSettings,
) -> Result<Measured, LabError> {
    let (w, h) = c.resolution;
    let other = |e: &dyn std::fmt::Display| LabError::Other(e.to_string());
    let mut frames: Vec<Vec<PassTiming>> = Vec::new();
    let mut encode = Vec::new();
    let mut uploads = Vec::new();
    let mut timed = true;
    for f in 0..(c.warmup + c.frames) as usize {
        let cam = &poses[f % poses.len()];
        // Moving lights move first, as a frame of an application would move them.
        let update = match movers {
            Some(m) => Some(stage(name, &format!("frame {f} lights moved"), || {
                m.update(ctx, f as u32)
            })?),
            None => None,
        };
        // Stochastic ranges are drawn afresh each frame, timed with it.
        let drawn = match draws {
            Some(d) => d.draw(ctx, f as u32)?,
            None => None,
        };
        gpu_scene.set_view(ctx, cam, w, h, 0);
        ctx.take_encode_ms();
        let o = stage(name, &format!("frame {f} rendered"), || {
            renderer.render(
                ctx,
                gpu_scene,
                c.backend,
                &c.strategy,
                &settings(cam),
                (w, h),
            )
        })
        .map_err(|e| other(&e))?;
        let enc = ctx.take_encode_ms();
        if f >= c.warmup as usize {
            match o.timings {
                Some(mut t) => {
                    if let Some(g) = drawn {
                        t.splice(0..0, g);
                    }
                    if let Some(g) = update.as_ref().and_then(|u| u.gpu.clone()) {
                        t.splice(0..0, g);
                    }
                    frames.push(t);
                }
                None => timed = false,
            }
            encode.push(enc);
            uploads.extend(update.and_then(|u| u.host_ms));
        }
    }
    Ok(Measured {
        frames,
        encode,
        uploads,
        timed,
    })
}

/// The worst of each measure over a cell's checked poses (a stochastic cell's image error
/// against infinite range: its seeds' mean).
struct Worst {
    false_negatives: Option<u64>,
    fp_ratio: Option<f64>,
    max_per_bin: Option<u64>,
    per_pixel_mean: Option<f64>,
    needed_per_pixel_mean: Option<f64>,
    dropped: u64,
    nonfinite: u64,
    psnr: Option<f64>,
    flip: Option<f64>,
    max_abs: Option<f64>,
    psnr_inf: Option<f64>,
    flip_inf: Option<f64>,
    max_abs_inf: Option<f64>,
    rmse_inf: Option<f64>,
    energy_inf: Option<f64>,
    exposure_inf: Option<f64>,
}

impl Worst {
    fn of(evals: &[PoseEval], noise: Option<&Noise>) -> Worst {
        let first = &evals[0];
        // The worst pose of each measure.
        let max_u64 = |f: &dyn Fn(&PoseEval) -> Option<u64>| evals.iter().filter_map(f).max();
        let max_f64 =
            |f: &dyn Fn(&PoseEval) -> Option<f64>| evals.iter().filter_map(f).reduce(f64::max);
        let min_f64 =
            |f: &dyn Fn(&PoseEval) -> Option<f64>| evals.iter().filter_map(f).reduce(f64::min);
        let false_negatives = evals
            .iter()
            .map(|e| e.metrics.as_ref().map(|m| m.false_negatives))
            .try_fold(0u64, |a, f| f.map(|f| a + f));
        let fp_ratio = max_f64(&|e| e.metrics.as_ref().and_then(|m| m.false_positive_ratio));
        let max_per_bin = max_u64(&|e| e.metrics.as_ref().map(|m| u64::from(m.max_lights_per_bin)));
        let per_pixel_mean = max_f64(&|e| Some(e.lights_per_pixel_mean));
        let dropped = max_u64(&|e| Some(e.dropped)).unwrap_or(0);
        let nonfinite = max_u64(&|e| Some(e.nonfinite)).unwrap_or(0);
        let (psnr, flip, max_abs) = (
            min_f64(&|e| e.acc.map(|a| a.psnr_db)),
            max_f64(&|e| e.acc.map(|a| a.flip_mean)),
            max_f64(&|e| e.acc.map(|a| a.max_abs_error)),
        );
        let (psnr_inf, mut flip_inf, max_abs_inf) = (
            min_f64(&|e| e.acc_inf.map(|a| a.psnr_db)),
            max_f64(&|e| e.acc_inf.map(|a| a.flip_mean)),
            max_f64(&|e| e.acc_inf.map(|a| a.max_abs_error)),
        );
        let mut rmse_inf = max_f64(&|e| e.acc_inf.map(|a| a.rmse));
        // The energy error of the pose farthest from zero.
        let mut energy_inf = evals
            .iter()
            .filter_map(|e| e.acc_inf.map(|a| a.energy_error))
            .reduce(|a, b| if b.abs() > a.abs() { b } else { a });
        let mut exposure_inf = first.acc_inf.map(|a| f64::from(a.exposure));
        if let Some(n) = noise {
            // A stochastic cell's image error is its seeds' mean.
            flip_inf = Some(n.flip_mean);
            rmse_inf = Some(n.rmse);
            energy_inf = Some(n.energy_error);
            exposure_inf = Some(n.exposure);
        }
        let needed_per_pixel_mean =
            max_f64(&|e| e.metrics.as_ref().map(|m| m.lights_needed_per_pixel_mean));
        Worst {
            false_negatives,
            fp_ratio,
            max_per_bin,
            per_pixel_mean,
            needed_per_pixel_mean,
            dropped,
            nonfinite,
            psnr,
            flip,
            max_abs,
            psnr_inf,
            flip_inf,
            max_abs_inf,
            rmse_inf,
            energy_inf,
            exposure_inf,
        }
    }
}

/// The render and the lights-per-pixel heatmap, at most 480 pixels wide, for the report.
fn save_images(
    out: &Path,
    id: &str,
    color: &manylights_shade::HdrImage,
    per_pixel: &[u32],
    w: u32,
    h: u32,
) -> Result<(), LabError> {
    let small = |img: image::RgbImage| {
        if w > 480 {
            let nh = ((h as f32) * 480.0 / w as f32).round().max(1.0) as u32;
            image::imageops::resize(&img, 480, nh, image::imageops::FilterType::Triangle)
        } else {
            img
        }
    };
    let max = per_pixel.iter().copied().max().unwrap_or(0).max(1);
    for (name, img) in [
        ("render", small(color.tonemap(1.0))),
        ("heat", small(heatmap::pixels(per_pixel, w, h, max))),
    ] {
        let mut bytes = Vec::new();
        img.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .map_err(|e| LabError::Other(e.to_string()))?;
        write_atomic(&out.join("images").join(format!("{id}_{name}.png")), &bytes)?;
    }
    Ok(())
}
