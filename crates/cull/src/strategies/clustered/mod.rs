//! 3D clusters (Olsson, Billeter, Assarsson, HPG 2012): the view frustum split into tiles and
//! depth slices, lights assigned per light (`shaders/cull/clustered/`; oracle
//! [`crate::cpu::clustered`]). The passes of a run:
//!
//! 1. `cull.occupancy` (with `skip_empty` or the box test): the clusters that hold covered
//!    pixels, and with the box test the depth bounds of each cluster's pixels; with `cells`,
//!    `cull.clustered.cells` then sets each cluster's 2.5D cells (a bit for each of the 32
//!    cells of its pixels' depth range that holds a pixel; `CULL_FLAG_DEPTH_MASK`, which the
//!    cluster test applies as 2.5D culling does a tile's); then, where the
//!    boxes fit a binding, `cull.clustered.boxes` stores each cluster's box once
//!    (`CULL_FLAG_CLUSTER_BOXES`), which the count and fill passes read rather than computing
//!    it again for every light that reaches the cluster's tile.
//! 2. `cull.clustered.count`: a thread a light counts the clusters of its tiles and slices;
//!    a light over 4 tiles is queued instead, and `cull.clustered.wide_args` turns the queue's
//!    lengths into the indirect dispatch of `cull.clustered.count_wide`: 8 threads a medium
//!    light (at most 32 tiles), [`crate::layout::CLUSTER_LANES`] a wide one or a band of its
//!    rows ([`crate::Culler::cluster_lane_tiles`]; one thread emitting a whole-screen light's
//!    12,000 entries would idle the GPU).
//! 3. The capacity cap and the scan ([`crate::blocks::lists`]).
//! 4. `cull.clustered.fill` and `cull.clustered.fill_wide`, in the same split. Where the
//!    lists were sized before the count (back-to-back runs, as the steady frame's) and the
//!    boxes are stored ([`crate::Culler::cluster_pairs`]), the count passes instead hold the
//!    pairs they count (8 a thread in registers, written at an offset a workgroup takes with
//!    one atomic; a thread that counted more walks its clusters again, writing each) in a
//!    region after the boxes, 8 bytes a list entry, and `cull.clustered.scatter` (a thread a
//!    pair) puts each in its list: the fill passes' tests are not made twice.
//! 5. With `ordered` (the default), `cull.clustered.order_lists` lists the clusters whose lists
//!    need sorting, `cull.clustered.order_args` turns their counts into indirect dispatches, and
//!    `cull.clustered.order_short` and `cull.clustered.order_bits` (or, past
//!    [`crate::layout::CLUSTER_ORDER_BITS_LIGHTS`] lights or without
//!    [`crate::Culler::cluster_order_bits`], `cull.clustered.order`) sort each listed cluster's
//!    list into light order, so that images are bit-identical run to run.
//! 6. `cull.finalize`.
//!
//! With few lights (at most [`crate::Culler::cluster_tiles_max_lights`], and at most
//! [`crate::CLUSTER_TILES_MAX_PAIRS`] (tile, light) pairs) and at most
//! [`crate::layout::CLUSTER_TILE_SLICES`] slices, the tile path runs instead: a workgroup a tile
//! of `cull.clustered.tiles_count` (`shaders/cull/clustered/cluster_tiles.wgsl`) reduces its
//! pixels to each slice's depth bounds, takes the lights 256 at a time, shares the (light,
//! slice) tests among its threads and stores each cluster's count and its mask, a bit a light,
//! and adds its clusters' counts to the lists' total; then `cull.clustered.masks_fill` (a
//! thread a cluster) writes each list from its mask, and its range, taking its offset from a
//! cursor a workgroup at a time (no scan; with a capacity, which caps the counts after the
//! count pass, after the scan of the counts). The same lists, in light order (at offsets that
//! differ run to run), without occupancy, queue, order or finalize passes. The masks hold a
//! bit per (cluster, light), rounded to 256 lights: 0.8 MB at 500 lights at 1080p in 64-pixel
//! tiles of 24 slices, at most 128 MB (2^24 pairs x 64 slices); where they would not fit a
//! storage binding, the per-light passes run.

