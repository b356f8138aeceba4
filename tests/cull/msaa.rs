//! MSAA: culling a multisampled depth buffer (`Culler::with_samples`). The tiles' depth bounds
//! are taken over every sample (against a reduction on the host of every sample's depth), and
//! every strategy's lists are conservative for every sample (the exact oracle checks each
//! covered sample at its standard position).

use super::*;

use manylights_cull::metrics::from_gpu_counts;
use manylights_gpu::prepass::{DepthPrepass, depth_target_msaa};

/// `case` drawn into a depth buffer of `samples` samples a pixel.
fn render_msaa(
    ctx: &GpuContext,
    case: &Case,
    w: u32,
    h: u32,
    samples: u32,
) -> (manylights_gpu::GpuScene, wgpu::Texture) {
    let gs = manylights_gpu::GpuScene::upload(ctx, &case.scene, &case.camera, w, h).unwrap();
    let depth = depth_target_msaa(ctx, w, h, samples);
    let view = depth.create_view(&Default::default());
    let mut timer = GpuTimer::new(ctx, 1);
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    DepthPrepass::with_samples(ctx, &gs, samples).encode(&mut enc, &gs, &view, &mut timer);
    ctx.submit_and_wait(enc, "msaa prepass").unwrap();
    (gs, depth)
}

fn settings(case: &Case) -> CullSettings {
    CullSettings::for_camera(&case.camera)
}

/// Gather's and 2.5D's tile depth data over a 4x multisampled depth buffer: each tile's
/// nearest and farthest covered sample and its covered samples, as the host reduces them
/// from every sample's depth; and, over the seeds, tiles whose samples reach past what their
/// pixels' centres alone would give (failure case 17 of RESEARCH.md: bounds from one sample a
/// pixel miss lights that reach the others).
#[test]
fn msaa_tile_depth_bounds_cover_every_sample() {
    let ctx = common::gpu();
    let samples = 4;
    ctx.check_msaa(samples).unwrap();
    let (w, h) = (61, 37);
    let mut wider = 0;
    for seed in 0..6u64 {
        let case = random_case(900 + seed);
        let (gs, depth) = render_msaa(&ctx, &case, w, h, samples);
        let culler = Culler::with_samples(&ctx, &gs, samples);
        let single = render(&ctx, &case, w, h);
        for s in [Strategy::tiled_gather(8), Strategy::depth_mask(16)] {
            let mut timer = GpuTimer::new(&ctx, 16);
            let out = culler
                .run(&ctx, &gs, &depth, &s, &settings(&case), &mut timer)
                .unwrap();
            let what = format!("{} {}", case.label, s.name());
            let p = out.params;
            let td = out.read_tile_depth(&ctx).unwrap();
            let z = culler.depth_samples(&ctx, &gs, &depth, &out).unwrap();
            assert_eq!(z.len(), (w * h * samples) as usize);
            let frame = GpuFrame::new(&case.camera, w, h, case.scene.lights.len() as u32);
            let tiles = (p.tiles_x * p.tiles_y) as usize;
            let mut lo = vec![f32::INFINITY; tiles];
            let mut hi = vec![0.0f32; tiles];
            let mut covered = vec![0u32; tiles];
            for y in 0..h {
                for x in 0..w {
                    let t = ((y / p.tile_size) * p.tiles_x + x / p.tile_size) as usize;
                    for k in 0..samples {
                        let d = z[((y * w + x) * samples + k) as usize];
                        if d < 1.0 {
                            lo[t] = lo[t].min(d);
                            hi[t] = hi[t].max(d);
                            covered[t] += 1;
                        }
                    }
                }
            }
            let (centre, _) = cpu::depth_bounds(&single.frame, &p, &single.depth, w, h);
            let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * a.abs().max(b.abs()).max(1e-3);
            for t in 0..tiles {
                assert_eq!(
                    td[t].covered, covered[t],
                    "{what}: tile {t}'s covered samples"
                );
                if covered[t] == 0 {
                    continue;
                }
                let (dmin, dmax) = (
                    geometry::linear_depth(&frame, lo[t]),
                    geometry::linear_depth(&frame, hi[t]),
                );
                assert!(
                    close(td[t].dmin, dmin) && close(td[t].dmax, dmax),
                    "{what}: tile {t} bounds {}..{} against the samples' {dmin}..{dmax}",
                    td[t].dmin,
                    td[t].dmax
                );
                if centre[t].covered == 0
                    || dmin < centre[t].dmin * 0.999
                    || dmax > centre[t].dmax * 1.001
                {
                    wider += 1;
                }
            }
        }
    }
    assert!(
        wider > 0,
        "no tile's samples reached past its pixel centres' bounds"
    );
}

