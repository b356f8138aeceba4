//! Each strategy's GPU lists against its CPU oracle, pass by pass (the scans, the lists, a
//! deliberate capacity), and the GPU exact oracle against the CPU's.

use super::*;

#[test]
fn scan_portable_matches_cpu_on_edge_sizes() {
    let ctx = common::gpu();
    check_scan(
        &ctx,
        &scan::Scan::with_path(&ctx, scan::ScanPath::Portable).unwrap(),
    );
}

/// The subgroup path on its own. lavapipe (subgroup size 8) and NVIDIA (32) both have
/// subgroups; an adapter without them fails here with that message rather than skipping.
#[test]
fn scan_subgroup_matches_cpu_on_edge_sizes() {
    let ctx = common::gpu();
    let s = scan::Scan::with_path(&ctx, scan::ScanPath::Subgroup).unwrap_or_else(|| {
        panic!(
            "adapter {} has no subgroup operations: the subgroup scan cannot be tested here",
            ctx.info.name
        )
    });
    check_scan(&ctx, &s);
}

fn check_scan(ctx: &GpuContext, s: &scan::Scan) {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
    for n in [
        0u32,
        1,
        2,
        255,
        1023,
        1024,
        1025,
        4099,
        16_383,
        16_384,
        16_385,
        1 << 20,
        (1 << 20) + 3,
        3_000_001,
    ] {
        for kind in ["random", "ones", "zeros"] {
            let data: Vec<u32> = (0..n)
                .map(|_| match kind {
                    "random" => rng.random_range(0..1000u32),
                    "ones" => 1,
                    _ => 0,
                })
                .collect();
            let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: None,
                size: (u64::from(n) * 4).max(4),
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            ctx.queue.write_buffer(&buf, 0, bytemuck::cast_slice(&data));
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            s.encode(ctx, &mut enc, &buf, n, &mut GpuTimer::new(ctx, 16));
            ctx.submit_and_wait(enc, "scan").unwrap();
            let got: Vec<u32> = bytemuck::pod_collect_to_vec(
                &readback::read_buffer(ctx, &buf, 0, (u64::from(n) * 4).max(4)).unwrap(),
            );
            assert_eq!(
                &got[..n as usize],
                &scan::cpu(&data)[..],
                "scan of {n} {kind}"
            );
        }
    }
}

