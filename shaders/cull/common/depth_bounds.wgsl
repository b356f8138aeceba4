// cull.depth_bounds: DEPTH_TILES tiles a workgroup (tiles DEPTH_TILES x + j of row y for
// workgroup (x, y)), 64 threads a tile: fewer, larger workgroups, as launching a workgroup
// costs more than a tile's work at small tiles. The nearest and farthest covered pixel (linear
// view depth) and the 2.5D geometry mask of every tile (Harada 2012, GPU Pro 4 section 5.6.1:
// 32 cells over [dmin, dmax]). Background pixels (depth 1.0, the clear value) are not covered
// and need no lights, so they do not widen the bounds.
//
// For gather's and 2.5D's coarse-to-fine passes the host adds rows of workgroups before the
// tiles' (wg.y < the rows past tiles_y), which store each light's tile rectangle instead (light_tiles,
// as scatter and clusters use: its view-space box cut at the near plane, projected), packed as
// (x0 | y0 << 16, x1 | y1 << 16), an empty one as (1, 0) (x0 > x1): one pass, not two, as
// each pass has a fixed cost larger than this work. For tiled scatter with tile masks
// (depth_bounds_blocks) those rows also queue each light's blocks of SCATTER_MASK_THREADS
// tiles of its rectangle, (light, block) pairs in block_queue, their number in
// cull_stats[6], so that the count pass (scatter_masks, tiled_scatter.wgsl) shares a large
// light's tiles among many workgroups. For gather's and 2.5D's lines path (see
// tile_lines.wgsl) this module's cull.tile_lines pass (tile_lines_pass) has only light
// workgroups, each taking 64 DEPTH_TILES lights and a chunk of lines, and writing those words
// of the tile lines and the lights' depth extents (store_light_lines); that path's list passes
// compute the tiles' depth data themselves.
@group(1) @binding(2) var<storage, read_write> tile_depth: array<TileDepth>;
@group(1) @binding(7) var<storage, read_write> block_queue: array<u32>;
@group(1) @binding(9) var<storage, read_write> light_rects: array<vec2<u32>>;
@group(1) @binding(10) var<storage, read_write> cull_stats: array<atomic<u32>>;
// The tile lines (tile_lines.wgsl): word w of line `line` at line * mask_words() + w; then
// each light's depth extent and its view-space sphere, eight words (f32 bits) a light.
@group(1) @binding(11) var<storage, read_write> tile_lines: array<u32>;

// A workgroup's blocks and their place in the queue.
var<workgroup> wg_blocks: atomic<u32>;
var<workgroup> wg_block_at: u32;

// Light `i`'s tile rectangle into light_rects, and with `blocks` its blocks into the queue
// (one atomic add a workgroup). Called in uniform control flow.
fn store_light_rect(i: u32, index: u32, blocks: bool) {
    var n = 0u;
    if i < cull.light_count {
        let r = light_tiles(cull_light(lights[i]));
        if r.x > r.z || r.y > r.w {
            light_rects[i] = vec2<u32>(1u, 0u);
        } else {
            light_rects[i] = vec2<u32>(u32(r.x) | (u32(r.y) << 16u), u32(r.z) | (u32(r.w) << 16u));
            n = (u32(r.z - r.x + 1) * u32(r.w - r.y + 1) + SCATTER_MASK_THREADS - 1u) / SCATTER_MASK_THREADS;
        }
    }
    if !blocks {
        return;
    }
    if index == 0u {
        atomicStore(&wg_blocks, 0u);
    }
    workgroupBarrier();
    var at = 0u;
    if n != 0u {
        at = atomicAdd(&wg_blocks, n);
    }
    workgroupBarrier();
    if index == 0u {
        let total = atomicLoad(&wg_blocks);
        if total != 0u {
            wg_block_at = atomicAdd(&cull_stats[6], total);
        }
    }
    workgroupBarrier();
    at += wg_block_at;
    for (var b = 0u; b < n; b++) {
        block_queue[2u * (at + b)] = i;
        block_queue[2u * (at + b) + 1u] = b;
    }
}

// A workgroup's lights (view space) and tile rectangles, for its words of the tile lines.
var<workgroup> wg_line_light: array<CullLight, 64 * DEPTH_TILES>;
var<workgroup> wg_line_rect: array<vec4<i32>, 64 * DEPTH_TILES>;
// And their depth bins (first, last), from their depth extents.
var<workgroup> wg_line_bins: array<vec2<i32>, 64 * DEPTH_TILES>;

