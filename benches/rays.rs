//! Shadow rays a second through the BVH of a scene's opaque triangles (`manylights_gpu::bvh`):
//! `rays.shadow/<scene>/<rays>`, the GPU time of the pass `shadow_rays.trace` (timestamps,
//! returned to criterion through `iter_custom`; criterion's throughput is then rays a second).
//! Segments as shading casts them: from points 1-5 cm off the scene's surfaces to fixtures (the
//! real scenes' lights), paired at random; half of them blocked or more in an interior. The BVH's
//! build and the rays' upload stay outside the measurement.
//!
//! `MANYLIGHTS_BENCH_QUICK=1` shrinks the ray counts for a smoke run on lavapipe; figures come
//! only from the GPU machine.

mod common;

use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use manylights_gpu::bvh::{GpuBvh, SceneBvh, ShadowRays};
use manylights_scene::generate::places;
use manylights_scene::gltf_import::GltfOptions;
use manylights_scene::procedural::ProceduralScene;
use manylights_scene::{LightGenerator, Scene, real};

use common::{configure, gpu, quick};

fn points(scene: &Scene, generator: LightGenerator, n: u32, seed: u64) -> Vec<Vec3> {
    places(scene, generator, n, seed).expect("lights")
}

fn shadow(c: &mut Criterion) {
    let ctx = gpu();
    let pass = ShadowRays::new(&ctx);
    let rays_n: u32 = if quick() { 4096 } else { 1 << 20 };
    let mut scenes: Vec<Scene> = vec![
        ProceduralScene::from_name("atrium")
            .unwrap()
            .build()
            .unwrap(),
    ];
    let real_names: &[&str] = if quick() {
        &["sponza"]
    } else {
        &["sponza", "kitchen"]
    };
    for name in real_names {
        scenes.push(
            real::load(name, &GltfOptions::default())
                .expect("a real scene")
                .0,
        );
    }
    let mut g = c.benchmark_group("rays.shadow");
    configure(&mut g);
    for scene in &scenes {
        let bvh = SceneBvh::build(scene).expect("the BVH");
        let gpu_bvh = GpuBvh::upload(&ctx, &bvh).expect("the BVH's upload");
        let from = points(
            scene,
            LightGenerator::OnSurfaces {
                offset: (0.01, 0.05),
            },
            rays_n,
            1,
        );
        let lights = points(
            scene,
            LightGenerator::Fixtures {
                drop: 0.15,
                on_walls: 0.4,
            },
            10_000,
            2,
        );
        let rays: Vec<(Vec3, Vec3)> = from
            .iter()
            .enumerate()
            .map(|(i, &a)| (a, lights[(i * 7919) % lights.len()]))
            .collect();
        let blocked = pass.trace(&ctx, &gpu_bvh, &rays).expect("a trace").blocked;
        eprintln!(
            "rays.shadow/{}: {} triangles, depth {}, built in {:?}; {} of {} rays blocked",
            scene.name,
            bvh.triangles.len(),
            bvh.depth,
            bvh.build,
            blocked.iter().filter(|&&b| b).count(),
            rays.len()
        );
        g.throughput(Throughput::Elements(u64::from(rays_n)));
        g.bench_with_input(BenchmarkId::new(&scene.name, rays_n), &rays, |b, rays| {
            b.iter_custom(|iters| {
                let mut total = 0.0;
                for _ in 0..iters {
                    let t = pass.trace(&ctx, &gpu_bvh, rays).expect("a trace");
                    total += t
                        .gpu
                        .expect("timestamps: this bench times the GPU")
                        .iter()
                        .map(|p| p.ms)
                        .sum::<f64>();
                }
                Duration::from_secs_f64(total * 1e-3)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, shadow);
criterion_main!(benches);
