// The lighting grid hierarchy built on the GPU every frame: the WGSL twin of
// manylights_scene::hierarchy::Hierarchy::build_fixed (see its module docs for the levels and
// bands; that module is the oracle of this pass). Host side: manylights_gpu::hierarchy.
//
// One dispatch a level, in order:
// - `points` (mode 0): a thread a source light. A point light is written to the shaded lights
//   as level 0's light (colour x intensity, its band); a spot as it is (radius `reach`, a band
//   that never falls). A point light is spread into level 1's grid (`splat`).
// - `finalize` (mode 1): a thread a slot of level l's hash table. A node's sums become its
//   light (power, power-weighted position), written to the shaded lights with level l's band;
//   an empty slot becomes a dead light (no power, radius 0, at `far`). It is spread into level
//   l + 1's grid unless l is the last level.
// A grid's nodes are keyed by their index in the level's box of nodes (plus 1; 0 is an empty
// slot) in an open-addressing hash table of 16 words a slot: the key, then six 64-bit fixed
// point sums (so that they do not hang on the order of the additions): power r, g, b, and the
// power-weighted offset of the position from the node in units of the spacing, x, y, z, all
// scaled by `scale` (2^52 over the lights' total power: the sums fit 63 bits, and each term
// keeps an f32's 24 bits). How a slot holds them is the file before this one's:
// hierarchy_sums32.wgsl (two 32-bit atomics a sum) or hierarchy_sums64.wgsl (one 64-bit
// atomic, SHADER_INT64_ATOMIC_ALL_OPS): `slot_claim`, `slot_key`, `sum_add`,
// `sum_add_signed`, `sum_read`, `sum_read_signed`. The counters count splats dropped: a node
// outside its level's box, a table full.

struct Step {
    // mode (0 points, 1 finalize), items (source lights or slots), threads a dispatch row,
    // splat (1: spread into the next level)
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
}

@group(0) @binding(0) var<uniform> step: Step;
@group(0) @binding(1) var<storage, read> source: array<Light>;
// The shaded light each source light becomes (points pass).
@group(0) @binding(2) var<storage, read> target_index: array<u32>;
@group(0) @binding(3) var<storage, read_write> shaded: array<Light>;
// [nodes outside their level's box, splats into a full table]
@group(0) @binding(5) var<storage, read_write> dropped: array<atomic<u32>, 2>;

const MAX_PROBES: u32 = 256u;

// The slot of `key` in the next level's table (inserting it), or none.
fn slot_of(key: u32) -> i32 {
    let count = step.b.w;
    var probe = (key * 2654435769u) ^ (key >> 15u);
    probe = probe % count;
    var tries = 0u;
    loop {
        if tries >= min(count, MAX_PROBES) {
            return -1;
        }
        let at = step.b.z + probe;
        let old = slot_claim(at, key);
        if old == 0u || old == key {
            return i32(at);
        }
        probe = (probe + 1u) % count;
        tries += 1u;
    }
    return -1;
}

// Spreads a light's power over the 8 nodes of its cell of the next level's grid.
fn splat(position: vec3<f32>, power: vec3<f32>) {
    let spacing = bitcast<f32>(step.d.w);
    let u = position / spacing;
    let base = floor(u);
    let f = u - base;
    let origin = step.d.xyz;
    let dims = step.e.xyz;
    for (var corner = 0u; corner < 8u; corner++) {
        let bit = vec3<u32>(corner & 1u, (corner >> 1u) & 1u, (corner >> 2u) & 1u);
        let t = select(1.0 - f, f, bit == vec3<u32>(1u));
        let w = t.x * t.y * t.z;
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
        let key = (r.z * dims.y + r.y) * dims.x + r.x + 1u;
        let at = slot_of(key);
        if at < 0 {
            atomicAdd(&dropped[1], 1u);
            continue;
        }
        let c = w * power * step.c.w;
        let cs = c.r + c.g + c.b;
        let o = u - vec3<f32>(node);
        let at_u = u32(at);
        sum_add(at_u, 0u, c.r);
        sum_add(at_u, 1u, c.g);
        sum_add(at_u, 2u, c.b);
        sum_add_signed(at_u, 3u, cs * o.x);
        sum_add_signed(at_u, 4u, cs * o.y);
        sum_add_signed(at_u, 5u, cs * o.z);
    }
}

// A point light of a level: `power` at `position`, shaded with the level's band.
fn level_light(position: vec3<f32>, power: vec3<f32>) -> Light {
    var l: Light;
    l.position = position;
    l.radius = min(bitcast<f32>(step.s.w) * step.c.x, step.c.z);
    l.color = power;
    l.intensity = 1.0;
    l.direction = vec3<f32>(0.0);
    l.kind = LIGHT_KIND_POINT;
    l.cos_inner = 1.0;
    l.cos_outer = -1.0;
    l.alpha = -step.c.x;
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
        let r = -l.alpha;
        // The last level's r is infinite, and so is its end.
        let to = r * (c - t);
        l.radius = min(to, step.c.z);
        l.alpha = -to;
        l.interleave = bitcast<u32>(step.c.y * (1.0 + t)) | HARD_BAND;
    }
    return l;
}

fn item(id: vec3<u32>) -> u32 {
    return id.y * step.a.z + id.x;
}

@compute @workgroup_size(256)
fn points(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = item(id);
    if i >= step.a.y {
        return;
    }
    let l = source[i];
    if l.kind == LIGHT_KIND_SPOT {
        var s = l;
        s.radius = step.c.z;
        s.alpha = -step.far.w;
        s.interleave = 0u;
        shaded[target_index[i]] = s;
        return;
    }
    let power = l.color * l.intensity;
    shaded[target_index[i]] = sampled_light(level_light(l.position, power), target_index[i]);
    if step.a.w == 1u {
        splat(l.position, power);
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
        return;
    }
    let dims = step.h.xyz;
    let k = key - 1u;
    let node = step.g.xyz
        + vec3<i32>(vec3<u32>(k % dims.x, (k / dims.x) % dims.y, k / (dims.x * dims.y)));
    let offset = vec3<f32>(sum_read_signed(at, 3u), sum_read_signed(at, 4u), sum_read_signed(at, 5u))
        / weight;
    let position = (vec3<f32>(node) + offset) * bitcast<f32>(step.g.w);
    let power = p / step.c.w;
    shaded[step.b.y + t] = sampled_light(level_light(position, power), node_draw(key));
    if step.a.w == 1u {
        splat(position, power);
    }
}
