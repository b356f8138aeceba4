//! `render`: a frame of the reference or of a backend over a strategy, its images, and with
//! `--compare` its error against the references.

use std::path::PathBuf;

use anyhow::{Result, bail};
use manylights_cull::heatmap;
use manylights_gpu::{GpuContext, GpuScene};
use manylights_scene::RadiusRule;
use manylights_shade::image_out::{ImageSum, write_atomic};
use manylights_shade::{
    Backend, HdrFormat, HdrImage, ReferenceFrame, ReferenceRenderer, Renderer, Shadows,
    VisibilityPass, accuracy,
};

use crate::options::{BackendName, SceneArgs, StrategyArgs, print_timings};

#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub(crate) struct RenderArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    /// Shading backend: the brute-force reference, or a backend over a culling strategy
    /// (--strategy and its options; naive-forward culls nothing).
    #[arg(long, value_enum, default_value_t = BackendName::Reference)]
    pub(crate) backend: BackendName,
    #[command(flatten)]
    pub(crate) cull: StrategyArgs,
    /// Also render the reference and the infinite-range reference, and print the image error
    /// against each (max abs error, RMSE, PSNR, mean FLIP).
    #[arg(long)]
    pub(crate) compare: bool,
    /// With --compare, also write the FLIP error map against the reference as a PNG.
    #[arg(long, requires = "compare")]
    pub(crate) flip_map: bool,
    /// Exposure applied before tonemapping the PNG (and for FLIP).
    #[arg(long, default_value_t = 1.0)]
    pub(crate) exposure: f32,
    /// Also write the frame's data as NumPy arrays into DIR, as `cull --export` does (a backend
    /// over a strategy: forward, deferred or deferred-stored-position).
    #[arg(long, value_name = "DIR")]
    pub(crate) export: Option<PathBuf>,
    /// Samples a pixel (MSAA: 1, 2, 4, 8 where the device has them for the depth buffer and
    /// the HDR target; an unsupported count is an error naming the supported ones). Forward
    /// and naive forward shade each fragment once and resolve; the tiles' and clusters' depth
    /// bounds cover every sample; the reference renders at the same count. Deferred lights a
    /// multisampled G-buffer once a pixel, and each sample apart at edges (the stored position
    /// takes no MSAA); the visibility buffer lights each distinct triangle of an edge pixel once.
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub(crate) msaa: u32,
    /// The backend's lit image: f32 (32-bit floats), or f16 (16-bit floats, as engines' HDR
    /// targets: half the bytes the lighting pass writes, each channel rounded to half
    /// precision; the references keep 32 bits, so --compare shows the rounding). Not with
    /// --backend reference.
    #[arg(long, value_enum, default_value_t = HdrName::F32)]
    pub(crate) hdr: HdrName,
    /// How --backend visibility finds each pixel's triangle: compute (the default: a compute
    /// rasteriser, where it can: one sample a pixel, no glass, 64-bit atomic max on the device;
    /// the raster pass elsewhere) or raster (the raster pass always). Only with --backend
    /// visibility.
    #[arg(long, value_enum)]
    pub(crate) visibility_pass: Option<VisibilityPassName>,
    /// Shadows (--shadows, --shadow-rays); --compare's reference is shadowed exactly, its
    /// infinite-range reference not.
    #[command(flatten)]
    pub(crate) shadows: ShadowArgs,
}

/// `--shadows` and `--shadow-rays`, of `render`, `cull` and `tune`.
#[derive(clap::Args, Clone, Copy, Debug)]
pub(crate) struct ShadowArgs {
    /// Shadows: off (the default: every light shines through walls), exact (a shadow ray for
    /// every light that adds radiance at a pixel) or stochastic (--shadow-rays rays a pixel to
    /// lights drawn in proportion to their unshadowed luminance, the ratio estimator: biased,
    /// consistent), through the BVH of the scene's opaque triangles, built after the upload.
    #[arg(long = "shadows", value_enum, default_value_t = ShadowsName::Off)]
    pub(crate) mode: ShadowsName,
    /// Rays a pixel of --shadows stochastic: 1 to 16 (default 4).
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..=16))]
    pub(crate) shadow_rays: Option<u32>,
}