/// Every strategy: GPU lists equal the CPU oracle's (as sets per bin; only decisions the oracle
/// marks borderline may differ), on several scenes and cameras, at 70 x 45 (not a multiple of
/// any tile size); every intermediate pass against its own oracle; zero false negatives; and
/// the shared per-pixel lookup agrees with the CPU's.
#[test]
fn gpu_lists_equal_cpu_oracle_and_have_no_false_negatives() {
    let ctx = common::gpu();
    let (w, h) = (70, 45);
    let mut total_border = 0;
    let mut cullers = None;
    for seed in [11u64, 12, 13, 14, 15, 16] {
        let mut case = random_case(seed);
        if seed >= 15 {
            // Over twice MIN_CHUNK lights: gather's coarse-to-fine passes take them in several chunks.
            let lights = case.scene.lights.clone();
            case.scene.lights = lights
                .iter()
                .cycle()
                .take(lights.len() + 600)
                .cloned()
                .collect();
            assert!(case.scene.lights.len() > 2 * manylights_cull::MIN_CHUNK as usize);
        }
        let r = render(&ctx, &case, w, h);
        // Gather's scans with subgroup operations (where the device has them) and without.
        let cullers = cullers.get_or_insert_with(|| {
            let sub = Culler::new(&ctx, &r.gpu_scene);
            assert_eq!(
                sub.gather_subgroups, ctx.features.subgroups,
                "gather must take its subgroup path where the device has subgroups"
            );
            // Gather's chunked fill, which tests again, and scatter's pairs and sort, where tile
            // masks would be used.
            let mut unmasked = Culler::new(&ctx, &r.gpu_scene);
            unmasked.mask_budget = 0;
            // Gather's and 2.5D's tile masks stored by the count pass, not their lines path.
            let mut stored = Culler::new(&ctx, &r.gpu_scene);
            stored.gather_lines = false;
            // Gather's portable scans; and the clusters' per-light passes, where the other
            // cullers take their tile path (these scenes have few lights).
            let mut portable = Culler::with_subgroups(&ctx, &r.gpu_scene, false);
            portable.cluster_tiles_max_lights = 0;
            [sub, portable, unmasked, stored]
        });
        let coarse_gather = |s: &Strategy| {
            matches!(
                s,
                Strategy::TiledGather { coarse: 1.., .. } | Strategy::DepthMask { coarse: 1.., .. }
            )
        };
        for (culler, s) in cullers.iter().flat_map(|c| {
            strategies()
                .into_iter()
                .filter(|s| {
                    (c.mask_budget > 0 && c.gather_lines)
                        || coarse_gather(s)
                        || (c.mask_budget == 0 && matches!(s, Strategy::TiledScatter { .. }))
                })
                .map(move |s| (c, s))
        }) {
            let what = format!(
                "{} {} (subgroups: {}, tile masks: {}, lines: {}, cluster tiles: {})",
                case.label,
                s.name(),
                culler.gather_subgroups,
                culler.mask_budget > 0,
                culler.gather_lines,
                culler.cluster_tiles_max_lights > 0
            );
            let out = run_gpu(&ctx, culler, &r, &case, &s);
            let p = out.params;
            let gpu = out.read(&ctx).unwrap();
            // Tile masks where they fit (these scenes are small), and all zero after the fill,
            // as the next count pass needs.
            let masks = out.read_tile_masks(&ctx).unwrap();
            let lines = out.read_tile_lines(&ctx).unwrap();
            let used_lines = lines.is_some();
            let gathers = matches!(s, Strategy::TiledGather { .. } | Strategy::DepthMask { .. });
            let maskable = p.capacity == 0
                && culler.mask_budget > 0
                && match s {
                    Strategy::TiledScatter { .. } => true,
                    _ => gathers && p.coarse > 0,
                };
            let by_lines = gathers && culler.gather_lines;
            assert_eq!(
                masks.is_some(),
                maskable && !by_lines,
                "{what}: tile masks used"
            );
            assert_eq!(
                lines.is_some(),
                maskable && by_lines,
                "{what}: tile lines used"
            );
            assert_eq!(out.used_tile_masks(), maskable, "{what}: the result column");
            if let Some(m) = masks {
                assert!(m.iter().all(|&w| w == 0), "{what}: tile masks left set");
            }
            if let Some(l) = lines {
                // Every bit the oracle sets at the lower slack, none it leaves clear at the upper.
                let [lo, hi] = cpu::tile_lines(&r.frame, &p, &r.lights);
                assert_eq!(l.len(), lo.len(), "{what}: tile line words");
                for (k, ((&g, &a), &b)) in l.iter().zip(&lo).zip(&hi).enumerate() {
                    assert!(
                        a & !g == 0 && g & !b == 0,
                        "{what}: tile line word {k}: GPU {g:#034b}, oracle {a:#034b} .. {b:#034b}"
                    );
                }
            }
            let oracle = match s {
                Strategy::Clustered { .. } => {
                    let occ = out.read_occupancy(&ctx).unwrap();
                    use manylights_cull::layout::{CULL_FLAG_SKIP_EMPTY, CULL_FLAG_TILE_BOX};
                    if p.flags & (CULL_FLAG_SKIP_EMPTY | CULL_FLAG_TILE_BOX) != 0 {
                        let bins = p.bins as usize;
                        let cpu_occ = cpu::occupancy(&r.frame, &p, &r.depth, w, h);
                        assert_eq!(occ[..bins], cpu_occ[..bins], "{what}: occupancy");
                        // The clusters' depth bounds, to the last bits of a GPU's linear depth.
                        for (k, (&g, &c)) in occ[bins..].iter().zip(&cpu_occ[bins..]).enumerate() {
                            let near = if k % 2 == 0 { (!g, !c) } else { (g, c) };
                            let (a, b) = (
                                geometry::from_ordered_bits(near.0),
                                geometry::from_ordered_bits(near.1),
                            );
                            assert!(
                                (g == 0) == (c == 0)
                                    && (g == 0
                                        || (a - b).abs()
                                            <= 4.0 * f32::EPSILON * a.abs().max(b.abs())),
                                "{what}: cluster {} depth bound {} {a} against {b}",
                                k / 2,
                                k % 2
                            );
                        }
                    }
                    cpu::clustered(&r.frame, &p, &r.lights, &occ)
                }
                _ => {
                    let td = out.read_tile_depth(&ctx).unwrap();
                    let (cpu_td, uncertain) = cpu::depth_bounds(&r.frame, &p, &r.depth, w, h);
                    for (t, (g, c)) in td.iter().zip(&cpu_td).enumerate() {
                        assert_eq!(g.covered, c.covered, "{what}: tile {t} covered");
                        let close = |a: f32, b: f32| {
                            (a - b).abs() <= 4.0 * f32::EPSILON * a.abs().max(b.abs())
                        };
                        assert!(
                            close(g.dmin, c.dmin) && close(g.dmax, c.dmax),
                            "{what}: tile {t} bounds {g:?} vs {c:?}"
                        );
                        // (Gather's lines path computes the 2.5D mask only for 2.5D.)
                        let no_mask = used_lines && !matches!(s, Strategy::DepthMask { .. });
                        assert_eq!(
                            g.mask & !uncertain[t],
                            if no_mask { 0 } else { c.mask & !uncertain[t] },
                            "{what}: tile {t} mask"
                        );
                    }
                    if matches!(s, Strategy::TiledScatter { .. }) {
                        // Same per-tile test, reached from the light's side, within the light's
                        // screen rectangle (cut at the near plane): a subset of gather's lists.
                        let gathered = cpu::gather(&r.frame, &p, &r.lights, &td);
                        let scattered = cpu::scatter(&r.frame, &p, &r.lights, &td);
                        for (b, (sl, gl)) in scattered.kept.iter().zip(&gathered.kept).enumerate() {
                            for l in sl {
                                assert!(
                                    gl.contains(l) || gathered.borderline[b].contains(l),
                                    "{what}: scatter keeps light {l} in tile {b}, gather does not"
                                );
                            }
                        }
                        scattered
                    } else if matches!(s, Strategy::ZBin { .. }) {
                        let order = out.read_stored(&ctx).unwrap().1[..r.lights.len()].to_vec();
                        check_zbin_order(&what, &r, &p, &order);
                        cpu::zbin_lists(&r.frame, &p, &r.lights, &td, &order)
                    } else {
                        cpu::gather(&r.frame, &p, &r.lights, &td)
                    }
                }
            };
            total_border += oracle
                .compare(&gpu)
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            let m = metrics(&r, &p, &gpu);
            assert_eq!(m.false_negatives, 0, "{what}: false negatives on the GPU");
            if seed == 16 {
                // Back-to-back runs in one submission, sized from this run: the same lists.
                let three_runs = |timer: &mut GpuTimer| {
                    culler
                        .run_repeated(
                            &ctx,
                            &r.gpu_scene,
                            &r.depth_tex,
                            &s,
                            &CullSettings::for_camera(&case.camera),
                            &out,
                            3,
                            timer,
                        )
                        .unwrap()
                };
                let mut timer = GpuTimer::new(&ctx, 256);
                let again = three_runs(&mut timer);
                check_plan(
                    &format!("{what}, repeated"),
                    &again.passes,
                    timer.read(&ctx).unwrap(),
                    3,
                );
                let again = again.read(&ctx).unwrap();
                assert_eq!(
                    again.ranges.len(),
                    gpu.ranges.len(),
                    "{what}: repeated bins"
                );
                for b in 0..gpu.ranges.len() {
                    assert_eq!(again.sorted(b), gpu.sorted(b), "{what}: repeated, bin {b}");
                }
                if let Some(t) = timer.read(&ctx).unwrap() {
                    // Each run's first pass, once a run.
                    let first = t.iter().filter(|p| p.label == t[0].label).count();
                    assert_eq!(first, 3, "{what}: three runs timed");
                }
                // Timed as spans, one timestamp pair a run around all its passes: three spans
                // named for the strategy, and the same lists.
                let mut spans = GpuTimer::spans(&ctx, 3)
                    .expect("the device writes timestamps between passes (lavapipe does)");
                let spanned = three_runs(&mut spans).read(&ctx).unwrap();
                for b in 0..gpu.ranges.len() {
                    assert_eq!(spanned.sorted(b), gpu.sorted(b), "{what}: spans, bin {b}");
                }
                let t = spans.read(&ctx).unwrap().expect("timestamps");
                let name = format!("cull.{}", s.name());
                assert_eq!(t.len(), 3, "{what}: three spans");
                assert!(
                    t.iter().all(|p| p.label == name && p.ms > 0.0),
                    "{what}: spans {t:?}"
                );
            }
            // The shared WGSL lookup reads the same lists as the CPU lookup.
            let per_pixel = culler
                .lights_per_pixel(&ctx, &r.gpu_scene, &r.depth_tex, &out)
                .unwrap();
            for y in 0..h {
                for x in 0..w {
                    let i = (y * w + x) as usize;
                    let z = r.depth[i];
                    let expect = if z < 1.0 {
                        gpu.list(geometry::bin_of(&r.frame, &p, [x, y], z) as usize)
                            .len() as u32
                    } else {
                        0
                    };
                    if per_pixel[i] != expect {
                        let c = geometry::slice_coord(&p, geometry::linear_depth(&r.frame, z));
                        assert!(
                            (c - c.round()).abs() < 1e-3,
                            "{what}: pixel ({x}, {y}) reads {} lights, CPU lookup {expect}",
                            per_pixel[i]
                        );
                    }
                }
            }
        }
    }
    println!("borderline decisions tolerated: {total_border}");
}

