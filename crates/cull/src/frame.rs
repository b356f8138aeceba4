//! One culling run: the buffers every strategy shares (`Frame`), and the driver that records a
//! strategy's plan once, sized exactly between two submissions, or back to back (`execute`).

use manylights_gpu::timing::{Category, GpuTimer};
use manylights_gpu::{GpuContext, GpuError, pipeline, readback};

use crate::blocks::occlusion::Occlusion;
use crate::layout::GpuCullParams;
use crate::record::{Buf, ListPass, Recorder, Step, StepInfo};
use crate::strategies::Plan;
use crate::{CullError, CullOutput, Strategy};

/// The per-run buffers of every strategy and the culling bind group over them.
pub(crate) struct Frame<'a> {
    pub ctx: &'a GpuContext,
    layout: &'a wgpu::BindGroupLayout,
    pub params: GpuCullParams,
    /// The depth buffer's size.
    pub size: (u32, u32),
    params_buf: wgpu::Buffer,
    depth_view: wgpu::TextureView,
    pub tile_depth: wgpu::Buffer,
    pub counts: wgpu::Buffer,
    pub offsets: wgpu::Buffer,
    cursors: wgpu::Buffer,
    ranges: wgpu::Buffer,
    occupancy: wgpu::Buffer,
    pub stats: wgpu::Buffer,
    /// What a timer of spans calls one run: `cull.<strategy>`.
    span: String,
}

impl<'a> Frame<'a> {
    /// The buffers for `params`, with `items` count entries (a count per bin, per (bin, chunk of
    /// lights), or per (light, lane) for tiled scatter's pairs).
    pub fn new(
        ctx: &'a GpuContext,
        layout: &'a wgpu::BindGroupLayout,
        depth: &wgpu::Texture,
        strategy: &Strategy,
        params: GpuCullParams,
        items: u64,
    ) -> Self {
        let bins = u64::from(params.bins);
        let tiles = u64::from(params.tiles_x * params.tiles_y);
        let params_buf =
            pipeline::uniform_buffer(&ctx.device, "cull.params", bytemuck::bytes_of(&params));
        Self {
            ctx,
            layout,
            params,
            size: (depth.width(), depth.height()),
            params_buf,
            // A depth buffer's depth aspect, or lookup bounds (a colour texture) whole.
            depth_view: depth.create_view(&wgpu::TextureViewDescriptor {
                aspect: if depth.format().is_depth_stencil_format() {
                    wgpu::TextureAspect::DepthOnly
                } else {
                    wgpu::TextureAspect::All
                },
                ..Default::default()
            }),
            tile_depth: storage_buf(ctx, Buf::TileDepth.name(), tiles * 16),
            counts: storage_buf(ctx, Buf::Counts.name(), (items + 1) * 4),
            offsets: storage_buf(ctx, Buf::Offsets.name(), (items + 1) * 4),
            cursors: storage_buf(ctx, Buf::Cursors.name(), bins * 4),
            ranges: storage_buf(ctx, Buf::Ranges.name(), bins * 8),
            // A flag a bin, then (clusters with the box test) its pixels' depth bounds, then
            // (CULL_FLAG_SLICE_MASKS) each tile's mask of occupied slices, two words, then (the
            // clusters' cells, CULL_FLAG_DEPTH_MASK) a word a bin.
            occupancy: storage_buf(ctx, Buf::Occupancy.name(), bins * 16 + tiles * 8),
            stats: storage_buf(ctx, Buf::Stats.name(), 48),
            span: format!("cull.{}", strategy.name()),
        }
    }

    /// The `CullParams` uniform.
    pub fn params_buf(&self) -> &wgpu::Buffer {
        &self.params_buf
    }

    /// `bin_ranges`.
    pub fn ranges(&self) -> &wgpu::Buffer {
        &self.ranges
    }

    /// The clusters' occupancy (and, with the box test, their pixels' depth bounds).
    pub fn occupancy(&self) -> &wgpu::Buffer {
        &self.occupancy
    }

    /// A storage buffer of this run.
    pub fn buf(&self, label: &str, size: u64) -> wgpu::Buffer {
        storage_buf(self.ctx, label, size)
    }

    /// The culling group: `indices` at binding 7 (the lists, or before them tiled scatter's
    /// block queue with tile masks), `pair_keys` at 9 (tiled scatter's pair keys, the clusters'
    /// wide-light queue, the light rectangles), `args` at 11 (the clusters' indirect dispatch,
    /// the tile masks, the tile lines).
    pub fn group(
        &self,
        indices: &wgpu::Buffer,
        pair_keys: &wgpu::Buffer,
        args: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        pipeline::group(
            &self.ctx.device,
            "cull.group1",
            self.layout,
            &[
                self.params_buf.as_entire_binding(),
                wgpu::BindingResource::TextureView(&self.depth_view),
                self.tile_depth.as_entire_binding(),
                self.counts.as_entire_binding(),
                self.offsets.as_entire_binding(),
                self.cursors.as_entire_binding(),
                self.ranges.as_entire_binding(),
                indices.as_entire_binding(),
                self.occupancy.as_entire_binding(),
                pair_keys.as_entire_binding(),
                self.stats.as_entire_binding(),
                args.as_entire_binding(),
            ],
        )
    }

