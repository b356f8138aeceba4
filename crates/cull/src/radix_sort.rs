//! `sort.radix`: a stable LSD radix sort of (u32 key, u32 value) pairs on the GPU, written here
//! because it is a subject of study. Tested against the standard library's stable sort and the
//! `lampshade` crate. Two paths ([`SortPath`]):
//!
//! - **Onesweep** (`shaders/sort/onesweep.wgsl`), where the adapter has subgroups of 8 to 32
//!   invocations: 8-bit digits; `sort.radix.init` zeroes the look-back state,
//!   `sort.radix.histogram` counts every pass's digits in one read of the keys, then one
//!   `sort.radix.onesweep` pass per digit ranks each partition's keys with subgroup ballots,
//!   finds its output offsets by decoupled look-back (with a fallback that counts a stalled
//!   predecessor's keys, so no workgroup waits on another) and writes the pairs out in digit
//!   order. Up to 2^28 - 1 pairs.
//! - **Portable** (`shaders/sort/radix_sort.wgsl`), anywhere: 4-bit digits; per pass
//!   `sort.radix.count` (per-block digit histograms, digit-major), the scan over them,
//!   `sort.radix.scatter` (stable in-block ranks).
//!
//! Only the key bits asked for are sorted: sorting tile indices of 8,160 tiles takes 13 bits,
//! two onesweep passes or four portable ones.

use std::sync::{Mutex, PoisonError};

use manylights_gpu::shader_file;
use manylights_gpu::shaders::{ShaderDef, WgslConst};
use manylights_gpu::timing::GpuTimer;
use manylights_gpu::{GpuContext, GpuError, pipeline};

use crate::layout::GROUPS_X;
use crate::scan::{Scan, ScanPath, groups_2d};

/// Bits sorted per pass of the portable path.
pub const RADIX_BITS: u32 = 4;
/// Threads per workgroup of the portable path.
pub const SORT_THREADS: u32 = 256;
/// Keys per thread of the portable path.
pub const SORT_PER_THREAD: u32 = 4;
/// Keys per block (workgroup) of the portable path; a 16-bit rank field holds up to 65,535.
pub const SORT_BLOCK: u32 = SORT_THREADS * SORT_PER_THREAD;
const _: () = assert!(SORT_BLOCK < 1 << 16);

/// Bits sorted per onesweep pass.
pub const ONESWEEP_BITS: u32 = 8;
/// Threads per onesweep workgroup (one digit each in the per-digit steps).
pub const ONESWEEP_THREADS: u32 = 256;
/// Keys per onesweep thread.
pub const ONESWEEP_PER_THREAD: u32 = 15;
/// Keys per onesweep partition (workgroup); its 16-bit count fields hold up to 65,535.
pub const ONESWEEP_PART: u32 = ONESWEEP_THREADS * ONESWEEP_PER_THREAD;
/// Smallest subgroup the onesweep path takes (its per-subgroup counts are sized for it).
pub const ONESWEEP_MIN_SUBGROUP: u32 = 8;
/// Largest subgroup the onesweep path takes (ballots are read as one 32-bit word).
pub const ONESWEEP_MAX_SUBGROUP: u32 = 32;
/// Keys a `sort.radix.histogram` workgroup counts.
pub const ONESWEEP_HIST_KEYS: u32 = 32_768;
/// Most pairs the onesweep path sorts: its look-back status words hold 28-bit counts.
pub const ONESWEEP_MAX_PAIRS: u32 = (1 << 28) - 1;
/// Default polls of a predecessor's look-back status before counting its keys instead.
pub const ONESWEEP_MAX_SPIN: u32 = 256;
const ONESWEEP_MAX_SUBGROUPS: u32 = ONESWEEP_THREADS / ONESWEEP_MIN_SUBGROUP;
const ONESWEEP_SHARED_WORDS: u32 =
    if ONESWEEP_MAX_SUBGROUPS * (1 << (ONESWEEP_BITS - 1)) > ONESWEEP_PART {
        ONESWEEP_MAX_SUBGROUPS * (1 << (ONESWEEP_BITS - 1))
    } else {
        ONESWEEP_PART
    };
/// Workgroup memory of `sort_onesweep`: the shared counts and reorder space, four arrays of a
/// word a digit, the subgroup sums and a few words.
const ONESWEEP_WORKGROUP_BYTES: u32 =
    4 * (ONESWEEP_SHARED_WORDS + 4 * (1 << ONESWEEP_BITS) + 2 * ONESWEEP_MAX_SUBGROUPS + 3);
