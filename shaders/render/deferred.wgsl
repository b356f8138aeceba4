// shade.deferred: the lighting pass of the deferred backend, one thread per pixel. Reads the
// G-buffer, reconstructs the surface point, reads the pixel's list through lookup.wgsl and
// writes HDR radiance (alpha 1 where covered, 0 for background, as the reference does).
@group(2) @binding(0) var gb_normal_depth: texture_2d<f32>;
@group(2) @binding(1) var gb_material: texture_2d<u32>;
// The stored world position (deferred_stored_position; a 1 x 1 placeholder otherwise).
@group(2) @binding(3) var gb_position: texture_2d<f32>;

// An entry point for each form of lists (list_shading.wgsl): `zbin` is a constant of each.
@compute @workgroup_size(8, 8)
fn deferred_shade(@builtin(global_invocation_id) id: vec3<u32>) {
    shading_pixel = id.xy;
    shade_pixel(id.xy, false, false);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_stored(@builtin(global_invocation_id) id: vec3<u32>) {
    shading_pixel = id.xy;
    shade_pixel(id.xy, true, false);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_tiles(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    shading_pixel = id.xy;
    shade_tile_group(id.xy, wg.xy, li, false);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_stored_tiles(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    shading_pixel = id.xy;
    shade_tile_group(id.xy, wg.xy, li, true);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_clusters(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    shading_pixel = id.xy;
    shade_cluster_group(id.xy, wg.xy, li, false);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_stored_clusters(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    shading_pixel = id.xy;
    shade_cluster_group(id.xy, wg.xy, li, true);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_zbin(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    shading_pixel = id.xy;
    shade_zbin_group(id.xy, wg.xy, li, false);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_stored_zbin(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    shading_pixel = id.xy;
    shade_zbin_group(id.xy, wg.xy, li, true);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_zbin_rounds(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    shading_pixel = id.xy;
    shade_zbin_rounds_group(id.xy, wg.xy, li, false);
}

@compute @workgroup_size(8, 8)
fn deferred_shade_stored_zbin_rounds(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    shading_pixel = id.xy;
    shade_zbin_rounds_group(id.xy, wg.xy, li, true);
}

// A pixel's depth and G-buffer texels, loaded together: one memory round trip, not the depth's
// and then, behind its test, the G-buffer's. (The tile path reads no depth: a pixel is covered
// where its G-buffer's view-space z is not zero, the G-buffer's clear value, as every camera's
// near plane is at a positive distance.)
struct Texels {
    z: f32,
    g: vec4<f32>,
    material: u32,
}

// (`vec4<f32>(...).x` reads the depth buffer's f32 as it is, and the x of the R32Float texture
// that the visibility buffer's compute rasteriser writes in its place: crate::pipelines's
// float_depth.)
fn load_texels(pixel: vec2<u32>) -> Texels {
    let z = vec4<f32>(textureLoad(depth_tex, pixel, 0)).x;
    return Texels(z, load_normal_depth(pixel), textureLoad(gb_material, pixel, 0).x);
}

// The G-buffer's normal and view depth (none in a visibility buffer).
fn load_normal_depth(pixel: vec2<u32>) -> vec4<f32> {
    if VISIBILITY {
        return vec4<f32>(0.0);
    }
    return textureLoad(gb_normal_depth, pixel, 0);
}

// Whether texels loaded without the depth cover their pixel: a G-buffer's view-space z is not
// zero (its clear value, as every camera's near plane is at a positive distance), a visibility
// buffer's id not 0.
fn texels_cover(t: Texels) -> bool {
    if VISIBILITY {
        return t.material != 0u;
    }
    return t.g.w != 0.0;
}

// Texels of a pixel outside the view: not covered (by depth or by view-space z).
const NO_TEXELS = Texels(1.0, vec4<f32>(0.0), 0u);

fn surface(pixel: vec2<u32>, t: Texels, stored: bool) -> Surface {
    let g = t.g;
    let ndc = vec2<f32>((f32(pixel.x) + 0.5) * frame.viewport.z * 2.0 - 1.0, 1.0 - (f32(pixel.y) + 0.5) * frame.viewport.w * 2.0);
    if VISIBILITY {
        return visibility_surface(ndc, t.material - 1u);
    }
    let m = materials[t.material];
    var p = (frame.world_from_view * vec4<f32>(view_point(ndc, g.w), 1.0)).xyz;
    if stored {
        p = textureLoad(gb_position, pixel, 0).xyz;
    }
    return Surface(p, g.xyz, view_dir(p), m);
}

fn shade_pixel(pixel: vec2<u32>, stored: bool, zbin: bool) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(pixel >= size) {
        return;
    }
    let t = load_texels(pixel);
    let z = t.z;
    if z >= 1.0 {
        textureStore(out_color, pixel, vec4<f32>(0.0));
        return;
    }
    let s = surface(pixel, t, stored);
    var c: vec3<f32>;
    if zbin {
        c = shade_zbin(zbin_cell(pixel, z), s.p, s.n, s.v, s.m);
    } else {
        c = shade_list(light_list(pixel, z), s.p, s.n, s.v, s.m);
    }
    textureStore(out_color, pixel, vec4<f32>(c, 1.0));
}

// The lights a workgroup holds in workgroup memory at a time (shade_tile_group,
// shade_cluster_group): 32 lights of 64 bytes, 2 KB a workgroup (1 KB for point lights, below;
// the timings here are from before that). On an H100 culling and lighting took 7-11% longer
// with 64 (4 KB), 2-3% with 48, up to 1% with 24, 1-2% with 16 and 6% with 8
// (docs/bench/HISTORY.md, "The lighting pass against its floor").
const TILE_GROUP_LIGHTS: u32 = 32u;
// In a POINT_LIGHTS pipeline the tile path holds only what shade_point_light reads, 32 bytes a
// light (position and radius, colour and intensity) in wg_points, and wg_lights shrinks to one
// entry (arrays sized by the override): at the Forward+ configuration 152.8 -> 151.7 µs, the
// hall at 5,000 lights 226.6 -> 225.7; the clusters' path (shade_parts_list) likewise, at 1M
// lights in clusters of 32 px x 32 1.92 -> 1.84 ms (H100, docs/bench/HISTORY.md). Each loop
// writes the store and the load out, as measured: through functions (hold_light, held_light)
// the tile path took 0.6% longer at the Forward+ configuration and in the hall at 5,000 lights.
// The clusters' loader reads a light's fields, not the whole Light: 1M lights at 32 x 32 1.847
// -> 1.832 ms. The tile path takes POINT_BATCH lights a batch, one a thread, in the same 2 KB as
// 32 of 64 bytes: 151.8 -> 151.2 µs at the Forward+ configuration, the hall at 5,000 lights
// 226.0 -> 224.8 (16 px) and 219.9 -> 218.5 (24 px) (H100).
const POINT_BATCH: u32 = 64u;
var<workgroup> wg_lights: array<Light, select(TILE_GROUP_LIGHTS, 1u, POINT_LIGHTS)>;
var<workgroup> wg_points: array<array<vec4<f32>, 2>, select(1u, POINT_BATCH, POINT_LIGHTS)>;
// With BAND_POINTS, each slot's band beside it (band_slot); its r is in the slot's alpha
// (point_energy).
var<workgroup> wg_bands: array<u32, select(1u, POINT_BATCH, BAND_POINTS)>;

// A band light's slot in wg_bands: the bits of its inner distance, never negative, with the top
// bit set for a sampled band (LIGHT_FLAG_HARD_BAND).
const SLOT_HARD_BAND: u32 = 0x80000000u;
fn band_slot(light: Light) -> u32 {
    return light.interleave | select(0u, SLOT_HARD_BAND, (light.kind & LIGHT_FLAG_HARD_BAND) != 0u);
}

// The second half of a point light's slot in wg_points: colour and intensity; for stochastic
// point lights (STOCHASTIC_POINTS) and the hierarchy's (BAND_POINTS) colour times intensity, and
// alpha.
fn point_energy(color: vec3<f32>, intensity: f32, alpha: f32) -> vec4<f32> {
    return select(vec4<f32>(color, intensity), vec4<f32>(color * intensity, alpha), STOCHASTIC_POINTS || BAND_POINTS);
}

// The band of slot k of wg_points (BAND_POINTS; otherwise 0, unread).
fn slot_band(k: u32) -> u32 {
    if BAND_POINTS {
        return wg_bands[k];
    }
    return 0u;
}

// The point light of slot halves q (position, radius) and e (point_energy) of wg_points, with
// its band's bits (slot_band).
fn point_light(q: vec4<f32>, e: vec4<f32>, band: u32) -> Light {
    let premultiplied = STOCHASTIC_POINTS || BAND_POINTS;
    var light: Light;
    light.position = q.xyz;
    light.radius = q.w;
    light.color = e.xyz;
    light.intensity = select(e.w, 1.0, premultiplied);
    light.alpha = select(0.0, e.w, premultiplied);
    light.interleave = band & ~SLOT_HARD_BAND;
    let falloff = select(select(LIGHT_FALLOFF_WINDOWED, LIGHT_FALLOFF_STOCHASTIC, STOCHASTIC_POINTS), LIGHT_FALLOFF_BAND, BAND_POINTS);
    light.kind = LIGHT_KIND_POINT | falloff | select(0u, LIGHT_FLAG_HARD_BAND, (band & SLOT_HARD_BAND) != 0u);
    return light;
}

// A list a tile, in tiles of a multiple of 8 pixels (ListForm::Tiles: the tiled strategies, and
// clusters of one slice): a workgroup's 8 x 8 pixels lie in one tile and read one list, so its
// lights go through workgroup memory (shade_group_list). Coverage comes from the G-buffer
// (Texels): without the depth's load the Forward+ configuration took 0.5% less and the hall at
// 5,000 lights 1.3% (H100, docs/bench/HISTORY.md).
fn shade_tile_group(pixel: vec2<u32>, group: vec2<u32>, li: u32, stored: bool) {
    let inside = all(pixel < vec2<u32>(frame.viewport.xy));
    var t = NO_TEXELS;
    if inside {
        t = Texels(0.0, load_normal_depth(pixel), textureLoad(gb_material, pixel, 0).x);
    }
    let covered = texels_cover(t);
    // Every thread loads the tile's range (one address for the workgroup, so the loop's bounds
    // are the same in every thread), with no barrier: 154.2 -> 152.7 µs at the Forward+
    // configuration, 229.7 -> 226.6 in the hall at 5,000 lights (H100), where one thread stored
    // it in workgroup memory for a workgroupUniformLoad.
    let tile = group * 8u / cull.tile_size;
    let list = bin_ranges[tile.y * cull.tiles_x + tile.x];
    var s: Surface;
    var c = vec3<f32>(0.0);
    if covered {
        s = surface(pixel, t, stored);
        c = emitted(s.m);
    }
    c = shade_group_list(list, li, covered, s, c);
    if inside {
        textureStore(out_color, pixel, select(vec4<f32>(0.0), vec4<f32>(lights_checked(c), 1.0), covered));
    }
}

// Adds the lights of `list` (uniform) to `c` where the pixel `takes` them: the workgroup loads
// them into workgroup memory TILE_GROUP_LIGHTS (POINT_BATCH in a POINT_LIGHTS pipeline) at a
// time, each by one thread for all 64 pixels, and each pixel that takes them sums them in the
// list's order (the same sums as shade_list).
fn shade_group_list(list: vec2<u32>, li: u32, takes: bool, s: Surface, c_in: vec3<f32>) -> vec3<f32> {
    let infinite = (frame.flags & FRAME_FLAG_INFINITE_RANGE) != 0u;
    var c = c_in;
    let batch = select(TILE_GROUP_LIGHTS, POINT_BATCH, POINT_LIGHTS);
    for (var base = 0u; base < list.y; base += batch) {
        let n = min(batch, list.y - base);
        if li < n {
            let light = lights[light_indices[list.x + base + li]];
            if POINT_LIGHTS {
                wg_points[li] = array<vec4<f32>, 2>(vec4<f32>(light.position, light.radius), point_energy(light.color, light.intensity, light.alpha));
                if BAND_POINTS {
                    wg_bands[li] = band_slot(light);
                }
            } else {
                wg_lights[li] = light;
            }
        }
        workgroupBarrier();
        if takes {
            lights_walked += n;
            var k = 0u;
            if POINT_LIGHTS {
                // Four lights at a time: their positions and radii loaded and their rejects
                // decided together (a vec4 of distances, a vec4 of verdicts), then each kept one
                // shaded in the list's order, so the sums are shade_list's. Beside the loop of
                // one light at a time (H100): the Forward+ configuration 150.7 -> 144.6 µs, the
                // hall at 5,000 lights 223.7 -> 213.1 (16 px) and 217.5 -> 205.2 (24 px). Four
                // lights each with its own reject test gained a third of that, eight lost 4%
                // (docs/bench/HISTORY.md).
                for (; k + 3u < n; k += 4u) {
                    let q = array<vec4<f32>, 4>(wg_points[k][0], wg_points[k + 1u][0], wg_points[k + 2u][0], wg_points[k + 3u][0]);
                    let t0 = q[0].xyz - s.p;
                    let t1 = q[1].xyz - s.p;
                    let t2 = q[2].xyz - s.p;
                    let t3 = q[3].xyz - s.p;
                    let d = vec4<f32>(length(t0), length(t1), length(t2), length(t3));
                    let keep = vec4<bool>(infinite) | !(d >= vec4<f32>(q[0].w, q[1].w, q[2].w, q[3].w));
                    if keep.x {
                        c += shade_listed(point_light(q[0], wg_points[k][1], slot_band(k)), s.p, t0, d.x, s.n, s.v, s.m);
                    }
                    if keep.y {
                        c += shade_listed(point_light(q[1], wg_points[k + 1u][1], slot_band(k + 1u)), s.p, t1, d.y, s.n, s.v, s.m);
                    }
                    if keep.z {
                        c += shade_listed(point_light(q[2], wg_points[k + 2u][1], slot_band(k + 2u)), s.p, t2, d.z, s.n, s.v, s.m);
                    }
                    if keep.w {
                        c += shade_listed(point_light(q[3], wg_points[k + 3u][1], slot_band(k + 3u)), s.p, t3, d.w, s.n, s.v, s.m);
                    }
                }
            }
            for (; k < n; k++) {
                var light: Light;
                if POINT_LIGHTS {
                    let q = wg_points[k];
                    light = point_light(q[0], q[1], slot_band(k));
                } else {
                    light = wg_lights[k];
                }
                let to_light = light.position - s.p;
                let d = length(to_light);
                if !infinite && d >= light.radius {
                    continue;
                }
                c += shade_listed(light, s.p, to_light, d, s.n, s.v, s.m);
            }
        }
        workgroupBarrier();
    }
    return c;
}

// The workgroup's 8 x 8 pixels in GROUP_PARTS parts of whole rows (part h: pixels
// h * GROUP_PART .. of the workgroup), each with the box of its covered pixels' surface points,
// words 6 h .. 6 h + 5: the least x, y, z as ~ordered_bits, the greatest as ordered_bits,
// widened from zero (workgroup memory starts at zero; a part without covered pixels keeps
// zeros). One part, the whole workgroup: culling and lighting at 1M lights in clusters of
// 24 px x 32 took 1.97-1.98 ms on an H100 with one, 2.02 with two (rows 0-3 and 4-7), 2.14 with
// four, and 2.11 without the boxes (docs/bench/HISTORY.md). With more than one part, box
// WHOLE_BOX (after the parts') holds every covered pixel, and a light that misses it is not
// tested against the parts (those timings are from before it).
const GROUP_PARTS: u32 = 1u;
const GROUP_PART: u32 = 64u / GROUP_PARTS;
const WHOLE_BOX: u32 = select(0u, GROUP_PARTS, GROUP_PARTS > 1u);
const PART_BOXES: u32 = WHOLE_BOX + 1u;
var<workgroup> wg_part_box: array<atomic<u32>, 6u * PART_BOXES>;
// The lights of a batch of shade_parts_list that may reach a pixel of each part: bit k % 32 of
// word 2 (GROUP_PARTS p + h) + k / 32 for part h, p the batch's parity (two sets, so that one is
// cleared while the other is read, with no barrier of its own). Two words a part: a
// POINT_LIGHTS pipeline takes POINT_BATCH (64) lights a batch here too, 1M lights at 32 x 32
// 1.832 -> 1.805 ms, at 24 x 32 1.896 -> 1.880 (H100).
var<workgroup> wg_part_keep: array<atomic<u32>, 4u * GROUP_PARTS>;

fn widen_part_box(li: u32, p: vec3<f32>) {
    widen_box(li / GROUP_PART, p);
    if GROUP_PARTS > 1u {
        widen_box(WHOLE_BOX, p);
    }
}

fn widen_box(h: u32, p: vec3<f32>) {
    let at = 6u * h;
    atomicMax(&wg_part_box[at], ~ordered_bits(p.x));
    atomicMax(&wg_part_box[at + 1u], ~ordered_bits(p.y));
    atomicMax(&wg_part_box[at + 2u], ~ordered_bits(p.z));
    atomicMax(&wg_part_box[at + 3u], ordered_bits(p.x));
    atomicMax(&wg_part_box[at + 4u], ordered_bits(p.y));
    atomicMax(&wg_part_box[at + 5u], ordered_bits(p.z));
}

// Whether `light`'s sphere may hold a covered pixel of part h: the squared distance from its
// centre to the part's box against its squared radius, with a relative margin of 1e-4. Each
// component of a point in the box is at least as far from the centre as the box's nearest
// point's, and rounding keeps that order, so a pixel the loop would shade (length(to_light) <
// radius) is never dropped: the same sums.
fn part_box_holds(h: u32, position: vec3<f32>, radius: f32) -> bool {
    let at = 6u * h;
    let far = atomicLoad(&wg_part_box[at + 3u]);
    if far == 0u {
        return false;
    }
    let lo = vec3<f32>(from_ordered_bits(~atomicLoad(&wg_part_box[at])), from_ordered_bits(~atomicLoad(&wg_part_box[at + 1u])), from_ordered_bits(~atomicLoad(&wg_part_box[at + 2u])));
    let hi = vec3<f32>(from_ordered_bits(far), from_ordered_bits(atomicLoad(&wg_part_box[at + 4u])), from_ordered_bits(atomicLoad(&wg_part_box[at + 5u])));
    let q = position - clamp(position, lo, hi);
    return dot(q, q) <= radius * radius * 1.0001;
}

// shade_group_list for the clusters' lists (shade_cluster_group): the loading thread also
// tests its light against each part's box of pixels (widen_part_box, before a barrier ahead of
// this call), and a pixel walks only the lights that may reach its part, in the list's order (a
// light out of reach adds nothing where it is skipped: the same sums). A cluster's list holds
// the lights that meet its tile's frustum between its pixels' depths; an 8 x 8 block's pixels
// are a ninth of a 24-pixel tile's, and at 1M lights most of the list misses them. `parity`
// carries the batches' parity from call to call in one workgroup. (On the tiles' lists, at the
// Forward+ configuration in 8-pixel tiles and the hall at 5,000 lights in 16, the same test with
// two parts cost 11% more: H100, docs/bench/HISTORY.md.)
fn shade_parts_list(list: vec2<u32>, li: u32, takes: bool, s: Surface, c_in: vec3<f32>, parity: ptr<function, u32>) -> vec3<f32> {
    let infinite = (frame.flags & FRAME_FLAG_INFINITE_RANGE) != 0u;
    var c = c_in;
    let h = li / GROUP_PART;
    let batch = select(TILE_GROUP_LIGHTS, POINT_BATCH, POINT_LIGHTS);
    for (var base = 0u; base < list.y; base += batch) {
        let n = min(batch, list.y - base);
        let p = *parity;
        if li < n {
            let i = light_indices[list.x + base + li];
            if POINT_LIGHTS {
                wg_points[li] = array<vec4<f32>, 2>(vec4<f32>(lights[i].position, lights[i].radius), point_energy(lights[i].color, lights[i].intensity, lights[i].alpha));
                if BAND_POINTS {
                    wg_bands[li] = band_slot(lights[i]);
                }
            } else {
                wg_lights[li] = lights[i];
            }
            let whole = GROUP_PARTS == 1u || infinite || part_box_holds(WHOLE_BOX, lights[i].position, lights[i].radius);
            for (var part = 0u; whole && part < GROUP_PARTS; part++) {
                if infinite || part_box_holds(part, lights[i].position, lights[i].radius) {
                    atomicOr(&wg_part_keep[2u * (GROUP_PARTS * p + part) + li / 32u], 1u << (li % 32u));
                }
            }
        }
        workgroupBarrier();
        let keeps = vec2<u32>(atomicLoad(&wg_part_keep[2u * (GROUP_PARTS * p + h)]), atomicLoad(&wg_part_keep[2u * (GROUP_PARTS * p + h) + 1u]));
        // The other parity's words, read in the batch before, cleared for the next.
        if li < 2u * GROUP_PARTS {
            atomicStore(&wg_part_keep[2u * GROUP_PARTS * (1u - p) + li], 0u);
        }
        *parity = 1u - p;
        if takes {
            lights_walked += countOneBits(keeps.x) + countOneBits(keeps.y);
        }
        // The loop's body is shade_group_list's, written again: as a function adding to `c`
        // through a pointer, the Forward+ configuration took 2.3% longer and the hall at 5,000
        // lights 2.6% (H100, docs/bench/HISTORY.md).
        for (var w = 0u; takes && w < 2u; w++) {
            var keep = keeps[w];
            while keep != 0u {
                let k = 32u * w + firstTrailingBit(keep);
                keep &= keep - 1u;
                var light: Light;
                if POINT_LIGHTS {
                    let q = wg_points[k];
                    light = point_light(q[0], q[1], slot_band(k));
                } else {
                    light = wg_lights[k];
                }
                let to_light = light.position - s.p;
                let d = length(to_light);
                if !infinite && d >= light.radius {
                    continue;
                }
                c += shade_listed(light, s.p, to_light, d, s.n, s.v, s.m);
            }
        }
        workgroupBarrier();
    }
    return c;
}

// Where a workgroup's covered pixels lie in more than one slice, each slice's list is tested
// against the box of that slice's pixels alone (slice_box), not the whole workgroup's: a pixel
// walks only its own slice's list, and the whole box of a block across a depth edge or along
// a slanted floor reaches lights that none of the slice's pixels can.
const SLICE_BOXES: bool = true;

// The part boxes (and, with several parts, the whole box) made again of the pixels that
// `take` the next slice's list. Every thread has passed the barrier that ends the last batch of the slice before (or,
// where that list was empty, the barrier after the box it did not read), so that no test of
// the old box is left when it is cleared.
fn slice_box(li: u32, takes: bool, p: vec3<f32>) {
    if li < 6u * PART_BOXES {
        atomicStore(&wg_part_box[li], 0u);
    }
    workgroupBarrier();
    if takes {
        widen_part_box(li, p);
    }
    workgroupBarrier();
}

// The slices a workgroup's covered pixels lie in, a bit a slice (shade_cluster_group).
var<workgroup> wg_slice_bits: array<atomic<u32>, CLUSTER_GROUP_SLICES / 32u>;
var<workgroup> wg_slice_bits_plain: array<u32, CLUSTER_GROUP_SLICES / 32u>;

// A list a cluster, in tiles of a multiple of 8 pixels and with many lights (ListForm::Clusters):
// a workgroup's 8 x 8 pixels lie in one tile and read the lists of the slices they lie in. The
// workgroup takes those slices in turn, each list's lights through workgroup memory
// (shade_group_list), and each pixel sums the lights of its own slice's list, in its order (the
// same sums as shade_list). A warp whose pixels lie in several slices walks each slice's list,
// where the loop a pixel walks them side by side; but the loop a pixel loads each index and then
// its light, one after the other, which at 50,000 lights and more cost more (H100: the hall at
// 50,000 lights 2.90 -> 2.44 ms; 1M lights, 32 px x 32 slices, 3.70 -> 3.31 ms), and at 500 and
// 3,072 lights less (109 against 216 µs; 268 against 277 µs): ListForm::of's rule. Walking the
// lists side by side through workgroup memory, or choosing a path a workgroup by its lists'
// lengths, was slower at every count (docs/bench/HISTORY.md).
fn shade_cluster_group(pixel: vec2<u32>, group: vec2<u32>, li: u32, stored: bool) {
    if li < CLUSTER_GROUP_SLICES / 32u {
        atomicStore(&wg_slice_bits[li], 0u);
    }
    workgroupBarrier();
    let inside = all(pixel < vec2<u32>(frame.viewport.xy));
    var t = NO_TEXELS;
    if inside {
        t = load_texels(pixel);
    }
    let z = t.z;
    let covered = z < 1.0;
    var slice = 0u;
    var s: Surface;
    var c = vec3<f32>(0.0);
    if covered {
        slice = depth_slice(linear_depth(z));
        atomicOr(&wg_slice_bits[slice / 32u], 1u << (slice % 32u));
        s = surface(pixel, t, stored);
        c = emitted(s.m);
        widen_part_box(li, s.p);
    }
    workgroupBarrier();
    if li < CLUSTER_GROUP_SLICES / 32u {
        wg_slice_bits_plain[li] = atomicLoad(&wg_slice_bits[li]);
    }
    let slices = workgroupUniformLoad(&wg_slice_bits_plain);
    var parity = 0u;
    let tile = group * 8u / cull.tile_size;
    let bin = tile.y * cull.tiles_x + tile.x;
    var in_slices = 0u;
    for (var w = 0u; w < CLUSTER_GROUP_SLICES / 32u; w++) {
        in_slices += countOneBits(slices[w]);
    }
    for (var w = 0u; w < CLUSTER_GROUP_SLICES / 32u; w++) {
        var bits = slices[w];
        while bits != 0u {
            let k = w * 32u + firstTrailingBit(bits);
            bits &= bits - 1u;
            if SLICE_BOXES && in_slices > 1u {
                slice_box(li, covered && slice == k, s.p);
            }
            let list = bin_ranges[k * cull.tiles_x * cull.tiles_y + bin];
            c = shade_parts_list(list, li, covered && slice == k, s, c, &parity);
        }
    }
    if inside {
        textureStore(out_color, pixel, select(vec4<f32>(0.0), vec4<f32>(lights_checked(c), 1.0), covered));
    }
}