use manylights_gpu::GpuError;

use crate::culler::{RunInputs, Timing};
use crate::frame::{Frame, Outputs};
use crate::layout::{
    CLUSTER_MASK_SLICES, CLUSTER_ORDER_BITS_LIGHTS, CLUSTER_TILE_SLICES, CULL_FLAG_CLUSTER_BOXES,
    CULL_FLAG_DEPTH_MASK, CULL_FLAG_ORDER_BITS, CULL_FLAG_SKIP_EMPTY, CULL_FLAG_SLICE_MASKS,
    CULL_FLAG_SPHERE_BOUNDS, CULL_FLAG_TILE_BOX, GROUPS_X, GpuCullParams,
};
use crate::record::{Buf, Dispatch, Step};
use crate::scan::groups_2d;
use crate::strategies::Plan;
use crate::{CullError, CullOutput, Kernel, Strategy};

mod pipelines;

pub(crate) use pipelines::Pipelines;

/// Runs the clusters.
pub(crate) fn run(
    r: &RunInputs<'_>,
    mut params: GpuCullParams,
    t: Timing<'_>,
) -> Result<CullOutput, CullError> {
    r.check_bins(&params)?;
    params.chunk = r.culler.cluster_lane_tiles;
    if r.culler.cluster_sphere_bounds {
        params.flags |= CULL_FLAG_SPHERE_BOUNDS;
    }
    if r.culler.cluster_order_bits && params.light_count <= CLUSTER_ORDER_BITS_LIGHTS {
        params.flags |= CULL_FLAG_ORDER_BITS;
    }
    r.ctx
        .check_storage("clusters' wide-light queue", queue_bytes(r, &params))?;
    let ordered = matches!(r.strategy, Strategy::Clustered { ordered: true, .. });
    let cells = matches!(r.strategy, Strategy::Clustered { cells: true, .. });
    if cells && params.flags & CULL_FLAG_TILE_BOX == 0 {
        return Err(CullError::InvalidParameter {
            field: "cells",
            value: "true".into(),
            accepted: "false where tile_boxes is false (the cells divide each cluster's pixels' \
                       depth range, which the box test keeps)",
        });
    }
    let limits = &r.ctx.limits;
    let binding = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    // (The cells take the per-light passes.)
    let by_tiles = !cells
        && params.slices <= CLUSTER_TILE_SLICES
        && params.light_count <= r.culler.cluster_tiles_max_lights
        && pairs(&params) <= crate::CLUSTER_TILES_MAX_PAIRS
        && mask_bytes(&params) <= binding;
    // The per-light passes with the box test read each cluster's box, computed once, where
    // the boxes fit a binding.
    if !by_tiles
        && r.culler.cluster_boxes
        && params.flags & CULL_FLAG_TILE_BOX != 0
        && box_bytes(&params) <= binding
    {
        params.flags |= CULL_FLAG_CLUSTER_BOXES;
        if r.culler.cluster_slice_masks && params.slices <= CLUSTER_MASK_SLICES {
            params.flags |= CULL_FLAG_SLICE_MASKS;
        }
    }
    let f = r.frame(params, u64::from(params.bins));
    let done = r.execute(&f, ClusterPlan::new(r, &f, ordered, by_tiles), t)?;
    f.finish(done)
}

/// The bytes of the wide lights' queue: a header, an entry for each light, and the band pool
/// ([`crate::Culler::cluster_band_pool`]; one entry a light by default), 16 bytes an entry.
fn queue_bytes(r: &RunInputs<'_>, p: &GpuCullParams) -> u64 {
    let pool = r.culler.cluster_band_pool.unwrap_or(p.light_count);
    (1 + u64::from(p.light_count) + u64::from(pool)) * 16
}

/// The (tile, light) pairs of a run.
fn pairs(p: &GpuCullParams) -> u64 {
    u64::from(p.tiles_x * p.tiles_y) * u64::from(p.light_count)
}

