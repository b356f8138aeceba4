// The lighting grid hierarchy built on the GPU every frame: the WGSL twin of
// manylights_scene::hierarchy::Hierarchy::build_fixed (see its module docs for the levels and
// bands; that module is the oracle of this pass). Host side: manylights_gpu::hierarchy.
//
// One dispatch a level, in order:
// - `points` (mode 0): a thread a source light (from step.o.x on: a build that keeps the
//   sums of the lights that never move splats only the others each frame). A point light is written to the shaded lights
//   as level 0's light (colour x intensity, its band); a spot as it is, with level 0's band. A
//   point light is binned into its cell of level 1's grid (`bin`), or, where the cell's nodes
//   leave the grid's box or the cells' table is full, spread into level 1's grid at once
//   (`splat`); a spot is spread at once into its direction bin's nodes (the point lights'
//   without bins), its power scaled to the bin's cone (a point light's)
//   (manylights_scene::hierarchy::spots).
// - `cells_room`, `fill`, `cell_splat` (after each pass that bins, with its step; the cells'
//   buffer cleared before it): each binned cell takes its lights' room in a list, its lights
//   write themselves there, and a thread a cell's corner spreads the cell's lights into that
//   node, its six sums added up in registers (Term) and added to the node's slot once: the same
//   integers as a splat a light (integer sums do not hang on their order), with a cell's
//   lights' atomics on a node's words made one. At a million lights a cell of level 1 holds
//   about 3 point lights; a cell of a coarser level holds up to 8 nodes of the level below.
// - `finalize` (mode 1): a thread a slot of level l's hash table. A node's sums become its
//   light (power, power-weighted position), written to the shaded lights with level l's band;
//   an empty slot becomes a dead light (no power, radius 0, at `far`). It is binned into its
//   cell of level l + 1's grid (as the points pass bins) unless l is the last level; a spot
//   aggregate (a node of a direction bin: a spot of the bin's cone) is spread at once.
// A grid's nodes are keyed by their index in the level's box of nodes plus the box's size
// times their direction bin (0: the point lights'), plus 1 (0 is an empty slot), in an
// open-addressing hash table of 16 words a slot: the key, then six 64-bit fixed
// point sums (so that they do not hang on the order of the additions): power r, g, b, and the
// power-weighted offset of the position from the node in units of the spacing, x, y, z, all
// scaled by `scale` (2^52 over the lights' total power: the sums fit 63 bits, and each term
// keeps an f32's 24 bits). How a slot holds them is the file before this one's:
// hierarchy_sums32.wgsl (two 32-bit atomics a sum) or hierarchy_sums64.wgsl (one 64-bit
// atomic, SHADER_INT64_ATOMIC_ALL_OPS): `slot_claim`, `slot_key`, `Term`
// (`term_of`, `term_of_signed`, `term_add`), `sum_add_term`, `sum_read`, `sum_read_signed`. The counters count splats dropped: a node
// outside its level's box, a table full.

struct Step {
    // mode (0 points, 1 finalize), items (source lights or slots), threads a dispatch row,
    // spread into the next level (0 no, the last level; 1 each item at once, splat; 2 binned
    // into cells first, bin)
    a: vec4<u32>,
    // first slot read (finalize), first shaded light written (finalize), first slot of the
    // next level, the next level's slot count
    b: vec4<u32>,
    // this level's band r (inf: it never falls), its band's inner distance, reach, scale
    c: vec4<f32>,
    // the next level's grid: its box's first node (xyz), spacing (w, as bits)
    d: vec4<i32>,
    // the next level's box of nodes: its size (xyz)
    e: vec4<u32>,
    // this level's grid (finalize): its box's first node (xyz), spacing (w, as bits)
    g: vec4<i32>,
    // this level's box of nodes (xyz)
    h: vec4<u32>,
    // where dead lights sit (xyz); w: infinity (a spot's band never falls)
    far: vec4<f32>,
    // the frame's seed, 1 where this level's bands are sampled (band_xi, sampled_light), the
    // level (node_draw), the bands' ramp (bits; manylights_scene::hierarchy::Band::ramp)
    s: vec4<u32>,
    // the points pass: its first source light (item k is source light o.x + k), the source
    // lights in all (where target_index's direction bins start)
    o: vec4<u32>,
}

