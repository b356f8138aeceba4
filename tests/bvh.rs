//! Shadow rays through the BVH of a scene's opaque triangles (`manylights_gpu::bvh`, traversed
//! in WGSL) against the f64 brute-force oracle (`manylights_scene::ray`), in every procedural
//! scene and every real one: segments from points just off the surfaces (where shading casts
//! them) and from anywhere in the scene's box, to anywhere in it. Every segment f64 decides must
//! get the same answer; those within rounding of an edge, an end or a plane are counted and
//! must stay few.

mod common;

use glam::Vec3;
use manylights_gpu::bvh::{GpuBvh, SceneBvh, ShadowRays};
use manylights_scene::generate::places;
use manylights_scene::gltf_import::GltfOptions;
use manylights_scene::procedural::{NAMES, ProceduralScene};
use manylights_scene::ray::{Blocked, opaque_triangles, segment};
use manylights_scene::{LightGenerator, LightSpec, RadiusRule, Scene, real};

fn points(scene: &Scene, generator: LightGenerator, n: u32, seed: u64) -> Vec<Vec3> {
    places(scene, generator, n, seed).unwrap()
}

/// `n` segments: a half from 1-5 cm off the surfaces, a quarter from anywhere in the box, each
/// to a point anywhere in the box; and a quarter from 1-5 cm off a surface to 10 cm behind it,
/// through it.
fn segments(scene: &Scene, n: u32) -> Vec<(Vec3, Vec3)> {
    let (half, quarter) = (n / 2, n / 4);
    let surface = points(
        scene,
        LightGenerator::OnSurfaces {
            offset: (0.01, 0.05),
        },
        half,
        1,
    );
    let from = points(scene, LightGenerator::Uniform, n - half - quarter, 2);
    let to = points(scene, LightGenerator::Uniform, n - quarter, 3);
    let through = LightSpec {
        generator: LightGenerator::OnSurfaces {
            offset: (0.01, 0.05),
        },
        count: quarter,
        seed: 4,
        radius: RadiusRule::Fixed(1.0),
        ..LightSpec::default()
    };
    let behind = through
        .generate(scene)
        .unwrap()
        .iter()
        .zip(through.anchors(scene).unwrap())
        .map(|(l, n)| (l.position, l.position - 0.15 * n))
        .collect::<Vec<_>>();
    surface
        .into_iter()
        .chain(from)
        .zip(to)
        .chain(behind)
        .collect()
}

/// The oracle's answer for every segment, over the cores.
fn oracle(tris: &[[Vec3; 3]], rays: &[(Vec3, Vec3)]) -> Vec<Blocked> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let chunk = rays.len().div_ceil(threads).max(1);
    std::thread::scope(|s| {
        let parts: Vec<_> = rays
            .chunks(chunk)
            .map(|c| {
                s.spawn(move || {
                    c.iter()
                        .map(|&(a, b)| segment(tris, a, b))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        parts.into_iter().flat_map(|p| p.join().unwrap()).collect()
    })
}

fn check(ctx: &manylights_gpu::GpuContext, rays_pass: &ShadowRays, scene: &Scene) {
    let name = &scene.name;
    let tris = opaque_triangles(scene);
    // About 1.5e8 f64 triangle tests a scene: 2,048 segments, fewer in the largest.
    let n = (150_000_000 / tris.len().max(1)).clamp(128, 2048) as u32;
    let bvh = SceneBvh::build(scene).unwrap();
    assert_eq!(
        bvh.triangles.len(),
        tris.len(),
        "{name}: every opaque triangle in the BVH"
    );
    let mut seen = bvh.source.clone();
    seen.sort_unstable();
    seen.dedup();
    assert_eq!(seen.len(), tris.len(), "{name}: each once");
    let gpu = GpuBvh::upload(ctx, &bvh).unwrap();
    let rays = segments(scene, n);
    let got = rays_pass.trace(ctx, &gpu, &rays).unwrap().blocked;
    let want = oracle(&tris, &rays);
    let (mut yes, mut no, mut ambiguous) = (0, 0, 0);
    for (i, (w, g)) in want.iter().zip(&got).enumerate() {
        match w {
            Blocked::Yes => yes += 1,
            Blocked::No => no += 1,
            Blocked::Ambiguous => {
                ambiguous += 1;
                continue;
            }
        }
        assert_eq!(
            *g,
            *w == Blocked::Yes,
            "{name}: segment {i} {:?} is {w:?} in f64, blocked = {g} on the GPU",
            rays[i]
        );
    }
    println!(
        "{name}: {} triangles, depth {}, {} nodes, built in {:?}; {n} segments: {yes} blocked, \
         {no} clear, {ambiguous} undecided in f64",
        tris.len(),
        bvh.depth,
        bvh.nodes.len(),
        bvh.build
    );
    assert!(
        yes > 0 && no > 0,
        "{name}: the segments test both answers ({yes}, {no})"
    );
    assert!(
        ambiguous * 50 <= rays.len(),
        "{name}: {ambiguous} of {} undecided",
        rays.len()
    );
}

#[test]
fn shadow_rays_through_the_bvh_match_the_f64_oracle_in_every_scene() {
    let ctx = common::gpu();
    let pass = ShadowRays::new(&ctx);
    for name in NAMES {
        let scene = ProceduralScene::from_name(name).unwrap().build().unwrap();
        check(&ctx, &pass, &scene);
    }
    for name in ["sponza", "staircase", "dining-room", "bathroom", "kitchen"] {
        let (scene, _) = real::load(name, &GltfOptions::default()).unwrap();
        check(&ctx, &pass, &scene);
    }
}

/// A scene without opaque triangles blocks nothing; an empty batch gives nothing.
#[test]
fn an_empty_scene_blocks_nothing() {
    let ctx = common::gpu();
    let pass = ShadowRays::new(&ctx);
    let bvh = GpuBvh::upload(&ctx, &SceneBvh::of_triangles(&[]).unwrap()).unwrap();
    let got = pass
        .trace(
            &ctx,
            &bvh,
            &[(Vec3::ZERO, Vec3::ONE), (Vec3::ONE, -Vec3::ONE)],
        )
        .unwrap();
    assert_eq!(got.blocked, vec![false, false]);
    assert!(pass.trace(&ctx, &bvh, &[]).unwrap().blocked.is_empty());
}