/// Every strategy over multisampled depth buffers (every count the device has, up to 8):
/// zero false negatives at every covered sample of every pixel, on random scenes; the oracle
/// counted samples, not pixels.
#[test]
fn msaa_lists_are_conservative_for_every_sample() {
    let ctx = common::gpu();
    let (w, h) = (48, 30);
    let mut needed = 0;
    let counts: Vec<u32> = ctx
        .msaa_counts()
        .into_iter()
        .filter(|&n| n > 1 && n <= 8)
        .collect();
    assert!(counts.contains(&4), "{counts:?}");
    for (i, &samples) in counts.iter().enumerate() {
        for seed in 0..3u64 {
            let case = random_case(950 + 10 * i as u64 + seed);
            let (gs, depth) = render_msaa(&ctx, &case, w, h, samples);
            let culler = Culler::with_samples(&ctx, &gs, samples);
            let frame = GpuFrame::new(&case.camera, w, h, case.scene.lights.len() as u32);
            for s in strategies() {
                let mut timer = GpuTimer::new(&ctx, 16);
                let out = culler
                    .run(&ctx, &gs, &depth, &s, &settings(&case), &mut timer)
                    .unwrap();
                let what = format!("{} {} x{samples}", case.label, s.name());
                let counts = culler
                    .exact_counts(&ctx, &gs, &depth, &out, frame.clip_from_world.inverse(), 1)
                    .unwrap();
                let pixels = counts.iter().filter(|c| c[3] > 0).count() as u64;
                let m = from_gpu_counts(&counts, &out.bin_lengths(&ctx).unwrap());
                assert_eq!(m.false_negatives, 0, "{what}: false negatives");
                assert!(
                    m.covered_pixels > pixels,
                    "{what}: {} covered samples over {pixels} pixels",
                    m.covered_pixels
                );
                needed += m.needed;
            }
        }
    }
    assert!(needed > 0, "no light reaches any sample of any case");
}

/// Clusters over a 4x multisampled depth buffer, on both paths (a workgroup a tile, and the
/// per-light passes' cull.occupancy): a pixel holds every cluster of its tile from its nearest
/// sample's slice to its farthest's, each over its part of the pixel's depths, as the host
/// oracle (`cpu::occupancy_samples`) marks them from every sample's depth; and, over the seeds,
/// pixels whose samples span slices between which no sample lies (so that a fragment looked up
/// at its centroid, between its samples' depths, finds a cluster that holds its lights).
#[test]
fn msaa_clusters_hold_every_slice_between_a_pixels_samples() {
    let ctx = common::gpu();
    let samples = 4;
    let (w, h) = (61, 37);
    let mut between = 0;
    for seed in 0..4u64 {
        let case = random_case(930 + seed);
        let (gs, depth) = render_msaa(&ctx, &case, w, h, samples);
        let tiles_path = Culler::with_samples(&ctx, &gs, samples);
        let mut per_light = Culler::with_samples(&ctx, &gs, samples);
        per_light.cluster_tiles_max_lights = 0;
        let frame = GpuFrame::new(&case.camera, w, h, case.scene.lights.len() as u32);
        for culler in [&tiles_path, &per_light] {
            let s = Strategy::Clustered {
                tile_size: 16,
                slices: 32,
                slicing: Slicing::Exponential,
                skip_empty: true,
                ordered: true,
                cells: false,
            };
            let mut timer = GpuTimer::new(&ctx, 16);
            let out = culler
                .run(&ctx, &gs, &depth, &s, &settings(&case), &mut timer)
                .unwrap();
            let what = format!(
                "{} per-light {}",
                case.label,
                culler.cluster_tiles_max_lights == 0
            );
            let p = out.params;
            let z = culler.depth_samples(&ctx, &gs, &depth, &out).unwrap();
            let occ = out.read_occupancy(&ctx).unwrap();
            let cpu_occ = cpu::occupancy_samples(&frame, &p, &z, w, h, samples);
            let bins = p.bins as usize;
            assert_eq!(occ[..bins], cpu_occ[..bins], "{what}: occupancy");
            for (k, (&g, &c)) in occ[bins..].iter().zip(&cpu_occ[bins..]).enumerate() {
                let (a, b) = if k % 2 == 0 { (!g, !c) } else { (g, c) };
                let (a, b) = (
                    geometry::from_ordered_bits(a),
                    geometry::from_ordered_bits(b),
                );
                assert!(
                    (g == 0) == (c == 0)
                        && (g == 0 || (a - b).abs() <= 1e-5 * a.abs().max(b.abs())),
                    "{what}: cluster {} depth bound {} {a} against {b}",
                    k / 2,
                    k % 2
                );
            }
            // Clusters held only by pixels whose samples lie on both sides of them.
            let tiles = (p.tiles_x * p.tiles_y) as usize;
            let mut by_samples = vec![false; bins];
            for y in 0..h {
                for x in 0..w {
                    for k in 0..samples {
                        let zk = z[((y * w + x) * samples + k) as usize];
                        if zk < 1.0 {
                            by_samples[geometry::bin_of(&frame, &p, [x, y], zk) as usize] = true;
                        }
                    }
                }
            }
            between += (0..bins)
                .filter(|&b| occ[b] != 0 && !by_samples[b] && b >= tiles)
                .count();
        }
    }
    assert!(between > 0, "no pixel's samples spanned an empty slice");
}

/// A sample count the device does not have is an error naming the ones it has.
#[test]
fn unsupported_sample_counts_are_rejected_naming_the_supported_ones() {
    let ctx = common::gpu();
    let counts = ctx.msaa_counts();
    assert!(counts.contains(&1) && counts.contains(&4), "{counts:?}");
    for bad in [0, 3, 5, 64] {
        let e = ctx.check_msaa(bad).unwrap_err().to_string();
        assert!(e.contains(&format!("{bad} samples")), "{e}");
        assert!(e.contains("1, ") && e.contains('4'), "{e}");
    }
}