const ONESWEEP_PASSES_MAX: u32 = 32 / ONESWEEP_BITS;
const _: () = assert!(ONESWEEP_PART < 1 << 16);
const _: () = assert!(ONESWEEP_THREADS >= 1 << ONESWEEP_BITS);

/// The portable sort shader.
pub const SHADER: ShaderDef = ShaderDef {
    name: "sort.radix",
    consts: &[
        WgslConst::U32("RADIX", 1 << RADIX_BITS),
        WgslConst::U32("SORT_THREADS", SORT_THREADS),
        WgslConst::U32("SORT_PER_THREAD", SORT_PER_THREAD),
        WgslConst::U32("SORT_BLOCK", SORT_BLOCK),
        WgslConst::U32("GROUPS_X", GROUPS_X),
    ],
    files: &[shader_file!("sort/radix_sort.wgsl")],
};

/// The onesweep sort shader (built only where the adapter has suitable subgroups).
pub const ONESWEEP_SHADER: ShaderDef = ShaderDef {
    name: "sort.radix.onesweep",
    consts: &[
        WgslConst::U32("OS_RADIX", 1 << ONESWEEP_BITS),
        WgslConst::U32("OS_THREADS", ONESWEEP_THREADS),
        WgslConst::U32("OS_PER_THREAD", ONESWEEP_PER_THREAD),
        WgslConst::U32("OS_PART", ONESWEEP_PART),
        WgslConst::U32("OS_MAX_SUBGROUPS", ONESWEEP_MAX_SUBGROUPS),
        WgslConst::U32("OS_SHARED_WORDS", ONESWEEP_SHARED_WORDS),
        WgslConst::U32("OS_HIST_BINS", ONESWEEP_PASSES_MAX << ONESWEEP_BITS),
        WgslConst::U32("OS_HIST_KEYS", ONESWEEP_HIST_KEYS),
        WgslConst::U32("GROUPS_X", GROUPS_X),
    ],
    files: &[shader_file!("sort/onesweep.wgsl")],
};

/// Which sort runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SortPath {
    /// 4-bit digits, count / scan / scatter per digit; assumes no subgroup size.
    Portable,
    /// 8-bit digits, one pass per digit with decoupled look-back; subgroups of 8 to 32.
    Onesweep,
}

/// Radix sort pipelines.
pub struct RadixSort {
    pipelines: Pipelines,
    /// Polls of a predecessor's look-back status before the onesweep path counts its keys
    /// instead ([`ONESWEEP_MAX_SPIN`] by default; unused by the portable path).
    pub max_spin: u32,
    /// Counts every predecessor's keys instead of reading its status (onesweep only): the
    /// look-back's fallback alone, for tests.
    pub fallback_only: bool,
    /// The onesweep path's scratch buffers of the last sort (look-back status, histograms,
    /// partition counters), reused by the next sort of as many pairs: a renderer sorting every
    /// frame allocates them once, not every frame.
    scratch: Mutex<Option<OnesweepScratch>>,
}

/// The onesweep path's scratch buffers for `status_words` look-back status words.
struct OnesweepScratch {
    status_words: u64,
    status: wgpu::Buffer,
    hist: wgpu::Buffer,
    counters: wgpu::Buffer,
}

enum Pipelines {
    Portable {
        layout: wgpu::BindGroupLayout,
        count: wgpu::ComputePipeline,
        scatter: wgpu::ComputePipeline,
        scan: Scan,
    },
    Onesweep {
        layout: wgpu::BindGroupLayout,
        init: wgpu::ComputePipeline,
        histogram: wgpu::ComputePipeline,
        onesweep: wgpu::ComputePipeline,
    },
}

/// Where the sorted pairs ended up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SortedIn {
    /// In the input buffers.
    Input,
    /// In the scratch buffers.
    Scratch,
}

/// Number of key bits needed to hold values up to `max_key`.
pub fn key_bits_for(max_key: u32) -> u32 {
    (32 - max_key.leading_zeros()).max(1)
}

/// Whether the onesweep path runs on this device: subgroups of 8 to 32 invocations and room
/// for its workgroup memory.
pub fn onesweep_supported(ctx: &GpuContext) -> bool {
    let (min, max) = ctx.features.subgroup_size;
    ctx.features.subgroups
        && min >= ONESWEEP_MIN_SUBGROUP
        && max <= ONESWEEP_MAX_SUBGROUP
        && ctx.limits.max_compute_workgroup_storage_size >= ONESWEEP_WORKGROUP_BYTES
}

