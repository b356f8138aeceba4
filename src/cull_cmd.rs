//! `cull`: one strategy's lists against the exact per-pixel oracle, heatmaps, and with
//! `--repeat` steady-state timings.

use std::path::PathBuf;

use anyhow::{Result, bail};
use manylights_cull::metrics::{self, ListMetrics};
use manylights_cull::{CullOutput, CullSettings, Culler, heatmap};
use manylights_gpu::lookup_bounds::{BoundsTargets, LookupBounds};
use manylights_gpu::prepass::{DepthPrepass, depth_target_msaa};
use manylights_gpu::stochastic::StochasticRanges;
use manylights_gpu::timing::{GpuTimer, MAX_QUERIES};
use manylights_gpu::{GpuContext, GpuScene};
use manylights_shade::image_out::write_atomic;

use crate::options::{SceneArgs, StrategyArgs, print_timings};

#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub(crate) struct CullArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    #[command(flatten)]
    pub(crate) cull: StrategyArgs,
    /// Top of the heatmaps' colour scale (default: the longest list shown), so that heatmaps
    /// of several runs can share one scale.
    #[arg(long)]
    pub(crate) heat_max: Option<u32>,
    /// For clusters, the depth slice the tile heatmap shows (default: the longest list over
    /// all slices of each tile).
    #[arg(long)]
    pub(crate) slice: Option<u32>,
    /// Also time this many runs back to back in one submission (no host round trip between
    /// or inside them, the lists sized from the first run) and print each pass's median over
    /// them: steady-state times, as the benchmarks measure; then the same runs timed with one
    /// pair of timestamps around each run's passes (where the device can write timestamps
    /// between passes), their median as `span`. 0: only the single run.
    #[arg(long, default_value_t = 0)]
    pub(crate) repeat: u32,
    /// Build the lists without tile masks (a bit per tile and light, used where they fit 16
    /// MiB): gather's and 2.5D's fill then tests every light again, and tiled scatter writes
    /// (tile, light) pairs and radix-sorts them, as Harada et al. 2012 describe.
    #[arg(long, conflicts_with = "mask_budget")]
    pub(crate) no_tile_masks: bool,
    /// Most bytes of tile masks the run may use (default: 16 MiB; 0 is --no-tile-masks), as an
    /// experiment's `mask_budget`. The output says whether the run used them.
    #[arg(long, value_name = "BYTES")]
    pub(crate) mask_budget: Option<u64>,
    /// Also write the run's data as NumPy arrays into DIR: the depth buffer, each pixel's
    /// lights needed and evaluated, the lists, the lights and the camera, with a manifest.json
    /// (docs/EXPERIMENTS.md, "Exports").
    #[arg(long, value_name = "DIR")]
    pub(crate) export: Option<PathBuf>,
    /// Samples a pixel of the depth buffer (MSAA: 1, 2, 4, 8 where the device has them; an
    /// unsupported count is an error naming the supported ones). The tiles' and clusters'
    /// depth bounds cover every sample, and the exact oracle checks every covered sample: the
    /// counts printed are then per sample.
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub(crate) msaa: u32,
    /// Culling by visibility after the lists: each bin's list loses the lights one of the
    /// scene's 64 largest opaque convex polygons hides from its whole cell (not with --strategy
    /// zbin). Prints the pairs dropped; the false negatives count against the shadowed exact
    /// set (a light needed where its shadow ray is clear), for which the BVH is built.
    #[arg(long)]
    pub(crate) occlusion: bool,
    /// With shadows (--shadows exact or stochastic), also count the shadow rays that shading
    /// these lists casts: the scene's BVH built, one deferred frame over the same strategy
    /// shaded with the shadows and its rays counted on the GPU.
    #[command(flatten)]
    pub(crate) shadows: crate::render_cmd::ShadowArgs,
}

