//! CPU oracles of z-binning's passes (`crate::strategies::zbin`): its keys and order, its bins'
//! ranges, and its lists a (tile, depth bin) cell.

use manylights_gpu::layout::{GpuFrame, GpuLight};

use super::{BORDER, OracleLists};
use crate::geometry::{
    self, CullLight, light_depth_extent, light_tiles, tile_box, tile_keeps, tile_side_planes,
};
use crate::layout::{GpuCullParams, GpuTileDepth};

/// Oracle of `cull.zbin.keys`: each light's sort key, the depth sub-bin of its centre
/// ([`crate::strategies::zbin::KEY_SUB`] a bin). A GPU's `log` may put a centre within a hair
/// of a sub-bin boundary on its other side: keys may then differ by one.
pub fn zbin_keys(frame: &GpuFrame, p: &GpuCullParams, lights: &[GpuLight]) -> Vec<u32> {
    let sub = crate::strategies::zbin::KEY_SUB;
    let max = (p.slices * sub - 1) as f32;
    lights
        .iter()
        .map(|l| {
            let d = -CullLight::new(frame, l, p.slack).center.z;
            (geometry::slice_coord(p, d) * sub as f32)
                .floor()
                .clamp(0.0, max) as u32
        })
        .collect()
}

/// The lights in z-binning's order: stably sorted by [`zbin_keys`] (what the GPU's radix sort
/// gives from the same keys).
pub fn zbin_order(frame: &GpuFrame, p: &GpuCullParams, lights: &[GpuLight]) -> Vec<u32> {
    let keys = zbin_keys(frame, p, lights);
    let mut order: Vec<u32> = (0..lights.len() as u32).collect();
    order.sort_by_key(|&i| keys[i as usize]);
    order
}

/// An empty range of sorted lights that widening by any light's `k..k + 1` turns into it.
#[allow(
    clippy::reversed_empty_ranges,
    reason = "empty on purpose: the neutral element of widening"
)]
const NO_LIGHTS: std::ops::Range<u32> = u32::MAX..0;

/// Oracle of `cull.zbin.bins` at slack `p.slack * k`, given the sorted lights `order`: each
/// depth bin's range `first..end` of sorted lights whose depth extent (as
/// [`light_depth_extent`], the bins between for a cone's empty one) touches it; lights wholly
/// beyond the far plane touch none.
pub fn zbin_ranges(
    frame: &GpuFrame,
    p: &GpuCullParams,
    lights: &[GpuLight],
    order: &[u32],
    k: f32,
) -> Vec<std::ops::Range<u32>> {
    let mut ranges = vec![NO_LIGHTS; p.slices as usize];
    for (s, &i) in order.iter().enumerate() {
        let c = CullLight::new(frame, &lights[i as usize], p.slack * k);
        let [lo, hi, _, _] = light_depth_extent(&c);
        if lo.min(hi) > p.far {
            continue;
        }
        let s = s as u32;
        for b in geometry::depth_slice(p, lo.min(hi))..=geometry::depth_slice(p, lo.max(hi)) {
            let r = &mut ranges[b as usize];
            *r = r.start.min(s)..r.end.max(s + 1);
        }
    }
    ranges
}

/// Oracle of z-binning's lists (`cull.zbin.bins` and `cull.zbin.masks`), a list a (tile, depth
/// bin) cell (cell `bin * tiles + tile`, as [`crate::CullOutput::read`] expands them), given
/// the sorted lights `order` and the tiles' depth data (from the GPU passes, so that this
/// oracle checks the bins and masks alone). Cell (t, b) keeps sorted light k when k lies in
/// bin b's range and in the ranges of the bins of tile t's depth bounds (one bin of margin
/// either side: the part of the mask the GPU computes), the light's rectangle holds the tile
/// and gather's tile test keeps it. Decisions are taken at the slack moved down and up by
/// [`BORDER`] (the ranges too), and with the tile's bins at its bounds moved by 1e-5 of
/// themselves (a GPU's `log` may bin a bound on the other side of a boundary).
pub fn zbin_lists(
    frame: &GpuFrame,
    p: &GpuCullParams,
    lights: &[GpuLight],
    tile_depth: &[GpuTileDepth],
    order: &[u32],
) -> OracleLists {
    let tiles = (p.tiles_x * p.tiles_y) as usize;
    let mut out = OracleLists::new(tiles * p.slices as usize);
    let [lo, hi] = [1.0 - BORDER, 1.0 + BORDER].map(|k| {
        let ranges = zbin_ranges(frame, p, lights, order, k);
        let sorted: Vec<(CullLight, [i32; 4])> = order
            .iter()
            .map(|&i| {
                let c = CullLight::new(frame, &lights[i as usize], p.slack * k);
                let rect = light_tiles(frame, p, &c);
                (c, rect)
            })
            .collect();
        (ranges, sorted)
    });
    // The sorted lights a tile's mask covers: the union of the ranges of bins b0..=b1.
    let union = |ranges: &[std::ops::Range<u32>], b0: u32, b1: u32| {
        ranges[b0 as usize..=b1 as usize]
            .iter()
            .fold(NO_LIGHTS, |u, r| u.start.min(r.start)..u.end.max(r.end))
    };
    let bin = |d: f32| geometry::depth_slice(p, d);
    for ty in 0..p.tiles_y {
        for tx in 0..p.tiles_x {
            let t = (ty * p.tiles_x + tx) as usize;
            let td = &tile_depth[t];
            if td.covered == 0 {
                continue;
            }
            let planes = tile_side_planes(frame, p, [tx, ty]);
            let bx = tile_box(frame, p, [tx, ty], td);
            let last = p.slices - 1;
            let (e0, e1) = (1.0 - 1e-5, 1.0 + 1e-5);
            // Narrow: the fewest bins the GPU may take; wide: the most.
            let narrow = (
                bin(td.dmin * e1).saturating_sub(1),
                (bin(td.dmax * e0) + 1).min(last),
            );
            let wide = (
                bin(td.dmin * e0).saturating_sub(1),
                (bin(td.dmax * e1) + 1).min(last),
            );
            let (x, y) = (tx as i32, ty as i32);
            // Once a tile, at each slack: the sorted lights its mask covers, and for each of
            // them whether its rectangle holds the tile and the tile test keeps it.
            let covers = [
                union(&lo.0, narrow.0, narrow.1),
                union(&hi.0, wide.0, wide.1),
            ];
            let span = covers[0].start.min(covers[1].start)..covers[0].end.max(covers[1].end);
            let keeps: Vec<[bool; 2]> = span
                .clone()
                .map(|k| {
                    [(&lo, &covers[0]), (&hi, &covers[1])].map(|((_, sorted), cover)| {
                        let (c, r) = &sorted[k as usize];
                        cover.contains(&k)
                            && x >= r[0]
                            && x <= r[2]
                            && y >= r[1]
                            && y <= r[3]
                            && tile_keeps(p, c, &planes, &bx, td)
                    })
                })
                .collect();
            for b in 0..p.slices as usize {
                let cell = b * tiles + t;
                let first = lo.0[b].start.min(hi.0[b].start).max(span.start);
                let end = lo.0[b].end.max(hi.0[b].end).min(span.end);
                for k in first..end {
                    let [keep_lo, keep_hi] = keeps[(k - span.start) as usize];
                    out.push(
                        cell,
                        order[k as usize],
                        lo.0[b].contains(&k) && keep_lo,
                        hi.0[b].contains(&k) && keep_hi,
                    );
                }
            }
        }
    }
    for v in out.kept.iter_mut().chain(out.borderline.iter_mut()) {
        v.sort_unstable();
    }
    out
}
