//! The passes of a culling run as data, and the one recorder that encodes them.
//!
//! A strategy does not encode passes itself: it declares the steps of its count phase and of its
//! fill phase (`strategies::Plan`) as [`Step`]s (a compute pass with its name, pipeline,
//! bind group, dispatch size and the buffers it reads and writes; a clear; the scan of the
//! counts; the radix sort of tiled scatter's pairs). [`Recorder::record`] encodes, labels and
//! times them, the same way for a single run, back-to-back runs and spans
//! (`frame::execute` decides which). Pass names are profiler scopes and result columns:
//! they stay exactly as they are.
//!
//! The buffers a step reads and writes ([`Buf`]) are what [`crate::CullOutput::passes`] reports
//! and what tests check: every buffer a pass reads is an input of the run or written by an
//! earlier step of it; and a pass's declared buffers are what its entry point reads and writes,
//! by naga's use of each global ([`Kernel`] names the shader and entry point;
//! `tests/cull/global_use.rs`). A pass "writes" a buffer it only updates atomically from a known
//! state (the counts, the cursors, the tile masks that every fill leaves zero). A pass declares
//! what its entry point may write under this run's flags, and reads what it reads under them.

use std::borrow::Cow;

use manylights_gpu::timing::{Category, GpuTimer};
use manylights_gpu::{GpuContext, GpuError, pipeline};

use crate::program::Kernel;
use crate::radix_sort::RadixSort;
use crate::scan::Scan;

/// A buffer of a culling run, by role (the names are the buffers' labels).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Buf {
    /// The depth buffer (an input).
    Depth,
    /// The scene's lights (an input).
    Lights,
    /// Per-tile depth data.
    TileDepth,
    /// Count entries (per bin, per (bin, chunk), or per (light, lane)).
    Counts,
    /// Their exclusive scan.
    Offsets,
    /// Per-bin fill cursors.
    Cursors,
    /// `bin_ranges`.
    Ranges,
    /// `light_indices` (tiled scatter: the pairs' lights).
    Indices,
    /// Cluster occupancy.
    Occupancy,
    /// Counters: dropped lights, totals, cursors of the masked and lines paths.
    Stats,
    /// Each light's tile rectangle.
    LightRects,
    /// A bit per (tile, light).
    TileMasks,
    /// A bit per (column or row of tiles or depth bin, light), and the lights' depth extents.
    TileLines,
    /// Tiled scatter's queue of (light, block of tiles).
    BlockQueue,
    /// The clusters' queue of wide lights.
    WideLights,
    /// The clusters' masks on their tile path (a bit per (cluster, light)).
    ClusterMasks,
    /// The indirect dispatch arguments of the wide lights' passes.
    WideArgs,
    /// The clusters' boxes (`cull.clustered.boxes`).
    ClusterBoxes,
    /// Tiled scatter's pair keys (tiles).
    PairKeys,
    /// Z-binning's covers: each tile's range of sorted lights (its scatter path).
    ZBinCovers,
    /// The scene's occluders (culling by visibility).
    Occluders,
}

impl Buf {
    /// Inputs of every run: read, never written by culling.
    pub const INPUTS: [Buf; 2] = [Buf::Depth, Buf::Lights];

    /// The buffer's label.
    pub fn name(self) -> &'static str {
        match self {
            Self::Depth => "depth",
            Self::Lights => "lights",
            Self::TileDepth => "cull.tile_depth",
            Self::Counts => "cull.bin_counts",
            Self::Offsets => "cull.bin_offsets",
            Self::Cursors => "cull.bin_cursors",
            Self::Ranges => "cull.bin_ranges",
            Self::Indices => "cull.light_indices",
            Self::Occupancy => "cull.occupancy",
            Self::Stats => "cull.stats",
            Self::LightRects => "cull.light_rects",
            Self::TileMasks => "cull.tile_masks",
            Self::TileLines => "cull.tile_lines",
            Self::BlockQueue => "cull.tiled_scatter.blocks",
            Self::WideLights => "cull.clustered.wide_lights",
            Self::ClusterMasks => "cull.clustered.masks",
            Self::WideArgs => "cull.clustered.wide_args",
            Self::ClusterBoxes => "cull.clustered.boxes",
            Self::PairKeys => "cull.pair_keys",
            Self::ZBinCovers => "cull.zbin.covers",
            Self::Occluders => "cull.occluders",
        }
    }
}

