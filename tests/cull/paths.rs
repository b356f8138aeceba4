//! Paths and options of a strategy against each other: tile masks, z-binning's narrowing of
//! gather's lists, the box test, and the clusters' tile path.

use super::*;

/// Runs `s` where tile masks must be used, checks they are left zero and that the lists equal
/// the CPU oracle's (over the GPU's tile depth data); returns the masks' words a tile and the
/// lists.
fn masked_lists_match_oracle(
    ctx: &GpuContext,
    culler: &Culler,
    r: &Rendered,
    case: &Case,
    s: &Strategy,
    what: &str,
) -> (usize, manylights_cull::BinLists) {
    let out = run_gpu(ctx, culler, r, case, s);
    let p = out.params;
    // Gather and 2.5D take their lines path, scatter stores tile masks.
    let words = match (
        out.read_tile_masks(ctx).unwrap(),
        out.read_tile_lines(ctx).unwrap(),
    ) {
        (Some(masks), None) => {
            assert!(masks.iter().all(|&m| m == 0), "{what}: tile masks left set");
            masks.len() / p.bins as usize
        }
        (None, Some(lines)) => lines.len() / (p.tiles_x + p.tiles_y) as usize,
        _ => panic!("{what}: tile masks or tile lines must fit"),
    };
    let td = out.read_tile_depth(ctx).unwrap();
    let gpu = out.read(ctx).unwrap();
    let oracle = match s {
        Strategy::TiledScatter { .. } => cpu::scatter(&r.frame, &out.params, &r.lights, &td),
        _ => cpu::gather(&r.frame, &out.params, &r.lights, &td),
    };
    oracle
        .compare(&gpu)
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    (words, gpu)
}

/// Tile masks of over 64 words a tile (over 4,096 lights, so each fill thread takes several
/// words, and the last threads none; with the lines path 32, 64 and 128 threads a tile): gather's, 2.5D's and scatter's lists equal their CPU oracles, each in
/// light order, and the masks are left zero.
#[test]
fn tile_masks_of_many_words_equal_the_oracle() {
    let ctx = common::gpu();
    let (w, h) = (72, 40);
    for (count, threads) in [(4100, 32), (9000, 64), (17000, 128)] {
        assert_eq!(line_threads(count), threads, "{count} lights");
        let mut case = random_case(21);
        let lights = case.scene.lights.clone();
        case.scene.lights = lights
            .iter()
            .cycle()
            .take(count as usize)
            .cloned()
            .collect();
        let r = render(&ctx, &case, w, h);
        let culler = Culler::new(&ctx, &r.gpu_scene);
        for s in [
            Strategy::tiled_gather(8),
            Strategy::depth_mask(8),
            Strategy::TiledScatter { tile_size: 8 },
        ] {
            let what = format!("{} {} {count} lights", case.label, s.name());
            let (words, gpu) = masked_lists_match_oracle(&ctx, &culler, &r, &case, &s, &what);
            assert!(words > 64, "{what}: over 64 words a tile");
            let mut kept = 0;
            for b in 0..gpu.ranges.len() {
                let list = gpu.list(b);
                assert!(
                    list.windows(2).all(|p| p[0] < p[1]),
                    "{what}: bin {b} in light order"
                );
                kept += list.len();
            }
            assert!(kept > 0, "{what}: some tile keeps a light");
        }
    }
}

/// Lights covering the whole screen of 32 x 24 tiles (768 tiles, three blocks of tiled
/// scatter's masks count pass each, shared among its workgroups): scatter's and gather's lists
/// equal their CPU oracles, with tile masks, and the masks are left zero.
#[test]
fn tile_masks_with_lights_over_many_blocks_equal_the_oracle() {
    let ctx = common::gpu();
    let (w, h) = (128, 96);
    let mut case = random_case(31);
    let reach = case.scene.light_bounds.extent().length() * 2.0;
    for l in &mut case.scene.lights {
        l.radius = reach;
    }
    let r = render(&ctx, &case, w, h);
    let culler = Culler::new(&ctx, &r.gpu_scene);
    for s in [
        Strategy::TiledScatter { tile_size: 4 },
        Strategy::tiled_gather(4),
    ] {
        let what = format!("{} {} ({} lights)", case.label, s.name(), r.lights.len());
        let (_, gpu) = masked_lists_match_oracle(&ctx, &culler, &r, &case, &s, &what);
        assert_eq!(gpu.ranges.len(), 32 * 24, "{what}");
        let longest = (0..gpu.ranges.len())
            .map(|b| gpu.list(b).len())
            .max()
            .unwrap_or(0);
        assert!(
            longest * 2 > r.lights.len(),
            "{what}: most lights reach some tile ({longest} at most)"
        );
    }
}