    /// The lists' indices for `total` entries, and the culling group over them (with
    /// `pair_keys` at binding 9 and `args` at 11, as [`Frame::group`]).
    pub fn lists(
        &self,
        total: u32,
        pair_keys: &wgpu::Buffer,
        args: &wgpu::Buffer,
    ) -> (wgpu::Buffer, wgpu::BindGroup) {
        let indices = self.buf(Buf::Indices.name(), u64::from(total) * 4);
        let group = self.group(&indices, pair_keys, args);
        (indices, group)
    }

    /// The clears at the start of a run. With tile masks (`masked`) only the stats: those passes
    /// use no counts, cursors or occupancy, and the masks' fill writes every tile's range. (Each
    /// clear is a transfer between passes, which costs time of its own.)
    pub fn clears(&self, masked: bool) -> Vec<Step<'_>> {
        if masked {
            return vec![Step::clear(Buf::Stats, &self.stats)];
        }
        vec![
            Step::clear(Buf::Counts, &self.counts),
            Step::clear(Buf::Cursors, &self.cursors),
            Step::clear(Buf::Occupancy, &self.occupancy),
            Step::clear(Buf::Ranges, &self.ranges),
            Step::clear(Buf::Stats, &self.stats),
        ]
    }

    /// Clears `bin_ranges` (z-binning widens its bins' ranges atomically from zero).
    pub fn clear_ranges(&self) -> Step<'_> {
        Step::clear(Buf::Ranges, &self.ranges)
    }

    /// The exclusive scan of the first `n` counts into the offsets.
    pub fn scan(&self, n: u32) -> Step<'_> {
        Step::Scan {
            counts: &self.counts,
            offsets: &self.offsets,
            n,
        }
    }

    /// `count` u32 words of the stats from word `first`, read back.
    pub fn stats(&self, first: u64, count: u64) -> Result<Vec<u32>, GpuError> {
        read_u32s(self.ctx, &self.stats, first, count)
    }

    /// The exact total of the `n` counts after [`Frame::scan`]: the scan's u32 total
    /// (`offsets[n]`), or, where the counts could sum past u32 (bins x lights > 2^32), the
    /// counts read back and summed in u64, so that a wrapped total never sizes the lists short.
    pub fn bins_total(&self, n: u32) -> Result<u64, GpuError> {
        let p = &self.params;
        if u64::from(p.bins) * u64::from(p.light_count) > u64::from(u32::MAX) {
            Ok(read_u32s(self.ctx, &self.counts, 0, u64::from(n))?
                .iter()
                .map(|&c| u64::from(c))
                .sum())
        } else {
            Ok(u64::from(
                read_u32s(self.ctx, &self.offsets, u64::from(n), 1)?[0],
            ))
        }
    }

    /// The output of a run of this frame; reads back the dropped count where a capacity was
    /// set.
    pub fn finish(self, run: Done) -> Result<CullOutput, CullError> {
        let Done {
            outputs,
            total,
            passes,
            occlusion,
        } = run;
        let dropped = if self.params.capacity != 0 {
            self.stats(0, 1)?[0]
        } else {
            0
        };
        let occluded = if occlusion { self.stats(10, 1)?[0] } else { 0 };
        Ok(CullOutput {
            dropped,
            occluded,
            params: self.params,
            params_buf: self.params_buf,
            ranges: self.ranges,
            indices: outputs.indices,
            total,
            tile_depth: self.tile_depth,
            occupancy: self.occupancy,
            tile_masks: outputs.tile_masks,
            tile_lines: outputs.tile_lines,
            passes,
        })
    }
}

/// A recorded and submitted run: what [`Frame::finish`] turns into the output.
pub(crate) struct Done {
    outputs: Outputs,
    total: u32,
    passes: Vec<StepInfo>,
    /// Whether `cull.occlusion` ran after the lists.
    occlusion: bool,
}

/// What a plan hands to the output besides the shared buffers.
pub(crate) struct Outputs {
    /// `light_indices`.
    pub indices: wgpu::Buffer,
    /// The tile masks, where the run used them.
    pub tile_masks: Option<wgpu::Buffer>,
    /// The tile lines, where the run used them.
    pub tile_lines: Option<wgpu::Buffer>,
}

/// Back-to-back runs of [`crate::Culler::run_repeated`]: how many, and the list entries (or
/// scatter's pairs) an earlier run of the same input needed.
#[derive(Clone, Copy)]
pub(crate) struct Repeat {
    pub total: u32,
    pub runs: u32,
}

impl Repeat {
    /// `runs` (at least one) runs sized from `earlier`, a single run of the same input.
    pub fn after(earlier: &CullOutput, runs: u32) -> Self {
        Self {
            total: earlier.total,
            runs: runs.max(1),
        }
    }

