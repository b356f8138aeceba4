//! The lists a culling run leaves on the GPU ([`CullOutput`]), ready for shading, and as read
//! back to the host ([`BinLists`]).

use manylights_gpu::{GpuContext, GpuError, readback};

use crate::blocks::{tile_lines, tile_masks};
use crate::layout::{
    CLUSTER_GROUP_MIN_LIGHTS, CLUSTER_GROUP_SLICES, CULL_FLAG_ZBIN, GpuCullParams, GpuTileDepth,
};
use crate::record::StepInfo;

/// The form of a run's lists on the GPU (`shaders/cull/common/lookup.wgsl`): a consumer picks
/// its entry point by it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ListForm {
    /// `bin_ranges[bin] = (offset, count)` into `light_indices` (every strategy but z-binning).
    Bins,
    /// The same, a list a tile, in tiles of a multiple of 8 pixels (the tiled strategies, and
    /// clusters of one slice): an 8 x 8 block of pixels reads one list.
    Tiles,
    /// Z-binning's depth bins' ranges of depth-sorted lights and tile masks.
    ZBin,
    /// A list a cluster, in tiles of a multiple of 8 pixels and 2 to
    /// [`crate::layout::CLUSTER_GROUP_SLICES`] slices, with more than
    /// [`crate::layout::CLUSTER_GROUP_MIN_LIGHTS`] lights: an 8 x 8 block of pixels reads the
    /// lists of its tile's clusters it lies in, and deferred lighting takes them a workgroup
    /// at a time (a pixel at a time with fewer lights, as `Bins`).
    Clusters,
}

impl ListForm {
    /// The form of lists built with `p`.
    pub fn of(p: &GpuCullParams) -> Self {
        if p.flags & CULL_FLAG_ZBIN != 0 {
            Self::ZBin
        } else if p.slices <= 1 && p.tile_size.is_multiple_of(8) {
            Self::Tiles
        } else if p.slices <= CLUSTER_GROUP_SLICES
            && p.tile_size.is_multiple_of(8)
            && p.light_count > CLUSTER_GROUP_MIN_LIGHTS
        {
            Self::Clusters
        } else {
            Self::Bins
        }
    }
}

/// Light lists read back to the host.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BinLists {
    /// (offset, count) per bin.
    pub ranges: Vec<[u32; 2]>,
    /// Light indices.
    pub indices: Vec<u32>,
}

impl BinLists {
    /// The lights of bin `b`.
    pub fn list(&self, b: usize) -> &[u32] {
        let [o, c] = self.ranges[b];
        &self.indices[o as usize..(o + c) as usize]
    }

    /// The lights of bin `b`, sorted.
    pub fn sorted(&self, b: usize) -> Vec<u32> {
        let mut v = self.list(b).to_vec();
        v.sort_unstable();
        v
    }
}

/// The lists of one frame on the GPU, ready for shading.
pub struct CullOutput {
    /// The parameters they were built with.
    pub params: GpuCullParams,
    /// The `CullParams` uniform.
    pub params_buf: wgpu::Buffer,
    /// `bin_ranges`.
    pub ranges: wgpu::Buffer,
    /// `light_indices` (at least one element).
    pub indices: wgpu::Buffer,
    /// Total list entries.
    pub total: u32,
    /// Lights dropped by a deliberate capacity (0 without one).
    pub dropped: u32,
    /// (Bin, light) pairs culling by visibility dropped, a light an occluder hides from every
    /// point of the bin's cell (0 without `CullSettings::occlusion`).
    pub occluded: u32,
    /// Per-tile depth data (tiled strategies).
    pub tile_depth: wgpu::Buffer,
    /// Cluster occupancy (clusters with `skip_empty`).
    pub occupancy: wgpu::Buffer,
    /// The tile masks, where the run used them (gather's and 2.5D's coarse-to-fine passes, and
    /// tiled scatter, within [`crate::Culler::mask_budget`]). Every fill leaves them all zero, as the
    /// next count pass needs (see [`crate::blocks::tile_masks`]).
    pub tile_masks: Option<wgpu::Buffer>,
    /// The tile lines, where the run took gather's and 2.5D's lines path (within
    /// [`crate::Culler::mask_budget`], with [`crate::Culler::gather_lines`]): for each column of tiles, then
    /// each row, then each depth bin, two words for each 64 lights, and after them each light's
    /// depth extent (see [`crate::blocks::tile_lines`]).
    pub tile_lines: Option<wgpu::Buffer>,
    /// The steps of the run as recorded (of one run, where runs went back to back), with the
    /// buffers each reads and writes.
    pub passes: Vec<StepInfo>,
}