/// Z-binning's tile test is gather's (with the light's rectangle), narrowed by its depth bins:
/// every cell's list is a subset of gather's list for its tile at the same tile size, over 50
/// seeds (CPU oracles), and over them all it evaluates fewer lights per pixel.
#[test]
fn zbin_keeps_a_subset_of_gathers_lists() {
    let ctx = common::gpu();
    let (w, h) = (37, 23);
    let (mut zbin_evaluated, mut gather_evaluated) = (0, 0);
    for seed in 3000..3050u64 {
        let case = random_case(seed);
        let r = render(&ctx, &case, w, h);
        for tile_size in [8, 16] {
            let zb = Strategy::ZBin {
                tile_size,
                bins: 64,
                slicing: Slicing::Exponential,
            };
            let gather = Strategy::TiledGather {
                tile_size,
                coarse: 0,
            };
            let pz = params(&r, &case, &zb);
            let pg = params(&r, &case, &gather);
            let td = cpu::depth_bounds(&r.frame, &pg, &r.depth, r.w, r.h).0;
            let g = cpu::gather(&r.frame, &pg, &r.lights, &td);
            let order = cpu::zbin_order(&r.frame, &pz, &r.lights);
            let z = cpu::zbin_lists(&r.frame, &pz, &r.lights, &td, &order);
            let tiles = (pz.tiles_x * pz.tiles_y) as usize;
            for (cell, kept) in z.kept.iter().enumerate() {
                let t = cell % tiles;
                for l in kept {
                    assert!(
                        g.kept[t].binary_search(l).is_ok()
                            || g.borderline[t].binary_search(l).is_ok(),
                        "{} tile {tile_size}: zbin keeps light {l} in cell {cell}, gather culls it from tile {t}",
                        case.label
                    );
                }
            }
            zbin_evaluated += metrics(&r, &pz, &z.to_bin_lists()).evaluated;
            gather_evaluated += metrics(&r, &pg, &g.to_bin_lists()).evaluated;
        }
    }
    println!("lights evaluated over 50 seeds: zbin {zbin_evaluated}, gather {gather_evaluated}");
    assert!(
        zbin_evaluated < gather_evaluated,
        "zbin evaluated {zbin_evaluated} lights, gather {gather_evaluated}"
    );
}

