//! CPU oracles of every culling pass, producing the same lists as the GPU.
//!
//! The oracles run the f32 mirror in [`crate::geometry`]. Besides the lists they return, per
//! bin, the *borderline* lights: those whose decision changes when the slack moves by
//! +-[`BORDER`] of itself. A GPU that fuses multiply-adds may decide those either way; every
//! other decision must match exactly. The band (1e-5 of a light's distance) is far above f32
//! rounding and far below any geometric feature.

use manylights_gpu::layout::{GpuFrame, GpuLight};

use crate::geometry::{
    self, CullLight, bin_of, depth_cell, depth_cell_scale, light_depth_extent, light_tiles,
    line_planes, linear_depth, outside_plane, tile_box, tile_keeps, tile_side_planes, zbin,
};
use crate::layout::{
    CULL_FLAG_DEPTH_MASK, CULL_FLAG_SKIP_EMPTY, CULL_FLAG_TILE_BOX, GpuCullParams, GpuTileDepth,
    ZBINS,
};

mod zbin;
pub use zbin::{zbin_keys, zbin_lists, zbin_order, zbin_ranges};

/// Relative band around the slack inside which a decision is borderline.
pub const BORDER: f32 = 0.1;

/// An oracle's lists: per bin, the lights it keeps (sorted) and the borderline ones.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct OracleLists {
    /// Lights kept, per bin, sorted.
    pub kept: Vec<Vec<u32>>,
    /// Lights whose decision is borderline, per bin, sorted.
    pub borderline: Vec<Vec<u32>>,
}

impl OracleLists {
    pub(crate) fn new(bins: usize) -> Self {
        Self {
            kept: vec![Vec::new(); bins],
            borderline: vec![Vec::new(); bins],
        }
    }

    fn push(&mut self, bin: usize, light: u32, lo: bool, hi: bool) {
        // `lo`/`hi`: the decision at slack * (1 -+ BORDER). Kept means kept at the real slack,
        // which lies between them; where they differ, the real decision is borderline too, and
        // we record it as kept (the conservative side) and borderline.
        if lo || hi {
            self.kept[bin].push(light);
        }
        if lo != hi {
            self.borderline[bin].push(light);
        }
    }

    /// Compares GPU lists (as sets per bin) with the oracle's; returns a description of the
    /// first difference that is not borderline, and the number of borderline differences.
    pub fn compare(&self, gpu: &crate::BinLists) -> Result<usize, String> {
        let mut tolerated = 0;
        for b in 0..self.kept.len() {
            let g = gpu.sorted(b);
            if g.windows(2).any(|w| w[0] == w[1]) {
                return Err(format!("bin {b}: duplicate light in GPU list {g:?}"));
            }
            for &l in &g {
                if self.kept[b].binary_search(&l).is_err() {
                    if self.borderline[b].binary_search(&l).is_ok() {
                        tolerated += 1;
                    } else {
                        return Err(format!("bin {b}: GPU keeps light {l}, oracle culls it"));
                    }
                }
            }
            for &l in &self.kept[b] {
                if g.binary_search(&l).is_err() {
                    if self.borderline[b].binary_search(&l).is_ok() {
                        tolerated += 1;
                    } else {
                        return Err(format!("bin {b}: oracle keeps light {l}, GPU culls it"));
                    }
                }
            }
        }
        Ok(tolerated)
    }

    /// As [`crate::BinLists`] (kept lights), for metrics.
    pub fn to_bin_lists(&self) -> crate::BinLists {
        let mut ranges = Vec::with_capacity(self.kept.len());
        let mut indices = Vec::new();
        for l in &self.kept {
            ranges.push([indices.len() as u32, l.len() as u32]);
            indices.extend_from_slice(l);
        }
        crate::BinLists { ranges, indices }
    }
}