/// How many workgroups a pass runs.
#[derive(Clone, Copy, Debug)]
pub enum Dispatch<'a> {
    /// A grid of workgroups.
    Grid([u32; 3]),
    /// Arguments written by an earlier pass into the buffer of that role, at a byte offset.
    Indirect(Buf, &'a wgpu::Buffer, u64),
}

impl From<(u32, u32)> for Dispatch<'_> {
    fn from((x, y): (u32, u32)) -> Self {
        Self::Grid([x, y, 1])
    }
}

impl From<[u32; 3]> for Dispatch<'_> {
    fn from(g: [u32; 3]) -> Self {
        Self::Grid(g)
    }
}

/// One compute pass: bind group 0 is the scene's, `group` is group 1.
pub struct Pass<'a> {
    /// Profiler scope and result column, such as `cull.tiled_gather.count`.
    pub name: Cow<'static, str>,
    /// Its pipeline and the code it runs.
    pub kernel: &'a Kernel,
    /// Bind group 1.
    pub group: &'a wgpu::BindGroup,
    /// Its workgroups.
    pub dispatch: Dispatch<'a>,
    /// Buffers it reads (written by an earlier step or inputs).
    pub reads: &'static [Buf],
    /// Buffers it writes.
    pub writes: &'static [Buf],
}

/// A step of a run.
pub enum Step<'a> {
    /// A compute pass.
    Pass(Pass<'a>),
    /// Zeroes `size` bytes (all with `None`) of `buffer` from `offset`: a transfer between passes.
    Clear {
        /// The buffer's role.
        what: Buf,
        /// The buffer.
        buffer: &'a wgpu::Buffer,
        /// First byte.
        offset: u64,
        /// Bytes, or the rest.
        size: Option<u64>,
    },
    /// Copies the first `n` counts (and one more, a zero) to the offsets and scans them in place
    /// (`scan.*` passes).
    Scan {
        /// The counts.
        counts: &'a wgpu::Buffer,
        /// The offsets.
        offsets: &'a wgpu::Buffer,
        /// Count entries.
        n: u32,
    },
    /// Sorts `pairs` (key, value) pairs by their low `bits` key bits (`sort.*` passes); where the
    /// sorted pairs end up is [`RadixSort::sorted_for`], known before it runs.
    Sort {
        /// Keys, and values, in and (by the sort's path) out.
        keys: &'a wgpu::Buffer,
        /// Values.
        vals: &'a wgpu::Buffer,
        /// Scratch keys.
        keys_tmp: &'a wgpu::Buffer,
        /// Scratch values.
        vals_tmp: &'a wgpu::Buffer,
        /// Pairs.
        pairs: u32,
        /// Key bits.
        bits: u32,
    },
}

impl<'a> Step<'a> {
    /// A compute pass of `pipeline` over `group`.
    pub fn pass(
        name: impl Into<Cow<'static, str>>,
        kernel: &'a Kernel,
        group: &'a wgpu::BindGroup,
        dispatch: impl Into<Dispatch<'a>>,
        reads: &'static [Buf],
        writes: &'static [Buf],
    ) -> Self {
        Self::Pass(Pass {
            name: name.into(),
            kernel,
            group,
            dispatch: dispatch.into(),
            reads,
            writes,
        })
    }

    /// Clears all of `buffer`.
    pub fn clear(what: Buf, buffer: &'a wgpu::Buffer) -> Self {
        Self::Clear {
            what,
            buffer,
            offset: 0,
            size: None,
        }
    }

    /// What the step is called, reads and writes.
    pub fn info(&self) -> StepInfo {
        let kernel = match self {
            Self::Pass(p) => Some((p.kernel.shader, p.kernel.entry)),
            _ => None,
        };
        let indirect = match self {
            Self::Pass(Pass {
                dispatch: Dispatch::Indirect(args, ..),
                ..
            }) => Some(*args),
            _ => None,
        };
        let (name, reads, writes): (Cow<'static, str>, &[Buf], &[Buf]) = match self {
            Self::Pass(p) => (p.name.clone(), p.reads, p.writes),
            Self::Clear { what, .. } => ("clear".into(), &[], std::slice::from_ref(what)),
            Self::Scan { .. } => ("scan".into(), &[Buf::Counts], &[Buf::Offsets]),
            Self::Sort { .. } => (
                "sort".into(),
                &[Buf::PairKeys, Buf::Indices],
                &[Buf::PairKeys, Buf::Indices],
            ),
        };
        StepInfo {
            name: name.into_owned(),
            kernel,
            indirect,
            reads: reads.to_vec(),
            writes: writes.to_vec(),
        }
    }
}