/// The box test (`CullSettings::tile_boxes`, on by default) against the side planes alone: with
/// it off, every strategy's GPU lists (gather's lines path, its stored masks, its chunks and
/// its single level; 2.5D; scatter's masks and pairs; z-binning; clusters, tested by their
/// pixels' boxes) equal their oracles too, and with it on every list is a subset of the list without it, over 6 seeds; over them
/// all it evaluates fewer lights per pixel, with no false negative.
#[test]
fn tile_boxes_keep_a_subset_of_the_planes_lists() {
    let ctx = common::gpu();
    let (w, h) = (70, 45);
    let mut totals = [0u64; 2];
    let mut cullers = None;
    for seed in [21u64, 22, 23, 24, 25, 26] {
        let case = random_case(seed);
        let r = render(&ctx, &case, w, h);
        let cullers = cullers.get_or_insert_with(|| {
            let mut stored = Culler::new(&ctx, &r.gpu_scene);
            stored.gather_lines = false;
            let mut unmasked = Culler::new(&ctx, &r.gpu_scene);
            unmasked.mask_budget = 0;
            [Culler::new(&ctx, &r.gpu_scene), stored, unmasked]
        });
        let strategies = [
            Strategy::tiled_gather(8),
            Strategy::TiledGather {
                tile_size: 16,
                coarse: 0,
            },
            Strategy::depth_mask(8),
            Strategy::TiledScatter { tile_size: 8 },
            Strategy::ZBin {
                tile_size: 8,
                bins: 32,
                slicing: Slicing::Exponential,
            },
            Strategy::Clustered {
                tile_size: 16,
                slices: 16,
                slicing: Slicing::Exponential,
                skip_empty: false,
                ordered: true,
                cells: false,
            },
        ];
        for (culler, s) in cullers
            .iter()
            .flat_map(|c| strategies.iter().map(move |s| (c, s)))
        {
            let what = format!(
                "{} {} (lines: {}, masks: {})",
                case.label,
                s.name(),
                culler.gather_lines,
                culler.mask_budget > 0
            );
            let lists = [true, false].map(|tile_boxes| {
                let settings = CullSettings {
                    tile_boxes,
                    ..CullSettings::for_camera(&case.camera)
                };
                let mut timer = GpuTimer::new(&ctx, 16);
                let out = culler
                    .run(&ctx, &r.gpu_scene, &r.depth_tex, s, &settings, &mut timer)
                    .unwrap();
                let p = out.params;
                let td = out.read_tile_depth(&ctx).unwrap();
                let gpu = out.read(&ctx).unwrap();
                let oracle = match s {
                    Strategy::TiledScatter { .. } => cpu::scatter(&r.frame, &p, &r.lights, &td),
                    Strategy::ZBin { .. } => {
                        let order = out.read_stored(&ctx).unwrap().1[..r.lights.len()].to_vec();
                        cpu::zbin_lists(&r.frame, &p, &r.lights, &td, &order)
                    }
                    Strategy::Clustered { .. } => {
                        let occ = out.read_occupancy(&ctx).unwrap();
                        cpu::clustered(&r.frame, &p, &r.lights, &occ)
                    }
                    _ => cpu::gather(&r.frame, &p, &r.lights, &td),
                };
                oracle
                    .compare(&gpu)
                    .unwrap_or_else(|e| panic!("{what}, tile_boxes {tile_boxes}: {e}"));
                let m = metrics(&r, &p, &gpu);
                assert_eq!(m.false_negatives, 0, "{what}, tile_boxes {tile_boxes}");
                totals[usize::from(!tile_boxes)] += m.evaluated;
                (gpu, oracle)
            });
            let [(with, _), (without, oracle)] = &lists;
            for b in 0..with.ranges.len() {
                let planes = without.sorted(b);
                for l in with.sorted(b) {
                    assert!(
                        planes.binary_search(&l).is_ok()
                            || oracle.borderline[b].binary_search(&l).is_ok(),
                        "{what}: the box test keeps light {l} in bin {b}, the planes alone do not"
                    );
                }
            }
        }
    }
    println!(
        "lights evaluated: with the box test {}, without {}",
        totals[0], totals[1]
    );
    assert!(totals[0] < totals[1], "{totals:?}");
}