pub(crate) fn cull(args: &CullArgs) -> Result<()> {
    let a = &args.scene;
    args.shadows.check()?;
    let strategy = args.cull.strategy()?;
    let scene = a.build()?;
    let ctx = a.gpu()?;
    let samples = args.msaa;
    check_samples(&ctx, args)?;
    let (w, h) = (a.width, a.height);
    // With --hierarchy, its lights in place of the scene's, built on the GPU.
    let crate::hierarchy_opt::Shaded {
        scene,
        mut gpu_scene,
        ..
    } = a.upload(&ctx, scene)?;
    if args.shadows.shadows().casts() || args.occlusion {
        gpu_scene.build_bvh(&ctx, &scene)?;
    }
    let draws = a.draws(&ctx, &gpu_scene, &scene)?;
    let frames = a.frames();
    let mut timer = GpuTimer::new(&ctx, 64);
    let (depth, bounds) = depth_prepass(&ctx, &gpu_scene, (w, h), samples, &mut timer)?;
    let culler = culler_for(
        &ctx,
        &gpu_scene,
        bounds.is_some(),
        samples,
        args.occlusion.then_some(&scene),
    );
    let cull_depth = bounds.as_ref().map_or(&depth, |(_, t)| &t.bounds);
    let settings = CullSettings {
        mask_budget: if args.no_tile_masks {
            Some(0)
        } else {
            args.mask_budget
        },
        occlusion: args.occlusion,
        ..args.cull.settings(&scene.camera)?
    };
    let frame =
        manylights_gpu::layout::GpuFrame::new(&scene.camera, w, h, scene.lights.len() as u32);
    // The exact oracle's counts of a run's lists, at every pixel.
    let exact_counts = |out: &CullOutput| {
        culler.exact_counts_with(
            &ctx,
            &gpu_scene,
            &depth,
            out,
            frame.clip_from_world.inverse(),
            1,
            args.occlusion,
        )
    };
    // With --stochastic, each frame's draws culled and checked; the last frame's lists are
    // the ones shown, timed and exported.
    let earlier = earlier_frames(&ctx, draws.as_ref(), frames, || {
        let out = culler.run(
            &ctx,
            &gpu_scene,
            cull_depth,
            &strategy,
            &settings,
            &mut GpuTimer::untimed(),
        )?;
        let counts = exact_counts(&out)?;
        Ok(metrics::from_gpu_counts(&counts, &out.bin_lengths(&ctx)?))
    })?;
    let out = culler.run(
        &ctx, &gpu_scene, cull_depth, &strategy, &settings, &mut timer,
    )?;
    let timings = timer.read(&ctx)?;
    let repeated = if args.repeat > 0 {
        let run = manylights_lab::steady::Repeated {
            ctx: &ctx,
            culler: &culler,
            scene: &gpu_scene,
            depth: cull_depth,
            strategy: &strategy,
            settings: &settings,
            first: &out,
        };
        repeated_timings(&run, timings.as_deref(), args)?
    } else {
        String::new()
    };
    let lengths = out.bin_lengths(&ctx)?;
    let counts = exact_counts(&out)?;
    let m = metrics::from_gpu_counts(&counts, &lengths);
    // Lights evaluated a pixel (with MSAA, the mean over its covered samples).
    let per_pixel: Vec<u32> = counts.iter().map(|c| c[0] / c[3].max(1)).collect();
    let heat = write_heatmaps(args, &strategy, &out, (&lengths, &per_pixel))?;
    println!(
        "{}: {} triangles, {} lights, {w}x{h}{}, {strategy:?}",
        scene.name,
        scene.triangle_count(),
        scene.lights.len(),
        if samples > 1 {
            format!(", MSAA {samples} (counts per covered sample)")
        } else {
            String::new()
        }
    );
    print_points(m.covered_pixels, bounds.is_some(), samples);
    print_earlier(&earlier, frames);
    print_lists(&m, &out, args.occlusion);
    let counts = deferred_counts(&ctx, (&gpu_scene, &scene), (&strategy, &settings), args)?;
    print_counts(counts, &m);
    print_timings(timings.as_deref());
    print!("{repeated}");
    println!("{heat}");
    if let Some(export) = &args.export {
        let run = manylights_lab::export::RunToExport {
            ctx: &ctx,
            culler: &culler,
            scene: &gpu_scene,
            depth: &depth,
            lists: &out,
            frame: &frame,
            strategy: strategy.name(),
        };
        let files = manylights_lab::export::export_run(&run, export)?;
        println!("exported {} files to {}", files.len(), export.display());
    }
    let false_negatives =
        m.false_negatives + earlier.iter().map(|e| e.false_negatives).sum::<u64>();
    if false_negatives > 0 {
        bail!(
            "{false_negatives} false negatives{}: a conservative strategy must have none (a bug, or --slack too small)",
            if frames > 1 {
                format!(" over {frames} frames")
            } else {
                String::new()
            }
        );
    }
    Ok(())
}