/// Oracle of `cull.depth_bounds`: per tile depth data from the depth buffer (`w` x `h`, rows
/// from the top), and per tile the mask bits whose pixel sits within a hair of a cell boundary
/// (a GPU's rounding of the linear depth may set the neighbouring bit instead).
pub fn depth_bounds(
    frame: &GpuFrame,
    p: &GpuCullParams,
    depth: &[f32],
    w: u32,
    h: u32,
) -> (Vec<GpuTileDepth>, Vec<u32>) {
    let tiles = (p.tiles_x * p.tiles_y) as usize;
    let mut out = vec![GpuTileDepth::default(); tiles];
    let mut zmin = vec![f32::INFINITY; tiles];
    let mut zmax = vec![0.0f32; tiles];
    let tile_of = |x: u32, y: u32| ((y / p.tile_size) * p.tiles_x + x / p.tile_size) as usize;
    for y in 0..h {
        for x in 0..w {
            let z = depth[(y * w + x) as usize];
            if z < 1.0 {
                let t = tile_of(x, y);
                zmin[t] = zmin[t].min(z);
                zmax[t] = zmax[t].max(z);
                out[t].covered += 1;
            }
        }
    }
    for t in 0..tiles {
        if out[t].covered > 0 {
            out[t].dmin = linear_depth(frame, zmin[t]);
            out[t].dmax = linear_depth(frame, zmax[t]);
        }
    }
    let mut uncertain = vec![0u32; tiles];
    for y in 0..h {
        for x in 0..w {
            let z = depth[(y * w + x) as usize];
            if z < 1.0 {
                let t = tile_of(x, y);
                let td = out[t];
                let scale = depth_cell_scale(&td);
                let d = linear_depth(frame, z);
                let cell = depth_cell(d, td.dmin, scale);
                out[t].mask |= 1 << cell;
                let f = (d - td.dmin) * scale;
                if (f - f.round()).abs() < 1e-4 * f.abs().max(1.0) {
                    uncertain[t] |=
                        (1 << cell) | (1 << cell.saturating_sub(1)) | (1 << (cell + 1).min(31));
                }
            }
        }
    }
    (out, uncertain)
}

/// Oracle of `cull.tiled_gather` and `cull.depth_mask` (the flag in `p` decides), given the
/// per-tile depth data (from the GPU pass, so that this oracle checks the light tests alone).
/// With a coarse level (`p.coarse > 0`) a tile keeps a light only where the light's tile
/// rectangle ([`light_tiles`], as scatter has it) holds the tile too; the coarse tests
/// themselves only skip lights that fail these tests, so they need no oracle of their own.
/// The single level is the paper's test alone.
pub fn gather(
    frame: &GpuFrame,
    p: &GpuCullParams,
    lights: &[GpuLight],
    tile_depth: &[GpuTileDepth],
) -> OracleLists {
    let everywhere = [0, 0, p.tiles_x as i32 - 1, p.tiles_y as i32 - 1];
    // Per light, at the slack moved down and up by BORDER: the light and its rectangle.
    let tested: Vec<[(CullLight, [i32; 4]); 2]> = lights
        .iter()
        .map(|l| {
            [1.0 - BORDER, 1.0 + BORDER].map(|k| {
                let c = CullLight::new(frame, l, p.slack * k);
                let rect = if p.coarse > 0 {
                    light_tiles(frame, p, &c)
                } else {
                    everywhere
                };
                (c, rect)
            })
        })
        .collect();
    let mut out = OracleLists::new(p.bins as usize);
    for ty in 0..p.tiles_y {
        for tx in 0..p.tiles_x {
            let bin = (ty * p.tiles_x + tx) as usize;
            let t = &tile_depth[bin];
            let planes = tile_side_planes(frame, p, [tx, ty]);
            let bx = tile_box(frame, p, [tx, ty], t);
            let (x, y) = (tx as i32, ty as i32);
            let keeps = |(l, r): &(CullLight, [i32; 4])| {
                x >= r[0]
                    && x <= r[2]
                    && y >= r[1]
                    && y <= r[3]
                    && tile_keeps(p, l, &planes, &bx, t)
            };
            for (i, [lo, hi]) in tested.iter().enumerate() {
                out.push(bin, i as u32, keeps(lo), keeps(hi));
            }
        }
    }
    out
}