/// The GPU exact oracle agrees with the CPU's: the same covered pixels and lists evaluated, no
/// false negatives, and lights needed equal up to the decisions within 1e-4 of a light's radius
/// or cone edge (f32 on the GPU, f64 on the CPU).
#[test]
fn gpu_exact_oracle_matches_cpu() {
    let ctx = common::gpu();
    let mut culler = None;
    for seed in 5000..5006u64 {
        let case = random_case(seed);
        let r = render(&ctx, &case, 53, 31);
        let culler = culler.get_or_insert_with(|| Culler::new(&ctx, &r.gpu_scene));
        for s in [
            Strategy::tiled_gather(8),
            Strategy::Clustered {
                tile_size: 8,
                slices: 12,
                slicing: Slicing::Exponential,
                skip_empty: true,
                ordered: true,
                cells: false,
            },
        ] {
            let out = run_gpu(&ctx, culler, &r, &case, &s);
            let lists = out.read(&ctx).unwrap();
            let counts = culler
                .exact_counts(
                    &ctx,
                    &r.gpu_scene,
                    &r.depth_tex,
                    &out,
                    r.frame.clip_from_world.inverse(),
                    1,
                )
                .unwrap();
            let (g, c) = (
                manylights_cull::metrics::from_gpu_counts(&counts, &out.bin_lengths(&ctx).unwrap()),
                metrics(&r, &out.params, &lists),
            );
            let what = format!("{} {}", case.label, s.name());
            assert_eq!(g.covered_pixels, c.covered_pixels, "{what}");
            assert_eq!(g.false_negatives, 0, "{what}: GPU oracle");
            // Borderline (pixel, light) pairs by the f64 oracle.
            let points = surface_points(&r.frame, &r.depth, r.w, r.h);
            let mut border = 0u64;
            for p in points.iter().flatten() {
                for l in &case.scene.lights {
                    let d = (*p - l.position.as_dvec3()).length() / f64::from(l.radius);
                    let cone = l.cone().map_or(1.0, |(axis, _, cos_o)| {
                        let dir = (*p - l.position.as_dvec3()).normalize_or_zero();
                        (dir.dot(axis.as_dvec3()) - f64::from(cos_o)).abs()
                    });
                    if (d - 1.0).abs() < 1e-4 || (d < 1.0 && cone < 1e-4) {
                        border += 1;
                    }
                }
            }
            assert!(
                g.needed.abs_diff(c.needed) <= border,
                "{what}: needed {} (GPU) vs {} (CPU), {border} borderline",
                g.needed,
                c.needed
            );
            assert_eq!(g.evaluated, c.evaluated, "{what}: evaluated");
        }
    }
}

