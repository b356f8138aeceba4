//! CPU-side benchmarks: scene and light generation, each strategy's CPU oracle, per-frame
//! command encoding and uploading light data. Named after what they time (`scene.atrium`,
//! `lights.<generator>`, `cull.<strategy>.cpu`, `encode.<backend>`, `upload.lights`).
//! `MANYLIGHTS_BENCH_QUICK=1` shrinks the sizes for a smoke run.

mod common;

use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use manylights_cull::{CullSettings, Strategy, cpu};
use manylights_gpu::layout::{GpuFrame, GpuLight};
use manylights_gpu::prepass::{DepthPrepass, depth_target};
use manylights_gpu::timing::GpuTimer;
use manylights_gpu::{GpuScene, readback};
use manylights_scene::procedural::ProceduralScene;
use manylights_scene::{LightGenerator, LightSpec, RadiusRule};
use manylights_shade::{Backend, Renderer};

use common::{configure, gpu, quick};

fn counts() -> Vec<u32> {
    if quick() {
        vec![1024, 16_384]
    } else {
        vec![1024, 16_384, 262_144, 1_048_576]
    }
}

fn generation(c: &mut Criterion) {
    let mut g = c.benchmark_group("scene.atrium");
    configure(&mut g);
    g.bench_function("build", |b| {
        b.iter(|| {
            ProceduralScene::from_name("atrium")
                .unwrap()
                .build()
                .unwrap()
        })
    });
    g.finish();
    let scene = ProceduralScene::from_name("atrium")
        .unwrap()
        .build()
        .unwrap();
    for (name, generator) in [
        ("uniform", LightGenerator::Uniform),
        ("light_field", LightGenerator::LightField),
        ("surface", LightGenerator::SurfaceHugging { offset: 0.1 }),
    ] {
        let mut g = c.benchmark_group(format!("lights.{name}"));
        configure(&mut g);
        for n in counts() {
            g.throughput(Throughput::Elements(u64::from(n)));
            let spec = LightSpec {
                generator,
                count: n,
                radius: RadiusRule::Fixed(0.5),
                ..LightSpec::default()
            };
            g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
                b.iter(|| spec.generate(&scene).unwrap())
            });
        }
        g.finish();
    }
}

fn oracles(c: &mut Criterion) {
    let ctx = gpu();
    let (w, h, n) = if quick() {
        (80, 45, 256)
    } else {
        (320, 180, 4096)
    };
    let mut scene = ProceduralScene::from_name("atrium")
        .unwrap()
        .build()
        .unwrap();
    scene.lights = LightSpec {
        count: n,
        radius: RadiusRule::Fixed(1.0),
        ..LightSpec::default()
    }
    .generate(&scene)
    .unwrap();
    let gs = GpuScene::upload(&ctx, &scene, &scene.camera, w, h).unwrap();
    let depth_tex = depth_target(&ctx, w, h);
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    DepthPrepass::new(&ctx, &gs).encode(
        &mut enc,
        &gs,
        &depth_tex.create_view(&Default::default()),
        &mut GpuTimer::new(&ctx, 1),
    );
    ctx.submit_and_wait(enc, "bench prepass").unwrap();
    let depth: Vec<f32> = bytemuck::pod_collect_to_vec(
        &readback::read_texture(&ctx, &depth_tex, wgpu::TextureAspect::DepthOnly).unwrap(),
    );
    let frame = GpuFrame::new(&scene.camera, w, h, n);
    let lights: Vec<GpuLight> = scene.lights.iter().map(GpuLight::from).collect();
    let settings = CullSettings::for_camera(&scene.camera);
    for s in Strategy::defaults() {
        let p = s.params(w, h, n, &settings);
        let mut g = c.benchmark_group(format!("cull.{}.cpu", s.name()));
        configure(&mut g);
        g.bench_function(BenchmarkId::from_parameter(format!("{w}x{h}/{n}")), |b| {
            b.iter(|| match s {
                Strategy::Clustered { .. } => cpu::clustered(
                    &frame,
                    &p,
                    &lights,
                    &cpu::occupancy(&frame, &p, &depth, w, h),
                ),
                Strategy::TiledScatter { .. } => cpu::scatter(
                    &frame,
                    &p,
                    &lights,
                    &cpu::depth_bounds(&frame, &p, &depth, w, h).0,
                ),
                Strategy::ZBin { .. } => cpu::zbin_lists(
                    &frame,
                    &p,
                    &lights,
                    &cpu::depth_bounds(&frame, &p, &depth, w, h).0,
                    &cpu::zbin_order(&frame, &p, &lights),
                ),
                _ => cpu::gather(
                    &frame,
                    &p,
                    &lights,
                    &cpu::depth_bounds(&frame, &p, &depth, w, h).0,
                ),
            })
        });
        g.finish();
    }
}

fn encoding_and_upload(c: &mut Criterion) {
    let ctx = gpu();
    let (w, h) = if quick() { (80, 45) } else { (1920, 1080) };
    let mut scene = ProceduralScene::from_name("atrium")
        .unwrap()
        .build()
        .unwrap();
    scene.lights = LightSpec {
        count: 1024,
        ..LightSpec::default()
    }
    .generate(&scene)
    .unwrap();
    let gs = GpuScene::upload(&ctx, &scene, &scene.camera, w, h).unwrap();
    let renderer = Renderer::new(&ctx, &gs);
    let settings = CullSettings::for_camera(&scene.camera);
    for backend in [Backend::Forward, Backend::Deferred, Backend::NaiveForward] {
        let mut g = c.benchmark_group(format!("encode.{}", backend.name()));
        configure(&mut g);
        g.bench_function(BenchmarkId::from_parameter(format!("{w}x{h}/1024")), |b| {
            b.iter_custom(|iters| {
                let mut total = 0.0;
                for _ in 0..iters {
                    ctx.take_encode_ms();
                    renderer
                        .render(
                            &ctx,
                            &gs,
                            backend,
                            &Strategy::tiled_gather(16),
                            &settings,
                            (w, h),
                        )
                        .unwrap();
                    total += ctx.take_encode_ms();
                }
                Duration::from_secs_f64(total * 1e-3)
            })
        });
        g.finish();
    }
    let mut g = c.benchmark_group("upload.lights");
    configure(&mut g);
    for n in counts() {
        let lights: Vec<GpuLight> = (0..n)
            .map(|i| GpuLight {
                radius: 1.0 + i as f32 * 1e-6,
                ..bytemuck::Zeroable::zeroed()
            })
            .collect();
        let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: u64::from(n) * 64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        g.throughput(Throughput::Bytes(u64::from(n) * 64));
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter_custom(|iters| {
                let t = Instant::now();
                for _ in 0..iters {
                    ctx.queue
                        .write_buffer(&buf, 0, bytemuck::cast_slice(&lights));
                    ctx.submit_and_wait(
                        ctx.device.create_command_encoder(&Default::default()),
                        "upload",
                    )
                    .unwrap();
                }
                t.elapsed()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, generation, oracles, encoding_and_upload);
criterion_main!(benches);
