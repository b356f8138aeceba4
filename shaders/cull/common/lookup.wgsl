// The one pixel-to-list lookup every shading backend uses, whatever the strategy.
// Bindings of group 1 for list consumers: 0 = CullParams, 1 = bin_ranges, 2 = light_indices,
// 3 = the depth buffer, 4 = a per-pixel output, 5 = a pass-specific uniform (host:
// manylights_cull::Culler::lists_layout).
//
// Two forms of lists. Every strategy but z-binning: bin_ranges[bin] = (offset, count) into
// light_indices (light_list). Z-binning (CULL_FLAG_ZBIN, shaders/cull/zbin/): bin_ranges[b] =
// (~first, end) of depth bin b's range of depth-sorted lights ((0, 0): none), light_indices[k]
// for k < light_count the k-th light in depth order, and after them each tile's mask, a bit a
// sorted light (tile t's word w at light_count + t * zbin_words() + w); a pixel's lights are
// its tile's bits within its depth bin's range (zbin_cell, zbin_bits). Consumers branch on
// zbin_lists() (uniform: one branch a pixel, not a light).
@group(1) @binding(1) var<storage, read> bin_ranges: array<vec2<u32>>;
@group(1) @binding(2) var<storage, read> light_indices: array<u32>;

// (offset, count) of the light list of a pixel.
fn light_list(pixel: vec2<u32>, z: f32) -> vec2<u32> {
    return bin_ranges[bin_of(pixel, z)];
}

// Whether the lists are z-binning's.
fn zbin_lists() -> bool {
    return (cull.flags & CULL_FLAG_ZBIN) != 0u;
}

// Z-binning's lights of a pixel: the first word of its tile's mask in light_indices, and its
// depth bin's range [first, end) of sorted lights.
struct ZBinCell {
    mask: u32,
    first: u32,
    end: u32,
}

// Words of a tile's mask.
fn zbin_words() -> u32 {
    return (cull.light_count + 31u) / 32u;
}

fn zbin_cell(pixel: vec2<u32>, z: f32) -> ZBinCell {
    let tile = pixel / cull.tile_size;
    let r = bin_ranges[depth_slice(linear_depth(z))];
    return ZBinCell(cull.light_count + (tile.y * cull.tiles_x + tile.x) * zbin_words(), ~r.x, r.y);
}

// Word w of a cell's mask within its range (for first / 32 <= w <= (end - 1) / 32, with
// first < end): bit k % 32 set when sorted light k = 32 w + bit is the pixel's; the light is
// light_indices[k].
fn zbin_bits(c: ZBinCell, w: u32) -> u32 {
    let lo = select(0u, c.first % 32u, w == c.first / 32u);
    let hi = select(31u, (c.end - 1u) % 32u, w == (c.end - 1u) / 32u);
    return light_indices[c.mask + w] & bit_range(lo, hi);
}

// The number of lights of a z-binning cell.
fn zbin_count(c: ZBinCell) -> u32 {
    var n = 0u;
    if c.first < c.end {
        for (var w = c.first / 32u; w <= (c.end - 1u) / 32u; w++) {
            n += countOneBits(zbin_bits(c, w));
        }
    }
    return n;
}

// The number of lights a pixel's list hands it, either form.
fn list_length(pixel: vec2<u32>, z: f32) -> u32 {
    if zbin_lists() {
        return zbin_count(zbin_cell(pixel, z));
    }
    return light_list(pixel, z).y;
}