/// The bytes of the tile path's masks: a bit per (cluster, light), in whole batches of
/// `CLUSTER_TILE_THREADS` (256) lights.
fn mask_bytes(p: &GpuCullParams) -> u64 {
    u64::from(p.bins) * u64::from(p.light_count.div_ceil(256)) * 32
}

/// The bytes of the clusters' boxes (`cull.clustered.boxes`): 8 words a cluster.
fn box_bytes(p: &GpuCullParams) -> u64 {
    u64::from(p.bins) * 32
}

/// A run of the clusters.
struct ClusterPlan<'a> {
    r: &'a RunInputs<'a>,
    f: &'a Frame<'a>,
    ordered: bool,
    /// The tile path (a workgroup a tile; see the module's top).
    by_tiles: bool,
    /// On it, with `cull.clustered.rects`.
    rects: bool,
    /// On it, no scan: the count pass's total sizes the lists, and the fill takes each
    /// cluster's offset from a cursor (without a capacity, which caps the counts after the
    /// count pass, and where the total fits a u32).
    cursor: bool,
    /// The wide lights' queue (binding 9; its first word is its length).
    wide: wgpu::Buffer,
    /// Their indirect dispatch arguments (binding 11 of the pass that writes them; an indirect
    /// buffer cannot also be bound for storage in the dispatch that reads it).
    wide_args: wgpu::Buffer,
    /// The clusters' boxes (binding 11 of the per-light passes, `CULL_FLAG_CLUSTER_BOXES`);
    /// with `pairs`, the pair region after them.
    boxes: Option<wgpu::Buffer>,
    /// The count passes hold their pairs and `cull.clustered.scatter` fills the lists
    /// ([`crate::Culler::cluster_pairs`]): a run sized before its count, with the boxes.
    pairs: bool,
    /// Whether the count phase was recorded (before [`Plan::size`]: the lists were not sized
    /// up front, and the fill passes fill them).
    counted: std::cell::Cell<bool>,
    group_a: wgpu::BindGroup,
    group_args: wgpu::BindGroup,
    sized: Option<(wgpu::Buffer, wgpu::BindGroup)>,
}