impl RadixSort {
    /// Builds the onesweep path where the device supports it ([`onesweep_supported`]), and
    /// otherwise the portable path with the subgroup scan where the device has subgroups.
    pub fn new(ctx: &GpuContext) -> Self {
        Self::onesweep(ctx).unwrap_or_else(|| Self::with_scan(ctx, Scan::new(ctx)))
    }

    /// The portable path over a given scan path; `None` where that scan path is unavailable.
    pub fn with_scan_path(ctx: &GpuContext, path: ScanPath) -> Option<Self> {
        Scan::with_path(ctx, path).map(|scan| Self::with_scan(ctx, scan))
    }

    /// The onesweep path; `None` where the device does not support it.
    pub fn onesweep(ctx: &GpuContext) -> Option<Self> {
        if !onesweep_supported(ctx) {
            return None;
        }
        let d = &ctx.device;
        let (layout, module, pl) = uniform_and_storage(ctx, &ONESWEEP_SHADER, 7);
        Some(Self {
            pipelines: Pipelines::Onesweep {
                init: pipeline::compute(d, &module, &pl, "sort_init"),
                histogram: pipeline::compute(d, &module, &pl, "sort_histogram"),
                onesweep: pipeline::compute(d, &module, &pl, "sort_onesweep"),
                layout,
            },
            max_spin: ONESWEEP_MAX_SPIN,
            fallback_only: false,
            scratch: Mutex::new(None),
        })
    }

    fn with_scan(ctx: &GpuContext, scan: Scan) -> Self {
        let d = &ctx.device;
        let (layout, module, pl) = uniform_and_storage(ctx, &SHADER, 5);
        Self {
            pipelines: Pipelines::Portable {
                count: pipeline::compute(d, &module, &pl, "sort_count"),
                scatter: pipeline::compute(d, &module, &pl, "sort_scatter"),
                layout,
                scan,
            },
            max_spin: ONESWEEP_MAX_SPIN,
            fallback_only: false,
            scratch: Mutex::new(None),
        }
    }

    /// The path these pipelines run.
    pub fn path(&self) -> SortPath {
        match self.pipelines {
            Pipelines::Portable { .. } => SortPath::Portable,
            Pipelines::Onesweep { .. } => SortPath::Onesweep,
        }
    }

    /// Bits sorted per pass.
    pub fn radix_bits(&self) -> u32 {
        match self.path() {
            SortPath::Portable => RADIX_BITS,
            SortPath::Onesweep => ONESWEEP_BITS,
        }
    }

    /// Where a sort of `key_bits` bits leaves the pairs: the input buffers after an even number
    /// of passes.
    pub fn sorted_in(&self, key_bits: u32) -> SortedIn {
        if key_bits
            .clamp(1, 32)
            .div_ceil(self.radix_bits())
            .is_multiple_of(2)
        {
            SortedIn::Input
        } else {
            SortedIn::Scratch
        }
    }

    /// Where a sort of `n` pairs of `key_bits` bits leaves them: as [`RadixSort::sorted_in`],
    /// and in the input buffers where there is nothing to sort (`n` <= 1).
    pub fn sorted_for(&self, n: u32, key_bits: u32) -> SortedIn {
        if n <= 1 {
            SortedIn::Input
        } else {
            self.sorted_in(key_bits)
        }
    }

