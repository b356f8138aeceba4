//! The clusters' order passes, each sort on lists built to reach it.

use super::*;

/// The clusters' order passes put every list into light order by each of their sorts, on the
/// per-light passes with 20,000 lights (over 16,384, so that a bucket of 256 spans 128 light
/// indices and a list can crowd one; at most 65,536, so that the bitmap's sort runs). Among
/// 20,000 small lights (a seventh of them in view), some cover the whole view: every 6th, 20th
/// or 64th light (lists over 2,048, over 512 and under 512 lights, a few lights a bucket: the
/// bucket sort, in place in the list buffer and in workgroup memory), or the first 600 or 300 (lists that
/// crowd their buckets, which the network sorts instead, in place and in workgroup memory), or
/// every 2nd (lists over 4,096 lights: the network in place). Each list, with the bitmap
/// ([`Culler::cluster_order_bits`]) and without it, is the unordered run's, sorted.
#[test]
fn cluster_order_passes_sort_every_list() {
    let ctx = common::gpu();
    let (w, h) = (70, 45);
    let mut scene = ProceduralScene::Atrium(AtriumParams {
        bays: 3,
        storeys: 2,
        cloth: false,
        glass: false,
    })
    .build()
    .unwrap();
    let ext = scene.light_bounds.extent();
    let small = LightSpec {
        generator: LightGenerator::Uniform,
        count: 20_000,
        seed: 9,
        radius: RadiusRule::Fixed(ext.max_element() * 0.002),
        intensity: 1.0,
        spot_fraction: 0.0,
        ..LightSpec::default()
    }
    .generate(&scene)
    .unwrap();
    let clusters = |ordered| Strategy::Clustered {
        tile_size: 16,
        slices: 8,
        slicing: Slicing::Exponential,
        skip_empty: false,
        ordered,
        cells: false,
    };
    let mut cullers: Option<[Culler; 2]> = None;
    // (label, whether light `i` covers the view, the longest list's length)
    type Covering = (&'static str, fn(usize) -> bool, std::ops::Range<usize>);
    let covering: [Covering; 6] = [
        ("every 2nd", |i| i % 2 == 0, 4097..20_000),
        ("every 6th", |i| i % 6 == 0, 2049..4097),
        ("every 20th", |i| i % 20 == 0, 513..2049),
        ("every 64th", |i| i % 64 == 0, 16..513),
        ("the first 600", |i| i < 600, 513..2049),
        ("the first 300", |i| i < 300, 16..513),
    ];
    for (label, covers, longest_in) in covering {
        scene.lights = small.clone();
        for (i, l) in scene.lights.iter_mut().enumerate() {
            if covers(i) {
                l.radius = ext.length() * 2.0;
            } else if i % 7 != 0 {
                // Out of every list: a seventh of the small lights stay in the scene.
                l.position = scene.light_bounds.min - ext * 10.0;
            }
        }
        let case = Case {
            camera: scene.camera,
            scene: scene.clone(),
            label: format!("{label} covering"),
        };
        let r = render(&ctx, &case, w, h);
        let [bits, network] = cullers.get_or_insert_with(|| {
            let culler = |bits: bool| {
                let mut c = Culler::new(&ctx, &r.gpu_scene);
                c.cluster_order_bits = bits;
                c
            };
            [culler(true), culler(false)]
        });
        let unordered = run_gpu(&ctx, bits, &r, &case, &clusters(false))
            .read(&ctx)
            .unwrap();
        let longest = (0..unordered.ranges.len())
            .map(|b| unordered.list(b).len())
            .max()
            .unwrap();
        assert!(
            longest_in.contains(&longest),
            "{}: the longest list, {longest}, not in {longest_in:?}",
            case.label
        );
        for (culler, sort) in [(&*bits, "bitmap"), (&*network, "buckets")] {
            let ordered = run_gpu(&ctx, culler, &r, &case, &clusters(true))
                .read(&ctx)
                .unwrap();
            assert_eq!(ordered.ranges.len(), unordered.ranges.len());
            for b in 0..ordered.ranges.len() {
                assert_eq!(
                    ordered.list(b),
                    unordered.sorted(b).as_slice(),
                    "{} ({sort}): bin {b}",
                    case.label
                );
            }
        }
    }
}