/// A step as [`crate::CullOutput::passes`] lists it: a pass's name (`clear`, `scan` and `sort`
/// for the other steps) and the buffers it reads and writes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StepInfo {
    /// The pass's name.
    pub name: String,
    /// A pass's shader and entry point (none for the other steps).
    pub kernel: Option<(&'static str, &'static str)>,
    /// The buffer of a pass's indirect dispatch arguments (read by the dispatch, not by a
    /// global of its entry point).
    pub indirect: Option<Buf>,
    /// Buffers it reads.
    pub reads: Vec<Buf>,
    /// Buffers it writes.
    pub writes: Vec<Buf>,
}

/// Encodes steps: the one place culling passes are recorded, labelled and timed.
pub struct Recorder<'a> {
    /// The device.
    pub ctx: &'a GpuContext,
    /// Bind group 0 of every pass (the scene).
    pub scene: &'a wgpu::BindGroup,
    /// The scan of [`Step::Scan`].
    pub scan: &'a Scan,
    /// The sort of [`Step::Sort`].
    pub sort: &'a RadixSort,
}

impl Recorder<'_> {
    /// Encodes `steps` in order into `enc`; each pass is timed as its name, in
    /// [`Category::Cull`] (by a timer of passes; a timer of spans times whole runs,
    /// `frame::execute`).
    pub fn record(
        &self,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        steps: &[Step<'_>],
    ) -> Result<(), GpuError> {
        let outer = timer.set_category(Category::Cull);
        let recorded = self.record_steps(enc, timer, steps);
        timer.set_category(outer);
        recorded
    }

    fn record_steps(
        &self,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        steps: &[Step<'_>],
    ) -> Result<(), GpuError> {
        for step in steps {
            match step {
                Step::Pass(p) => self.pass(enc, timer, p),
                Step::Clear {
                    buffer,
                    offset,
                    size,
                    ..
                } => enc.clear_buffer(buffer, *offset, *size),
                Step::Scan { counts, offsets, n } => {
                    enc.copy_buffer_to_buffer(counts, 0, offsets, 0, (u64::from(*n) + 1) * 4);
                    self.scan.encode(self.ctx, enc, offsets, n + 1, timer);
                }
                Step::Sort {
                    keys,
                    vals,
                    keys_tmp,
                    vals_tmp,
                    pairs,
                    bits,
                } => {
                    let sorted = self.sort.encode(
                        self.ctx, enc, keys, vals, keys_tmp, vals_tmp, *pairs, *bits, timer,
                    )?;
                    // The steps after the sort were declared for this place.
                    assert_eq!(sorted, self.sort.sorted_for(*pairs, *bits));
                }
            }
        }
        Ok(())
    }

    fn pass(&self, enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer, p: &Pass<'_>) {
        match p.dispatch {
            Dispatch::Grid(groups) => pipeline::dispatch_3d(
                enc,
                timer,
                &p.name,
                &p.kernel.pipeline,
                &[self.scene, p.group],
                groups,
            ),
            Dispatch::Indirect(_, args, offset) => {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(&p.name),
                    timestamp_writes: timer.compute_pass(&p.name),
                });
                pass.set_pipeline(&p.kernel.pipeline);
                pass.set_bind_group(0, self.scene, &[]);
                pass.set_bind_group(1, p.group, &[]);
                pass.dispatch_workgroups_indirect(args, offset);
            }
        }
    }
}

/// A pass that reads the lists of each back-to-back run of
/// [`crate::Culler::run_repeated_with`] (a shading pass), recorded after every run and inside
/// its span: culling and the pass that pays for its lists, timed together as a frame does.
pub trait ListPass {
    /// Binds the lists once they are sized, before any run is recorded: `lists` are the
    /// bindings 0, 1, 2 of every list consumer (`CullParams`, `bin_ranges`, `light_indices`;
    /// [`crate::CullOutput::list_bindings`]), in the form `form`.
    fn bind(
        &mut self,
        ctx: &GpuContext,
        lists: [wgpu::BindingResource<'_>; 3],
        form: crate::ListForm,
    );
    /// Records the pass, timed as its name.
    fn record(&self, enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer);
    /// The timed passes [`ListPass::record`] records (one, or more where it shades in
    /// several, as forward shading over transparent surfaces does).
    fn passes(&self) -> u32 {
        1
    }
}