/// Oracle of the tile lines that `cull.tile_lines` writes for gather's and 2.5D's lines path
/// (`shaders/cull/common/tile_lines.wgsl`): for each column of tiles, then each row, then each depth
/// bin, two words for each 64 lights, bit `i % 32` of word `i / 32` set when light `i`'s
/// rectangle spans the line and the light is inside the line's two side planes, or for a bin
/// when the bins of its depth extent hold it. Returned at the slack moved down and up
/// by [`BORDER`]: a GPU's word must hold every bit of the first and no bit outside the second.
pub fn tile_lines(frame: &GpuFrame, p: &GpuCullParams, lights: &[GpuLight]) -> [Vec<u32>; 2] {
    let words = lights.len().div_ceil(64) * 2;
    let side = p.tiles_x + p.tiles_y;
    let lines = (side + ZBINS) as usize;
    [1.0 - BORDER, 1.0 + BORDER].map(|k| {
        let mut out = vec![0u32; lines * words];
        for (i, l) in lights.iter().enumerate() {
            let c = CullLight::new(frame, l, p.slack * k);
            let [lo, hi, _, _] = light_depth_extent(&c);
            for b in zbin(p, lo.min(hi))..=zbin(p, lo.max(hi)) {
                out[(side + b) as usize * words + i / 32] |= 1 << (i % 32);
            }
            let r = light_tiles(frame, p, &c);
            for line in 0..p.tiles_x + p.tiles_y {
                let (at, lo, hi) = if line < p.tiles_x {
                    (line as i32, r[0], r[2])
                } else {
                    ((line - p.tiles_x) as i32, r[1], r[3])
                };
                let inside = line_planes(frame, p, line)
                    .iter()
                    .all(|&pl| !outside_plane(pl, &c));
                if lo <= at && at <= hi && inside {
                    out[line as usize * words + i / 32] |= 1 << (i % 32);
                }
            }
        }
        out
    })
}

/// Calls `f` for each cluster of each covered pixel of a depth buffer of `samples` samples a
/// pixel, with the pixel's part of its depths there (linear; `geometry::pixel_slice_range`): a
/// pixel holds every cluster of its tile from its nearest covered sample's slice to its
/// farthest's.
fn for_pixel_clusters(
    frame: &GpuFrame,
    p: &GpuCullParams,
    depth: &[f32],
    (w, h): (u32, u32),
    samples: u32,
    mut f: impl FnMut(u32, [f32; 2]),
) {
    let tiles = p.tiles_x * p.tiles_y;
    for y in 0..h {
        for x in 0..w {
            let at = ((y * w + x) * samples) as usize;
            let covered = depth[at..at + samples as usize]
                .iter()
                .filter(|&&z| z < 1.0);
            let (z0, z1) = covered.fold((1.0f32, 0.0f32), |(a, b), &z| (a.min(z), b.max(z)));
            if z0 >= 1.0 {
                continue;
            }
            let (b0, b1) = (bin_of(frame, p, [x, y], z0), bin_of(frame, p, [x, y], z1));
            let d = [linear_depth(frame, z0), linear_depth(frame, z1)];
            for b in (b0..=b1).step_by(tiles as usize) {
                f(
                    b,
                    geometry::pixel_slice_range(p, b / tiles, [b0 / tiles, b1 / tiles], d),
                );
            }
        }
    }
}

/// Oracle of `cull.occupancy`: 1 for each cluster holding a covered pixel, and after the bins'
/// flags, with the box test, two words a bin: its pixels' depth bounds as
/// (`!ordered_bits(dmin)`, `ordered_bits(dmax)`), zero where none (a GPU's `linear_depth` may
/// differ from this one in the last bit).
pub fn occupancy(frame: &GpuFrame, p: &GpuCullParams, depth: &[f32], w: u32, h: u32) -> Vec<u32> {
    occupancy_samples(frame, p, depth, w, h, 1)
}