/// The tile and pixel heatmaps of a run's lists (`lengths`: each bin's; `per_pixel`: lights
/// evaluated a pixel), written under `--out`, on one scale: what the output line says of them.
fn write_heatmaps(
    args: &CullArgs,
    strategy: &manylights_cull::Strategy,
    out: &CullOutput,
    (lengths, per_pixel): (&[u32], &[u32]),
) -> Result<String> {
    let (w, h) = (args.scene.width, args.scene.height);
    let tiles = heatmap::tile_counts(&out.params, lengths, args.slice);
    let max = args
        .heat_max
        .unwrap_or_else(|| tiles.iter().copied().max().unwrap_or(0).max(1));
    let dir = args
        .scene
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out/cull"));
    let tile_png = dir.join(format!("heatmap_tiles_{}.png", strategy.name()));
    let pixel_png = dir.join(format!("heatmap_pixels_{}.png", strategy.name()));
    let (tile_img, pixel_img) = (
        heatmap::tiles(&out.params, &tiles, w, h, max),
        heatmap::pixels(per_pixel, w, h, max),
    );
    for (path, img) in [(&tile_png, tile_img), (&pixel_png, pixel_img)] {
        write_atomic(path, |f| {
            img.write_to(f, image::ImageFormat::Png)
                .map_err(|e| e.to_string())
        })?;
    }
    Ok(format!(
        "heat scale 0..{max} lights; wrote {} and {}",
        tile_png.display(),
        pixel_png.display()
    ))
}

/// The lights deferred shading walks and the shadow rays it casts ([`deferred_counts`]), each
/// over the covered points and the lights walked over the lights needed too.
fn print_counts((walked, rays): (u64, Option<u64>), m: &ListMetrics) {
    let points = m.covered_pixels.max(1) as f64;
    println!(
        "  lights walked           {walked} ({:.2} a covered point, {:.3} per light needed; deferred shading of the lists)",
        walked as f64 / points,
        walked as f64 / m.needed.max(1) as f64
    );
    if let Some(rays) = rays {
        println!(
            "  shadow rays             {rays} ({:.2} a covered point; deferred shading of the lists)",
            rays as f64 / points
        );
    }
}

/// What one deferred frame shading `strategy`'s lists walks and casts, counted on the GPU over
/// the stochastic ranges the lights hold: the lights its pixels walk
/// (`GpuScene::count_lights_walked`), and with shadows the shadow rays
/// (`GpuScene::count_rays`); with --occlusion, over the lists culling by visibility leaves.
fn deferred_counts(
    ctx: &GpuContext,
    (gpu_scene, scene): (&GpuScene, &manylights_scene::Scene),
    (strategy, settings): (&manylights_cull::Strategy, &CullSettings),
    args: &CullArgs,
) -> Result<(u64, Option<u64>)> {
    use manylights_shade::{Backend, Renderer};
    let (w, h) = (args.scene.width, args.scene.height);
    let camera = &scene.camera;
    let mut renderer =
        Renderer::with_samples(ctx, gpu_scene, args.msaa)?.with_shadows(args.shadows.shadows());
    if args.occlusion {
        renderer
            .culler
            .set_occluders(ctx, &manylights_scene::occluders::of_scene(scene))?;
    }
    let render = || {
        renderer
            .render(
                ctx,
                gpu_scene,
                Backend::Deferred,
                strategy,
                settings,
                (w, h),
            )
            .map(|_| ())
    };
    let walked = gpu_scene.count_lights_walked(ctx, (camera, w, h), render)?;
    let rays = match args.shadows.shadows().casts() {
        true => Some(gpu_scene.count_rays(ctx, (camera, w, h), render)?),
        false => None,
    };
    Ok((walked, rays))
}