    /// The total the repeated runs needed, which must be the earlier run's.
    fn check(self, total: u64) -> Result<(), CullError> {
        if total == u64::from(self.total) {
            Ok(())
        } else {
            Err(CullError::SizeChanged {
                earlier: self.total,
                now: total,
            })
        }
    }
}

/// Records and submits `plan`, a plan over `f`. Without `repeat`, once: the count phase, its
/// total read back, the fill's buffers sized exactly from it, the fill phase (two
/// submissions). With it, `repeat.runs` times back to back in one submission (each run a span
/// `cull.<strategy>` for a timer of spans), sized from the earlier run and checked against it,
/// each run followed by `then` (inside its span) where there is one.
#[expect(
    clippy::too_many_arguments,
    reason = "a run's plan, its recorder and timer, the repeat, the pass after it and the occlusion pass"
)]
pub(crate) fn execute<P: Plan>(
    f: &Frame<'_>,
    rec: &Recorder<'_>,
    mut plan: P,
    timer: &mut GpuTimer,
    repeat: Option<Repeat>,
    mut then: Option<&mut dyn ListPass>,
    occlusion: Option<&Occlusion>,
) -> Result<Done, CullError> {
    // Culling by visibility after the lists (none where the scene has no occluder).
    let occlusion = occlusion.filter(|o| o.count() > 0);
    let ctx = f.ctx;
    let (total, passes) = match repeat {
        None => {
            let mut enc = ctx.encoder("cull.count");
            let count = plan.count(false);
            rec.record(&mut enc, timer, &count)?;
            let mut passes: Vec<StepInfo> = count.iter().map(Step::info).collect();
            drop(count);
            ctx.submit_and_wait(enc, "culling: count")?;
            let (what_bytes, what) = plan.total_names();
            let total = checked_entries(ctx, what_bytes, what, plan.total()?)?;
            plan.size(total);
            let occlusion_group = occlusion.map(|o| o.group(f, plan.indices()));
            let mut fill = plan.fill(false);
            if let (Some(o), Some(g)) = (occlusion, &occlusion_group) {
                fill.push(o.step(f, g));
            }
            let mut enc = ctx.encoder("cull.fill");
            rec.record(&mut enc, timer, &fill)?;
            timer.resolve(&mut enc);
            passes.extend(fill.iter().map(Step::info));
            drop(fill);
            ctx.submit_and_wait(enc, "culling: fill")?;
            (total, passes)
        }
        Some(r) => {
            plan.size(r.total);
            if let Some(pass) = then.as_mut() {
                pass.bind(
                    ctx,
                    [
                        f.params_buf.as_entire_binding(),
                        f.ranges.as_entire_binding(),
                        plan.indices().as_entire_binding(),
                    ],
                    crate::ListForm::of(&f.params),
                );
            }
            let occlusion_group = occlusion.map(|o| o.group(f, plan.indices()));
            let steps: Vec<Step<'_>> = plan
                .count(true)
                .into_iter()
                .chain(plan.fill(true))
                .chain(
                    occlusion
                        .zip(occlusion_group.as_ref())
                        .map(|(o, g)| o.step(f, g)),
                )
                .collect();
            let mut enc = ctx.encoder("cull.repeated");
            for _ in 0..r.runs {
                let outer = timer.set_category(Category::Cull);
                timer.span_begin(&mut enc, &f.span);
                timer.set_category(outer);
                rec.record(&mut enc, timer, &steps)?;
                if let Some(pass) = then.as_ref() {
                    pass.record(&mut enc, timer);
                }
                timer.span_end(&mut enc);
            }
            timer.resolve(&mut enc);
            let passes = steps.iter().map(Step::info).collect();
            drop(steps);
            ctx.submit_and_wait(enc, "culling: repeated runs")?;
            r.check(plan.total()?)?;
            (r.total, passes)
        }
    };
    Ok(Done {
        outputs: plan.outputs(),
        total,
        passes,
        occlusion: occlusion.is_some(),
    })
}

/// `entries` list entries, checked: they must fit one storage binding (`what_bytes`) and u32
/// offsets (`what`), or it is an error, never a wrapped, short buffer.
fn checked_entries(
    ctx: &GpuContext,
    what_bytes: &str,
    what: &str,
    entries: u64,
) -> Result<u32, GpuError> {
    ctx.check_storage(what_bytes, entries * 4)?;
    u32::try_from(entries).map_err(|_| GpuError::OverLimit {
        what: what.into(),
        value: entries,
        limit: u32::MAX.into(),
        limit_name: "u32 list offsets",
    })
}

/// `count` u32 words of `buf` from word `first`, read back.
pub(crate) fn read_u32s(
    ctx: &GpuContext,
    buf: &wgpu::Buffer,
    first: u64,
    count: u64,
) -> Result<Vec<u32>, GpuError> {
    Ok(bytemuck::pod_collect_to_vec(&readback::read_buffer(
        ctx,
        buf,
        first * 4,
        count * 4,
    )?))
}

/// A storage buffer (at least 4 bytes) that can be cleared and read back.
pub(crate) fn storage_buf(ctx: &GpuContext, label: &str, size: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(4),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}