/// At the most lights the device holds (`manylights_cull::max_lights`: on lavapipe its loop
/// limit, which a loop entered by no lane also counts) the GPU exact oracle still counts every
/// light: lights needed equal the CPU's (up to borderline decisions) and no false negatives, in
/// the atrium's uniform lights of radius 0.5 m. (Before its shadowed test moved out of its
/// loops, llvmpipe ended them at 21,845 lights here.)
#[test]
fn gpu_exact_oracle_counts_every_light_the_device_holds() {
    let ctx = common::gpu();
    let mut case = random_case(5000);
    case.scene = ProceduralScene::Atrium(AtriumParams::default())
        .build()
        .unwrap();
    case.camera = case.scene.camera;
    case.label = "atrium".into();
    let count = manylights_cull::max_lights(&ctx).min(40_000);
    case.scene.lights = LightSpec {
        generator: LightGenerator::Uniform,
        count,
        seed: 1,
        radius: RadiusRule::Fixed(0.5),
        intensity: 0.5,
        ..LightSpec::default()
    }
    .generate(&case.scene)
    .unwrap();
    let r = render(&ctx, &case, 40, 24);
    let culler = Culler::new(&ctx, &r.gpu_scene);
    let s = Strategy::Clustered {
        tile_size: 8,
        slices: 16,
        slicing: Slicing::Exponential,
        skip_empty: false,
        ordered: true,
        cells: false,
    };
    let out = run_gpu(&ctx, &culler, &r, &case, &s);
    let counts = culler
        .exact_counts(
            &ctx,
            &r.gpu_scene,
            &r.depth_tex,
            &out,
            r.frame.clip_from_world.inverse(),
            1,
        )
        .unwrap();
    let g = manylights_cull::metrics::from_gpu_counts(&counts, &out.bin_lengths(&ctx).unwrap());
    let c = metrics(&r, &out.params, &out.read(&ctx).unwrap());
    println!(
        "{count} lights: needed {} (GPU), {} (CPU)",
        g.needed, c.needed
    );
    assert!(c.needed > 0, "no pixel needs a light");
    assert_eq!(c.false_negatives, 0, "CPU oracle");
    assert_eq!(g.false_negatives, 0, "GPU oracle at {count} lights");
    assert!(
        g.needed.abs_diff(c.needed) * 1000 <= c.needed,
        "needed {} (GPU) vs {} (CPU)",
        g.needed,
        c.needed
    );
}