impl<'a> ClusterPlan<'a> {
    fn new(r: &'a RunInputs<'a>, f: &'a Frame<'a>, ordered: bool, by_tiles: bool) -> Self {
        let p = &f.params;
        let placeholder = &r.culler.placeholder;
        // The wide-light queue's binding holds the masks on the tile path.
        let wide = if by_tiles {
            f.buf(Buf::ClusterMasks.name(), mask_bytes(p).max(16))
        } else {
            // After the fill, the clusters whose lists need sorting (cull.clustered.order_lists).
            f.buf(
                Buf::WideLights.name(),
                queue_bytes(r, p).max((4 + u64::from(p.bins)) * 4),
            )
        };
        // On the tile path, the lights' rectangles at the same binding.
        let rects = by_tiles && pairs(p) >= r.culler.cluster_tile_rect_pairs;
        let wide_args = f.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(if rects {
                Buf::LightRects.name()
            } else {
                Buf::WideArgs.name()
            }),
            // The wide passes' dispatch, then the order passes' two.
            size: if rects {
                u64::from(p.light_count).max(1) * 16
            } else {
                32
            },
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
            mapped_at_creation: false,
        });
        let cursor = by_tiles
            && p.capacity == 0
            && u64::from(p.bins) * u64::from(p.light_count) <= u64::from(u32::MAX);
        let boxes = (p.flags & CULL_FLAG_CLUSTER_BOXES != 0)
            .then(|| f.buf(Buf::ClusterBoxes.name(), box_bytes(p)));
        let args = match (&boxes, by_tiles) {
            (Some(b), _) => b,
            (None, true) => &wide_args,
            (None, false) => placeholder,
        };
        Self {
            r,
            f,
            ordered,
            by_tiles,
            cursor,
            rects,
            group_a: f.group(placeholder, &wide, args),
            group_args: f.group(placeholder, &wide, &wide_args),
            wide,
            wide_args,
            boxes,
            pairs: false,
            counted: std::cell::Cell::new(false),
            sized: None,
        }
    }

    /// What a per-light pass reads: `with_boxes` where it reads the clusters' boxes.
    fn reads(&self, without: &'static [Buf], with_boxes: &'static [Buf]) -> &'static [Buf] {
        if self.boxes.is_some() {
            with_boxes
        } else {
            without
        }
    }

    /// A thread a light.
    fn light_groups(&self) -> (u32, u32) {
        groups_2d(self.f.params.light_count.div_ceil(64), GROUPS_X)
    }

    /// A workgroup a tile (the tile path).
    fn tile_groups(&self) -> (u32, u32) {
        (self.f.params.tiles_x, self.f.params.tiles_y)
    }

    /// Which per-light pipelines run: with the cells (`CULL_FLAG_DEPTH_MASK`) or without.
    fn cells(&self) -> usize {
        usize::from(self.f.params.flags & CULL_FLAG_DEPTH_MASK != 0)
    }

    /// The fill passes (the lists not sized up front, or no pairs held).
    fn fill_passes<'s>(&'s self, group: &'s wgpu::BindGroup) -> Vec<Step<'s>> {
        let g = self.r.pipelines.clustered();
        vec![
            Step::pass(
                "cull.clustered.fill",
                &g.per_light[self.cells()].fill,
                group,
                self.light_groups(),
                self.reads(
                    &[Buf::Lights, Buf::Occupancy, Buf::Offsets],
                    &[Buf::Lights, Buf::Occupancy, Buf::Offsets, Buf::ClusterBoxes],
                ),
                &[Buf::Indices, Buf::Cursors],
            ),
            Step::pass(
                "cull.clustered.fill_wide",
                &g.per_light[self.cells()].fill_wide,
                group,
                Dispatch::Indirect(Buf::WideArgs, &self.wide_args, 0),
                self.reads(
                    &[
                        Buf::WideLights,
                        Buf::WideArgs,
                        Buf::Lights,
                        Buf::Occupancy,
                        Buf::Offsets,
                    ],
                    &[
                        Buf::WideLights,
                        Buf::WideArgs,
                        Buf::Lights,
                        Buf::Occupancy,
                        Buf::Offsets,
                        Buf::ClusterBoxes,
                    ],
                ),
                &[Buf::Indices, Buf::Cursors],
            ),
        ]
    }

    /// The pairs the count passes held: the lists' total.
    fn total_pairs(&self) -> u32 {
        let b = self.boxes.as_ref().expect("pairs with the boxes");
        ((b.size() - box_bytes(&self.f.params)) / 8) as u32
    }

    /// The count pass (`wide`: its wide passes'), holding its pairs with `pairs`.
    fn count_kernel(&self, wide: bool) -> &Kernel {
        let k = &self.r.pipelines.clustered().per_light[self.cells()];
        match (wide, self.pairs) {
            (false, false) => &k.count,
            (false, true) => &k.count_pairs,
            (true, false) => &k.count_wide,
            (true, true) => &k.count_wide_pairs,
        }
    }
}