    /// Encodes a stable sort of the first `n` pairs of (`keys`, `vals`) by the low `key_bits`
    /// bits of the keys, ping-ponging with (`keys_tmp`, `vals_tmp`) (each at least `n`
    /// elements). Returns which pair of buffers holds the result ([`RadixSort::sorted_in`]).
    #[expect(
        clippy::too_many_arguments,
        reason = "four buffers of a ping-pong sort, plus its size"
    )]
    pub fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        keys: &wgpu::Buffer,
        vals: &wgpu::Buffer,
        keys_tmp: &wgpu::Buffer,
        vals_tmp: &wgpu::Buffer,
        n: u32,
        key_bits: u32,
        timer: &mut GpuTimer,
    ) -> Result<SortedIn, GpuError> {
        let key_bits = key_bits.clamp(1, 32);
        if n <= 1 {
            return Ok(SortedIn::Input);
        }
        let buffers = [keys, vals, keys_tmp, vals_tmp];
        match &self.pipelines {
            Pipelines::Portable {
                layout,
                count,
                scatter,
                scan,
            } => encode_portable(
                ctx, encoder, layout, count, scatter, scan, buffers, n, key_bits, timer,
            )?,
            Pipelines::Onesweep {
                layout,
                init,
                histogram,
                onesweep,
            } => {
                if n > ONESWEEP_MAX_PAIRS {
                    return Err(GpuError::OverCapacity {
                        what: "radix sort pairs (onesweep path)".into(),
                        value: n.into(),
                        limit: ONESWEEP_MAX_PAIRS.into(),
                        why: "its 28-bit look-back counts hold; the portable path \
                              (RadixSort::with_scan_path) sorts up to 2^32 - 1",
                    });
                }
                let stages = [init, histogram, onesweep];
                self.encode_onesweep(ctx, encoder, layout, stages, buffers, n, key_bits, timer)?;
            }
        }
        Ok(self.sorted_in(key_bits))
    }

    /// The onesweep path's scratch buffers for `status_words` status words: the last sort's
    /// where it had as many (`sort.radix.init` zeroes them in every sort), new ones otherwise.
    fn onesweep_scratch(
        &self,
        ctx: &GpuContext,
        status_words: u64,
    ) -> (wgpu::Buffer, wgpu::Buffer, wgpu::Buffer) {
        let mut cached = self.scratch.lock().unwrap_or_else(PoisonError::into_inner);
        let s = match cached.take() {
            Some(s) if s.status_words == status_words => s,
            _ => {
                let scratch = |label: &str, words: u64| {
                    ctx.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some(label),
                        size: words * 4,
                        usage: wgpu::BufferUsages::STORAGE,
                        mapped_at_creation: false,
                    })
                };
                OnesweepScratch {
                    status_words,
                    status: scratch("sort.radix.status", status_words),
                    hist: scratch(
                        "sort.radix.hist",
                        u64::from(ONESWEEP_PASSES_MAX << ONESWEEP_BITS),
                    ),
                    counters: scratch("sort.radix.counters", u64::from(ONESWEEP_PASSES_MAX)),
                }
            }
        };
        let out = (s.status.clone(), s.hist.clone(), s.counters.clone());
        *cached = Some(s);
        out
    }

    #[expect(
        clippy::too_many_arguments,
        reason = "the pipelines and buffers of one sort"
    )]
    fn encode_onesweep(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        layout: &wgpu::BindGroupLayout,
        [init, histogram, onesweep]: [&wgpu::ComputePipeline; 3],
        buffers: [&wgpu::Buffer; 4],
        n: u32,
        key_bits: u32,
        timer: &mut GpuTimer,
    ) -> Result<(), GpuError> {
        let passes = key_bits.div_ceil(ONESWEEP_BITS);
        let parts = n.div_ceil(ONESWEEP_PART);
        let status_len = u64::from(parts) << ONESWEEP_BITS;
        ctx.check_storage("radix sort look-back status", status_len * 4)?;
        let (status, hist, counters) = self.onesweep_scratch(ctx, status_len);
        let groups: Vec<wgpu::BindGroup> = (0..passes)
            .map(|pass| {
                let [src_k, src_v, dst_k, dst_v] = ping_pong(pass, buffers);
                let digit_bits = ONESWEEP_BITS.min(key_bits - pass * ONESWEEP_BITS);
                let params = [
                    n,
                    pass,
                    pass * ONESWEEP_BITS,
                    (1 << digit_bits) - 1,
                    digit_bits,
                    passes,
                    key_bits,
                    self.max_spin,
                    u32::from(self.fallback_only),
                    0,
                    0,
                    0,
                ];
                let params = pipeline::uniform_buffer(
                    &ctx.device,
                    "sort.radix.params",
                    bytemuck::cast_slice(&params),
                );
                pipeline::buffers_group(
                    &ctx.device,
                    "sort.radix.onesweep",
                    layout,
                    &[
                        &params, src_k, src_v, dst_k, dst_v, &hist, &status, &counters,
                    ],
                )
            })
            .collect();
        let init_groups = u32::try_from(status_len.div_ceil(u64::from(ONESWEEP_THREADS)))
            .unwrap_or(u32::MAX)
            .clamp(
                (ONESWEEP_PASSES_MAX << ONESWEEP_BITS) / ONESWEEP_THREADS,
                4096,
            );
        pipeline::dispatch(
            encoder,
            timer,
            "sort.radix.init",
            init,
            &[&groups[0]],
            (init_groups, 1),
        );
        pipeline::dispatch(
            encoder,
            timer,
            "sort.radix.histogram",
            histogram,
            &[&groups[0]],
            groups_2d(n.div_ceil(ONESWEEP_HIST_KEYS), GROUPS_X),
        );
        for group in &groups {
            pipeline::dispatch(
                encoder,
                timer,
                "sort.radix.onesweep",
                onesweep,
                &[group],
                groups_2d(parts, GROUPS_X),
            );
        }
        Ok(())
    }
}

