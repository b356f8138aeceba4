// shade.visibility_compute: the visibility buffer's pass rasterised in compute (the visibility
// backend's default, crate::vis_compute). The opaque triangles' nearest id a pixel goes
// into a 64-bit key a pixel, (0xffffffff - depth bits) << 32 | (0xffffffff - id), by atomicMax:
// the nearest depth wins, equal depths the smaller id, as in the raster pass, whose depth test
// Less keeps the first triangle drawn; 0, the clear value, is no triangle (a key's high word is
// never 0: depths are at most 1).
// A thread a triangle clips it against the near plane (at most two triangles), rasterises a
// small one itself and queues a large one, set up; vis_scan numbers the queued triangles'
// VC_BLOCK-pixel square blocks and vis_blocks takes them a workgroup a block. Coverage, as the
// hardware's: vertices snapped to 1/256 pixel (Vulkan's usual subPixelPrecisionBits, 8), pixel
// centres inside the edges, ties by the top-left rule, the edge functions exact in 64-bit
// integers. (A triangle with a vertex past VC_EXACT_LIMIT pixels from the corner, where fixed
// point would overflow, is tested in f32 on unsnapped vertices: the hardware clips such ones to
// its guard band, which no rule here reproduces.) Depth: NDC z interpolated linearly in screen
// space, as the hardware's.

@group(1) @binding(0) var<storage, read> vc_vertices: array<u32>;
@group(1) @binding(1) var<storage, read> vc_indices: array<u32>;
@group(1) @binding(2) var<storage, read_write> vc_keys: array<atomic<u64>>;
// (large triangles queued, unused); the queue: four vec4 an entry, each vertex's screen
// position and depth (w: 0, the id's bits, 1 where exact), then its rectangle in blocks
// (x0, y0, width, height, as bits). Two entries a triangle at most: it cannot overflow.
@group(1) @binding(3) var<storage, read_write> vc_queue_count: array<atomic<u32>, 2>;
@group(1) @binding(4) var<storage, read_write> vc_queue: array<vec4<f32>>;
// x: opaque triangles; y: queue capacity (entries); z: blocks' workgroups.
@group(1) @binding(5) var<uniform> vc_params: vec4<u32>;
// The queued triangles' first block each in one numbering of all their blocks (vis_scan), and
// after the last entry the blocks' count.
@group(1) @binding(6) var<storage, read_write> vc_first: array<u32>;

override VC_BLOCK: u32 = 64u;
// Larger bounding boxes (pixels) go to the blocks.
override VC_SMALL: u32 = 256u;

// The largest |pixel coordinate| of a vertex tested exactly: 2^21 pixels, 2^29 in 1/256 pixel,
// so that differences fit an i32 and products of two an i64.
const VC_EXACT_LIMIT: f32 = 2097152.0;

struct ScreenTri {
    // xy: pixel coordinates (y down; snapped to 1/256 pixel where exact), z: NDC depth, for
    // each vertex.
    p: array<vec3<f32>, 3>,
    valid: bool,
    // Snapped, and tested in fixed point.
    exact: bool,
}

// The clipped polygon of triangle t (at most four vertices, in clip space) and its count.
struct Clipped {
    v: array<vec4<f32>, 4>,
    n: u32,
}

fn vc_position(i: u32) -> vec3<f32> {
    return bitcast<vec3<f32>>(vec3<u32>(vc_vertices[VERTEX_WORDS * i], vc_vertices[VERTEX_WORDS * i + 1u], vc_vertices[VERTEX_WORDS * i + 2u]));
}