/// Draws the stochastic ranges of frames `0..frames` in turn (none without `draws`) and
/// checks each but the last with `check`; the last frame's draw is left for the run shown.
fn earlier_frames(
    ctx: &GpuContext,
    draws: Option<&StochasticRanges>,
    frames: u32,
    mut check: impl FnMut() -> Result<ListMetrics>,
) -> Result<Vec<ListMetrics>> {
    let mut earlier = Vec::new();
    for f in 0..frames {
        if let Some(d) = draws {
            d.draw(ctx, f)?;
        }
        if f + 1 < frames {
            earlier.push(check()?);
        }
    }
    Ok(earlier)
}

/// The frames before the last one's counts, with `--accumulate K`.
/// Checks `--msaa` on the device and against `--export` and `--glass` (exports hold one depth
/// a pixel).
fn check_samples(ctx: &GpuContext, args: &CullArgs) -> Result<()> {
    let samples = args.msaa;
    if args.scene.glass && args.export.is_some() {
        bail!(
            "--export with --glass: exports hold one depth a pixel, not glass; export without --glass"
        );
    }
    ctx.check_msaa(samples)
        .map_err(|e| anyhow::anyhow!("invalid --msaa {samples}: {e}"))?;
    if samples > 1 && args.export.is_some() {
        bail!(
            "--export with --msaa {samples}: exports hold one depth a pixel; export without --msaa"
        );
    }
    Ok(())
}

/// The depth prepass of `gpu_scene` at `size` and `samples`, submitted, timed by `timer`; over
/// transparent surfaces with the lookup bounds culling reads, as the forward backend culls
/// them (from the nearest glass to the opaque surface, where the exact oracle also checks
/// every visible glass fragment).
/// The points the exact oracle checked: with lookup bounds (`bounds`) covered samples and
/// visible transparent fragments, with MSAA covered samples, else covered pixels.
fn print_points(points: u64, bounds: bool, samples: u32) {
    if bounds {
        println!("  shaded points           {points}");
    } else if samples > 1 {
        println!("  covered samples         {points}");
    } else {
        println!("  covered pixels          {points}");
    }
}

/// The culler of a run: over the lookup bounds (`bounds`) or the depth buffer of `samples`
/// samples, with `occluders_of`'s occluders for culling by visibility.
fn culler_for(
    ctx: &GpuContext,
    gpu_scene: &GpuScene,
    bounds: bool,
    samples: u32,
    occluders_of: Option<&manylights_scene::Scene>,
) -> Culler {
    let mut culler = if bounds {
        Culler::with_bounds(ctx, gpu_scene, samples)
    } else {
        Culler::with_samples(ctx, gpu_scene, samples)
    };
    if let Some(scene) = occluders_of {
        culler
            .set_occluders(ctx, &manylights_scene::occluders::of_scene(scene))
            .expect("of_scene takes at most OCCLUDERS_MAX");
    }
    culler
}

fn depth_prepass(
    ctx: &GpuContext,
    gpu_scene: &GpuScene,
    (w, h): (u32, u32),
    samples: u32,
    timer: &mut GpuTimer,
) -> Result<(wgpu::Texture, Option<(LookupBounds, BoundsTargets)>)> {
    let depth = depth_target_msaa(ctx, w, h, samples);
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    let depth_view = depth.create_view(&Default::default());
    let bounds = gpu_scene.has_transparent().then(|| {
        let b = LookupBounds::new(ctx, gpu_scene, samples);
        let t = b.targets(ctx, (w, h), &depth, true);
        (b, t)
    });
    match &bounds {
        Some((b, t)) if b.has_prepass() => {
            b.encode_prepass(&mut enc, gpu_scene, &depth_view, t, timer)
        }
        _ => DepthPrepass::with_samples(ctx, gpu_scene, samples).encode(
            &mut enc,
            gpu_scene,
            &depth_view,
            timer,
        ),
    }
    if let Some((b, t)) = &bounds {
        b.encode_bounds(&mut enc, gpu_scene, t, b.has_prepass(), timer);
    }
    ctx.submit_and_wait(enc, "depth prepass")?;
    Ok((depth, bounds))
}