/// Pass `pass`'s (source keys, source values, destination keys, destination values) of a
/// ping-pong sort over (keys, values, scratch keys, scratch values): even passes read the input.
fn ping_pong(pass: u32, [k, v, kt, vt]: [&wgpu::Buffer; 4]) -> [&wgpu::Buffer; 4] {
    if pass.is_multiple_of(2) {
        [k, v, kt, vt]
    } else {
        [kt, vt, k, v]
    }
}

/// A bind-group layout of a uniform at binding 0 and `storage` read-write storage buffers
/// after it, `shader`'s module, and the pipeline layout of that one group.
fn uniform_and_storage(
    ctx: &GpuContext,
    shader: &ShaderDef,
    storage: u32,
) -> (
    wgpu::BindGroupLayout,
    wgpu::ShaderModule,
    wgpu::PipelineLayout,
) {
    let d = &ctx.device;
    let c = wgpu::ShaderStages::COMPUTE;
    let mut entries = vec![pipeline::entry(0, c, pipeline::UNIFORM)];
    entries.extend((1..=storage).map(|b| pipeline::entry(b, c, pipeline::storage(false))));
    let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(shader.name),
        entries: &entries,
    });
    let pl = pipeline::layout(d, shader.name, &[&layout]);
    (layout, shader.create(d), pl)
}

#[expect(
    clippy::too_many_arguments,
    reason = "the pipelines and buffers of one sort"
)]
fn encode_portable(
    ctx: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    layout: &wgpu::BindGroupLayout,
    count: &wgpu::ComputePipeline,
    scatter: &wgpu::ComputePipeline,
    scan: &Scan,
    buffers: [&wgpu::Buffer; 4],
    n: u32,
    key_bits: u32,
    timer: &mut GpuTimer,
) -> Result<(), GpuError> {
    let passes = key_bits.div_ceil(RADIX_BITS);
    let blocks = n.div_ceil(SORT_BLOCK);
    let hist_len = blocks * (1 << RADIX_BITS);
    ctx.check_storage("radix sort histogram", u64::from(hist_len) * 4)?;
    let hist = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("sort.radix.hist"),
        size: u64::from(hist_len) * 4,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let (gx, gy) = groups_2d(blocks, GROUPS_X);
    for pass in 0..passes {
        let [src_k, src_v, dst_k, dst_v] = ping_pong(pass, buffers);
        let params = pipeline::uniform_buffer(
            &ctx.device,
            "sort.radix.params",
            bytemuck::cast_slice(&[
                n,
                pass * RADIX_BITS,
                blocks,
                (1u32 << RADIX_BITS.min(key_bits - pass * RADIX_BITS)) - 1,
            ]),
        );
        let group = pipeline::buffers_group(
            &ctx.device,
            "sort.radix",
            layout,
            &[&params, src_k, src_v, dst_k, dst_v, &hist],
        );
        pipeline::dispatch(
            encoder,
            timer,
            "sort.radix.count",
            count,
            &[&group],
            (gx, gy),
        );
        scan.encode(ctx, encoder, &hist, hist_len, timer);
        pipeline::dispatch(
            encoder,
            timer,
            "sort.radix.scatter",
            scatter,
            &[&group],
            (gx, gy),
        );
    }
    Ok(())
}

/// The CPU oracle: a stable sort of pairs by the low `key_bits` bits of the key.
pub fn cpu(keys: &[u32], vals: &[u32], key_bits: u32) -> (Vec<u32>, Vec<u32>) {
    let mask = if key_bits >= 32 {
        u32::MAX
    } else {
        (1u32 << key_bits) - 1
    };
    let mut pairs: Vec<(u32, u32)> = keys.iter().copied().zip(vals.iter().copied()).collect();
    pairs.sort_by_key(|&(k, _)| k & mask);
    pairs.into_iter().unzip()
}