impl CullOutput {
    /// Whether the run decided its lists as a bit per (tile, light): with tile masks, or with
    /// tile lines (whose per-tile words are never stored). The `tile_masks` result column.
    pub fn used_tile_masks(&self) -> bool {
        self.tile_masks.is_some() || self.tile_lines.is_some()
    }

    /// Reads the tile lines back (their words, not the lights' depth extents after them),
    /// where the run used them.
    pub fn read_tile_lines(&self, ctx: &GpuContext) -> Result<Option<Vec<u32>>, GpuError> {
        read_words(
            ctx,
            self.tile_lines.as_ref(),
            tile_lines::bytes(&self.params),
        )
    }

    /// The lists' bindings 0, 1, 2 (`CullParams`, `bin_ranges`, `light_indices`), as every
    /// consumer's bind group starts.
    pub fn list_bindings(&self) -> [wgpu::BindingResource<'_>; 3] {
        [
            self.params_buf.as_entire_binding(),
            self.ranges.as_entire_binding(),
            self.indices.as_entire_binding(),
        ]
    }

    /// Bytes of the lists: ranges plus indices (z-binning: its bins' ranges, the sorted lights
    /// and the tiles' masks).
    pub fn list_bytes(&self) -> u64 {
        u64::from(self.params.bins) * 8 + u64::from(self.total) * 4
    }

    /// Whether the lists are z-binning's (see `shaders/cull/common/lookup.wgsl`).
    pub fn is_zbin(&self) -> bool {
        self.form() == ListForm::ZBin
    }

    /// The form of the lists.
    pub fn form(&self) -> ListForm {
        ListForm::of(&self.params)
    }

    /// Reads the lists back: a list a bin, and for z-binning a list a (tile, depth bin) cell,
    /// cell `bin * tiles + tile` (as clusters number theirs; [`crate::geometry::bin_of`]),
    /// expanded from the masks and ranges ([`zbin_cells`]).
    pub fn read(&self, ctx: &GpuContext) -> Result<BinLists, GpuError> {
        let (ranges, indices) = self.read_stored(ctx)?;
        if self.is_zbin() {
            return Ok(zbin_cells(&self.params, &ranges, &indices));
        }
        Ok(BinLists { ranges, indices })
    }

    /// The length of every bin's list (z-binning: every cell's, as [`CullOutput::read`]
    /// numbers them), without expanding z-binning's lists.
    pub fn bin_lengths(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        if self.is_zbin() {
            let (ranges, indices) = self.read_stored(ctx)?;
            return Ok(zbin_lengths(&self.params, &ranges, &indices));
        }
        let ranges: Vec<[u32; 2]> = bytemuck::pod_collect_to_vec(&readback::read_buffer(
            ctx,
            &self.ranges,
            0,
            u64::from(self.params.bins) * 8,
        )?);
        Ok(ranges.iter().map(|r| r[1]).collect())
    }

    /// `bin_ranges` and `light_indices` as they are on the GPU (z-binning: in its own form).
    pub fn read_stored(&self, ctx: &GpuContext) -> Result<(Vec<[u32; 2]>, Vec<u32>), GpuError> {
        let ranges = readback::read_buffer(ctx, &self.ranges, 0, u64::from(self.params.bins) * 8)?;
        let indices = if self.total > 0 {
            readback::read_buffer(ctx, &self.indices, 0, u64::from(self.total) * 4)?
        } else {
            Vec::new()
        };
        Ok((
            bytemuck::pod_collect_to_vec(&ranges),
            bytemuck::pod_collect_to_vec(&indices),
        ))
    }

    /// Reads the per-tile depth data back (meaningful for tiled strategies).
    pub fn read_tile_depth(&self, ctx: &GpuContext) -> Result<Vec<GpuTileDepth>, GpuError> {
        let n = u64::from(self.params.tiles_x * self.params.tiles_y);
        Ok(bytemuck::pod_collect_to_vec(&readback::read_buffer(
            ctx,
            &self.tile_depth,
            0,
            n * 16,
        )?))
    }

