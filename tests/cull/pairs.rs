//! The clusters' held pairs (`Culler::cluster_pairs`): in back-to-back runs, whose lists are
//! sized up front, the count passes hold each (cluster, light) pair and
//! `cull.clustered.scatter` fills the lists in place of the fill passes.

use super::*;

/// Over 10 random scenes (radii up to 0.4 of the scene: some threads count more pairs than they
/// hold and walk their clusters again), three grids (with the cells, unordered, with a
/// capacity), with pairs held and not: one run's lists (the fill passes') equal the CPU
/// oracle's; three runs back to back declare the scatter exactly where pairs are held, and
/// fill the same lists bin for bin (in light order where ordered; with a capacity, lists of
/// the same lengths and as many lights dropped).
#[test]
fn held_pairs_fill_the_lists_the_fill_passes_fill() {
    let ctx = common::gpu();
    let (w, h) = (64, 40);
    let mut cullers = None;
    let mut most_clusters = 0;
    let mut scattered = 0;
    for seed in 71u64..81 {
        let case = random_case(seed);
        let r = render(&ctx, &case, w, h);
        let cullers = cullers.get_or_insert_with(|| {
            [true, false].map(|pairs| {
                let mut c = Culler::new(&ctx, &r.gpu_scene);
                // The per-light passes at every light count.
                c.cluster_tiles_max_lights = 0;
                c.cluster_pairs = pairs;
                c
            })
        });
        for (tile_size, slices, cells, ordered, capacity) in [
            (16, 16, false, true, None),
            (8, 32, true, true, None),
            (16, 24, false, false, None),
            (8, 16, false, true, Some(3)),
        ] {
            let s = Strategy::Clustered {
                tile_size,
                slices,
                slicing: Slicing::Exponential,
                skip_empty: false,
                ordered,
                cells,
            };
            let settings = CullSettings {
                capacity,
                ..CullSettings::for_camera(&case.camera)
            };
            for culler in cullers.iter() {
                let what = format!(
                    "{} clusters {tile_size} x {slices} (cells {cells}, ordered {ordered}, \
                     capacity {capacity:?}, pairs {})",
                    case.label, culler.cluster_pairs
                );
                let mut timer = GpuTimer::new(&ctx, 64);
                let out = culler
                    .run(&ctx, &r.gpu_scene, &r.depth_tex, &s, &settings, &mut timer)
                    .unwrap();
                assert!(
                    !out.passes
                        .iter()
                        .any(|p| p.name == "cull.clustered.scatter"),
                    "{what}: a run sized after its count scatters"
                );
                let gpu = out.read(&ctx).unwrap();
                if capacity.is_none() {
                    let occ = out.read_occupancy(&ctx).unwrap();
                    cpu::clustered(&r.frame, &out.params, &r.lights, &occ)
                        .compare(&gpu)
                        .unwrap_or_else(|e| panic!("{what}: {e}"));
                    let mut clusters = vec![0usize; r.lights.len()];
                    for &l in &gpu.indices {
                        clusters[l as usize] += 1;
                    }
                    most_clusters = most_clusters.max(clusters.into_iter().max().unwrap_or(0));
                }
                let mut timer = GpuTimer::new(&ctx, 256);
                let again = culler
                    .run_repeated(
                        &ctx,
                        &r.gpu_scene,
                        &r.depth_tex,
                        &s,
                        &settings,
                        &out,
                        3,
                        &mut timer,
                    )
                    .unwrap();
                check_plan(&what, &again.passes, timer.read(&ctx).unwrap(), 3);
                let held = culler.cluster_pairs && !gpu.indices.is_empty();
                let has = |n: &str| again.passes.iter().any(|p| p.name == n);
                assert_eq!(has("cull.clustered.scatter"), held, "{what}: the scatter");
                assert_eq!(
                    has("cull.clustered.fill") || has("cull.clustered.fill_wide"),
                    !held,
                    "{what}: the fill passes"
                );
                scattered += usize::from(held);
                assert_eq!(again.dropped, out.dropped, "{what}: dropped");
                let again = again.read(&ctx).unwrap();
                assert_eq!(again.ranges.len(), gpu.ranges.len(), "{what}: bins");
                for b in 0..gpu.ranges.len() {
                    if capacity.is_some() {
                        assert_eq!(
                            again.ranges[b][1], gpu.ranges[b][1],
                            "{what}: bin {b} length"
                        );
                    } else if ordered {
                        assert_eq!(again.list(b), gpu.list(b), "{what}: bin {b}");
                    } else {
                        assert_eq!(again.sorted(b), gpu.sorted(b), "{what}: bin {b}");
                    }
                }
            }
        }
    }
    assert!(scattered > 0, "no run held its pairs");
    assert!(
        most_clusters > 8,
        "no light reaches more clusters than a thread holds ({most_clusters})"
    );
}