@group(0) @binding(0) var<uniform> step: Step;
@group(0) @binding(1) var<storage, read> source: array<Light>;
// The shaded light each source light becomes (points pass), then each source light's direction
// bin (0: a point light; b: spot_bins[b - 1]).
@group(0) @binding(2) var<storage, read> target_index: array<u32>;
@group(0) @binding(3) var<storage, read_write> shaded: array<Light>;
// [nodes outside their level's box, splats into a full table]
@group(0) @binding(5) var<storage, read_write> dropped: array<atomic<u32>, 2>;
// The cells of the next level's grid that this pass's items are binned into (cell_word): word 0
// the lists' total, then for each of step.b.w slots of an open-addressing table its key (the
// cell's lowest node's, as slot_of keys nodes), its items, its list's offset and its fill
// cursor; then each item's cell slot (NO_CELL: spread at once, or no light), then the lists of
// item indices.
@group(0) @binding(6) var<storage, read_write> cells: array<atomic<u32>>;

// A direction bin's cone (manylights_scene::hierarchy::SpotBin, as a light holds it): its axis
// and the cosines of its inner and outer angles, and its flux (spot_flux).
struct SpotBin {
    axis: vec3<f32>,
    cos_inner: f32,
    cos_outer: f32,
    flux: f32,
    pad: vec2<f32>,
}
@group(0) @binding(7) var<storage, read> spot_bins: array<SpotBin>;

// A point light's flux (manylights_scene::hierarchy::spots::POINT_FLUX).
const POINT_FLUX: f32 = 2.0;

// The integral over the cosine in [-1, 1] of the cone of cosines (ci, co) (light_spot's):
// manylights_scene::hierarchy::spots::spot_flux.
fn spot_flux(ci: f32, co: f32) -> f32 {
    let w = max(ci - co, 1e-4);
    let t = max(min(1.0 - co, w), 0.0);
    return t * t * t / (3.0 * w * w) + max(1.0 - co - w, 0.0);
}

const NO_CELL: u32 = 0xffffffffu;

// The most slots cell_of probes before a light is spread at once instead (nothing is lost).
const MAX_PROBES: u32 = 256u;

// Probes of slot_of that step 1, 2, 3, ... slots on (triangular probing) before it steps one
// slot at a time: a grid's keys come in runs, and one slot at a time from the first let some
// boxes' tables grow runs of tens of slots (crates/gpu/examples/hash_probes.rs).
const TRIANGULAR_PROBES: u32 = 64u;

// The slot of `key` in the next level's table (inserting it), or none where every slot holds
// another key: after its triangular probes it probes the whole table one slot at a time, so a
// table with room always takes a node (the plan sizes each with a quarter more slots than its
// level's nodes).
fn slot_of(key: u32) -> i32 {
    let count = step.b.w;
    var probe = (key * 2654435769u) ^ (key >> 15u);
    probe = probe % count;
    var tries = 0u;
    loop {
        if tries >= count + TRIANGULAR_PROBES {
            return -1;
        }
        let at = step.b.z + probe;
        let old = slot_claim(at, key);
        if old == 0u || old == key {
            return i32(at);
        }
        tries += 1u;
        probe = (probe + select(1u, tries, tries < TRIANGULAR_PROBES)) % count;
    }
    return -1;
}

// Corner `corner` (0..7) of a cell as an offset of 0 or 1 along each axis.
fn corner_bits(corner: u32) -> vec3<u32> {
    return vec3<u32>(corner & 1u, (corner >> 1u) & 1u, (corner >> 2u) & 1u);
}

// The trilinear weight of corner `bit` for a light at fraction `f` of its cell: splat's and
// cell_splat's, so that both add the same terms.
fn corner_weight(f: vec3<f32>, bit: vec3<u32>) -> f32 {
    let t = select(1.0 - f, f, bit == vec3<u32>(1u));
    return t.x * t.y * t.z;
}

// Spreads a light's power over the 8 nodes of its cell of the next level's grid, in direction
// bin `bin` (0: the point lights').
fn splat(position: vec3<f32>, power: vec3<f32>, bin: u32) {
    let spacing = bitcast<f32>(step.d.w);
    let u = position / spacing;
    let base = floor(u);
    let f = u - base;
    let origin = step.d.xyz;
    let dims = step.e.xyz;
    for (var corner = 0u; corner < 8u; corner++) {
        let bit = corner_bits(corner);
        let w = corner_weight(f, bit);
        if w == 0.0 {
            continue;
        }
        let node = vec3<i32>(base) + vec3<i32>(bit);
        let rel = node - origin;
        if any(rel < vec3<i32>(0)) || any(vec3<u32>(rel) >= dims) {
            atomicAdd(&dropped[0], 1u);
            continue;
        }
        let r = vec3<u32>(rel);
        let key = (r.z * dims.y + r.y) * dims.x + r.x + bin * dims.x * dims.y * dims.z + 1u;
        let at = slot_of(key);
        if at < 0 {
            atomicAdd(&dropped[1], 1u);
            continue;
        }
        let c = w * power * step.c.w;
        let cs = c.r + c.g + c.b;
        let o = u - vec3<f32>(node);
        let at_u = u32(at);
        sum_add_term(at_u, 0u, term_of(c.r));
        sum_add_term(at_u, 1u, term_of(c.g));
        sum_add_term(at_u, 2u, term_of(c.b));
        sum_add_term(at_u, 3u, term_of_signed(cs * o.x));
        sum_add_term(at_u, 4u, term_of_signed(cs * o.y));
        sum_add_term(at_u, 5u, term_of_signed(cs * o.z));
    }
}