impl ShadowArgs {
    /// The shadows asked for (stochastic: one frame, frame 0's draws).
    pub(crate) fn shadows(self) -> Shadows {
        match self.mode {
            ShadowsName::Off => Shadows::Off,
            ShadowsName::Exact => Shadows::Exact,
            ShadowsName::Stochastic => Shadows::stochastic(self.shadow_rays.unwrap_or(4)),
        }
    }

    /// An error where --shadow-rays is given without --shadows stochastic.
    pub(crate) fn check(self) -> Result<()> {
        if let (Some(k), ShadowsName::Off | ShadowsName::Exact) = (self.shadow_rays, self.mode) {
            anyhow::bail!(
                "--shadow-rays {k} with --shadows {}: rays a pixel are only for --shadows \
                 stochastic",
                self.shadows().name()
            );
        }
        Ok(())
    }
}

/// `--shadows`'s values.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ShadowsName {
    Off,
    Exact,
    Stochastic,
}

/// `--visibility-pass`'s values.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum VisibilityPassName {
    Compute,
    Raster,
}

/// `--hdr`'s values.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum HdrName {
    F32,
    F16,
}

pub(crate) fn render(args: &RenderArgs) -> Result<()> {
    validate(args)?;
    let samples = args.msaa;
    let a = &args.scene;
    let scene = a.build()?;
    let strategy = args.cull.strategy()?;
    let settings = args.cull.settings(&scene.camera)?;
    let ctx = a.gpu()?;
    let (w, h) = (a.width, a.height);
    // With --hierarchy, its lights in place of the scene's, built on the GPU.
    let crate::hierarchy_opt::Shaded {
        scene,
        mut gpu_scene,
        as_they_are,
    } = a.upload(&ctx, scene)?;
    let shadows = args.shadows.shadows();
    if shadows.casts() {
        let bvh = gpu_scene.build_bvh(&ctx, &scene)?;
        println!(
            "shadows {}: the BVH of {} opaque triangles (depth {}) built in {:.1} ms",
            shadows.name(),
            bvh.triangles.len(),
            bvh.depth,
            bvh.build.as_secs_f64() * 1e3
        );
    }
    let draws = a.draws(&ctx, &gpu_scene, &scene)?;
    let frames = a.frames();
    let draw = |f: u32| -> Result<()> {
        if let Some(d) = &draws {
            d.draw(&ctx, f)?;
        }
        Ok(())
    };
    let dir = a.out.clone().unwrap_or_else(|| PathBuf::from("out/render"));
    println!(
        "{}: {} triangles, {} lights, {w}x{h}{}",
        scene.name,
        scene.triangle_count(),
        scene.lights.len(),
        if samples > 1 {
            format!(", MSAA {samples} (lights per pixel: the longest list of its samples)")
        } else {
            String::new()
        }
    );
    if draws.is_some() {
        print_stochastic(a, frames);
    }
    let run = Run {
        args,
        ctx: &ctx,
        scene: &scene,
        gpu_scene: &gpu_scene,
        infinite_scene: as_they_are.as_ref().unwrap_or(&gpu_scene),
        strategy: &strategy,
        settings: &settings,
        frames,
        draw: &draw,
        stochastic: draws.is_some(),
    };
    let reference = ReferenceRenderer::with_samples(&ctx, &gpu_scene, samples)
        .map_err(|e| anyhow::anyhow!("invalid --msaa {samples}: {e}"))?
        .with_shadows(&ctx, &gpu_scene, shadows);
    let mut outputs: Vec<(PathBuf, image::RgbImage)> = Vec::new();
    let (name, image) = if args.backend == BackendName::Reference {
        let (mean, last) = reference_frames(&ctx, &reference, &gpu_scene, (w, h), frames, &draw)?;
        print_timings(last.timings.as_deref());
        ("reference", mean)
    } else {
        let (name, image, heat) = run.backend(&dir)?;
        outputs.push(heat);
        (name, image)
    };
    let bad = image.non_finite_count();
    if bad > 0 {
        bail!("the render holds {bad} NaN/Inf pixels; nothing was written");
    }
    if args.compare {
        if let Some(flip) = run.compare(&reference, &image)? {
            outputs.push((dir.join(format!("flip_{name}.png")), flip));
        }
    }
    let png = dir.join(format!("{name}.png"));
    let exr = dir.join(format!("{name}.exr"));
    image.write_exr(&exr)?;
    image.write_png(&png, args.exposure)?;
    for (path, img) in &outputs {
        write_atomic(path, |f| {
            img.write_to(f, image::ImageFormat::Png)
                .map_err(|e| e.to_string())
        })?;
        println!("wrote {}", path.display());
    }
    println!("wrote {} and {}", png.display(), exr.display());
    Ok(())
}