// Light-row workgroup `group`: lights 64 DEPTH_TILES g .. (g + 1) 64 DEPTH_TILES (2 DEPTH_TILES
// words of the tile lines) and lines LINES_PER_GROUP c .. (c + 1) LINES_PER_GROUP, for g and c
// the quotient and remainder of `group` by the line chunks. Each thread takes one light into
// workgroup memory (view space, and its tile rectangle: none past the last light), and the
// first line chunk's also stores its depth extent (light_depth_extent) after the lines; then
// each thread takes one (line, word) pair, consecutive threads consecutive lines of a word. A
// pair's word has bit k set when light 32 word + k's rectangle spans the line (its columns for a
// column, its rows for a row) and the light is inside both of the line's planes (line_planes).
// A tile's candidates are then its column's bits and its row's: exactly the lights whose
// rectangle holds it and that pass its four side planes. Every word of every line below
// mask_words() is written, so the lines need no clear. Workgroup 0 also zeroes the list passes'
// cursor, cull_stats[5]. Called in uniform control flow.
fn store_light_lines(group: u32, index: u32) {
    let lines = cull.tiles_x + cull.tiles_y + ZBINS;
    let chunks = (lines + LINES_PER_GROUP - 1u) / LINES_PER_GROUP;
    let first = group / chunks * 64u * DEPTH_TILES;
    let chunk = group % chunks;
    // The list passes' cursor starts each run at zero (back-to-back runs clear nothing).
    if group == 0u && index == 0u {
        atomicStore(&cull_stats[5], 0u);
    }
    if first >= cull.light_count {
        return;
    }
    let words = mask_words();
    let i = first + index;
    var rect = vec4<i32>(0, 0, -1, -1);
    var bins = vec2<i32>(1, 0);
    if i < cull.light_count {
        let l = cull_light(lights[i]);
        rect = light_tiles(l);
        wg_line_light[index] = l;
        let e = light_depth_extent(l);
        // (A cone's narrowed extent may be empty, lo > hi: its bins are then those between, so
        // that every tile whose depth bounds extent_keeps passes shares a bin with it.)
        bins = vec2<i32>(i32(zbin(min(e.x, e.y))), i32(zbin(max(e.x, e.y))));
        if chunk == 0u {
            let at = lines * words + 8u * i;
            tile_lines[at] = bitcast<u32>(e.x);
            tile_lines[at + 1u] = bitcast<u32>(e.y);
            tile_lines[at + 2u] = bitcast<u32>(e.z);
            tile_lines[at + 3u] = bitcast<u32>(e.w);
            // And its sphere in view space, slack included, for the box test.
            tile_lines[at + 4u] = bitcast<u32>(l.center.x);
            tile_lines[at + 5u] = bitcast<u32>(l.center.y);
            tile_lines[at + 6u] = bitcast<u32>(l.center.z);
            tile_lines[at + 7u] = bitcast<u32>(l.radius + l.slack);
        }
    }
    wg_line_rect[index] = rect;
    wg_line_bins[index] = bins;
    workgroupBarrier();
    // Consecutive threads take consecutive lines of one word, so that a subgroup tests one
    // light at a time (one workgroup-memory address, and lines next to each other mostly agree
    // on whether the light's rectangle spans them).
    let line = chunk * LINES_PER_GROUP + index % LINES_PER_GROUP;
    let w = index / LINES_PER_GROUP;
    let word = first / 32u + w;
    if line >= lines || word >= words {
        return;
    }
    var bits = 0u;
    let side = cull.tiles_x + cull.tiles_y;
    if line >= side {
        // A depth bin: the lights whose bins hold it.
        let b = i32(line - side);
        for (var k = 0u; k < 32u; k++) {
            let r = wg_line_bins[w * 32u + k];
            if r.x <= b && b <= r.y {
                bits |= 1u << k;
            }
        }
        tile_lines[line * words + word] = bits;
        return;
    }
    let column = line < cull.tiles_x;
    let at = i32(select(line - cull.tiles_x, line, column));
    let planes = line_planes(line);
    for (var k = 0u; k < 32u; k++) {
        let s = w * 32u + k;
        let r = wg_line_rect[s];
        let span = select(r.yw, r.xz, column);
        if span.x <= at && at <= span.y {
            let l = wg_line_light[s];
            if !outside_plane(planes[0], l) && !outside_plane(planes[1], l) {
                bits |= 1u << k;
            }
        }
    }
    tile_lines[line * words + word] = bits;
}

@compute @workgroup_size(64 * DEPTH_TILES)
fn depth_bounds(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) index: u32) {
    lights_or_tiles(wg, groups, index, LIGHT_ROWS_RECTS);
}

@compute @workgroup_size(64 * DEPTH_TILES)
fn depth_bounds_blocks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) index: u32) {
    lights_or_tiles(wg, groups, index, LIGHT_ROWS_BLOCKS);
}

// cull.tile_lines: gather's lines path, light workgroups only (store_light_lines).
@compute @workgroup_size(64 * DEPTH_TILES)
fn tile_lines_pass(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) index: u32) {
    store_light_lines(wg.y * groups.x + wg.x, index);
}

// What the light rows store: rectangles, or rectangles and blocks.
const LIGHT_ROWS_RECTS: u32 = 0u;
const LIGHT_ROWS_BLOCKS: u32 = 1u;

// Workgroup wg's lights (the rows before the tiles', so that their longer chains start early)
// or tiles. Uniform (a workgroup's id), so the barriers are reached by all threads or none.
fn lights_or_tiles(wg: vec3<u32>, groups: vec3<u32>, index: u32, rows: u32) {
    let light_rows = groups.y - cull.tiles_y;
    let first = (wg.y * groups.x + wg.x) * 64u * DEPTH_TILES;
    if wg.y < light_rows {
        store_light_rect(first + index, index, rows == LIGHT_ROWS_BLOCKS);
    } else {
        _ = tile_bounds(vec3<u32>(wg.x, wg.y - light_rows, 0u), index, true, DEPTH_TILES, 64u);
    }
}