// Word k (0 key, 1 lights, 2 offset, 3 cursor) of cell slot c.
fn cell_word(c: u32, k: u32) -> u32 {
    return 4u + 4u * c + k;
}

// Where item i's cell slot is.
fn light_cell(i: u32) -> u32 {
    return 4u + 4u * step.b.w + i;
}

// Entry j of the cells' lists.
fn cell_list(j: u32) -> u32 {
    return 4u + 4u * step.b.w + step.a.y + j;
}

// The slot of cell `key` in the cells' table (inserting it), or NO_CELL where it is full.
fn cell_of(key: u32) -> u32 {
    let count = step.b.w;
    var probe = ((key * 2654435769u) ^ (key >> 15u)) % count;
    for (var tries = 0u; tries < min(count, MAX_PROBES); tries++) {
        let at = cell_word(probe, 0u);
        let r = atomicCompareExchangeWeak(&cells[at], 0u, key);
        if r.exchanged || r.old_value == key {
            return probe;
        }
        // A weak exchange that failed on an empty slot is tried again.
        if r.old_value != 0u {
            probe = (probe + 1u) % count;
        }
    }
    return NO_CELL;
}

// Item i is binned into no cell (a spot, a dead slot), where this pass bins (the cells' buffer
// holds this pass's items only then).
fn no_cell(i: u32) {
    if step.a.w == 2u {
        atomicStore(&cells[light_cell(i)], NO_CELL);
    }
}

// Bins item i (a source point light, or a level's light) at `position` of power `power` into
// its cell of the next level's grid (cell_splat spreads it); a light whose cell's nodes are not
// all in the grid's box, or whose cell finds no room, is spread at once (splat).
fn bin(i: u32, position: vec3<f32>, power: vec3<f32>) {
    let spacing = bitcast<f32>(step.d.w);
    let rel = vec3<i32>(floor(position / spacing)) - step.d.xyz;
    var c = NO_CELL;
    if all(rel >= vec3<i32>(0)) && all(vec3<u32>(rel) + 1u < step.e.xyz) {
        let r = vec3<u32>(rel);
        c = cell_of((r.z * step.e.y + r.y) * step.e.x + r.x + 1u);
    }
    atomicStore(&cells[light_cell(i)], c);
    if c == NO_CELL {
        splat(position, power, 0u);
        return;
    }
    atomicAdd(&cells[cell_word(c, 1u)], 1u);
}

// Item i of direction bin `b` spreads into the next level as the step says (step.a.w): a
// point light's binned, at once, or not; a spot's at once, or not.
fn spread(i: u32, position: vec3<f32>, power: vec3<f32>, b: u32) {
    if b > 0u {
        no_cell(i);
        if step.a.w > 0u {
            splat(position, power, b);
        }
    } else if step.a.w == 2u {
        bin(i, position, power);
    } else if step.a.w == 1u {
        splat(position, power, 0u);
    }
}

// Light l shaped as a spot of direction bin b's cone (b > 0), or as it is.
fn with_cone(l_in: Light, b: u32) -> Light {
    var l = l_in;
    if b > 0u {
        let cone = spot_bins[b - 1u];
        l.kind = LIGHT_KIND_SPOT | LIGHT_FALLOFF_BAND;
        l.direction = cone.axis;
        l.cos_inner = cone.cos_inner;
        l.cos_outer = cone.cos_outer;
    }
    return l;
}