/// A deliberate capacity drops exactly the lights beyond it, counts every one of them, and the
/// loss shows as false negatives: the capped lists are the uncapped ones truncated.
#[test]
fn capacity_drops_are_counted() {
    let ctx = common::gpu();
    let case = random_case(6001);
    let r = render(&ctx, &case, 64, 40);
    let culler = Culler::new(&ctx, &r.gpu_scene);
    for s in [
        Strategy::tiled_gather(16),
        Strategy::TiledScatter { tile_size: 16 },
        Strategy::Clustered {
            tile_size: 16,
            slices: 8,
            slicing: Slicing::Linear,
            skip_empty: false,
            ordered: true,
            cells: false,
        },
    ] {
        let full = run_gpu(&ctx, &culler, &r, &case, &s);
        let full_lists = full.read(&ctx).unwrap();
        let cap = 2;
        let expected: u64 = full_lists
            .ranges
            .iter()
            .map(|r| u64::from(r[1].saturating_sub(cap)))
            .sum();
        assert!(
            expected > 0,
            "{}: the case must overflow a capacity of {cap}",
            s.name()
        );
        let settings = CullSettings {
            capacity: Some(cap),
            ..CullSettings::for_camera(&case.camera)
        };
        let capped = culler
            .run(
                &ctx,
                &r.gpu_scene,
                &r.depth_tex,
                &s,
                &settings,
                &mut GpuTimer::new(&ctx, 16),
            )
            .unwrap();
        assert_eq!(
            u64::from(capped.dropped),
            expected,
            "{}: dropped lights",
            s.name()
        );
        let lists = capped.read(&ctx).unwrap();
        for b in 0..lists.ranges.len() {
            let full_set = full_lists.sorted(b);
            assert!(lists.list(b).len() as u32 <= cap);
            assert!(
                lists
                    .list(b)
                    .iter()
                    .all(|l| full_set.binary_search(l).is_ok()),
                "{}: bin {b} keeps a light it did not hold",
                s.name()
            );
        }
        assert!(
            metrics(&r, &capped.params, &lists).false_negatives > 0,
            "{}: the loss must show",
            s.name()
        );
        assert_eq!(full.dropped, 0);
    }
}