/// The clusters' tile path (a workgroup a tile, [`Culler::cluster_tiles_max_lights`]), with the
/// lights' rectangles computed at every tile or in a pass of their own, gives the per-light
/// passes' lists, bin for bin and in light order, and leaves the same occupancy words,
/// with and without the box test and `skip_empty`, over several seeds; past
/// `CLUSTER_TILE_SLICES` slices the per-light passes run. The per-light passes give the same
/// lists with each cluster's box stored once (`cull.clustered.boxes`, with the box test) and
/// computed at every test ([`Culler::cluster_boxes`] false), testing every slice of a light's
/// range rather than only a tile's occupied slices ([`Culler::cluster_slice_masks`] false), and
/// with the wide lights split into bands of rows ([`Culler::cluster_lane_tiles`] 1: a band for
/// each 32 tiles), also where the band pool holds only some of the bands
/// ([`Culler::cluster_band_pool`]).
#[test]
fn cluster_tile_path_equals_the_per_light_passes() {
    use manylights_cull::layout::CLUSTER_TILE_SLICES;
    let ctx = common::gpu();
    let (w, h) = (70, 45);
    let mut cullers = None;
    for seed in [31u64, 32, 33, 34, 35, 36] {
        let case = random_case(seed);
        let r = render(&ctx, &case, w, h);
        let [
            by_tiles,
            with_rects,
            per_light,
            boxes_inline,
            unmasked,
            banded,
            pool_short,
        ] = cullers.get_or_insert_with(|| {
            // A culler set by `set`; `per_light`: on the per-light passes.
            let culler = |per_light: bool, set: &dyn Fn(&mut Culler)| {
                let mut c = Culler::new(&ctx, &r.gpu_scene);
                if per_light {
                    c.cluster_tiles_max_lights = 0;
                }
                set(&mut c);
                c
            };
            [
                culler(false, &|_| {}),
                // With the lights' rectangles in a pass of their own (these scenes are too
                // small to reach its default bound).
                culler(false, &|c| c.cluster_tile_rect_pairs = 0),
                culler(true, &|_| {}),
                culler(true, &|c| c.cluster_boxes = false),
                culler(true, &|c| c.cluster_slice_masks = false),
                culler(true, &|c| c.cluster_lane_tiles = 1),
                culler(true, &|c| {
                    c.cluster_lane_tiles = 1;
                    c.cluster_band_pool = Some(3);
                }),
            ]
        });
        for (tile_size, slices, skip_empty, tile_boxes) in [
            (8, 24, false, true),
            (16, 8, true, false),
            (8, CLUSTER_TILE_SLICES, false, false),
            (16, CLUSTER_TILE_SLICES, true, true),
            (8, CLUSTER_TILE_SLICES + 1, true, true),
        ] {
            let s = Strategy::Clustered {
                tile_size,
                slices,
                slicing: Slicing::Exponential,
                skip_empty,
                ordered: true,
                cells: false,
            };
            let what = format!(
                "{}: {tile_size} px, {slices} slices, skip_empty {skip_empty}, tile_boxes {tile_boxes}",
                case.label
            );
            let settings = CullSettings {
                tile_boxes,
                ..CullSettings::for_camera(&case.camera)
            };
            let cullers = [
                &*by_tiles,
                &*with_rects,
                &*per_light,
                &*boxes_inline,
                &*unmasked,
                &*banded,
                &*pool_short,
            ];
            let [a, r2, b, b2, b3, b4, b5] = cullers.map(|c| {
                let mut timer = GpuTimer::new(&ctx, 16);
                let out = c
                    .run(&ctx, &r.gpu_scene, &r.depth_tex, &s, &settings, &mut timer)
                    .unwrap();
                check_plan(&what, &out.passes, timer.read(&ctx).unwrap(), 1);
                out
            });
            let ran = |o: &manylights_cull::CullOutput, pass: &str| {
                o.passes.iter().any(|p| p.name == pass)
            };
            let tiles = slices <= CLUSTER_TILE_SLICES;
            assert_eq!(
                ran(&a, "cull.clustered.tiles_count"),
                tiles,
                "{what}: the tile path"
            );
            assert!(
                !ran(&a, "cull.clustered.rects"),
                "{what}: rectangles inline"
            );
            assert_eq!(
                ran(&r2, "cull.clustered.rects"),
                tiles,
                "{what}: the rectangles' pass"
            );
            assert!(
                !ran(&b, "cull.clustered.tiles_count"),
                "{what}: the per-light passes"
            );
            assert_eq!(
                ran(&b, "cull.clustered.boxes"),
                tile_boxes,
                "{what}: the clusters' boxes"
            );
            assert_eq!(
                ran(&a, "cull.clustered.boxes"),
                tile_boxes && !tiles,
                "{what}: the boxes' pass past the tile path"
            );
            assert!(!ran(&b2, "cull.clustered.boxes"), "{what}: no boxes' pass");
            // The tile path sizes its lists from its count pass's total: no scan.
            assert_eq!(
                a.passes.iter().any(|p| p.name == "scan"),
                !tiles,
                "{what}: the scan"
            );
            assert_eq!(a.total, b.total, "{what}: the lists' total");
            let lb = b.read(&ctx).unwrap();
            if tiles {
                // With a capacity (which caps the counts after the count pass) the tile path
                // scans the capped counts: each list the first lights of its uncapped one.
                let capped = by_tiles
                    .run(
                        &ctx,
                        &r.gpu_scene,
                        &r.depth_tex,
                        &s,
                        &CullSettings {
                            capacity: Some(2),
                            ..settings
                        },
                        &mut GpuTimer::new(&ctx, 16),
                    )
                    .unwrap();
                assert!(
                    capped.passes.iter().any(|p| p.name == "scan"),
                    "{what}: a capacity's scan"
                );
                let lc = capped.read(&ctx).unwrap();
                for bin in 0..lb.ranges.len() {
                    let full = lb.list(bin);
                    let kept = &full[..full.len().min(2)];
                    assert_eq!(lc.list(bin), kept, "{what}, capacity 2: bin {bin}");
                }
            }
            // The flags and the depth bounds (the slice masks after them are the per-light
            // passes' own).
            let flags_and_bounds = 3 * lb.ranges.len();
            let occupancy = b.read_occupancy(&ctx).unwrap()[..flags_and_bounds].to_vec();
            for (o, path) in [
                (&a, "tile path"),
                (&r2, "tile path with rectangles"),
                (&b2, "per-light passes computing each box"),
                (&b3, "per-light passes over every slice of a light's range"),
                (&b4, "per-light passes with bands of 32 tiles"),
                (&b5, "per-light passes with bands, the pool holding 3"),
            ] {
                let la = o.read(&ctx).unwrap();
                assert_eq!(la.ranges.len(), lb.ranges.len(), "{what}, {path}: bins");
                for bin in 0..la.ranges.len() {
                    assert_eq!(la.list(bin), lb.list(bin), "{what}, {path}: bin {bin}");
                }
                if skip_empty || tile_boxes {
                    assert_eq!(
                        o.read_occupancy(&ctx).unwrap()[..flags_and_bounds],
                        occupancy,
                        "{what}, {path}: occupancy"
                    );
                }
            }
        }
    }
}