/// [`occupancy`] over a depth buffer of `samples` samples a pixel (`depth` holds a pixel's
/// samples one after another, as `Culler::depth_samples` reads them): a pixel holds every
/// cluster of its tile from its nearest covered sample's slice to its farthest's, each over
/// its part of the pixel's depths (`geometry::pixel_slice_range`).
pub fn occupancy_samples(
    frame: &GpuFrame,
    p: &GpuCullParams,
    depth: &[f32],
    w: u32,
    h: u32,
    samples: u32,
) -> Vec<u32> {
    let bins = p.bins as usize;
    let mut occ = vec![0u32; bins * 3];
    for_pixel_clusters(frame, p, depth, (w, h), samples, |b, [lo, hi]| {
        let k = b as usize;
        occ[k] = 1;
        if p.flags & CULL_FLAG_TILE_BOX != 0 {
            occ[bins + 2 * k] = occ[bins + 2 * k].max(!geometry::ordered_bits(lo));
            occ[bins + 2 * k + 1] = occ[bins + 2 * k + 1].max(geometry::ordered_bits(hi));
        }
    });
    occ
}

/// The first occupancy word of the clusters' 2.5D cells (WGSL `cells_at`): after a flag a
/// bin, two depth bounds a bin and two slice-mask words a tile.
fn cells_at(p: &GpuCullParams) -> usize {
    (3 * p.bins + 2 * p.tiles_x * p.tiles_y) as usize
}

/// Oracle of `cull.clustered.cells` (`Strategy::Clustered::cells`), given the occupancy's depth
/// bounds (from the GPU pass, so that this checks the cells alone): each cluster's bits of the
/// 32 cells of its pixels' depth range that its pixels' depths fall in (a pixel of several
/// samples: its part of their range in each of its clusters, `geometry::pixel_slice_range`).
/// A word a bin.
pub fn cluster_cells(
    frame: &GpuFrame,
    p: &GpuCullParams,
    depth: &[f32],
    (w, h): (u32, u32),
    samples: u32,
    occupancy: &[u32],
) -> Vec<u32> {
    let mut cells = vec![0u32; p.bins as usize];
    for_pixel_clusters(frame, p, depth, (w, h), samples, |b, [lo, hi]| {
        let k = (p.bins + 2 * b) as usize;
        let t = GpuTileDepth {
            dmin: geometry::from_ordered_bits(!occupancy[k]),
            dmax: geometry::from_ordered_bits(occupancy[k + 1]),
            mask: 0,
            covered: 1,
        };
        let scale = depth_cell_scale(&t);
        cells[b as usize] |=
            geometry::bit_range(depth_cell(lo, t.dmin, scale), depth_cell(hi, t.dmin, scale));
    });
    cells
}

/// With the box test, whether light `l` may reach a pixel of cluster `bin` of tile `tile`
/// (WGSL `cluster_box_keeps`), from the occupancy's depth bounds (and with
/// `CULL_FLAG_DEPTH_MASK` its 2.5D cells).
fn cluster_box_keeps(
    frame: &GpuFrame,
    p: &GpuCullParams,
    l: &CullLight,
    tile: [u32; 2],
    bin: u32,
    occupancy: &[u32],
) -> bool {
    let at = (p.bins + 2 * bin) as usize;
    let far = occupancy[at + 1];
    if far == 0 {
        return false;
    }
    let t = GpuTileDepth {
        dmin: geometry::from_ordered_bits(!occupancy[at]),
        dmax: geometry::from_ordered_bits(far),
        mask: if p.flags & CULL_FLAG_DEPTH_MASK != 0 {
            occupancy[cells_at(p) + bin as usize]
        } else {
            0
        },
        covered: 1,
    };
    geometry::depth_keeps(p, l, &t)
        && geometry::sphere_meets_box(l.center, l.radius + l.slack, &tile_box(frame, p, tile, &t))
}