    /// Reads the tile masks back, where the run used them.
    pub fn read_tile_masks(&self, ctx: &GpuContext) -> Result<Option<Vec<u32>>, GpuError> {
        read_words(
            ctx,
            self.tile_masks.as_ref(),
            tile_masks::bytes(&self.params),
        )
    }

    /// Reads the cluster occupancy back (meaningful for clusters with `skip_empty` or the box
    /// test): a flag a bin, then two words a bin, the depth bounds of its pixels as
    /// (`!ordered(dmin)`, `ordered(dmax)`), zero where none ([`crate::cpu::occupancy`]); then
    /// two words a tile (its mask of occupied slices, `CULL_FLAG_SLICE_MASKS`), then a word a
    /// bin, its 2.5D cells (`Strategy::Clustered::cells`, [`crate::cpu::cluster_cells`]).
    pub fn read_occupancy(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        let (bins, tiles) = (
            u64::from(self.params.bins),
            u64::from(self.params.tiles_x * self.params.tiles_y),
        );
        Ok(bytemuck::pod_collect_to_vec(&readback::read_buffer(
            ctx,
            &self.occupancy,
            0,
            bins * 16 + tiles * 8,
        )?))
    }
}

/// Z-binning's range of depth bin `b` as stored, `(~first, end)`, as `first..end` (empty for an
/// untouched bin).
pub fn zbin_range(stored: [u32; 2]) -> std::ops::Range<u32> {
    !stored[0]..stored[1]
}

/// Z-binning's lists as a list a cell (cell `bin * tiles + tile`): the sorted lights of the
/// bin's range whose bit the tile's mask sets, in depth order. `ranges` and `indices` as the
/// GPU holds them (`shaders/cull/common/lookup.wgsl`).
pub fn zbin_cells(p: &GpuCullParams, ranges: &[[u32; 2]], indices: &[u32]) -> BinLists {
    let n = p.light_count as usize;
    let words = n.div_ceil(32);
    let tiles = (p.tiles_x * p.tiles_y) as usize;
    let mut out = BinLists {
        ranges: Vec::with_capacity(ranges.len() * tiles),
        indices: Vec::new(),
    };
    for &r in ranges {
        for t in 0..tiles {
            let mask = &indices[n + t * words..n + (t + 1) * words];
            let start = out.indices.len() as u32;
            for k in zbin_range(r) {
                if mask[k as usize / 32] & (1 << (k % 32)) != 0 {
                    out.indices.push(indices[k as usize]);
                }
            }
            out.ranges.push([start, out.indices.len() as u32 - start]);
        }
    }
    out
}

/// The lengths of [`zbin_cells`]' lists, from prefix counts of each tile's bits.
pub fn zbin_lengths(p: &GpuCullParams, ranges: &[[u32; 2]], indices: &[u32]) -> Vec<u32> {
    let n = p.light_count as usize;
    let words = n.div_ceil(32);
    let tiles = (p.tiles_x * p.tiles_y) as usize;
    let mut lengths = vec![0u32; ranges.len() * tiles];
    // Bits of the tile's mask below sorted light k.
    let mut below = vec![0u32; words + 1];
    for t in 0..tiles {
        let mask = &indices[n + t * words..n + (t + 1) * words];
        for (w, &m) in mask.iter().enumerate() {
            below[w + 1] = below[w] + m.count_ones();
        }
        let before = |k: u32| {
            let (w, b) = (k as usize / 32, k % 32);
            let partial = if b == 0 {
                0
            } else {
                (mask[w] << (32 - b)).count_ones()
            };
            below[w] + partial
        };
        for (b, &r) in ranges.iter().enumerate() {
            let k = zbin_range(r);
            if k.start < k.end {
                lengths[b * tiles + t] = before(k.end) - before(k.start);
            }
        }
    }
    lengths
}

/// The first `bytes` of `buf` as words, where there is a buffer.
fn read_words(
    ctx: &GpuContext,
    buf: Option<&wgpu::Buffer>,
    bytes: u64,
) -> Result<Option<Vec<u32>>, GpuError> {
    buf.map(|b| {
        Ok(bytemuck::pod_collect_to_vec(&readback::read_buffer(
            ctx, b, 0, bytes,
        )?))
    })
    .transpose()
}
