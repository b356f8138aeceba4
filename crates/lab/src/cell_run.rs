//! One cell of an experiment ([`run_cell`], called by [`crate::runner`]): its scene and lights,
//! its frames, their steady-state timing, the list metrics and accuracy at every pose, and the
//! report's images; its row of results from them in [`crate::cell_row`].

use std::path::{Path, PathBuf};

use manylights_cull::{CullSettings, heatmap};
use manylights_gpu::hierarchy::GpuHierarchy;
use manylights_gpu::timing::PassTiming;
use manylights_gpu::{GpuContext, GpuScene, LightModel};
use manylights_scene::gltf_import::{self, GltfOptions};
use manylights_scene::{Camera, Scene};
use manylights_shade::{InfiniteReference, ReferenceRenderer, Renderer};

use crate::cell_row::{RowParts, cell_row};
use crate::dynamic::{Movers, hierarchy_plan};
use crate::evaluate::{Pose, PoseEval, References, Steady, evaluate};
use crate::experiment::{CameraSpec, Cell, Config, Experiment};
use crate::noise::{Draws, Noise, measure};
use crate::renderers::{ReferenceFrames, Renderers};
use crate::results::Row;
use crate::runner::stage;
use crate::{LabError, write_atomic};

/// The cell's scene with its generated lights after its own, and how many lights it has of
/// its own.
fn build_scene(c: &Config, base: &Path) -> Result<(Scene, usize), LabError> {
    let mut scene = match c.scene.procedural() {
        Some(p) => p.build()?,
        None => {
            let crate::experiment::SceneSpec::Gltf(p) = &c.scene else {
                unreachable!("procedural handled")
            };
            let path: PathBuf = if Path::new(p).is_absolute() {
                p.into()
            } else {
                base.join(p)
            };
            let (scene, report) = gltf_import::load(&path, &GltfOptions::default())?;
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
    let lights = c.lights.generate(&scene)?;
    let own = scene.lights.len();
    scene.lights.extend(lights);
    scene.validate()?;
    Ok((scene, own))
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
        let (scene, own_lights) = stage(name, "scene built", || build_scene(c, base))?;
        let hier = stage(name, "hierarchy planned", || hierarchy_plan(c, &scene))?;
        let shaded = hier.as_ref().map_or(&scene, |(_, s)| s);
        let poses: Vec<Camera> = match &c.camera {
            CameraSpec::Default => vec![scene.camera],
            CameraSpec::Pose(p) => vec![p.camera()],
            CameraSpec::Path(ps) => ps.iter().map(|p| p.camera()).collect(),
        };
        let (w, h) = c.resolution;
        ctx.check_resolution(w, h)?;
        let model = LightModel::of_rule(&c.lights.radius, own_lights as u32);
        let gpu_scene = stage(name, "scene uploaded", || {
            GpuScene::upload_with(ctx, shaded, model, &poses[0], w, h)
        })?;
        let as_they_are = match (&hier, c.accuracy) {
            (Some(_), true) => Some(GpuScene::upload(ctx, &scene, &poses[0], w, h)?),
            _ => None,
        };
        let shaded_lights = shaded.lights.len();
        let hierarchy = hier
            .map(|(plan, _)| GpuHierarchy::new(ctx, plan, &scene.lights, &gpu_scene))
            .transpose()?;
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
    let draws = Draws::new(ctx, c, &gpu_scene, &scene, own_lights)?;
    let renderer = stage(name, "pipelines built", || {
        renderers.get(ctx, &gpu_scene, c.msaa, c.hdr, c.visibility_pass)
    })
    .map_err(|e| LabError::from(e).during(format!("msaa = {}", c.msaa)))?;
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
    let reference = c
        .accuracy
        .then(|| ReferenceRenderer::with_samples(ctx, &gpu_scene, c.msaa))
        .transpose()?;
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
    let checks = checked_frames(c, poses.len(), moving);
    if let (true, false, Some(m)) = (sampled_bands(c), moving, &mut movers) {
        // Static lights with sampled bands: every check sees frame 0's draws (the timed frames
        // drew their own, as many as the steady-state warm-up took).
        m.update(ctx, 0)?;
    }
    let mut evals = evaluate_checks(
        &PoseChecks {
            ctx,
            renderer,
            refs: refs.as_ref(),
            gpu_scene: &gpu_scene,
            c,
            poses: &poses,
            name,
            timed,
            export: c.export.then(|| out.join("cells").join(&id)),
        },
        &checks,
        (draws.as_ref(), &mut movers),
        &settings,
    )?;
    if let Some(m) = &movers {
        m.check(ctx)?;
    }
    // The hierarchy's build was timed back to back at the first check (`evaluate`).
    let hierarchy_steady = evals.first_mut().and_then(|e| e.steady_build.take());
    let first = &evals[0];
    save_images(out, &id, &first.color, &first.per_pixel, w, h)?;
    // Stochastic cells: each seed's image against infinite range (static lights only).
    let noise: Option<Noise> = match (&draws, &first.infinite) {
        (Some(d), Some(inf)) if !moving => Some(stage(name, "seeds measured", || {
            let at = Pose {
                ctx,
                renderer,
                gpu_scene: &gpu_scene,
                c,
                cam: &poses[0],
                settings: &settings(&poses[0]),
                name,
            };
            measure(&at, d, inf)
        })?),
        _ => None,
    };
    Ok(cell_row(RowParts {
        exp,
        cell,
        c,
        ctx,
        commit,
        scene: &scene,
        transparent: gpu_scene.has_transparent(),
        light_count: shaded_lights as u64,
        evals: &evals,
        poses: checks.len() as u32,
        draws: draws.as_ref(),
        noise,
        hierarchy_steady,
        measured: (&frames, &encode, &uploads, timed),
    }))
}

/// The poses a cell checks, each with the frame whose lights it checks: every pose of its path
/// (`None`: the lights as they are), or with moving lights every measured frame (at its pose).
fn checked_frames(c: &Config, poses: usize, moving: bool) -> Vec<(usize, Option<u32>)> {
    if moving {
        (c.warmup..c.warmup + c.frames)
            .map(|f| (f as usize % poses, Some(f)))
            .collect()
    } else {
        (0..poses).map(|k| (k, None)).collect()
    }
}

/// Whether the cell's lights are a hierarchy with sampled bands.
fn sampled_bands(c: &Config) -> bool {
    matches!(
        c.lights.radius,
        manylights_scene::RadiusRule::Hierarchy {
            sample_from: Some(_),
            ..
        }
    )
}

/// What each checked pose (or measured frame of moving lights) of a cell is evaluated with.
struct PoseChecks<'a> {
    ctx: &'a GpuContext,
    renderer: &'a Renderer,
    refs: Option<&'a References<'a>>,
    gpu_scene: &'a GpuScene,
    c: &'a Config,
    poses: &'a [Camera],
    name: &'a str,
    /// Whether the frames were timed (steady-state culling is measured at the first check).
    timed: bool,
    /// Where the first check's export goes (`export: true`).
    export: Option<PathBuf>,
}

/// Evaluates each check `(pose, frame)`, the lights moved to the frame's places and its
/// stochastic ranges drawn first.
fn evaluate_checks(
    p: &PoseChecks<'_>,
    checks: &[(usize, Option<u32>)],
    (draws, movers): (Option<&Draws>, &mut Option<Movers>),
    settings: &dyn Fn(&Camera) -> CullSettings,
) -> Result<Vec<PoseEval>, LabError> {
    let (ctx, name) = (p.ctx, p.name);
    let mut evals = Vec::with_capacity(checks.len());
    for (k, &(pose_index, frame)) in checks.iter().enumerate() {
        let cam = &p.poses[pose_index];
        let pose = match (frame, &mut *movers) {
            (Some(f), Some(m)) => {
                m.update(ctx, f)?;
                format!("{name} frame {f} (pose {pose_index})")
            }
            _ => format!("{name} pose {pose_index}"),
        };
        if let Some(d) = draws {
            // Each check sees the ranges of its frame (the first frame's where none moves).
            d.draw(ctx, frame.unwrap_or(0))?;
        }
        let at = Pose {
            ctx,
            renderer: p.renderer,
            gpu_scene: p.gpu_scene,
            c: p.c,
            cam,
            settings: &settings(cam),
            name: &pose,
        };
        evals.push(evaluate(
            &at,
            p.refs,
            // Steady-state culling (and the hierarchy's build) at the first pose, over as many
            // runs as measured frames.
            (k == 0 && p.timed).then(|| Steady {
                runs: p.c.frames,
                hierarchy: movers.as_ref().and_then(Movers::hierarchy),
            }),
            p.export.as_deref().filter(|_| k == 0),
        )?);
    }
    Ok(evals)
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
        })?;
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
        )?;
        write_atomic(&out.join("images").join(format!("{id}_{name}.png")), &bytes)?;
    }
    Ok(())
}
