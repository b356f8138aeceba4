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
use manylights_shade::Renderer;

use crate::cell_row::{RowParts, cell_row};
use crate::evaluate::{Pose, PoseEval, evaluate, steady_hierarchy_build};
use crate::experiment::{CameraSpec, Cell, Config, Experiment};
use crate::frame_lights::{FrameLights, LightsOf, hierarchy_plan};
use crate::noise::{Noise, measure};
use crate::references::{ReferenceSet, References};
use crate::renderers::{LoadedScenes, ReferenceFrames, Renderers};
use crate::results::Row;
use crate::runner::stage;
use crate::steady::SteadyCull;
use crate::{LabError, write_atomic};

/// The cell's scene with its generated lights after its own, and how many lights it has of
/// its own; a scene file the cell before loaded is taken from `loaded`.
fn build_scene(c: &Config, base: &Path, loaded: &LoadedScenes) -> Result<(Scene, usize), LabError> {
    use crate::experiment::SceneSpec;
    let (from, loaded) = match &c.scene {
        SceneSpec::Gltf(p) => {
            let path: PathBuf = if Path::new(p).is_absolute() {
                p.into()
            } else {
                base.join(p)
            };
            let from = path.display().to_string();
            let scene = loaded.get(&from, || {
                gltf_import::load(&path, &GltfOptions::default()).map_err(LabError::from)
            })?;
            (from, scene)
        }
        SceneSpec::Real(name) => {
            let scene = loaded.get(&format!("real:{name}"), || {
                manylights_scene::real::load(name, &GltfOptions::default()).map_err(LabError::from)
            })?;
            (name.clone(), scene)
        }
        _ => {
            let p = c
                .scene
                .procedural()
                .expect("every other scene is procedural");
            (String::new(), (p.build()?, Default::default()))
        }
    };
    let (mut scene, report) = loaded;
    if report.unread_textures > 0 {
        tracing::warn!(
            "{from}: {} material textures are not read (their factors are)",
            report.unread_textures
        );
    }
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
    fn upload(
        ctx: &GpuContext,
        c: &Config,
        (base, loaded): (&Path, &LoadedScenes),
        name: &str,
    ) -> Result<Self, LabError> {
        let (scene, own_lights) = stage(name, "scene built", || build_scene(c, base, loaded))?;
        let hier = stage(name, "hierarchy planned", || {
            hierarchy_plan(c, &scene, own_lights)
        })?;
        let shaded = hier.as_ref().map_or(&scene, |(_, s)| s);
        let poses: Vec<Camera> = match &c.camera {
            CameraSpec::Default => vec![scene.camera],
            CameraSpec::Pose(p) => vec![p.camera()],
            CameraSpec::Path(ps) => ps.iter().map(|p| p.camera()).collect(),
            CameraSpec::Walkthrough(w) => w.cameras(&scene.camera),
        };
        let (w, h) = c.resolution;
        ctx.check_resolution(w, h)?;
        let model = LightModel::of_rule(&c.lights.radius, own_lights as u32);
        let mut gpu_scene = stage(name, "scene uploaded", || {
            GpuScene::upload_with(ctx, shaded, model, &poses[0], w, h)
        })?;
        // Rays are cast by the cell's shading and by the shadowed references.
        let rays = c.shadows.casts() || c.shadowed_truth() || c.occlusion;
        if rays {
            stage(name, "BVH built", || gpu_scene.build_bvh(ctx, shaded))?;
        }
        let as_they_are = match (&hier, c.accuracy) {
            (Some(_), true) => {
                let mut s = GpuScene::upload(ctx, &scene, &poses[0], w, h)?;
                if c.shadowed_truth() {
                    stage(name, "BVH of the lights as they are built", || {
                        s.build_bvh(ctx, &scene)
                    })?;
                }
                Some(s)
            }
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

/// Runs one cell, top to bottom: its scene, lights and hierarchy built and uploaded, its
/// renderer taken; its warm-up and measured frames rendered; each checked pose measured (the
/// exact oracle, steady-state timings at the first, accuracy) and a stochastic cell's seeds;
/// its images written and its row made.
pub(crate) fn run_cell(
    ctx: &GpuContext,
    exp: &Experiment,
    cell: &Cell,
    (base, out): (&Path, &Path),
    commit: &str,
    (renderers, kept_frames, loaded): (&mut Renderers, &ReferenceFrames, &LoadedScenes),
) -> Result<Row, LabError> {
    let resolved = cell.config.at_limits(ctx);
    let c = &resolved;
    let id = cell.id();
    let name = cell.name.as_str();
    // Build: the scene, its lights and hierarchy on the GPU, the renderer.
    let CellScene {
        scene,
        own_lights,
        shaded_lights,
        poses,
        gpu_scene,
        as_they_are,
        hierarchy,
    } = CellScene::upload(ctx, c, (base, loaded), name)?;
    let (w, h) = c.resolution;
    let of = LightsOf {
        scene: &scene,
        gpu_scene: &gpu_scene,
        first: own_lights,
        as_they_are: as_they_are.as_ref(),
    };
    let mut lights = FrameLights::new(ctx, c, &of, hierarchy)?;
    if c.occlusion {
        // The renderers are built first, then given the scene's occluders.
        stage(name, "pipelines built", || {
            renderers.get_with_unshadowed(
                ctx,
                &gpu_scene,
                (c.msaa, c.hdr, c.shadows),
                c.visibility_pass,
            )
        })?;
        let occ = manylights_scene::occluders::of_scene(&scene);
        tracing::debug!(cell = name, occluders = occ.len(), "occluders chosen");
        renderers.set_occluders(ctx, &occ)?;
    }
    let (renderer, unshadowed) = stage(name, "pipelines built", || {
        renderers.get_with_unshadowed(
            ctx,
            &gpu_scene,
            (c.msaa, c.hdr, c.shadows),
            c.visibility_pass,
        )
    })
    .map_err(|e| LabError::from(e).during(format!("msaa = {}", c.msaa)))?;
    let settings = |cam: &Camera| CullSettings {
        slack: c.slack,
        capacity: c.capacity,
        mask_budget: c.mask_budget,
        tile_boxes: c.tile_boxes,
        occlusion: c.occlusion,
        ..CullSettings::for_camera(cam)
    };
    let run = CellFrames {
        ctx,
        c,
        name,
        poses: &poses,
        gpu_scene: &gpu_scene,
        renderer,
        unshadowed,
        settings: &settings,
    };
    // Render: the warm-up and measured frames.
    let measured = render_frames(&run, &mut lights)?;
    // Measure: every checked pose (a path's poses are all checked; with moving lights, every
    // measured frame, the lights where that frame had them), images at the first.
    let moving = lights.moving();
    let set = c
        .accuracy
        .then(|| ReferenceSet::new(ctx, &gpu_scene, c))
        .transpose()?;
    // The infinite-range references are cached in the run folder, except for moving lights.
    let refs = set.as_ref().map(|set| References {
        set,
        cache: (!moving).then(|| (out, crate::reference_cache::scene_fingerprint(&scene))),
        // Kept frames hold one build's lights: not for lights that move. Sampled bands are
        // drawn for frame 0 before the checks, the same draws in every build.
        frames: (!moving).then_some(kept_frames),
        lights_as_they_are: as_they_are.as_ref(),
    });
    let checks = checked_frames(c, poses.len(), moving);
    let checked = check_poses(
        &run,
        &Checks {
            refs: refs.as_ref(),
            timed: measured.timed,
            export: c.export.then(|| out.join("cells").join(&id)),
            frames: &checks,
        },
        &mut lights,
    )?;
    lights.check(ctx)?;
    let evals = checked.evals;
    let first = &evals[0];
    // Stochastic cells: each seed's image against infinite range (static lights only).
    let noise: Option<Noise> = match (lights.draws(), &first.infinite) {
        (Some(d), Some(inf)) if !moving => Some(stage(name, "seeds measured", || {
            let at_first = settings(&poses[0]);
            let at = run.pose(&poses[0], name, &at_first);
            measure(&at, d, (inf, first.shadowed.as_ref()))
        })?),
        _ => None,
    };
    // Write: the images and the row.
    save_images(
        out,
        &id,
        (&first.color, first.infinite.as_ref()),
        &first.per_pixel,
        (w, h),
    )?;
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
        draws: lights.draws(),
        noise,
        hierarchy_steady: checked.hierarchy_steady,
        measured: (
            &measured.frames,
            &measured.encode,
            &measured.uploads,
            measured.timed,
        ),
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

/// What a cell's frames are rendered with: its configuration, poses, scene and renderer.
struct CellFrames<'a> {
    ctx: &'a GpuContext,
    c: &'a Config,
    /// The cell's name in the log.
    name: &'a str,
    poses: &'a [Camera],
    gpu_scene: &'a GpuScene,
    renderer: &'a Renderer,
    /// With shadows, the renderer without them.
    unshadowed: Option<&'a Renderer>,
    /// Culling's settings for a camera.
    settings: &'a dyn Fn(&Camera) -> CullSettings,
}

impl<'a> CellFrames<'a> {
    /// Pose `cam`, named `name` in the log, culled with `settings`.
    fn pose<'p>(&'p self, cam: &'p Camera, name: &'p str, settings: &'p CullSettings) -> Pose<'p>
    where
        'a: 'p,
    {
        Pose {
            ctx: self.ctx,
            renderer: self.renderer,
            unshadowed: self.unshadowed,
            gpu_scene: self.gpu_scene,
            c: self.c,
            cam,
            settings,
            name,
            hierarchy: None,
        }
    }
}

/// What a cell's checks are measured against and where their results go.
struct Checks<'a> {
    refs: Option<&'a References<'a>>,
    /// Whether the frames were timed (steady state is measured at the first check).
    timed: bool,
    /// Where the first check's export goes (`export: true`).
    export: Option<PathBuf>,
    /// Each check's pose and the frame whose lights it sees ([`checked_frames`]).
    frames: &'a [(usize, Option<u32>)],
}

/// What a cell's checks measured.
struct Checked {
    evals: Vec<PoseEval>,
    /// The hierarchy's build back to back, timed at the first check.
    hierarchy_steady: Option<SteadyCull>,
}

/// Measures each check `(pose, frame)`, the lights as the frame had them: the frame and its GPU
/// measures, at the first of a timed cell its steady state and the hierarchy's build back to
/// back, then its accuracy.
fn check_poses(
    run: &CellFrames<'_>,
    checks: &Checks<'_>,
    lights: &mut FrameLights,
) -> Result<Checked, LabError> {
    let ctx = run.ctx;
    let mut evals = Vec::with_capacity(checks.frames.len());
    let mut hierarchy_steady = None;
    for (k, &(pose_index, frame)) in checks.frames.iter().enumerate() {
        let cam = &run.poses[pose_index];
        let pose = match frame.filter(|_| lights.moving()) {
            Some(f) => format!("{} frame {f} (pose {pose_index})", run.name),
            None => format!("{} pose {pose_index}", run.name),
        };
        lights.before_check(ctx, k, frame)?;
        let settings = (run.settings)(cam);
        let mut at = run.pose(cam, &pose, &settings);
        at.hierarchy = lights.hierarchy();
        // Steady state at the first pose, over as many runs as measured frames.
        let steady_runs = (k == 0 && checks.timed).then_some(run.c.frames);
        let mut eval = evaluate(
            &at,
            k == 0,
            steady_runs,
            checks.export.as_deref().filter(|_| k == 0),
        )?;
        if let (Some(runs), Some(hier)) = (steady_runs, lights.hierarchy()) {
            hierarchy_steady = steady_hierarchy_build(ctx, hier, runs, &pose)?;
        }
        if let Some(refs) = checks.refs {
            eval.score(&at, refs)?;
        }
        evals.push(eval);
    }
    Ok(Checked {
        evals,
        hierarchy_steady,
    })
}

/// A cell's measured frames: each one's passes (the lights' work first), the host's encode
/// times, the lights' upload times; `timed` false where the device has no timestamps.
struct Measured {
    frames: Vec<Vec<PassTiming>>,
    encode: Vec<f64>,
    uploads: Vec<f64>,
    timed: bool,
}

/// Renders a cell's warm-up and measured frames, a pose each in turn, as an application's
/// frames go: the lights' work first (moved, the hierarchy built, stochastic ranges drawn),
/// then the frame.
fn render_frames(run: &CellFrames<'_>, lights: &mut FrameLights) -> Result<Measured, LabError> {
    let CellFrames {
        ctx,
        c,
        name,
        poses,
        gpu_scene,
        renderer,
        settings,
        ..
    } = *run;
    let (w, h) = c.resolution;
    let mut frames: Vec<Vec<PassTiming>> = Vec::new();
    let mut encode = Vec::new();
    let mut uploads = Vec::new();
    let mut timed = true;
    for f in 0..(c.warmup + c.frames) as usize {
        let cam = &poses[f % poses.len()];
        let before = stage(name, &format!("frame {f} lights"), || {
            lights.before_frame(ctx, f as u32)
        })?;
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
                    if let Some(g) = before.gpu {
                        t.splice(0..0, g);
                    }
                    frames.push(t);
                }
                None => timed = false,
            }
            encode.push(enc);
            uploads.extend(before.host_ms);
        }
    }
    Ok(Measured {
        frames,
        encode,
        uploads,
        timed,
    })
}

/// The render, the lights-per-pixel heatmap and, where the infinite-range reference was
/// rendered, the FLIP map against it (at the reference's exposure, as `flip_mean_infinite`),
/// each at most 480 pixels wide, for the report.
fn save_images(
    out: &Path,
    id: &str,
    (color, infinite): (
        &manylights_shade::HdrImage,
        Option<&manylights_shade::HdrImage>,
    ),
    per_pixel: &[u32],
    (w, h): (u32, u32),
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
    let mut images = vec![
        ("render", small(color.tonemap(1.0))),
        ("heat", small(heatmap::pixels(per_pixel, w, h, max))),
    ];
    if let Some(inf) = infinite {
        use manylights_shade::accuracy::{exposure_of, flip_map};
        images.push(("flip", small(flip_map(color, inf, exposure_of(inf)))));
    }
    for (name, img) in images {
        let mut bytes = Vec::new();
        img.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )?;
        write_atomic(&out.join("images").join(format!("{id}_{name}.png")), &bytes)?;
    }
    Ok(())
}