// A point light of a level: `power` at `position`, shaded with the level's band.
fn level_light(position: vec3<f32>, power: vec3<f32>) -> Light {
    var l: Light;
    l.position = position;
    l.radius = min(bitcast<f32>(step.s.w) * step.c.x, step.c.z);
    l.color = power;
    l.intensity = 1.0;
    l.direction = vec3<f32>(0.0);
    l.kind = LIGHT_KIND_POINT | LIGHT_FALLOFF_BAND;
    l.cos_inner = 1.0;
    l.cos_outer = -1.0;
    l.alpha = step.c.x;
    l.interleave = bitcast<u32>(step.c.y);
    return l;
}

// The draw in (0, 1) of the light whose draw is `id` this frame
// (manylights_scene::hierarchy::band_xi): a point light's id is its shaded index, an
// aggregate's its node's (node_draw), so a frame's draws do not hang on the order in which the
// build's threads took the hash table's slots.
fn band_xi(id: u32) -> f32 {
    return stochastic_unit(pcg(id ^ pcg(step.s.x)));
}

// The draw id of level step.s.z's node of key `key` (manylights_scene::hierarchy::node_draw).
fn node_draw(key: u32) -> u32 {
    return pcg(key ^ pcg(step.s.z));
}

// A level's light of draw id `id` (band_xi): with its band sampled where the level's are
// (manylights_scene::hierarchy::Band::sampled: weight 1 between inner (1 + (c - 1) xi) and
// r (c - (c - 1) xi) for ramps of c, the reach cut to match).
fn sampled_light(l_in: Light, id: u32) -> Light {
    var l = l_in;
    if step.s.y == 1u {
        let c = bitcast<f32>(step.s.w);
        let t = (c - 1.0) * band_xi(id);
        let r = l.alpha;
        // The last level's r is infinite, and so is its end.
        let to = r * (c - t);
        l.radius = min(to, step.c.z);
        l.alpha = to;
        l.interleave = bitcast<u32>(step.c.y * (1.0 + t));
        l.kind |= LIGHT_FLAG_HARD_BAND;
    }
    return l;
}

fn item(id: vec3<u32>) -> u32 {
    return id.y * step.a.z + id.x;
}

@compute @workgroup_size(256)
fn points(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = item(id);
    if k >= step.a.y {
        return;
    }
    let i = step.o.x + k;
    let l = source[i];
    let power = l.color * l.intensity;
    let t = target_index[i];
    var s = level_light(l.position, power);
    let b = target_index[step.o.y + i];
    if light_shape(l) == LIGHT_KIND_SPOT {
        // A spot as it is, with level 0's band; spread at once into its bin's nodes (the point
        // lights' where b is 0) with the power that the bin's cone (a point light's) emits as
        // much with.
        let level = s;
        s = l;
        s.kind = LIGHT_KIND_SPOT | LIGHT_FALLOFF_BAND;
        s.radius = level.radius;
        s.alpha = level.alpha;
        s.interleave = level.interleave;
        shaded[t] = sampled_light(s, t);
        no_cell(k);
        if step.a.w > 0u {
            var flux = POINT_FLUX;
            if b > 0u {
                flux = spot_bins[b - 1u].flux;
            }
            splat(l.position, power * (spot_flux(l.cos_inner, l.cos_outer) / flux), b);
        }
        return;
    }
    shaded[t] = sampled_light(s, t);
    spread(k, l.position, power, 0u);
}

// The lists' room a workgroup of cells_room takes at once (one global atomic a workgroup, not
// one a cell: a million cells' adds to one word were a quarter of a millisecond).
var<workgroup> room_total: atomic<u32>;
var<workgroup> room_first: u32;

// A thread a slot of the cells' table: a cell's list takes its room, after those of the cells
// before it in its workgroup (the lists' order is free: a cell reads only its own).
@compute @workgroup_size(256)
fn cells_room(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    if local == 0u {
        atomicStore(&room_total, 0u);
    }
    workgroupBarrier();
    let t = item(id);
    var n = 0u;
    if t < step.b.w && atomicLoad(&cells[cell_word(t, 0u)]) != 0u {
        n = atomicLoad(&cells[cell_word(t, 1u)]);
    }
    var before = 0u;
    if n > 0u {
        before = atomicAdd(&room_total, n);
    }
    workgroupBarrier();
    if local == 0u {
        room_first = atomicAdd(&cells[0], atomicLoad(&room_total));
    }
    let first = workgroupUniformLoad(&room_first);
    if n > 0u {
        atomicStore(&cells[cell_word(t, 2u)], first + before);
    }
}

// A thread an item: a binned one writes its index into its cell's list.
@compute @workgroup_size(256)
fn fill(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = item(id);
    if i >= step.a.y {
        return;
    }
    let c = atomicLoad(&cells[light_cell(i)]);
    if c == NO_CELL {
        return;
    }
    let at = atomicLoad(&cells[cell_word(c, 2u)]) + atomicAdd(&cells[cell_word(c, 3u)], 1u);
    atomicStore(&cells[cell_list(at)], i);
}