impl Plan for ClusterPlan<'_> {
    fn count(&self, _sized: bool) -> Vec<Step<'_>> {
        self.counted.set(true);
        let (f, q) = (self.f, self.r.pipelines);
        let g = q.clustered();
        if self.by_tiles {
            // Every cluster's count is stored and every range finalized: only the stats need
            // clearing, and with the cursor not those (its passes zero the words they use).
            let mut steps = if self.cursor {
                Vec::new()
            } else {
                f.clears(true)
            };
            let writes = &[Buf::Counts, Buf::Occupancy, Buf::ClusterMasks, Buf::Stats];
            if self.rects {
                steps.push(Step::pass(
                    "cull.clustered.rects",
                    &g.light_rects,
                    &self.group_a,
                    self.light_groups(),
                    &[Buf::Lights],
                    &[Buf::LightRects],
                ));
                steps.push(Step::pass(
                    "cull.clustered.tiles_count",
                    &g.tiles_count_rects,
                    &self.group_a,
                    self.tile_groups(),
                    &[Buf::Lights, Buf::Depth, Buf::LightRects],
                    writes,
                ));
            } else {
                steps.push(Step::pass(
                    "cull.clustered.tiles_count",
                    &g.tiles_count,
                    &self.group_a,
                    self.tile_groups(),
                    &[Buf::Lights, Buf::Depth],
                    writes,
                ));
            }
            if !self.cursor {
                steps.extend(q.lists.count_tail(f, &self.group_a, f.params.bins));
            }
            return steps;
        }
        let mut steps = f.clears(false);
        // The queue's lengths: wide lights, bands reserved, medium lights.
        steps.push(Step::Clear {
            what: Buf::WideLights,
            buffer: &self.wide,
            offset: 0,
            size: Some(12),
        });
        if f.params.flags & (CULL_FLAG_SKIP_EMPTY | CULL_FLAG_TILE_BOX) != 0 {
            let (w, h) = f.size;
            steps.push(Step::pass(
                "cull.occupancy",
                &g.occupancy,
                &self.group_a,
                (w.div_ceil(8), h.div_ceil(8)),
                &[Buf::Depth],
                &[Buf::Occupancy],
            ));
        }
        if f.params.flags & CULL_FLAG_DEPTH_MASK != 0 {
            let (w, h) = f.size;
            steps.push(Step::pass(
                "cull.clustered.cells",
                &g.cells,
                &self.group_a,
                (w.div_ceil(8), h.div_ceil(8)),
                &[Buf::Depth, Buf::Occupancy],
                &[Buf::Occupancy],
            ));
        }
        if self.boxes.is_some() {
            steps.push(Step::pass(
                "cull.clustered.boxes",
                &g.boxes,
                &self.group_a,
                groups_2d(f.params.bins.div_ceil(64), GROUPS_X),
                &[Buf::Occupancy],
                // With CULL_FLAG_SLICE_MASKS the tiles' slice masks too, in the occupancy.
                &[Buf::ClusterBoxes, Buf::Occupancy],
            ));
        }
        steps.extend([
            Step::pass(
                "cull.clustered.count",
                self.count_kernel(false),
                &self.group_a,
                self.light_groups(),
                self.reads(
                    &[Buf::Lights, Buf::Occupancy],
                    &[Buf::Lights, Buf::Occupancy, Buf::ClusterBoxes],
                ),
                if self.pairs {
                    &[Buf::Counts, Buf::WideLights, Buf::ClusterBoxes, Buf::Stats]
                } else {
                    &[Buf::Counts, Buf::WideLights]
                },
            ),
            Step::pass(
                "cull.clustered.wide_args",
                &g.wide_args,
                &self.group_args,
                (1, 1),
                &[Buf::WideLights],
                &[Buf::WideArgs],
            ),
            Step::pass(
                "cull.clustered.count_wide",
                self.count_kernel(true),
                &self.group_a,
                Dispatch::Indirect(Buf::WideArgs, &self.wide_args, 0),
                self.reads(
                    &[Buf::WideLights, Buf::WideArgs, Buf::Lights, Buf::Occupancy],
                    &[
                        Buf::WideLights,
                        Buf::WideArgs,
                        Buf::Lights,
                        Buf::Occupancy,
                        Buf::ClusterBoxes,
                    ],
                ),
                if self.pairs {
                    &[Buf::Counts, Buf::ClusterBoxes, Buf::Stats]
                } else {
                    &[Buf::Counts]
                },
            ),
        ]);
        steps.extend(q.lists.count_tail(f, &self.group_a, f.params.bins));
        steps
    }

    fn total(&self) -> Result<u64, GpuError> {
        if self.cursor {
            // Before the fill, the count pass's total (cull_stats[3]); after it (back to back,
            // sized up front), the cursor's end (cull_stats[7]): the fill zeroes the total.
            let word = if self.sized.is_some() { 7 } else { 3 };
            return Ok(u64::from(self.f.stats(word, 1)?[0]));
        }
        self.f.bins_total(self.f.params.bins)
    }

    fn size(&mut self, total: u32) {
        if !self.counted.get() && self.boxes.is_some() && self.r.culler.cluster_pairs && total > 0 {
            // Sized up front: the boxes' buffer gains the pair region, the lists' total.
            let p = &self.f.params;
            let bytes = box_bytes(p) + u64::from(total) * 8;
            let limits = &self.r.ctx.limits;
            if bytes
                <= limits
                    .max_storage_buffer_binding_size
                    .min(limits.max_buffer_size)
            {
                let boxes = self.f.buf(Buf::ClusterBoxes.name(), bytes);
                self.group_a = self.f.group(&self.r.culler.placeholder, &self.wide, &boxes);
                self.boxes = Some(boxes);
                self.pairs = true;
            }
        }
        let args = self.boxes.as_ref().unwrap_or(&self.r.culler.placeholder);
        self.sized = Some(self.f.lists(total, &self.wide, args));
    }

    fn indices(&self) -> &wgpu::Buffer {
        &self.sized.as_ref().expect("sized before the indices").0
    }

    fn fill(&self, _sized: bool) -> Vec<Step<'_>> {
        let (_, group) = self.sized.as_ref().expect("sized before the fill");
        let (f, q) = (self.f, self.r.pipelines);
        let g = q.clustered();
        if self.by_tiles {
            // It writes every range: no cull.finalize.
            let (pipeline, reads, writes): (_, &[Buf], &[Buf]) = if self.cursor {
                (
                    &g.masks_fill_cursor,
                    &[Buf::Counts, Buf::ClusterMasks, Buf::Stats],
                    &[Buf::Indices, Buf::Ranges, Buf::Stats],
                )
            } else {
                (
                    &g.masks_fill,
                    &[Buf::Counts, Buf::Offsets, Buf::ClusterMasks],
                    &[Buf::Indices, Buf::Ranges],
                )
            };
            return vec![Step::pass(
                "cull.clustered.masks_fill",
                pipeline,
                group,
                groups_2d(f.params.bins.div_ceil(64), GROUPS_X),
                reads,
                writes,
            )];
        }
        let mut steps = if self.pairs {
            vec![Step::pass(
                "cull.clustered.scatter",
                &g.scatter,
                group,
                groups_2d(self.total_pairs().div_ceil(64), GROUPS_X),
                &[Buf::ClusterBoxes, Buf::Stats, Buf::Offsets],
                &[Buf::Indices, Buf::Cursors],
            )]
        } else {
            self.fill_passes(group)
        };
        if self.ordered {
            steps.push(Step::pass(
                "cull.clustered.order_lists",
                &g.order_lists,
                group,
                groups_2d(f.params.bins.div_ceil(64), GROUPS_X),
                &[Buf::Counts],
                &[Buf::WideLights, Buf::Stats],
            ));
            steps.push(Step::pass(
                "cull.clustered.order_args",
                &g.order_args,
                &self.group_args,
                (1, 1),
                &[Buf::Stats],
                &[Buf::WideArgs],
            ));
            let long = if f.params.flags & CULL_FLAG_ORDER_BITS != 0 {
                ("cull.clustered.order_bits", &g.order_bits, 16)
            } else {
                ("cull.clustered.order", &g.order, 16)
            };
            for (name, pipeline, offset) in
                [("cull.clustered.order_short", &g.order_short, 0), long]
            {
                steps.push(Step::pass(
                    name,
                    pipeline,
                    group,
                    Dispatch::Indirect(Buf::WideArgs, &self.wide_args, offset),
                    &[
                        Buf::WideLights,
                        Buf::WideArgs,
                        Buf::Stats,
                        Buf::Offsets,
                        Buf::Counts,
                        Buf::Indices,
                    ],
                    &[Buf::Indices],
                ));
            }
        }
        steps.push(q.lists.finalize(f, group));
        steps
    }

    fn outputs(self) -> Outputs {
        Outputs {
            indices: self.sized.expect("sized before the output").0,
            tile_masks: None,
            tile_lines: None,
        }
    }
}
