// cull.zbin.scatter: z-binning's masks a light at a time (the scatter path of cull.zbin, where
// there are many lights; zbin.wgsl has the passes before it and the gather path). The masks are
// the same bits as zbin_masks sets: sorted light k's bit in tile t is set when k lies within the
// tile's cover (the union of the ranges of the bins of its depth bounds, cull.zbin.covers),
// the light's rectangle holds the tile and gather's tile test keeps it. cull.zbin.covers has
// zeroed every mask word before this pass. Its own module, since the masks are atomics here
// (lights of one word set their bits concurrently) and plain words in zbin.wgsl.
//
// Group 1 here: 2 the tiles' depth, 7 light_indices (the sorted lights, then the masks), 9 the
// lights' tile rectangles (as cull.depth_bounds stores them), 11 each tile's cover (first, end).
@group(1) @binding(2) var<storage, read_write> tile_depth: array<TileDepth>;
@group(1) @binding(7) var<storage, read_write> zbin_masks: array<atomic<u32>>;
@group(1) @binding(9) var<storage, read_write> zbin_rects: array<u32>;
@group(1) @binding(11) var<storage, read_write> zbin_covers: array<u32>;

// Threads a sorted light: lane j takes every ZBIN_SCATTER_LANES-th tile of its rectangle from
// the j-th, so that a light over many tiles is shared.
const ZBIN_SCATTER_LANES: u32 = 4u;

// A thread a (sorted light, lane): the light's bit in every tile of its rectangle that keeps it.
@compute @workgroup_size(64)
fn zbin_scatter(@builtin(global_invocation_id) id: vec3<u32>) {
    let t = id.y * GROUPS_X * 64u + id.x;
    let k = t / ZBIN_SCATTER_LANES;
    if k >= cull.light_count {
        return;
    }
    let i = atomicLoad(&zbin_masks[k]);
    let r0 = zbin_rects[2u * i];
    let r1 = zbin_rects[2u * i + 1u];
    let x0 = r0 & 0xffffu;
    let y0 = r0 >> 16u;
    let x1 = r1 & 0xffffu;
    let y1 = r1 >> 16u;
    // An empty rectangle is stored as x0 > x1.
    if x0 > x1 || y0 > y1 {
        return;
    }
    let width = x1 - x0 + 1u;
    let count = width * (y1 - y0 + 1u);
    let l = cull_light(lights[i]);
    let at = cull.light_count + k / 32u;
    let words = (cull.light_count + 31u) / 32u;
    let bit = 1u << (k % 32u);
    for (var j = t % ZBIN_SCATTER_LANES; j < count; j += ZBIN_SCATTER_LANES) {
        let tile = vec2<u32>(x0 + j % width, y0 + j / width);
        let b = tile.y * cull.tiles_x + tile.x;
        if k < zbin_covers[2u * b] || k >= zbin_covers[2u * b + 1u] {
            continue;
        }
        if tile_keeps_at(l, tile, tile_side_planes(tile), tile_depth[b]) {
            atomicOr(&zbin_masks[at + b * words], bit);
        }
    }
}
