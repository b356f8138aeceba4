//! `sort.radix`: a stable LSD radix sort of (u32 key, u32 value) pairs on the GPU, written here
//! because it is a subject of study (`shaders/sort/radix_sort.wgsl`). Portable: it assumes no
//! subgroup size. Tested against the standard library's stable sort and the `lampshade` crate.
//!
//! Per pass of [`RADIX_BITS`] bits: `sort.radix.count` (per-block digit histograms, digit-major),
//! the portable scan over them, `sort.radix.scatter` (stable in-block ranks). Only the key bits
//! asked for are sorted: sorting tile indices of 8,160 tiles takes 13 bits, four passes.

use manylights_gpu::shader_file;
use manylights_gpu::shaders::{ShaderDef, WgslConst};
use manylights_gpu::timing::GpuTimer;
use manylights_gpu::{GpuContext, GpuError, pipeline};
use wgpu::util::DeviceExt;

use crate::layout::GROUPS_X;
use crate::scan::{Scan, ScanPath, groups_2d};

/// Bits sorted per pass.
pub const RADIX_BITS: u32 = 4;
/// Threads per workgroup.
pub const SORT_THREADS: u32 = 256;
/// Keys per thread.
pub const SORT_PER_THREAD: u32 = 4;
/// Keys per block (workgroup); a 16-bit rank field holds up to 65,535.
pub const SORT_BLOCK: u32 = SORT_THREADS * SORT_PER_THREAD;
const _: () = assert!(SORT_BLOCK < 1 << 16);

/// The sort shader.
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

/// Radix sort pipelines.
pub struct RadixSort {
    layout: wgpu::BindGroupLayout,
    count: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    scan: Scan,
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

impl RadixSort {
    /// Builds the pipelines, with the subgroup scan where the device has subgroups.
    pub fn new(ctx: &GpuContext) -> Self {
        Self::with_scan(ctx, Scan::new(ctx))
    }

    /// Builds the pipelines over a given scan path; `None` where that path is unavailable.
    pub fn with_scan_path(ctx: &GpuContext, path: ScanPath) -> Option<Self> {
        Scan::with_path(ctx, path).map(|scan| Self::with_scan(ctx, scan))
    }

    fn with_scan(ctx: &GpuContext, scan: Scan) -> Self {
        let d = &ctx.device;
        let c = wgpu::ShaderStages::COMPUTE;
        let mut entries = vec![pipeline::entry(0, c, pipeline::UNIFORM)];
        entries.extend((1..=5).map(|b| pipeline::entry(b, c, pipeline::storage(false))));
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("sort.radix"),
            entries: &entries,
        });
        let module = SHADER.create(d);
        let pl = pipeline::layout(d, "sort.radix", &[&layout]);
        Self {
            count: pipeline::compute(d, &module, &pl, "sort_count"),
            scatter: pipeline::compute(d, &module, &pl, "sort_scatter"),
            layout,
            scan,
        }
    }

    /// Encodes a stable sort of the first `n` pairs of (`keys`, `vals`) by the low `key_bits`
    /// bits of the keys, ping-ponging with (`keys_tmp`, `vals_tmp`) (each at least `n`
    /// elements). Returns which pair of buffers holds the result.
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
        let passes = key_bits.clamp(1, 32).div_ceil(RADIX_BITS);
        if n <= 1 {
            return Ok(SortedIn::Input);
        }
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
            let (src_k, src_v, dst_k, dst_v) = if pass % 2 == 0 {
                (keys, vals, keys_tmp, vals_tmp)
            } else {
                (keys_tmp, vals_tmp, keys, vals)
            };
            let params = ctx
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("sort.radix.params"),
                    contents: bytemuck::cast_slice(&[
                        n,
                        pass * RADIX_BITS,
                        blocks,
                        (1u32 << RADIX_BITS.min(key_bits.clamp(1, 32) - pass * RADIX_BITS)) - 1,
                    ]),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
            let group = pipeline::buffers_group(
                &ctx.device,
                "sort.radix",
                &self.layout,
                &[&params, src_k, src_v, dst_k, dst_v, &hist],
            );
            pipeline::dispatch(
                encoder,
                timer,
                "sort.radix.count",
                &self.count,
                &[&group],
                (gx, gy),
            );
            self.scan.encode(ctx, encoder, &hist, hist_len, timer);
            pipeline::dispatch(
                encoder,
                timer,
                "sort.radix.scatter",
                &self.scatter,
                &[&group],
                (gx, gy),
            );
        }
        Ok(if passes.is_multiple_of(2) {
            SortedIn::Input
        } else {
            SortedIn::Scratch
        })
    }
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