fn vc_clip(t: u32) -> Clipped {
    var c: array<vec4<f32>, 3>;
    for (var k = 0u; k < 3u; k++) {
        c[k] = frame.clip_from_world * vec4<f32>(vc_position(vc_indices[3u * t + k]), 1.0);
    }
    var out: Clipped;
    out.n = 0u;
    // Sutherland-Hodgman against z >= 0 (the near plane of a [0, 1] depth range).
    for (var k = 0u; k < 3u; k++) {
        let a = c[k];
        let b = c[(k + 1u) % 3u];
        if a.z >= 0.0 {
            out.v[out.n] = a;
            out.n += 1u;
        }
        if (a.z >= 0.0) != (b.z >= 0.0) {
            let s = a.z / (a.z - b.z);
            out.v[out.n] = mix(a, b, s);
            out.n += 1u;
        }
    }
    return out;
}

fn vc_screen(c: vec4<f32>) -> vec3<f32> {
    let ndc = c.xyz / c.w;
    return vec3<f32>((ndc.x * 0.5 + 0.5) * frame.viewport.x, (0.5 - ndc.y * 0.5) * frame.viewport.y, ndc.z);
}

// Part `part` (0 or 1) of triangle t's clipped polygon as a fan, in screen space.
fn vc_part(cl: Clipped, part: u32) -> ScreenTri {
    var s: ScreenTri;
    s.valid = cl.n >= 3u + part;
    if !s.valid {
        return s;
    }
    s.p[0] = vc_screen(cl.v[0]);
    s.p[1] = vc_screen(cl.v[1u + part]);
    s.p[2] = vc_screen(cl.v[2u + part]);
    let far = max(max(abs(s.p[0].xy), abs(s.p[1].xy)), abs(s.p[2].xy));
    s.exact = all(far < vec2<f32>(VC_EXACT_LIMIT));
    if s.exact {
        for (var k = 0u; k < 3u; k++) {
            s.p[k] = vec3<f32>(round(s.p[k].xy * 256.0) / 256.0, s.p[k].z);
        }
    }
    return s;
}

// A snapped position in 1/256 pixel (exact: it is a multiple of 1/256 below 2^21).
fn vc_fixed(p: vec2<f32>) -> vec2<i32> {
    return vec2<i32>(p * 256.0);
}

// vc_edge in fixed point, exact.
fn vc_edge_fixed(a: vec2<i32>, b: vec2<i32>, q: vec2<i32>) -> i64 {
    return i64(b.x - a.x) * i64(q.y - a.y) - i64(b.y - a.y) * i64(q.x - a.x);
}

// Pixel (x, y)'s centre in 1/256 pixel.
fn vc_centre_fixed(x: u32, y: u32) -> vec2<i32> {
    return vec2<i32>(i32(x) * 256 + 128, i32(y) * 256 + 128);
}

// s's doubled signed area: exact in sign (and zero) where s is.
fn vc_area(s: ScreenTri) -> f32 {
    if s.exact {
        return f32(vc_edge_fixed(vc_fixed(s.p[0].xy), vc_fixed(s.p[1].xy), vc_fixed(s.p[2].xy)));
    }
    return vc_edge(s.p[0].xy, s.p[1].xy, s.p[2].xy);
}

