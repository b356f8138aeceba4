//! The GPU radix sort (`sort.radix`, both paths: onesweep and portable) and the scan under the
//! portable path, against the standard library's stable sort and against the published
//! `lampshade` radix sort, on the same device.

mod common;

use manylights_cull::radix_sort::{self, RadixSort, SortPath, SortedIn};
use manylights_cull::scan::ScanPath;
use manylights_gpu::timing::GpuTimer;
use manylights_gpu::{GpuContext, readback};
use rand::{RngExt, SeedableRng};

fn upload(ctx: &GpuContext, data: &[u32]) -> wgpu::Buffer {
    let b = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: (data.len() as u64 * 4).max(4),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    ctx.queue.write_buffer(&b, 0, bytemuck::cast_slice(data));
    b
}

fn download(ctx: &GpuContext, b: &wgpu::Buffer, n: usize) -> Vec<u32> {
    if n == 0 {
        return Vec::new();
    }
    bytemuck::pod_collect_to_vec(&readback::read_buffer(ctx, b, 0, n as u64 * 4).unwrap())
}

fn gpu_sort(
    ctx: &GpuContext,
    sort: &RadixSort,
    keys: &[u32],
    vals: &[u32],
    bits: u32,
) -> (Vec<u32>, Vec<u32>) {
    let n = keys.len();
    let (k, v) = (upload(ctx, keys), upload(ctx, vals));
    let (kt, vt) = (upload(ctx, &vec![0; n]), upload(ctx, &vec![0; n]));
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    let at = sort
        .encode(
            ctx,
            &mut enc,
            &k,
            &v,
            &kt,
            &vt,
            n as u32,
            bits,
            &mut GpuTimer::new(ctx, 512),
        )
        .unwrap();
    ctx.submit_and_wait(enc, "sort").unwrap();
    let (k, v) = if at == SortedIn::Input {
        (k, v)
    } else {
        (kt, vt)
    };
    (download(ctx, &k, n), download(ctx, &v, n))
}

/// Index and values of the first difference, for a readable failure.
fn first_diff(a: &(Vec<u32>, Vec<u32>), b: &(Vec<u32>, Vec<u32>)) -> Option<String> {
    if a.0.len() != b.0.len() {
        return Some(format!("lengths {} vs {}", a.0.len(), b.0.len()));
    }
    (0..a.0.len())
        .find(|&i| a.0[i] != b.0[i] || a.1[i] != b.1[i])
        .map(|i| {
            format!(
                "at {i}: ({}, {}) vs ({}, {})",
                a.0[i], a.1[i], b.0[i], b.1[i]
            )
        })
}

/// lampshade's key-value radix sort on the same device.
fn lampshade_sort(
    lamp: &mut lampshade::KeyValueSorter,
    keys: &[u32],
    vals: &[u32],
    bits: u32,
) -> (Vec<u32>, Vec<u32>) {
    let pairs: Vec<lampshade::KeyValue> = keys
        .iter()
        .zip(vals)
        .map(|(&k, &v)| lampshade::KeyValue::new(k, v))
        .collect();
    let sorted = pollster::block_on(lamp.sort_with_key_bits(&pairs, bits)).expect("lampshade sort");
    sorted.into_iter().map(|kv| (kv.key, kv.value)).unzip()
}

fn key_sets(n: usize, rng: &mut rand_pcg::Pcg64) -> Vec<(&'static str, Vec<u32>)> {
    let random: Vec<u32> = (0..n).map(|_| rng.random::<u32>()).collect();
    let mut sorted = random.clone();
    sorted.sort_unstable();
    let reverse: Vec<u32> = sorted.iter().rev().copied().collect();
    let few: Vec<u32> = (0..n).map(|_| rng.random_range(0..7u32)).collect();
    vec![
        ("random", random),
        ("all equal", vec![0xdead_beef; n]),
        ("sorted", sorted),
        ("reverse", reverse),
        ("few distinct", few),
    ]
}

/// Keys random, all equal, already sorted, reverse sorted and with few distinct values; counts
/// 0, 1, non-powers of two and block edges; all 32 key bits and a partial key (13 bits, the tile
/// index of 1080p at 16 px). Values are the input positions, so equality with the standard
/// library's stable sort checks stability too.
#[test]
fn radix_sort_portable_matches_std_stable_sort() {
    let ctx = common::gpu();
    check_against_std(
        &ctx,
        &RadixSort::with_scan_path(&ctx, ScanPath::Portable).unwrap(),
    );
}

/// The same cases with the subgroup scan under the sort (lavapipe and NVIDIA have subgroups).
#[test]
fn radix_sort_subgroup_matches_std_stable_sort() {
    let ctx = common::gpu();
    let sort = RadixSort::with_scan_path(&ctx, ScanPath::Subgroup)
        .unwrap_or_else(|| panic!("adapter {} has no subgroup operations", ctx.info.name));
    check_against_std(&ctx, &sort);
}

/// The onesweep path (8-bit digits, decoupled look-back) on the same cases, plus partition edges.
#[test]
fn radix_sort_onesweep_matches_std_stable_sort() {
    let ctx = common::gpu();
    assert_eq!(RadixSort::new(&ctx).path(), SortPath::Onesweep);
    let sort = onesweep(&ctx);
    check_against_std(&ctx, &sort);
    check_sizes(&ctx, &sort, &[3839, 3840, 3841, 7681], None);
    // One-pass sorts (8 and 5 key bits) back to back with one sorter, which reuses its scratch
    // buffers for as many pairs: each sort must start from a cleared look-back status, not
    // read the one before's (whose words carry the same pass).
    let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
    for n in [3841, 100_003] {
        for bits in [8, 8, 5, 8] {
            let keys: Vec<u32> = (0..n).map(|_| rng.random::<u32>()).collect();
            let vals: Vec<u32> = (0..n as u32).collect();
            let got = gpu_sort(&ctx, &sort, &keys, &vals, bits);
            let expect = radix_sort::cpu(&keys, &vals, bits);
            assert!(
                first_diff(&got, &expect).is_none(),
                "{n} keys, {bits} bits, sorted after another: {}",
                first_diff(&got, &expect).unwrap()
            );
        }
    }
}

