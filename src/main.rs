//! `manylights`: the command-line front end.
//!
//! Exit codes: 0 success; 1 a run failed (bad input values, a malformed scene file, no usable
//! GPU adapter, a device error, an unwritable output); 2 the command line itself is malformed
//! (unknown option, unparsable number, value outside an option's range).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand, ValueEnum};
use manylights_gpu::{GpuContext, GpuOptions, GpuScene};
use manylights_scene::gltf_import::{self, GltfOptions};
use manylights_scene::procedural::{self, ProceduralScene};
use manylights_scene::{LightGenerator, LightSpec, RadiusRule, Scene};
use manylights_shade::ReferenceRenderer;

/// Light-culling research workbench: culling strategies and shading backends on wgpu,
/// measured for speed and for exactness against a brute-force reference.
#[derive(Parser, Debug)]
#[command(name = "manylights", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene with the brute-force reference renderer (every light at every pixel, no
    /// culling) and write the HDR image (EXR) and a tonemapped PNG.
    ///
    /// Lights are generated deterministically from --seed and added to any lights the scene
    /// holds (glTF KHR_lights_punctual). The output files are written atomically: a failed run
    /// leaves no partial file.
    Render(RenderArgs),
}

#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
struct RenderArgs {
    /// A procedural scene (atrium, pillars, topdown, city) or a path to a .gltf/.glb file.
    #[arg(long, default_value = "atrium")]
    scene: String,
    /// Number of lights to generate (0 renders only the scene's own lights).
    #[arg(long, default_value_t = 1024)]
    lights: u32,
    /// Where lights are placed.
    #[arg(long, value_enum, default_value_t = Generator::Field)]
    generator: Generator,
    /// Seed of every random choice of the light generator.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Fixed light radius in metres (the light contributes exactly nothing beyond it).
    #[arg(long, default_value_t = 3.0, conflicts_with = "threshold")]
    radius: f32,
    /// Derive each radius from its intensity instead: the distance where intensity / d^2 falls
    /// to this threshold.
    #[arg(long)]
    threshold: Option<f32>,
    /// Intensity of every generated light.
    #[arg(long, default_value_t = 4.0)]
    intensity: f32,
    /// Fraction of generated lights that are spot lights, in [0, 1].
    #[arg(long, default_value_t = 0.0)]
    spot_fraction: f32,
    /// Image width in pixels (at most the device's max_texture_dimension_2d).
    #[arg(long, default_value_t = 1280, value_parser = clap::value_parser!(u32).range(1..=65536))]
    width: u32,
    /// Image height in pixels (at most the device's max_texture_dimension_2d).
    #[arg(long, default_value_t = 720, value_parser = clap::value_parser!(u32).range(1..=65536))]
    height: u32,
    /// Exposure applied before tonemapping the PNG.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Output directory (created if needed).
    #[arg(long, default_value = "out/render")]
    out: PathBuf,
    /// GPU adapter: a substring of its name or its index (default: $MANYLIGHTS_ADAPTER, else the
    /// first discrete GPU, else any adapter, lavapipe included).
    #[arg(long)]
    adapter: Option<String>,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum Generator {
    /// Uniform in the scene's light volume.
    Uniform,
    /// On the scene's surfaces, lifted 0.1 m along the normal.
    Surface,
    /// Eight Gaussian hot spots of 1.5 m standard deviation.
    Clustered,
    /// A stratified field through the whole volume (the Forward+ paper's demo).
    Field,
}

fn load_scene(name: &str) -> Result<Scene> {
    let looks_like_file = name.ends_with(".gltf") || name.ends_with(".glb") || name.contains('/');
    if looks_like_file {
        let (scene, report) =
            gltf_import::load(std::path::Path::new(name), &GltfOptions::default())?;
        if report.skipped_primitives + report.skipped_directional_lights > 0 {
            eprintln!(
                "note: {name}: skipped {} point/line primitives and {} directional lights (not supported)",
                report.skipped_primitives, report.skipped_directional_lights
            );
        }
        Ok(scene)
    } else {
        ProceduralScene::from_name(name)
            .with_context(|| {
                format!(
                    "--scene {name}: not a file path (.gltf/.glb) and not one of {}",
                    procedural::NAMES.join(", ")
                )
            })?
            .build()
            .map_err(Into::into)
    }
}

fn render(args: &RenderArgs) -> Result<()> {
    if !(args.exposure.is_finite() && args.exposure > 0.0) {
        bail!("invalid --exposure {}: a finite value > 0", args.exposure);
    }
    let mut scene = load_scene(&args.scene)?;
    let spec = LightSpec {
        generator: match args.generator {
            Generator::Uniform => LightGenerator::Uniform,
            Generator::Surface => LightGenerator::SurfaceHugging { offset: 0.1 },
            Generator::Clustered => LightGenerator::Clustered {
                clusters: 8,
                spread: 1.5,
            },
            Generator::Field => LightGenerator::LightField,
        },
        count: args.lights,
        seed: args.seed,
        radius: args
            .threshold
            .map_or(RadiusRule::Fixed(args.radius), RadiusRule::Threshold),
        intensity: args.intensity,
        spot_fraction: args.spot_fraction,
        ..LightSpec::default()
    };
    let generated = spec
        .generate(&scene)
        .context("invalid light options (--radius, --threshold, --intensity, --spot-fraction)")?;
    scene.lights.extend(generated);
    scene
        .validate()
        .with_context(|| format!("scene {}", scene.name))?;

    let ctx = GpuContext::new(&GpuOptions {
        adapter: args.adapter.clone(),
    })?;
    eprintln!("adapter: {}", ctx.summary());
    ctx.check_resolution(args.width, args.height)
        .context("invalid --width/--height")?;
    let gpu_scene = GpuScene::upload(&ctx, &scene, &scene.camera, args.width, args.height)?;
    let renderer = ReferenceRenderer::new(&ctx, &gpu_scene);
    let frame = renderer.render(&ctx, &gpu_scene, args.width, args.height)?;
    let bad = frame.color.non_finite_count();
    if bad > 0 {
        bail!("the render holds {bad} NaN/Inf pixels; nothing was written");
    }
    let png = args.out.join("reference.png");
    let exr = args.out.join("reference.exr");
    frame.color.write_exr(&exr)?;
    frame.color.write_png(&png, args.exposure)?;
    println!(
        "{}: {} triangles, {} lights, {}x{}",
        scene.name,
        scene.triangle_count(),
        scene.lights.len(),
        args.width,
        args.height
    );
    match &frame.timings {
        Some(t) => {
            for p in t {
                println!("  {:<18} {:>8} {:>10.3} ms", p.label, p.kind.as_str(), p.ms);
            }
        }
        None => println!("  (no GPU timings: the adapter has no timestamp queries)"),
    }
    println!("wrote {} and {}", png.display(), exr.display());
    Ok(())
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Render(args) => render(args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