// Item i of this pass's step as binned: a source light (the points pass), or the light this
// level's slot i became (finalize: its power the colour, intensity 1), the same position and
// power bin had.
fn cell_item(i: u32) -> Light {
    if step.a.x == 0u {
        return source[step.o.x + i];
    }
    return shaded[step.b.y + i];
}

// Eight threads a slot of the cells' table, a thread a corner: the cell's lights spread into
// that node of the next level's grid as `splat` spreads each (the same weights and terms, from
// the same f32 arithmetic), the node's six sums added up first. (A thread a cell, its corners
// in turn, took 0.64 ms at a million lights: eight hash look-ups and list walks in a row.)
@compute @workgroup_size(256)
fn cell_splat(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = item(id);
    let t = i / 8u;
    let corner = i % 8u;
    if t >= step.b.w {
        return;
    }
    let key = atomicLoad(&cells[cell_word(t, 0u)]);
    if key == 0u {
        return;
    }
    let n = atomicLoad(&cells[cell_word(t, 1u)]);
    let first = atomicLoad(&cells[cell_word(t, 2u)]);
    let spacing = bitcast<f32>(step.d.w);
    let dims = step.e.xyz;
    let k = key - 1u;
    let rel = vec3<u32>(k % dims.x, (k / dims.x) % dims.y, k / (dims.x * dims.y));
    let bit = corner_bits(corner);
    let node = step.d.xyz + vec3<i32>(rel + bit);
    var sums = array<Term, 6>(term_zero(), term_zero(), term_zero(), term_zero(), term_zero(), term_zero());
    var splats = 0u;
    for (var j = 0u; j < n; j++) {
        let l = cell_item(atomicLoad(&cells[cell_list(first + j)]));
        let power = l.color * l.intensity;
        let u = l.position / spacing;
        let f = u - floor(u);
        let w = corner_weight(f, bit);
        if w == 0.0 {
            continue;
        }
        let c = w * power * step.c.w;
        let cs = c.r + c.g + c.b;
        let o = u - vec3<f32>(node);
        sums[0] = term_add(sums[0], term_of(c.r));
        sums[1] = term_add(sums[1], term_of(c.g));
        sums[2] = term_add(sums[2], term_of(c.b));
        sums[3] = term_add(sums[3], term_of_signed(cs * o.x));
        sums[4] = term_add(sums[4], term_of_signed(cs * o.y));
        sums[5] = term_add(sums[5], term_of_signed(cs * o.z));
        splats += 1u;
    }
    if splats == 0u {
        return;
    }
    let r = rel + bit;
    let at = slot_of((r.z * dims.y + r.y) * dims.x + r.x + 1u);
    if at < 0 {
        atomicAdd(&dropped[1], splats);
        return;
    }
    for (var s = 0u; s < 6u; s++) {
        sum_add_term(u32(at), s, sums[s]);
    }
}

@compute @workgroup_size(256)
fn finalize(@builtin(global_invocation_id) id: vec3<u32>) {
    let t = item(id);
    if t >= step.a.y {
        return;
    }
    let at = step.b.x + t;
    let key = slot_key(at);
    let p = vec3<f32>(sum_read(at, 0u), sum_read(at, 1u), sum_read(at, 2u));
    let weight = p.r + p.g + p.b;
    if key == 0u || weight <= 0.0 {
        var dead = level_light(step.far.xyz, vec3<f32>(0.0));
        dead.radius = 0.0;
        dead.intensity = 0.0;
        shaded[step.b.y + t] = dead;
        no_cell(t);
        return;
    }
    let dims = step.h.xyz;
    let nodes = dims.x * dims.y * dims.z;
    let b = (key - 1u) / nodes;
    let k = (key - 1u) % nodes;
    let node = step.g.xyz
        + vec3<i32>(vec3<u32>(k % dims.x, (k / dims.x) % dims.y, k / (dims.x * dims.y)));
    let offset = vec3<f32>(sum_read_signed(at, 3u), sum_read_signed(at, 4u), sum_read_signed(at, 5u))
        / weight;
    let position = (vec3<f32>(node) + offset) * bitcast<f32>(step.g.w);
    let power = p / step.c.w;
    shaded[step.b.y + t] = sampled_light(with_cone(level_light(position, power), b), node_draw(key));
    spread(t, position, power, b);
}
