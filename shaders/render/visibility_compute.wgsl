// shade.visibility_compute: the visibility pass rasterised in compute (issue 49's item 4, a
// building block not yet wired into a backend). The opaque triangles' nearest id a pixel goes
// into a 64-bit key a pixel, (0xffffffff - depth bits) << 32 | id, by atomicMax: the nearest
// depth wins, equal depths the larger id (deterministic); 0, the clear value, is no triangle.
// A thread a triangle clips it against the near plane (at most two triangles), rasterises a
// small one itself and queues a large one, set up; vis_scan numbers the queued triangles'
// VC_BLOCK-pixel square blocks and vis_blocks takes them a workgroup a block. Coverage: pixel
// centres inside the edges, ties by the top-left rule, in f32 on unsnapped vertices (the
// hardware snaps them to 1/256 pixel, so edge pixels may differ). Depth: NDC z interpolated
// linearly in screen space, as the hardware's.

@group(1) @binding(0) var<storage, read> vc_vertices: array<u32>;
@group(1) @binding(1) var<storage, read> vc_indices: array<u32>;
@group(1) @binding(2) var<storage, read_write> vc_keys: array<atomic<u64>>;
// (large triangles queued, unused); the queue: four vec4 an entry, each vertex's screen
// position and depth (w: the doubled area, the id's bits, 0), then its rectangle in blocks
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

struct ScreenTri {
    // xy: pixel coordinates (y down), z: NDC depth, for each vertex.
    p: array<vec3<f32>, 3>,
    valid: bool,
}

// The clipped polygon of triangle t (at most four vertices, in clip space) and its count.
struct Clipped {
    v: array<vec4<f32>, 4>,
    n: u32,
}

fn vc_position(i: u32) -> vec3<f32> {
    return bitcast<vec3<f32>>(vec3<u32>(vc_vertices[7u * i], vc_vertices[7u * i + 1u], vc_vertices[7u * i + 2u]));
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
    return s;
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

// Tests pixel (x, y) against s (wound positively, `area` > 0) and keeps its key.
fn vc_pixel(s: ScreenTri, area: f32, x: u32, y: u32, id: u32) {
    let q = vec2<f32>(f32(x) + 0.5, f32(y) + 0.5);
    let e0 = vc_edge(s.p[1].xy, s.p[2].xy, q);
    let e1 = vc_edge(s.p[2].xy, s.p[0].xy, q);
    let e2 = vc_edge(s.p[0].xy, s.p[1].xy, q);
    let in0 = e0 > 0.0 || (e0 == 0.0 && vc_top_left(s.p[1].xy, s.p[2].xy));
    let in1 = e1 > 0.0 || (e1 == 0.0 && vc_top_left(s.p[2].xy, s.p[0].xy));
    let in2 = e2 > 0.0 || (e2 == 0.0 && vc_top_left(s.p[0].xy, s.p[1].xy));
    if !(in0 && in1 && in2) {
        return;
    }
    let z = (e0 * s.p[0].z + e1 * s.p[1].z + e2 * s.p[2].z) / area;
    if z < 0.0 || z > 1.0 {
        return;
    }
    let key = (u64(0xffffffffu - bitcast<u32>(z)) << 32u) | u64(id);
    atomicMax(&vc_keys[y * u32(frame.viewport.x) + x], key);
}

// s wound positively (swapping two vertices where needed) and its doubled area; 0 where
// degenerate.
fn vc_wound(s_in: ScreenTri) -> ScreenTri {
    var s = s_in;
    let area = vc_edge(s.p[0].xy, s.p[1].xy, s.p[2].xy);
    if area < 0.0 {
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
        let area = vc_edge(s.p[0].xy, s.p[1].xy, s.p[2].xy);
        if area <= 0.0 {
            continue;
        }
        let r = vc_rect(s);
        if r.x >= r.z || r.y >= r.w {
            continue;
        }
        let size = r.zw - r.xy;
        if size.x * size.y <= VC_SMALL {
            for (var y = r.y; y < r.w; y++) {
                for (var x = r.x; x < r.z; x++) {
                    vc_pixel(s, area, x, y, t + 1u);
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
        vc_queue[4u * e] = vec4<f32>(s.p[0], area);
        vc_queue[4u * e + 1u] = vec4<f32>(s.p[1], bitcast<f32>(t + 1u));
        vc_queue[4u * e + 2u] = vec4<f32>(s.p[2], 0.0);
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

// Every queued triangle's blocks, a block at a time over vc_params.z workgroups (block b the
// (b - first)-th of the entry whose first block is the last at or before b, found by bisection);
// blocks outside an edge are skipped; each of the 256 threads tests VC_BLOCK^2 / 256 of its pixels.
@compute @workgroup_size(256)
fn vis_blocks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let count = min(atomicLoad(&vc_queue_count[0]), vc_params.y);
    let total = vc_first[count];
    for (var b = wg.x; b < total; b += vc_params.z) {
        var lo = 0u;
        var hi = count;
        while hi - lo > 1u {
            let mid = (lo + hi) / 2u;
            if vc_first[mid] <= b {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let e = lo;
        let rect = bitcast<vec4<u32>>(vc_queue[4u * e + 3u]);
        let k = b - vc_first[e];
        let q0 = vc_queue[4u * e];
        let q1 = vc_queue[4u * e + 1u];
        var s: ScreenTri;
        s.p[0] = q0.xyz;
        s.p[1] = q1.xyz;
        s.p[2] = vc_queue[4u * e + 2u].xyz;
        s.valid = true;
        let block = rect.xy + vec2<u32>(k % rect.z, k / rect.z);
        let corner = vec2<f32>(block * VC_BLOCK) + 0.5;
        if vc_block_outside(s, corner, corner + f32(VC_BLOCK - 1u)) {
            continue;
        }
        let r = vc_rect(s);
        let id = bitcast<u32>(q1.w);
        for (var j = li; j < VC_BLOCK * VC_BLOCK; j += 256u) {
            let x = block.x * VC_BLOCK + j % VC_BLOCK;
            let y = block.y * VC_BLOCK + j / VC_BLOCK;
            if x >= r.x && x < r.z && y >= r.y && y < r.w {
                vc_pixel(s, q0.w, x, y, id);
            }
        }
    }
}

// Whether every pixel centre of the rectangle lo..hi lies strictly outside one of s's edges (a
// block to skip: the edge function is below 0 at all four corners).
fn vc_block_outside(s: ScreenTri, lo: vec2<f32>, hi: vec2<f32>) -> bool {
    for (var i = 0u; i < 3u; i++) {
        let a = s.p[(i + 1u) % 3u].xy;
        let b = s.p[(i + 2u) % 3u].xy;
        let m = max(max(vc_edge(a, b, lo), vc_edge(a, b, hi)), max(vc_edge(a, b, vec2<f32>(lo.x, hi.y)), vc_edge(a, b, vec2<f32>(hi.x, lo.y))));
        if m < 0.0 {
            return true;
        }
    }
    return false;
}