/// The lists' measures: false negatives, false positives, lengths, bytes, drops, tile masks
/// (and, with `occlusion`, the pairs culling by visibility dropped).
fn print_lists(m: &ListMetrics, out: &CullOutput, occlusion: bool) {
    println!("  false negatives         {}", m.false_negatives);
    match m.false_positive_ratio {
        Some(r) => println!("  false-positive ratio    {r:.3} (lights evaluated / lights needed)"),
        None => println!("  false-positive ratio    n/a (no pixel needs a light)"),
    }
    println!("  lights per pixel        {:.2}", m.lights_per_pixel_mean);
    println!("  max lights per bin      {}", m.max_lights_per_bin);
    println!(
        "  list entries / bytes    {} / {}",
        out.total,
        out.list_bytes()
    );
    println!("  dropped lights          {}", out.dropped);
    println!(
        "  tile masks              {}",
        match (&out.tile_masks, &out.tile_lines) {
            (Some(m), _) => format!("used ({} bytes)", m.size()),
            (None, Some(l)) => format!("used as tile lines ({} bytes)", l.size()),
            (None, None) => "not used".into(),
        }
    );
    if occlusion {
        println!(
            "  occluded pairs          {} (bin, light) pairs dropped by culling by visibility \
             (the false negatives: against the shadowed exact set)",
            out.occluded
        );
    }
}

fn print_earlier(earlier: &[ListMetrics], frames: u32) {
    if frames <= 1 {
        return;
    }
    println!(
        "  stochastic ranges       {frames} frames drawn; the counts below are frame {}'s",
        frames - 1
    );
    for (f, e) in earlier.iter().enumerate() {
        println!(
            "  frame {f:<4}              false negatives {}, lights per pixel {:.2}, false-positive ratio {}",
            e.false_negatives,
            e.lights_per_pixel_mean,
            e.false_positive_ratio
                .map_or_else(|| "n/a".into(), |r| format!("{r:.3}"))
        );
    }
}

/// `cull --repeat N`: N runs of `run` back to back in one submission; each pass's median over
/// them, as lines to print. `timings`: the first run's frame (its depth prepass and culling),
/// none without timestamp queries.
pub(crate) fn repeated_timings(
    run: &manylights_lab::steady::Repeated<'_>,
    timings: Option<&[manylights_gpu::timing::PassTiming]>,
    args: &CullArgs,
) -> Result<String> {
    use std::fmt::Write as _;
    let n = args.repeat;
    let Some(timings) = timings else {
        return Ok("  (no GPU timings: the adapter has no timestamp queries)\n".into());
    };
    // The culling passes of the first run (the others are the prepass, a raster pass, and the
    // lookup bounds', `prepass.*`).
    let passes = timings
        .iter()
        .filter(|p| {
            p.kind == manylights_gpu::timing::PassKind::Compute && !p.label.starts_with("prepass.")
        })
        .count() as u32;
    let most = manylights_lab::steady::max_runs(passes);
    if n > most {
        bail!(
            "invalid --repeat {n}: this strategy runs {passes} passes, and one timer holds {} \
             passes, so at most {most} runs",
            MAX_QUERIES / 2
        );
    }
    let s = manylights_lab::steady::steady_cull(run, passes, n)?
        .expect("timestamps were there for the first run");
    let mut lines = format!("  {n} runs back to back (median per pass):\n");
    for p in &s.passes {
        writeln!(
            lines,
            "  {:<28} {:>8} {:>10.3} ms",
            p.label,
            p.kind.as_str(),
            p.ms
        )?;
    }
    writeln!(
        lines,
        "  {:<28} {:>8} {:>10.3} ms",
        "total (median run)", "", s.total_ms
    )?;
    // The same runs again with one pair of timestamps around each run's passes, none between
    // them: the run as a frame waits for it, clears and gaps between passes included.
    if let Some(span) = s.span_ms {
        writeln!(
            lines,
            "  {:<28} {:>8} {span:>10.3} ms",
            "span (one timestamp pair)", ""
        )?;
    }
    Ok(lines)
}