/// What every stage of a `render` run reads.
struct Run<'a> {
    args: &'a RenderArgs,
    ctx: &'a GpuContext,
    scene: &'a manylights_scene::Scene,
    gpu_scene: &'a GpuScene,
    /// The lights as they are (with --hierarchy, not the shaded ones): the infinite-range
    /// reference's.
    infinite_scene: &'a GpuScene,
    strategy: &'a manylights_cull::Strategy,
    settings: &'a manylights_cull::CullSettings,
    frames: u32,
    draw: &'a dyn Fn(u32) -> Result<()>,
    stochastic: bool,
}

/// The options that cannot go together, refused before any work.
fn validate(args: &RenderArgs) -> Result<()> {
    // The strategy's own options first: those it would ignore name the strategies that read them.
    args.cull.strategy()?;
    args.shadows.check()?;
    if !(args.exposure.is_finite() && args.exposure > 0.0) {
        bail!("invalid --exposure {}: a finite value > 0", args.exposure);
    }
    if args.export.is_some()
        && matches!(
            args.backend,
            BackendName::Reference | BackendName::NaiveForward
        )
    {
        bail!(
            "--export needs lists: use --backend forward, deferred or deferred-stored-position \
             (--backend {} culls nothing)",
            backend_name(args.backend)
        );
    }
    if args.hdr == HdrName::F16 && args.backend == BackendName::Reference {
        bail!(
            "--hdr f16 with --backend reference: the reference keeps 32 bits (a backend, such \
             as --backend deferred, or --hdr f32)"
        );
    }
    if args.scene.glass && args.export.is_some() {
        bail!(
            "--export with --glass: exports hold one depth a pixel, not glass; export without --glass"
        );
    }
    if args.msaa > 1 && args.export.is_some() {
        bail!(
            "--export with --msaa {}: exports hold one depth a pixel; export without --msaa",
            args.msaa
        );
    }
    if args.visibility_pass.is_some() && args.backend != BackendName::Visibility {
        bail!(
            "--visibility-pass is read only by --backend visibility; --backend {} would ignore it",
            backend_name(args.backend)
        );
    }
    if matches!(
        args.backend,
        BackendName::Reference | BackendName::NaiveForward
    ) && let Some(option) = args.cull.culling_option_given()
    {
        bail!(
            "{option} is read only by a backend that culls (forward, deferred,              deferred-stored-position, visibility); --backend {} culls nothing and would ignore it",
            backend_name(args.backend)
        );
    }
    if args.msaa > 1 && args.backend == BackendName::DeferredStoredPosition {
        bail!(
            "invalid --msaa {} with --backend deferred-stored-position: the stored \
             position takes no MSAA (use --backend deferred, forward, naive-forward or \
             reference, or --msaa 1)",
            args.msaa
        );
    }
    Ok(())
}

/// `backend` as `--backend` names it.
fn backend_name(backend: BackendName) -> String {
    clap::ValueEnum::to_possible_value(&backend)
        .map_or_else(String::new, |v| v.get_name().to_owned())
}

