// The tiles' depth data (Harada 2012, GPU Pro 4 section 5.6.1), shared by cull.depth_bounds
// (depth_bounds.wgsl) and gather's lines path, whose list passes compute their own tiles'
// (tile_lines.wgsl): the nearest and farthest covered pixel (linear view depth), the covered
// pixels, and the 2.5D geometry mask (32 cells over [dmin, dmax]). Background pixels (depth
// 1.0, the clear value) are not covered and need no lights, so they do not widen the bounds.
// With MSAA every sample counts (DEPTH_SAMPLES a pixel; `covered` then counts samples), and
// the mask holds every cell between a pixel's samples.
// The module composes depth_input.wgsl (depth_span) and declares tile_depth (binding 2).

var<workgroup> wg_tile_zmin: array<atomic<u32>, TILE_SLOTS>;
var<workgroup> wg_tile_zmax: array<atomic<u32>, TILE_SLOTS>;
var<workgroup> wg_tile_mask: array<atomic<u32>, TILE_SLOTS>;
var<workgroup> wg_tile_covered: array<atomic<u32>, TILE_SLOTS>;

// The depth data of workgroup wg's tiles, `tiles` tiles of row wg.y a workgroup (at most
// TILE_SLOTS), `threads` threads a tile (thread `index`'s tile is the index / threads-th):
// stored in tile_depth and returned to every thread of the tile; with `with_mask` false, the
// 2.5D mask is left 0 (one look at the pixels, not two). Each thread reduces its own pixels,
// then reduce_tile_depth the tile's threads.
// Called in uniform control flow.
fn tile_bounds(wg: vec3<u32>, index: u32, with_mask: bool, tiles: u32, threads: u32) -> TileDepth {
    let j = index / threads;
    let li = index % threads;
    let tile = vec2<u32>(wg.x * tiles + j, wg.y);
    if li == 0u && with_mask {
        atomicStore(&wg_tile_mask[j], 0u);
    }
    let size = vec2<u32>(frame.viewport.xy);
    let origin = tile * cull.tile_size;
    // A tile past the last column (in the last workgroup of a row) has no pixels here.
    let n = select(0u, cull.tile_size * cull.tile_size, tile.x < cull.tiles_x);
    // Depth in [0, 1) is a non-negative float: its bits order like its value.
    var own = vec3<u32>(0x7f800000u, 0u, 0u);
    for (var i = li; i < n; i += threads) {
        let p = origin + vec2<u32>(i % cull.tile_size, i / cull.tile_size);
        if all(p < size) {
            let z = depth_span(p);
            if z.covered > 0u {
                own = vec3<u32>(
                    min(own.x, bitcast<u32>(z.near)),
                    max(own.y, bitcast<u32>(z.far)),
                    own.z + z.covered,
                );
            }
        }
    }
    let r = reduce_tile_depth(j, li, own);
    var t: TileDepth;
    t.covered = r.z;
    if r.z > 0u {
        t.dmin = linear_depth(bitcast<f32>(r.x));
        t.dmax = linear_depth(bitcast<f32>(r.y));
    }
    if with_mask {
        if r.z > 0u {
            let scale = depth_cell_scale(t);
            var cells = 0u;
            for (var i = li; i < n; i += threads) {
                let p = origin + vec2<u32>(i % cull.tile_size, i / cull.tile_size);
                if all(p < size) {
                    // Every cell from the pixel's nearest covered sample to its farthest: with
                    // MSAA a fragment is looked up at its centroid, whose depth lies between
                    // its samples' (one sample: the cell of its depth).
                    let z = depth_span(p);
                    if z.covered > 0u {
                        let c0 = depth_cell(linear_depth(z.near), t.dmin, scale);
                        if DEPTH_SAMPLES == 1u {
                            cells |= 1u << c0;
                        } else {
                            cells |= bit_range(c0, depth_cell(linear_depth(z.far), t.dmin, scale));
                        }
                    }
                }
            }
            if cells != 0u {
                atomicOr(&wg_tile_mask[j], cells);
            }
        }
        workgroupBarrier();
        t.mask = atomicLoad(&wg_tile_mask[j]);
    }
    if li == 0u && tile.x < cull.tiles_x {
        tile_depth[tile.y * cull.tiles_x + tile.x] = t;
    }
    return t;
}

// (min depth bits, max depth bits, covered pixels) over the threads of tile j (thread li of
// it holding `own`), through workgroup atomics (subgroup min, max and add measured slower on
// an H100). Two barriers; called in uniform control flow.
fn reduce_tile_depth(j: u32, li: u32, own: vec3<u32>) -> vec3<u32> {
    if li == 0u {
        atomicStore(&wg_tile_zmin[j], 0x7f800000u);
        atomicStore(&wg_tile_zmax[j], 0u);
        atomicStore(&wg_tile_covered[j], 0u);
    }
    workgroupBarrier();
    if own.z != 0u {
        atomicMin(&wg_tile_zmin[j], own.x);
        atomicMax(&wg_tile_zmax[j], own.y);
        atomicAdd(&wg_tile_covered[j], own.z);
    }
    workgroupBarrier();
    return vec3<u32>(atomicLoad(&wg_tile_zmin[j]), atomicLoad(&wg_tile_zmax[j]), atomicLoad(&wg_tile_covered[j]));
}