/// The clusters light `l` is emitted to, at one slack (with the box test, those whose pixels'
/// box it meets).
fn clustered_light(
    frame: &GpuFrame,
    p: &GpuCullParams,
    l: &CullLight,
    occupancy: &[u32],
    mut emit: impl FnMut(u32),
) {
    let dlo = -l.center.z - l.radius - l.slack;
    let dhi = -l.center.z + l.radius + l.slack;
    if dlo > p.far {
        return;
    }
    let (s0, s1) = (geometry::depth_slice(p, dlo), geometry::depth_slice(p, dhi));
    let [x0, y0, x1, y1] = light_tiles(frame, p, l);
    for ty in y0..=y1 {
        for tx in x0..=x1 {
            let planes = tile_side_planes(frame, p, [tx as u32, ty as u32]);
            if planes.iter().any(|&pl| geometry::outside_plane(pl, l)) {
                continue;
            }
            for s in s0..=s1 {
                let bin = s * p.tiles_x * p.tiles_y + ty as u32 * p.tiles_x + tx as u32;
                let tile = [tx as u32, ty as u32];
                if p.flags & CULL_FLAG_TILE_BOX == 0
                    || cluster_box_keeps(frame, p, l, tile, bin, occupancy)
                {
                    emit(bin);
                }
            }
        }
    }
}

/// Oracle of `cull.clustered`, given the cluster occupancy (from the GPU pass) when
/// `skip_empty` is set.
pub fn clustered(
    frame: &GpuFrame,
    p: &GpuCullParams,
    lights: &[GpuLight],
    occupancy: &[u32],
) -> OracleLists {
    let bins = p.bins as usize;
    let mut out = OracleLists::new(bins);
    let skip = p.flags & CULL_FLAG_SKIP_EMPTY != 0;
    let mut lo_set = vec![false; bins];
    let mut touched = Vec::new();
    for (i, l) in lights.iter().enumerate() {
        clustered_light(
            frame,
            p,
            &CullLight::new(frame, l, p.slack * (1.0 - BORDER)),
            occupancy,
            |b| {
                lo_set[b as usize] = true;
                touched.push(b);
            },
        );
        let mut hi_bins = Vec::new();
        clustered_light(
            frame,
            p,
            &CullLight::new(frame, l, p.slack * (1.0 + BORDER)),
            occupancy,
            |b| hi_bins.push(b),
        );
        hi_bins.extend(touched.iter().copied());
        hi_bins.sort_unstable();
        hi_bins.dedup();
        for &b in &hi_bins {
            if skip && occupancy[b as usize] == 0 {
                continue;
            }
            let lo = lo_set[b as usize];
            // The hi-slack set contains the lo-slack set (more slack, more bins), except
            // through rounding; a bin in only one of them is borderline.
            let hi = true;
            out.push(b as usize, i as u32, lo, hi);
        }
        for b in touched.drain(..) {
            lo_set[b as usize] = false;
        }
    }
    out
}

/// Oracle of `cull.tiled_scatter`: per light, the tiles of its screen rectangle that keep it
/// (the same per-tile test as gather), given the per-tile depth data.
pub fn scatter(
    frame: &GpuFrame,
    p: &GpuCullParams,
    lights: &[GpuLight],
    tile_depth: &[GpuTileDepth],
) -> OracleLists {
    let mut out = OracleLists::new(p.bins as usize);
    for (i, l) in lights.iter().enumerate() {
        let [lo, hi] = [1.0 - BORDER, 1.0 + BORDER].map(|k| CullLight::new(frame, l, p.slack * k));
        let (rl, rh) = (light_tiles(frame, p, &lo), light_tiles(frame, p, &hi));
        for ty in rl[1].min(rh[1])..=rl[3].max(rh[3]) {
            for tx in rl[0].min(rh[0])..=rl[2].max(rh[2]) {
                let inside = |r: &[i32; 4]| tx >= r[0] && tx <= r[2] && ty >= r[1] && ty <= r[3];
                let tile = [tx as u32, ty as u32];
                let bin = (tile[1] * p.tiles_x + tile[0]) as usize;
                let planes = tile_side_planes(frame, p, tile);
                let td = &tile_depth[bin];
                let bx = tile_box(frame, p, tile, td);
                let keep_lo = inside(&rl) && tile_keeps(p, &lo, &planes, &bx, td);
                let keep_hi = inside(&rh) && tile_keeps(p, &hi, &planes, &bx, td);
                out.push(bin, i as u32, keep_lo, keep_hi);
            }
        }
    }
    for v in out.kept.iter_mut().chain(out.borderline.iter_mut()) {
        v.sort_unstable();
    }
    out
}