/// Many lights over a narrow target: `cull.depth_bounds`'s light rows (each light's tile
/// rectangle, and scatter's blocks of tiles) would pass the device's workgroups along a
/// dimension if as wide as the tiles' rows (stability case 14 on an H200: tens of millions of
/// lights over 8 x 4 pixels), so they widen. With the limit lowered so that they must (8 workgroups: 4,100
/// lights take 17 workgroups of rows over 5 rows of tiles), gather's chunked lists (rectangles),
/// scatter's masks (blocks) and z-binning's lists (rectangles) equal their CPU oracles.
#[test]
fn depth_bounds_light_rows_widen_within_the_dispatch_limit() {
    let mut ctx = common::gpu();
    ctx.limits.max_compute_workgroups_per_dimension = 8;
    let (w, h) = (72, 40);
    let mut case = random_case(23);
    let lights = case.scene.lights.clone();
    case.scene.lights = lights.iter().cycle().take(4100).cloned().collect();
    let r = render(&ctx, &case, w, h);
    let mut culler = Culler::new(&ctx, &r.gpu_scene);
    culler.gather_lines = false;
    for s in [
        Strategy::tiled_gather(8),
        Strategy::TiledScatter { tile_size: 8 },
        cases::strategies()
            .into_iter()
            .find(|s| matches!(s, Strategy::ZBin { .. }))
            .unwrap(),
    ] {
        let what = format!("{} {} (4,100 lights, 8 workgroups)", case.label, s.name());
        let out = run_gpu(&ctx, &culler, &r, &case, &s);
        let td = out.read_tile_depth(&ctx).unwrap();
        let gpu = out.read(&ctx).unwrap();
        let p = out.params;
        assert!(
            p.tiles_y < 8 && p.light_count.div_ceil(256) + p.tiles_y > 8,
            "{what}"
        );
        let oracle = match s {
            Strategy::TiledScatter { .. } => cpu::scatter(&r.frame, &p, &r.lights, &td),
            Strategy::ZBin { .. } => cpu::zbin_lists(
                &r.frame,
                &p,
                &r.lights,
                &td,
                &cpu::zbin_order(&r.frame, &p, &r.lights),
            ),
            _ => cpu::gather(&r.frame, &p, &r.lights, &td),
        };
        oracle
            .compare(&gpu)
            .unwrap_or_else(|e| panic!("{what}: {e}"));
    }
}