impl Run<'_> {
    /// The backend's frames over the strategy: their mean image, its name, and the
    /// lights-per-pixel heatmap of the last frame (whose lists, counts and exports are
    /// printed and written).
    fn backend(
        &self,
        dir: &std::path::Path,
    ) -> Result<(&'static str, HdrImage, (PathBuf, image::RgbImage))> {
        let Run {
            args,
            ctx,
            scene,
            gpu_scene,
            frames,
            draw,
            ..
        } = *self;
        let (w, h) = (args.scene.width, args.scene.height);
        let samples = args.msaa;
        let (strategy, settings) = (self.strategy, self.settings);
        let hdr = match args.hdr {
            HdrName::F32 => HdrFormat::F32,
            HdrName::F16 => HdrFormat::F16,
        };
        let backend = match args.backend {
            BackendName::Forward => Backend::Forward,
            BackendName::Deferred => Backend::Deferred,
            BackendName::DeferredStoredPosition => Backend::DeferredStoredPosition,
            BackendName::Visibility => Backend::Visibility,
            BackendName::NaiveForward | BackendName::Reference => Backend::NaiveForward,
        };
        let mut renderer = Renderer::with_format(ctx, gpu_scene, samples, hdr)
            .map_err(|e| anyhow::anyhow!("invalid --msaa {samples}: {e}"))?
            .with_shadows(args.shadows.shadows());
        renderer.visibility_pass = match args.visibility_pass {
            None | Some(VisibilityPassName::Compute) => VisibilityPass::Compute,
            Some(VisibilityPassName::Raster) => VisibilityPass::Raster,
        };
        // With --accumulate, the frames' mean; lists, counts and exports are the last
        // frame's (whose ranges the lights hold afterwards).
        let mut sum = ImageSum::default();
        let mut last = None;
        for f in 0..frames {
            draw(f)?;
            let out = renderer.render(ctx, gpu_scene, backend, strategy, settings, (w, h))?;
            sum.add(&out.color);
            last = Some(out);
        }
        let out = last.expect("at least one frame");
        if frames > 1 {
            println!(
                "  (lists, counts and timings: frame {} of {frames})",
                frames - 1
            );
        }
        if backend != Backend::NaiveForward {
            println!("  strategy {strategy:?}");
        }
        print_timings(out.timings.as_deref());
        let per_pixel: Vec<u32> = match &out.lists {
            Some(lists) => renderer
                .culler
                .lights_per_pixel(ctx, gpu_scene, &out.depth, lists)?,
            None => out
                .color
                .data
                .iter()
                .map(|c| {
                    if c[3] > 0.0 {
                        scene.lights.len() as u32
                    } else {
                        0
                    }
                })
                .collect(),
        };
        if let Some(lists) = &out.lists {
            println!(
                "  list entries / bytes    {} / {}",
                lists.total,
                lists.list_bytes()
            );
            println!("  dropped lights          {}", lists.dropped);
        }
        if out.gbuffer_bytes > 0 {
            if out.computed_visibility() {
                println!(
                    "  visibility buffer bytes {} (compute rasteriser: keys, ids, depths)",
                    out.gbuffer_bytes
                );
            } else if out.backend == Backend::Visibility {
                println!("  visibility buffer bytes {}", out.gbuffer_bytes);
            } else {
                println!("  G-buffer bytes          {}", out.gbuffer_bytes);
            }
        }
        let covered = out.color.data.iter().filter(|c| c[3] > 0.0).count().max(1);
        let max = per_pixel.iter().copied().max().unwrap_or(0).max(1);
        let mean = per_pixel.iter().map(|&n| f64::from(n)).sum::<f64>() / covered as f64;
        println!("  lights per pixel        {mean:.2} (mean over covered pixels), {max} at most");
        if renderer.shadows().casts() {
            // The last frame again, its rays counted (frames that are timed count none).
            let rays = gpu_scene.count_rays(ctx, (&scene.camera, w, h), || {
                renderer
                    .render(ctx, gpu_scene, backend, strategy, settings, (w, h))
                    .map(|_| ())
            })?;
            println!(
                "  shadow rays             {rays} ({:.2} a covered pixel)",
                rays as f64 / covered as f64
            );
        }
        if let (Some(export), Some(lists)) = (&args.export, &out.lists) {
            let frame = manylights_gpu::layout::GpuFrame::new(
                &scene.camera,
                w,
                h,
                scene.lights.len() as u32,
            );
            let run = manylights_lab::export::RunToExport {
                ctx,
                culler: &renderer.culler,
                scene: gpu_scene,
                depth: &out.depth,
                lists,
                frame: &frame,
                strategy: strategy.name(),
            };
            let files = manylights_lab::export::export_run(&run, export)?;
            println!("exported {} files to {}", files.len(), export.display());
        }
        let heat = dir.join(format!("heatmap_lights_per_pixel_{}.png", backend.name()));
        Ok((
            backend.name(),
            sum.mean().expect("at least one frame"),
            (heat, heatmap::pixels(&per_pixel, w, h, max)),
        ))
    }

    /// `--compare`: the errors against the reference over the same draws and against
    /// infinite range, printed; with `--flip-map`, FLIP's map against the reference.
    fn compare(
        &self,
        reference: &ReferenceRenderer,
        image: &HdrImage,
    ) -> Result<Option<image::RgbImage>> {
        let Run {
            args,
            ctx,
            scene,
            gpu_scene,
            infinite_scene,
            frames,
            draw,
            ..
        } = *self;
        let (w, h) = (args.scene.width, args.scene.height);
        // The reference over the same frames' draws (the same estimate, no culling), then
        // infinite range (no draws: ranges do not enter it).
        let (windowed, windowed_frame) =
            reference_frames(ctx, reference, gpu_scene, (w, h), frames, draw)?;
        let infinite = manylights_shade::infinite::infinite_image(
            ctx,
            (
                reference,
                &manylights_shade::InfiniteReference::new(ctx, infinite_scene),
            ),
            infinite_scene,
            &scene.camera,
            (w, h),
            Some(&windowed_frame),
        )?;
        // The same cut-off at the output's exposure; infinite range at the exposure adapted
        // to its reference (accuracy::exposure_of).
        let cutoff = if self.stochastic {
            "reference (same draws)"
        } else if args.scene.hierarchy.is_some() {
            "reference (same hierarchy)"
        } else {
            "reference"
        };
        if frames > 1 {
            println!("  errors of the mean of {frames} frames:");
        }
        for (label, r, exposure) in [
            (cutoff, &windowed, args.exposure),
            (
                "infinite-range reference",
                &infinite,
                accuracy::exposure_of(&infinite),
            ),
        ] {
            let e = accuracy::compare(image, r, exposure);
            println!(
                "  vs {label:<25} max abs {:.3e} ({:.2e} of peak), RMSE {:.3e}, PSNR {:.2} dB, mean FLIP {:.5} (exposure {:.3}), energy {:+.4}",
                e.max_abs_error,
                e.max_abs_error / e.peak.max(f64::MIN_POSITIVE),
                e.rmse,
                e.psnr_db,
                e.flip_mean,
                e.exposure,
                e.energy_error
            );
        }
        Ok(args
            .flip_map
            .then(|| accuracy::flip_map(image, &windowed, args.exposure)))
    }
}