// Edge function of edge a -> b at point q (positive inside a triangle wound clockwise on the
// screen, y down).
fn vc_edge(a: vec2<f32>, b: vec2<f32>, q: vec2<f32>) -> f32 {
    return (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
}

// Whether an edge a -> b of a positively wound triangle takes pixel centres on it: top edges
// (horizontal, going right) and left edges (going up, y down).
fn vc_top_left(a: vec2<f32>, b: vec2<f32>) -> bool {
    let d = b - a;
    return (d.y == 0.0 && d.x > 0.0) || d.y < 0.0;
}

// Whether edge a -> b takes a point whose edge function is e (positive, or zero on a top or left
// edge; the f32 path's test).
fn vc_takes(e: f32, a: vec2<f32>, b: vec2<f32>) -> bool {
    return e > 0.0 || (e == 0.0 && vc_top_left(a, b));
}

// Keeps the key of depth weights e (the three edge functions at pixel (x, y), inside s) for
// triangle `id`.
fn vc_keep(s: ScreenTri, e: vec3<f32>, x: u32, y: u32, id: u32) {
    let z = (e.x * s.p[0].z + e.y * s.p[1].z + e.z * s.p[2].z) / (e.x + e.y + e.z);
    if z < 0.0 || z > 1.0 {
        return;
    }
    let key = (u64(0xffffffffu - bitcast<u32>(z)) << 32u) | u64(0xffffffffu - id);
    atomicMax(&vc_keys[y * u32(frame.viewport.x) + x], key);
}

// Tests pixel (x, y) against s (wound positively, of positive area; not exact: f32 on unsnapped
// vertices) and keeps its key.
fn vc_pixel(s: ScreenTri, x: u32, y: u32, id: u32) {
    let q = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
    let e = vec3<f32>(vc_edge(s.p[1].xy, s.p[2].xy, q), vc_edge(s.p[2].xy, s.p[0].xy, q), vc_edge(s.p[0].xy, s.p[1].xy, q));
    let in0 = vc_takes(e.x, s.p[1].xy, s.p[2].xy);
    let in1 = vc_takes(e.y, s.p[2].xy, s.p[0].xy);
    let in2 = vc_takes(e.z, s.p[0].xy, s.p[1].xy);
    if in0 && in1 && in2 {
        vc_keep(s, e, x, y, id);
    }
}

// An exact triangle's edge functions in fixed point (1/256 pixel, squared), stepped from pixel
// to pixel by additions: edge i is the one opposite vertex i.
struct Edges {
    // At the pixel the walk starts from.
    e: vec3<i64>,
    // Their change a pixel to the right, and a pixel down.
    dx: vec3<i64>,
    dy: vec3<i64>,
    // The least value a covered centre has: 0 on a top or left edge, 1 on the others.
    least: vec3<i64>,
}

fn vc_edges(s: ScreenTri, x: u32, y: u32) -> Edges {
    let q = vc_centre_fixed(x, y);
    var f: array<vec2<i32>, 3>;
    for (var k = 0u; k < 3u; k++) {
        f[k] = vc_fixed(s.p[k].xy);
    }
    var out: Edges;
    for (var i = 0u; i < 3u; i++) {
        let a = f[(i + 1u) % 3u];
        let b = f[(i + 2u) % 3u];
        out.e[i] = vc_edge_fixed(a, b, q);
        out.dx[i] = -i64(b.y - a.y) * i64(256);
        out.dy[i] = i64(b.x - a.x) * i64(256);
        out.least[i] = select(i64(1), i64(0), vc_top_left(s.p[(i + 1u) % 3u].xy, s.p[(i + 2u) % 3u].xy));
    }
    return out;
}

// Keeps the key of the pixel at (x, y) whose edge functions are e, where it is covered.
fn vc_fixed_pixel(s: ScreenTri, ed: Edges, e: vec3<i64>, x: u32, y: u32, id: u32) {
    if all(e >= ed.least) {
        // (Each i64 to f32 keeps its sign: the weights are the edge functions rounded.)
        vc_keep(s, vec3<f32>(f32(e.x), f32(e.y), f32(e.z)), x, y, id);
    }
}

// s wound positively (swapping two vertices where needed).
fn vc_wound(s_in: ScreenTri) -> ScreenTri {
    var s = s_in;
    if !s.valid {
        return s;
    }
    if vc_area(s) < 0.0 {
        let t = s.p[1];
        s.p[1] = s.p[2];
        s.p[2] = t;
    }
    return s;
}

// The pixel rectangle (x0, y0, x1, y1), exclusive ends, of pixel centres s may cover.
fn vc_rect(s: ScreenTri) -> vec4<u32> {
    let lo = min(min(s.p[0].xy, s.p[1].xy), s.p[2].xy);
    let hi = max(max(s.p[0].xy, s.p[1].xy), s.p[2].xy);
    let size = frame.viewport.xy;
    let a = clamp(floor(lo - 0.5), vec2<f32>(0.0), size);
    let b = clamp(ceil(hi - 0.5) + 1.0, vec2<f32>(0.0), size);
    return vec4<u32>(vec2<u32>(a), vec2<u32>(b));
}

@compute @workgroup_size(64)
fn vis_triangles(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = gid.x;
    if t >= vc_params.x {
        return;
    }
    let cl = vc_clip(t);
    for (var part = 0u; part < 2u; part++) {
        let s = vc_wound(vc_part(cl, part));
        if !s.valid {
            continue;
        }
        if vc_area(s) <= 0.0 {
            continue;
        }
        let r = vc_rect(s);
        if r.x >= r.z || r.y >= r.w {
            continue;
        }
        let size = r.zw - r.xy;
        if size.x * size.y <= VC_SMALL {
            if s.exact {
                // Row by row from the rectangle's corner, a pixel at a time by additions.
                let ed = vc_edges(s, r.x, r.y);
                var row = ed.e;
                for (var y = r.y; y < r.w; y++) {
                    var e = row;
                    for (var x = r.x; x < r.z; x++) {
                        vc_fixed_pixel(s, ed, e, x, y, t + 1u);
                        e += ed.dx;
                    }
                    row += ed.dy;
                }
            } else {
                for (var y = r.y; y < r.w; y++) {
                    for (var x = r.x; x < r.z; x++) {
                        vc_pixel(s, x, y, t + 1u);
                    }
                }
            }
            continue;
        }
        // Set up once, for vis_blocks.
        let b0 = r.xy / VC_BLOCK;
        let b1 = (r.zw + VC_BLOCK - 1u) / VC_BLOCK;
        let e = atomicAdd(&vc_queue_count[0], 1u);
        if e >= vc_params.y {
            atomicAdd(&vc_queue_count[1], 1u);
            continue;
        }
        vc_queue[4u * e] = vec4<f32>(s.p[0], 0.0);
        vc_queue[4u * e + 1u] = vec4<f32>(s.p[1], bitcast<f32>(t + 1u));
        vc_queue[4u * e + 2u] = vec4<f32>(s.p[2], f32(s.exact));
        vc_queue[4u * e + 3u] = bitcast<vec4<f32>>(vec4<u32>(b0, b1 - b0));
    }
}

var<workgroup> wg_sums: array<u32, 256>;

// The entry's blocks.
fn vc_blocks_of(e: u32) -> u32 {
    let rect = bitcast<vec4<u32>>(vc_queue[4u * e + 3u]);
    return rect.z * rect.w;
}

// One workgroup numbers the queued triangles' blocks: each thread sums a run of entries, the
// workgroup scans the sums, and each thread writes its entries' first blocks.
@compute @workgroup_size(256)
fn vis_scan(@builtin(local_invocation_index) li: u32) {
    let count = min(atomicLoad(&vc_queue_count[0]), vc_params.y);
    let run = (count + 255u) / 256u;
    let start = min(li * run, count);
    let end = min(start + run, count);
    var sum = 0u;
    for (var e = start; e < end; e++) {
        sum += vc_blocks_of(e);
    }
    wg_sums[li] = sum;
    workgroupBarrier();
    for (var d = 1u; d < 256u; d *= 2u) {
        var add = 0u;
        if li >= d {
            add = wg_sums[li - d];
        }
        workgroupBarrier();
        wg_sums[li] += add;
        workgroupBarrier();
    }
    var first = wg_sums[li] - sum;
    for (var e = start; e < end; e++) {
        vc_first[e] = first;
        first += vc_blocks_of(e);
    }
    if li == 255u {
        vc_first[count] = wg_sums[255];
    }
}

// Every queued triangle's blocks, a block at a time over vc_params.z workgroups, each taking a
// run of consecutive blocks in the blocks' numbering: it finds the entry of its first block by
// bisection (the last entry whose first block is at or before it) and then steps from entry to
// entry as its blocks pass their first blocks, so that a block costs no search; blocks outside
// an edge are skipped; each of the 256 threads tests VC_BLOCK^2 / 256 of its pixels.
@compute @workgroup_size(256)
fn vis_blocks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let count = min(atomicLoad(&vc_queue_count[0]), vc_params.y);
    let total = vc_first[count];
    let run = (total + vc_params.z - 1u) / vc_params.z;
    let start = wg.x * run;
    let end = min(start + run, total);
    if start >= end {
        return;
    }
    var lo = 0u;
    var hi = count;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if vc_first[mid] <= start {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    var e = lo;
    for (var b = start; b < end; b++) {
        // (vc_first[count] is the total, past every block: the step stops at the last entry.)
        while vc_first[e + 1u] <= b {
            e += 1u;
        }
        let rect = bitcast<vec4<u32>>(vc_queue[4u * e + 3u]);
        let k = b - vc_first[e];
        let q0 = vc_queue[4u * e];
        let q1 = vc_queue[4u * e + 1u];
        let q2 = vc_queue[4u * e + 2u];
        var s: ScreenTri;
        s.p[0] = q0.xyz;
        s.p[1] = q1.xyz;
        s.p[2] = q2.xyz;
        s.valid = true;
        s.exact = q2.w != 0.0;
        let block = rect.xy + vec2<u32>(k % rect.z, k / rect.z);
        if vc_block_outside(s, block * VC_BLOCK, block * VC_BLOCK + VC_BLOCK - 1u) {
            continue;
        }
        let r = vc_rect(s);
        let id = bitcast<u32>(q1.w);
        // A thread's pixels: one column of the block, every (256 / VC_BLOCK)-th row (VC_BLOCK a
        // power of two of at most 256).
        let x = block.x * VC_BLOCK + li % VC_BLOCK;
        let y0 = block.y * VC_BLOCK + li / VC_BLOCK;
        let rows = 256u / VC_BLOCK;
        if s.exact {
            let ed = vc_edges(s, x, y0);
            var e = ed.e;
            let step = ed.dy * i64(rows);
            for (var y = y0; y < (block.y + 1u) * VC_BLOCK; y += rows) {
                if x >= r.x && x < r.z && y >= r.y && y < r.w {
                    vc_fixed_pixel(s, ed, e, x, y, id);
                }
                e += step;
            }
        } else {
            for (var y = y0; y < (block.y + 1u) * VC_BLOCK; y += rows) {
                if x >= r.x && x < r.z && y >= r.y && y < r.w {
                    vc_pixel(s, x, y, id);
                }
            }
        }
    }
}

// Whether the centres of every pixel from lo to hi (inclusive) lie strictly outside one of s's
// edges (a block to skip: the edge function is below 0 at all four corner pixels' centres;
// exact where s is).
fn vc_block_outside(s: ScreenTri, lo: vec2<u32>, hi: vec2<u32>) -> bool {
    for (var i = 0u; i < 3u; i++) {
        let a = s.p[(i + 1u) % 3u].xy;
        let b = s.p[(i + 2u) % 3u].xy;
        var outside: bool;
        if s.exact {
            let fa = vc_fixed(a);
            let fb = vc_fixed(b);
            let m = max(max(vc_edge_fixed(fa, fb, vc_centre_fixed(lo.x, lo.y)), vc_edge_fixed(fa, fb, vc_centre_fixed(hi.x, hi.y))), max(vc_edge_fixed(fa, fb, vc_centre_fixed(lo.x, hi.y)), vc_edge_fixed(fa, fb, vc_centre_fixed(hi.x, lo.y))));
            outside = m < i64(0);
        } else {
            let l = vec2<f32>(lo) + 0.5;
            let h = vec2<f32>(hi) + 0.5;
            let m = max(max(vc_edge(a, b, l), vc_edge(a, b, h)), max(vc_edge(a, b, vec2<f32>(l.x, h.y)), vc_edge(a, b, vec2<f32>(h.x, l.y))));
            outside = m < 0.0;
        }
        if outside {
            return true;
        }
    }
    return false;
}
