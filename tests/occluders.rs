//! Culling by visibility's occluder test against the f64 shadow-ray oracle
//! (`manylights_scene::occluders`): over every procedural scene with random
//! lights and random cells about its surfaces, wherever an occluder is said to hide a light
//! from a cell, no point of the cell (nor one lifted off it as a shadow ray's origin is) has a
//! segment to the light that the f64 oracle calls clear. The test must fire: a share of the
//! (cell, light) pairs is hidden in every scene with walls.

use glam::DVec3;
use manylights_scene::occluders::{hides, occluders};
use manylights_scene::procedural::{NAMES, ProceduralScene};
use manylights_scene::ray::{Blocked, SHADOW_OFFSET, opaque_triangles, segment};
use manylights_scene::{LightGenerator, LightSpec, RadiusRule};

/// A small deterministic generator (SplitMix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Procedural scene `name` with `count` uniform lights of `seed` reaching across it, its
/// extent, its opaque triangles and its occluders (64 of at least 1e-3 of the extent squared).
fn lit_scene(
    name: &str,
    count: u32,
    seed: u64,
) -> (manylights_scene::Scene, f32, Vec<[glam::Vec3; 3]>, Vec<manylights_scene::occluders::Occluder>) {
    let mut scene = ProceduralScene::from_name(name).unwrap().build().unwrap();
    let extent = scene.light_bounds.extent().max_element();
    scene.lights = LightSpec {
        generator: LightGenerator::Uniform,
        count,
        seed,
        radius: RadiusRule::Fixed(extent),
        intensity: 1.0,
        ..LightSpec::default()
    }
    .generate(&scene)
    .unwrap();
    let tris = opaque_triangles(&scene);
    let occ = occluders(&tris, f64::from(extent * extent) * 1e-3, 64);
    (scene, extent, tris, occ)
}

#[test]
fn occluders_never_hide_a_light_a_point_of_the_cell_sees() {
    let mut total_hidden = 0;
    for (s_i, name) in NAMES.iter().enumerate() {
        let (scene, extent, tris, occ) = lit_scene(name, 120, 7 + s_i as u64);
        let areas: Vec<f64> = tris
            .iter()
            .map(|t| f64::from((t[1] - t[0]).cross(t[2] - t[0]).length()))
            .collect();
        let total: f64 = areas.iter().sum();
        let mut rng = Rng(0x5eed + s_i as u64);
        let (mut pairs, mut hidden, mut points, mut undecided) = (0, 0, 0, 0);
        for _ in 0..150 {
            // A surface point, area-weighted, and a box of 2% of the extent about it.
            let mut pick = rng.next() * total;
            let k = areas
                .iter()
                .position(|a| {
                    pick -= a;
                    pick <= 0.0
                })
                .unwrap_or(areas.len() - 1);
            let t = tris[k];
            let (mut u, mut v) = (rng.next() as f32, rng.next() as f32);
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let centre = (t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v).as_dvec3();
            let half = f64::from(extent) * 0.01;
            let corners: Vec<DVec3> = (0..8)
                .map(|c| {
                    centre
                        + DVec3::new(
                            if c & 1 == 0 { -half } else { half },
                            if c & 2 == 0 { -half } else { half },
                            if c & 4 == 0 { -half } else { half },
                        )
                })
                .collect();
            for light in &scene.lights {
                pairs += 1;
                let l = light.position.as_dvec3();
                let margin = 1e-5 * l.abs().max_element().max(centre.abs().max_element()).max(1.0);
                if !occ.iter().any(|o| hides(o, l, &corners, margin)) {
                    continue;
                }
                hidden += 1;
                // Points inside the box, some lifted off it by up to a shadow ray's lift.
                for _ in 0..12 {
                    let mut q = centre
                        + DVec3::new(rng.next() * 2.0 - 1.0, rng.next() * 2.0 - 1.0, rng.next() * 2.0 - 1.0)
                            * half;
                    let lift = f64::from(SHADOW_OFFSET) * q.abs().max_element().max(1.0);
                    q += DVec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5)
                        .normalize_or_zero()
                        * (lift * rng.next());
                    points += 1;
                    match segment(&tris, q.as_vec3(), light.position) {
                        Blocked::No => panic!(
                            "{name}: an occluder hides the light at {} from the cell about \
                             {centre}, but the point {q} sees it",
                            light.position
                        ),
                        Blocked::Ambiguous => undecided += 1,
                        Blocked::Yes => {}
                    }
                }
            }
        }
        println!(
            "{name}: {} occluders; {hidden} of {pairs} (cell, light) pairs hidden; {points} points \
             checked, {undecided} undecided",
            occ.len()
        );
        total_hidden += hidden;
        assert!(undecided * 20 <= points.max(1), "{name}: {undecided} of {points} undecided");
    }
    assert!(total_hidden > 1000, "the test must fire: {total_hidden} pairs hidden");
}