/// The brute-force reference over frames `0..frames`, each after `draw` drew its ranges: the
/// frames' mean image and the last frame (its surfaces, which the infinite-range reference
/// reads, and its timings).
fn reference_frames(
    ctx: &GpuContext,
    reference: &ReferenceRenderer,
    gpu_scene: &GpuScene,
    (w, h): (u32, u32),
    frames: u32,
    draw: &dyn Fn(u32) -> Result<()>,
) -> Result<(HdrImage, ReferenceFrame)> {
    let mut sum = ImageSum::default();
    let mut last = None;
    for f in 0..frames.max(1) {
        draw(f)?;
        let frame = reference.render(ctx, gpu_scene, w, h)?;
        sum.add(&frame.color);
        last = Some(frame);
    }
    Ok((
        sum.mean().expect("at least one frame"),
        last.expect("at least one frame"),
    ))
}

/// `--stochastic`'s settings, as a line of the output.
fn print_stochastic(a: &SceneArgs, frames: u32) {
    let RadiusRule::Stochastic {
        error,
        bound,
        interleave,
        draw,
        ..
    } = a.light_spec().radius
    else {
        return;
    };
    // Interleaved classes draw one hash each, whatever --draw says.
    let draws = if interleave > 1 {
        String::new()
    } else {
        format!(", {} draws", draw.name())
    };
    println!(
        "  stochastic light culling: error {error} ({} bound{draws}), {frames} frame{} drawn{}{}",
        bound.name(),
        if frames > 1 { "s" } else { "" },
        if frames > 1 { " and averaged" } else { "" },
        if interleave > 1 {
            format!(", {interleave} x {interleave} interleaved classes")
        } else {
            String::new()
        }
    );
}