/// The look-back's fallback alone (every predecessor counted from its keys, none read from its
/// status), and look-back without spinning (a predecessor not ready at the first poll is
/// counted): the same pairs as the standard library's stable sort.
#[test]
fn radix_sort_onesweep_fallback_matches_std_stable_sort() {
    let ctx = common::gpu();
    let mut sort = onesweep(&ctx);
    sort.fallback_only = true;
    check_sizes(&ctx, &sort, &[2, 3841, 7680, 100_003], None);
    sort.fallback_only = false;
    sort.max_spin = 0;
    check_sizes(&ctx, &sort, &[3841, 100_003, 1_000_001], None);
}

fn onesweep(ctx: &GpuContext) -> RadixSort {
    RadixSort::onesweep(ctx).unwrap_or_else(|| {
        panic!(
            "adapter {} has no subgroups of 8 to 32 invocations (has {:?}: {})",
            ctx.info.name,
            ctx.features.subgroup_size,
            ctx.summary()
        )
    })
}

fn check_against_std(ctx: &GpuContext, sort: &RadixSort) {
    let mut lamp = lampshade::KeyValueSorter::new(&ctx.device, &ctx.queue);
    check_sizes(
        ctx,
        sort,
        &[0, 1, 2, 3, 1000, 1023, 1024, 1025, 4097, 100_003],
        Some(&mut lamp),
    );
}

fn check_sizes(
    ctx: &GpuContext,
    sort: &RadixSort,
    sizes: &[usize],
    mut lamp: Option<&mut lampshade::KeyValueSorter>,
) {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(9);
    for &n in sizes {
        for (kind, keys) in key_sets(n, &mut rng) {
            let vals: Vec<u32> = (0..n as u32).collect();
            for bits in [32, 13] {
                let expect = radix_sort::cpu(&keys, &vals, bits);
                let got = gpu_sort(ctx, sort, &keys, &vals, bits);
                assert!(
                    first_diff(&got, &expect).is_none(),
                    "{n} keys, {kind}, {bits} bits: {}",
                    first_diff(&got, &expect).unwrap()
                );
                if let Some(lamp) = lamp.as_deref_mut()
                    && n > 0
                {
                    // lampshade takes partial keys only when they fit their bits: compare both
                    // sorts on the keys masked to `bits`.
                    let mask = if bits == 32 {
                        u32::MAX
                    } else {
                        (1 << bits) - 1
                    };
                    let masked: Vec<u32> = keys.iter().map(|k| k & mask).collect();
                    let got = if bits == 32 {
                        got
                    } else {
                        gpu_sort(ctx, sort, &masked, &vals, bits)
                    };
                    let theirs = lampshade_sort(lamp, &masked, &vals, bits);
                    assert!(
                        first_diff(&got, &theirs).is_none(),
                        "{n} keys, {kind}, {bits} bits vs lampshade: {}",
                        first_diff(&got, &theirs).unwrap()
                    );
                }
            }
        }
    }
}

/// Several million pairs: against the standard library and against lampshade's radix sort on the
/// same device (both stable, so the pairs agree exactly).
#[test]
fn radix_sort_matches_std_and_lampshade_on_millions() {
    let ctx = common::gpu();
    let sort = RadixSort::new(&ctx);
    let mut rng = rand_pcg::Pcg64::seed_from_u64(10);
    let mut lamp = lampshade::KeyValueSorter::new(&ctx.device, &ctx.queue);
    for (n, bits) in [(3_000_017usize, 32u32), (4_194_304, 20)] {
        let keys: Vec<u32> = (0..n)
            .map(|_| {
                rng.random::<u32>()
                    & if bits == 32 {
                        u32::MAX
                    } else {
                        (1 << bits) - 1
                    }
            })
            .collect();
        let vals: Vec<u32> = (0..n as u32).collect();
        let ours = gpu_sort(&ctx, &sort, &keys, &vals, bits);
        let std = radix_sort::cpu(&keys, &vals, bits);
        assert!(
            first_diff(&ours, &std).is_none(),
            "{n} keys vs std: {}",
            first_diff(&ours, &std).unwrap()
        );
        let theirs = lampshade_sort(&mut lamp, &keys, &vals, bits);
        assert!(
            first_diff(&ours, &theirs).is_none(),
            "{n} keys vs lampshade: {}",
            first_diff(&ours, &theirs).unwrap()
        );
    }
}

/// More pairs than the onesweep path's 28-bit look-back counts hold is an error naming the
/// limit, before any work is encoded.
#[test]
fn radix_sort_onesweep_refuses_more_pairs_than_it_counts() {
    let ctx = common::gpu();
    let sort = onesweep(&ctx);
    let b = upload(&ctx, &[0; 4]);
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    let err = sort
        .encode(
            &ctx,
            &mut enc,
            &b,
            &b,
            &b,
            &b,
            radix_sort::ONESWEEP_MAX_PAIRS + 1,
            32,
            &mut GpuTimer::new(&ctx, 16),
        )
        .expect_err("2^28 pairs")
        .to_string();
    assert!(
        err.contains("268435456") && err.contains("268435455") && err.contains("onesweep"),
        "{err}"
    );
}