/// The occluder test on the GPU (`occluder_hides`, f32, with `occlusion::margin`) against the
/// f64 test with no margin, over the cells and lights of the procedural scenes above: where the
/// GPU says an occluder hides a light from a cell, the f64 test says that occluder does (never
/// a light hidden that f64 geometry leaves in sight), and it finds at least 95% of the pairs the
/// f64 test finds with a margin of 1e-3 of the coordinates' size.
#[test]
fn the_gpu_occluder_test_is_conservative_against_f64() {
    use manylights_cull::occlusion::{GpuOccluder, OccluderTest, Query};
    let ctx = manylights_gpu::GpuContext::new(&manylights_gpu::GpuOptions::default())
        .expect("a Vulkan adapter (lavapipe is enough): run scripts/ensure-vulkan.sh");
    let test = OccluderTest::new(&ctx);
    let mut found = 0;
    for (s_i, name) in NAMES.iter().enumerate() {
        let (scene, extent, tris, occ) = lit_scene(name, 60, 70 + s_i as u64);
        let gpu_occ: Vec<GpuOccluder> = occ.iter().map(GpuOccluder::from).collect();
        let mut rng = Rng(0xcafe + s_i as u64);
        let mut queries = Vec::new();
        for _ in 0..100 {
            let t = tris[(rng.next() * tris.len() as f64) as usize % tris.len()];
            let centre = ((t[0] + t[1] + t[2]) / 3.0).as_dvec3();
            let half = f64::from(extent) * (0.002 + 0.02 * rng.next());
            let cell: [DVec3; 8] = std::array::from_fn(|c| {
                centre
                    + DVec3::new(
                        if c & 1 == 0 { -half } else { half },
                        if c & 2 == 0 { -half } else { half },
                        if c & 4 == 0 { -half } else { half },
                    )
            });
            for l in &scene.lights {
                queries.push((l.position.as_dvec3(), cell));
            }
        }
        let q: Vec<Query> = queries.iter().map(|(l, c)| Query::new(*l, c)).collect();
        let hidden = test.run(&ctx, &gpu_occ, &q).unwrap();
        let (mut gpu, mut wide) = (0, 0);
        for ((l, cell), h) in queries.iter().zip(&hidden) {
            let margin = 1e-3 * l.abs().max_element().max(cell[0].abs().max_element()).max(1.0);
            if occ.iter().any(|o| hides(o, *l, cell, margin)) {
                wide += 1;
                assert!(*h > 0, "{name}: f64 hides {l} from the cell at {} with a margin, the GPU does not", cell[0]);
            }
            if *h > 0 {
                gpu += 1;
                let o = &occ[*h as usize - 1];
                assert!(
                    hides(o, *l, cell, 0.0),
                    "{name}: the GPU hides {l} from the cell at {} behind occluder {}, f64 geometry does not",
                    cell[0],
                    h - 1
                );
            }
        }
        println!("{name}: {} queries, {gpu} hidden on the GPU, {wide} by f64 with a wide margin", q.len());
        assert!(gpu >= wide, "{name}");
        found += gpu;
    }
    assert!(found > 1000, "the test must fire: {found}");
}