/// The clusters with each light's tile rectangle from the exact bounds of its sphere's
/// projection ([`Culler::cluster_sphere_bounds`], Mara and McGuire 2013): on the per-light
/// passes and the tile path, the lists equal the CPU oracle's with the same bounds, have no
/// false negative, and are a subset of the lists from the box's corners, bin for bin (with the
/// box test, the same lists: only the candidate tiles are fewer, as the rectangles' tiles
/// summed over the lights show).
#[test]
fn cluster_sphere_bounds_give_a_conservative_subset() {
    let ctx = common::gpu();
    let (w, h) = (70, 45);
    let mut cullers = None;
    let (mut exact_tiles, mut corner_tiles) = (0i64, 0i64);
    for seed in [41u64, 42, 43, 44, 45, 46] {
        let case = random_case(seed);
        let r = render(&ctx, &case, w, h);
        let cullers = cullers.get_or_insert_with(|| {
            let make = |exact: bool, tiles: bool| {
                let mut c = Culler::new(&ctx, &r.gpu_scene);
                c.cluster_sphere_bounds = exact;
                if !tiles {
                    c.cluster_tiles_max_lights = 0;
                }
                c
            };
            [
                (make(false, false), make(true, false)),
                (make(false, true), make(true, true)),
            ]
        });
        for (corners, exact) in cullers.iter() {
            for (tile_size, slices) in [(8, 24), (16, 12)] {
                let s = Strategy::Clustered {
                    tile_size,
                    slices,
                    slicing: Slicing::Exponential,
                    skip_empty: false,
                    ordered: true,
                    cells: false,
                };
                let what = format!(
                    "{}: {tile_size} px x {slices}, per-light passes {}",
                    case.label,
                    exact.cluster_tiles_max_lights == 0
                );
                let a = run_gpu(&ctx, corners, &r, &case, &s);
                let b = run_gpu(&ctx, exact, &r, &case, &s);
                let (la, lb) = (a.read(&ctx).unwrap(), b.read(&ctx).unwrap());
                let p = b.params;
                assert!(
                    p.flags & manylights_cull::layout::CULL_FLAG_SPHERE_BOUNDS != 0
                        && geometry::sphere_bounds_apply(&r.frame, &p),
                    "{what}: the exact bounds apply"
                );
                cpu::clustered(&r.frame, &p, &r.lights, &b.read_occupancy(&ctx).unwrap())
                    .compare(&lb)
                    .unwrap_or_else(|e| panic!("{what}: {e}"));
                assert_eq!(
                    metrics(&r, &p, &lb).false_negatives,
                    0,
                    "{what}: false negatives"
                );
                for bin in 0..la.ranges.len() {
                    let (with, without) = (lb.sorted(bin), la.sorted(bin));
                    assert!(
                        with.iter().all(|l| without.contains(l)),
                        "{what}: bin {bin}: {with:?} not within {without:?}"
                    );
                }
                let without = GpuCullParams {
                    flags: p.flags & !manylights_cull::layout::CULL_FLAG_SPHERE_BOUNDS,
                    ..p
                };
                let area =
                    |r: [i32; 4]| i64::from((r[2] - r[0] + 1).max(0) * (r[3] - r[1] + 1).max(0));
                for l in &r.lights {
                    let c = geometry::CullLight::new(&r.frame, l, p.slack);
                    let (e, k) = (
                        geometry::light_tiles(&r.frame, &p, &c),
                        geometry::light_tiles(&r.frame, &without, &c),
                    );
                    assert!(
                        e[0] > e[2]
                            || e[1] > e[3]
                            || (e[0] >= k[0] && e[1] >= k[1] && e[2] <= k[2] && e[3] <= k[3]),
                        "{what}: rectangle {e:?} not within {k:?}"
                    );
                    exact_tiles += area(e);
                    corner_tiles += area(k);
                }
            }
        }
    }
    assert!(
        exact_tiles < corner_tiles,
        "the exact bounds' rectangles hold {exact_tiles} tiles, the corners' {corner_tiles}"
    );
    eprintln!("rectangles' tiles: {exact_tiles} exact, {corner_tiles} from the corners");
}

/// Z-binning's masks a light at a time (`Culler::zbin_scatter_min_lights` 0:
/// `cull.zbin.covers` and `cull.zbin.scatter`) against a tile at a time (`u32::MAX`:
/// `cull.zbin.masks`): over 8 seeds, in 8- and 16-pixel tiles, exponential and linear bins, with
/// the box test and without, and with 4,100 lights (129 words a tile), the sorted lights, the
/// bins' ranges and every mask word are the same, the scatter path's lists equal the CPU
/// oracle's with no false negative, the scatter path's three runs back to back leave the same
/// words as one, and each path runs the passes it names.
#[test]
fn zbin_scatter_masks_equal_the_gather_masks() {
    let ctx = common::gpu();
    let (w, h) = (70, 45);
    let mut cullers = None;
    let mut words = 0usize;
    for seed in [51u64, 52, 53, 54, 55, 56, 57, 58] {
        let mut case = random_case(seed);
        if seed == 58 {
            let lights = case.scene.lights.clone();
            case.scene.lights = lights.iter().cycle().take(4100).cloned().collect();
        }
        let r = render(&ctx, &case, w, h);
        let [scatter, gather] = cullers.get_or_insert_with(|| {
            [0, u32::MAX].map(|min| {
                let mut c = Culler::new(&ctx, &r.gpu_scene);
                c.zbin_scatter_min_lights = min;
                c
            })
        });
        for (s, tile_boxes) in [
            (8, 32, Slicing::Exponential, true),
            (16, 256, Slicing::Linear, true),
            (8, 64, Slicing::Exponential, false),
        ]
        .map(|(tile_size, bins, slicing, boxes)| {
            (
                Strategy::ZBin {
                    tile_size,
                    bins,
                    slicing,
                },
                boxes,
            )
        }) {
            let settings = CullSettings {
                tile_boxes,
                ..CullSettings::for_camera(&case.camera)
            };
            let what = format!("{} {s:?} tile_boxes {tile_boxes}", case.label);
            let [a, b] = [&*scatter, &*gather].map(|c| {
                let mut timer = GpuTimer::new(&ctx, 16);
                let out = c
                    .run(&ctx, &r.gpu_scene, &r.depth_tex, &s, &settings, &mut timer)
                    .unwrap();
                check_plan(&what, &out.passes, timer.read(&ctx).unwrap(), 1);
                out
            });
            let has =
                |o: &manylights_cull::CullOutput, n: &str| o.passes.iter().any(|p| p.name == n);
            assert!(
                has(&a, "cull.zbin.scatter") && !has(&a, "cull.zbin.masks"),
                "{what}: scatter path's passes"
            );
            assert!(
                has(&b, "cull.zbin.masks") && !has(&b, "cull.zbin.scatter"),
                "{what}: gather path's passes"
            );
            let (sa, sb) = (a.read_stored(&ctx).unwrap(), b.read_stored(&ctx).unwrap());
            assert_eq!(sa.0, sb.0, "{what}: bin ranges");
            let n = r.lights.len();
            assert_eq!(sa.1[..n], sb.1[..n], "{what}: sorted lights");
            let p = a.params;
            let per_tile = p.light_count.div_ceil(32) as usize;
            words = words.max(per_tile);
            for (k, (x, y)) in sa.1[n..].iter().zip(&sb.1[n..]).enumerate() {
                assert_eq!(
                    x,
                    y,
                    "{what}: tile {} mask word {}: scatter {x:#034b}, gather {y:#034b}",
                    k / per_tile,
                    k % per_tile
                );
            }
            assert_eq!(sa.1.len(), sb.1.len(), "{what}: mask words");
            // Back to back (each run zeroes only its covers' words): the same words again.
            let mut timer = GpuTimer::new(&ctx, 64);
            let again = scatter
                .run_repeated(
                    &ctx,
                    &r.gpu_scene,
                    &r.depth_tex,
                    &s,
                    &settings,
                    &a,
                    3,
                    &mut timer,
                )
                .unwrap();
            assert!(
                again.read_stored(&ctx).unwrap() == sa,
                "{what}: three runs back to back differ from one"
            );
            let td = a.read_tile_depth(&ctx).unwrap();
            let gpu = a.read(&ctx).unwrap();
            let order = sa.1[..n].to_vec();
            cpu::zbin_lists(&r.frame, &p, &r.lights, &td, &order)
                .compare(&gpu)
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_eq!(metrics(&r, &p, &gpu).false_negatives, 0, "{what}");
        }
    }
    assert!(words > 128, "some case has masks of over 128 words a tile");
}

/// The clusters' 2.5D cells (`Strategy::Clustered::cells`, `cull.clustered.cells`) against the
/// clusters without them, over 8 seeds, two grids, and each cluster's box stored or computed
/// at each test: each cluster's cells equal the CPU oracle's (over the GPU's depth bounds), the
/// lists equal the CPU oracle's with no false negative and are a subset of the lists without
/// cells, bin for bin, and over all seeds they hold fewer entries. Without the box test the run
/// is refused, naming the field.
#[test]
fn cluster_cells_keep_a_subset_of_the_lists_without() {
    let ctx = common::gpu();
    let (w, h) = (70, 45);
    let mut cullers = None;
    let mut entries = [0usize; 2];
    let mut cells_set = 0;
    for seed in [61u64, 62, 63, 64, 65, 66, 67, 68] {
        let case = random_case(seed);
        let r = render(&ctx, &case, w, h);
        let cullers = cullers.get_or_insert_with(|| {
            let mut computed = Culler::new(&ctx, &r.gpu_scene);
            computed.cluster_boxes = false;
            [Culler::new(&ctx, &r.gpu_scene), computed]
        });
        for (culler, (tile_size, slices, slicing)) in cullers.iter().flat_map(|c| {
            [(16, 16, Slicing::Exponential), (8, 32, Slicing::Linear)]
                .into_iter()
                .map(move |g| (c, g))
        }) {
            let strategy = |cells| Strategy::Clustered {
                tile_size,
                slices,
                slicing,
                skip_empty: false,
                ordered: true,
                cells,
            };
            let what = format!(
                "{} clusters {tile_size} x {slices} {slicing:?} (stored boxes: {})",
                case.label, culler.cluster_boxes
            );
            let [(without, _), (with, out)] = [false, true].map(|cells| {
                let out = run_gpu(&ctx, culler, &r, &case, &strategy(cells));
                let p = out.params;
                assert_eq!(
                    out.passes.iter().any(|s| s.name == "cull.clustered.cells"),
                    cells,
                    "{what}, cells {cells}: the cells pass"
                );
                let occ = out.read_occupancy(&ctx).unwrap();
                let gpu = out.read(&ctx).unwrap();
                cpu::clustered(&r.frame, &p, &r.lights, &occ)
                    .compare(&gpu)
                    .unwrap_or_else(|e| panic!("{what}, cells {cells}: {e}"));
                assert_eq!(
                    metrics(&r, &p, &gpu).false_negatives,
                    0,
                    "{what}, cells {cells}"
                );
                entries[usize::from(cells)] += gpu.indices.len();
                (gpu, out)
            });
            let p = out.params;
            let occ = out.read_occupancy(&ctx).unwrap();
            let bins = p.bins as usize;
            let at = 3 * bins + 2 * (p.tiles_x * p.tiles_y) as usize;
            let cells = cpu::cluster_cells(&r.frame, &p, &r.depth, (w, h), 1, &occ);
            for (b, (&g, &c)) in occ[at..at + bins].iter().zip(&cells).enumerate() {
                assert_eq!(
                    g, c,
                    "{what}: cluster {b} cells {g:#034b}, oracle {c:#034b}"
                );
            }
            cells_set += occ[at..at + bins].iter().filter(|&&c| c != 0).count();
            for b in 0..with.ranges.len() {
                let all = without.sorted(b);
                for l in with.sorted(b) {
                    assert!(
                        all.binary_search(&l).is_ok(),
                        "{what}: the cells keep light {l} in cluster {b}, the clusters without them do not"
                    );
                }
            }
        }
    }
    println!(
        "list entries over 8 seeds: {} with cells, {} without",
        entries[1], entries[0]
    );
    assert!(cells_set > 0, "no cluster has cells set");
    assert!(entries[1] < entries[0], "cells: {entries:?}");
    // Without the box test, whose depth bounds the cells divide: refused.
    let case = random_case(61);
    let r = render(&ctx, &case, w, h);
    let culler = Culler::new(&ctx, &r.gpu_scene);
    let settings = CullSettings {
        tile_boxes: false,
        ..CullSettings::for_camera(&case.camera)
    };
    let s = Strategy::Clustered {
        tile_size: 16,
        slices: 16,
        slicing: Slicing::Exponential,
        skip_empty: false,
        ordered: true,
        cells: true,
    };
    let mut timer = GpuTimer::new(&ctx, 16);
    let e = culler
        .run(&ctx, &r.gpu_scene, &r.depth_tex, &s, &settings, &mut timer)
        .err()
        .expect("cells without the box test are refused");
    assert!(e.to_string().contains("cells"), "{e}");
}
