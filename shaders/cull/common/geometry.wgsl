// Shared culling geometry: the WGSL twin of manylights_cull::geometry (CPU oracles mirror every
// function here in f32, in the same order of operations).
//
// Bins: a tile (tiled strategies) or a cluster (tile x depth slice). Lists: bin_ranges[bin] =
// (offset, count) into light_indices, written by every strategy and read by every backend
// through lookup.wgsl.
//
// Planes are vec4 (n, d) with inside = dot(n, p) + d >= 0, in view space, built from rows of
// clip_from_view (Gribb-Hartmann), so perspective and orthographic cameras share one code path.

// Host mirror: manylights_cull::layout::GpuCullParams.
struct CullParams {
    tiles_x: u32,
    tiles_y: u32,
    tile_size: u32,
    light_count: u32,
    // Depth slices of the cluster grid (1 for tiled strategies).
    slices: u32,
    // SLICING_LINEAR or SLICING_EXPONENTIAL.
    slicing: u32,
    // CULL_FLAG_* bits.
    flags: u32,
    bins: u32,
    near: f32,
    far: f32,
    // Conservative slack, relative to (|centre| + radius) of each light: absorbs f32 rounding
    // in planes and depth linearisation (see docs/STRATEGIES.md).
    slack: f32,
    // S / (far - near) (linear) or S / ln(far / near) (exponential).
    slice_scale: f32,
    // Deliberate cap on each list's length (0: none). Every light beyond it is counted in
    // cull_stats[0]; see lists.wgsl.
    capacity: u32,
    // Gather's coarse level (tiled_gather.wgsl): a coarse tile's side in tiles (8; 0: none),
    // coarse tiles across, and the lights of a chunk (a multiple of 64).
    coarse: u32,
    coarse_x: u32,
    chunk: u32,
}

@group(1) @binding(0) var<uniform> cull: CullParams;

// Per-tile depth data written by cull.depth_bounds. Host mirror: layout::GpuTileDepth.
struct TileDepth {
    // Linear view depth (distance along -Z) of the nearest and farthest covered pixel.
    dmin: f32,
    dmax: f32,
    // 2.5D geometry mask: bit k set when a covered pixel falls in depth cell k of [dmin, dmax].
    mask: u32,
    // Number of covered pixels (0: an empty tile needs no lights).
    covered: u32,
}

// A light as culling sees it, in view space.
struct CullLight {
    center: vec3<f32>,
    radius: f32,
    // Conservative slack in view-space units.
    slack: f32,
    is_cone: bool,
    axis: vec3<f32>,
    tan_outer: f32,
}

fn clip_row(i: u32) -> vec4<f32> {
    let m = frame.clip_from_view;
    return vec4<f32>(m[0][i], m[1][i], m[2][i], m[3][i]);
}

// A float's bits mapped so that unsigned order is the float order (negative depths of an
// orthographic camera included), and back.
fn ordered_bits(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn from_ordered_bits(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u & 0x7fffffffu, (u & 0x80000000u) != 0u));
}

// Linear view depth (distance along -Z, > 0 in front) of NDC depth z. With row 2 = (0, 0, A, B)
// and row 3 = (0, 0, C, D) of clip_from_view, z = (A vz + B) / (C vz + D). For a perspective
// camera the denominator (C z - A) subtracts nearly equal numbers, which is exact in floating
// point (Sterbenz), so the result has one rounding.
fn linear_depth(z: f32) -> f32 {
    let m = frame.clip_from_view;
    let a = m[2][2];
    let b = m[3][2];
    let c = m[2][3];
    let d = m[3][3];
    return -(b - d * z) / (c * z - a);
}

// NDC rectangle (x0, y0, x1, y1) of tile `tile`, clamped to the image (the last row and
// column may be partial when the resolution is not a multiple of the tile size).
fn tile_ndc(tile: vec2<u32>) -> vec4<f32> {
    let size = cull.tile_size;
    let px0 = f32(tile.x * size);
    let px1 = f32(min((tile.x + 1u) * size, u32(frame.viewport.x)));
    let py0 = f32(tile.y * size);
    let py1 = f32(min((tile.y + 1u) * size, u32(frame.viewport.y)));
    // Pixel rows grow downwards, NDC y upwards.
    return vec4<f32>(
        px0 * frame.viewport.z * 2.0 - 1.0,
        1.0 - py1 * frame.viewport.w * 2.0,
        px1 * frame.viewport.z * 2.0 - 1.0,
        1.0 - py0 * frame.viewport.w * 2.0,
    );
}

fn normalize_plane(p: vec4<f32>) -> vec4<f32> {
    return p / length(p.xyz);
}

// The four side planes of a tile's frustum: x >= x0 w, x <= x1 w, y >= y0 w, y <= y1 w.
fn tile_side_planes(tile: vec2<u32>) -> array<vec4<f32>, 4> {
    let r = tile_ndc(tile);
    let r0 = clip_row(0u);
    let r1 = clip_row(1u);
    let r3 = clip_row(3u);
    return array<vec4<f32>, 4>(
        normalize_plane(r0 - r.x * r3),
        normalize_plane(r.z * r3 - r0),
        normalize_plane(r1 - r.y * r3),
        normalize_plane(r.w * r3 - r1),
    );
}

fn cull_light(l: Light) -> CullLight {
    var out: CullLight;
    out.center = (frame.view_from_world * vec4<f32>(l.position, 1.0)).xyz;
    out.radius = l.radius;
    out.slack = cull.slack * (length(out.center) + l.radius);
    // The cone test applies to spots narrower than a hemisphere; wider ones use the sphere.
    out.is_cone = light_shape(l) == LIGHT_KIND_SPOT && l.cos_outer > CONE_MIN_COS;
    out.axis = (frame.view_from_world * vec4<f32>(l.direction, 0.0)).xyz;
    out.tan_outer = sqrt(max(1.0 - l.cos_outer * l.cos_outer, 0.0)) / max(l.cos_outer, CONE_MIN_COS);
    return out;
}

// Whether the light's influence lies entirely outside the plane: its sphere, and for a spot
// also the cone of height `radius` (which contains the spot's sector) are tested; either
// being outside is enough.
fn outside_plane(p: vec4<f32>, l: CullLight) -> bool {
    let dc = dot(p.xyz, l.center) + p.w;
    if dc < -(l.radius + l.slack) {
        return true;
    }
    if l.is_cone {
        // Support of the cone (apex, base disk of radius r tan) in direction n.
        let base = dot(p.xyz, l.center + l.axis * l.radius) + p.w;
        let n_perp = p.xyz - dot(p.xyz, l.axis) * l.axis;
        let reach = max(dc, base + l.radius * l.tan_outer * length(n_perp));
        return reach < -l.slack;
    }
    return false;
}

// Depth cell in [0, 31] of linear depth d in a tile spanning [dmin, dmin + 32 / scale].
fn depth_cell(d: f32, dmin: f32, scale: f32) -> u32 {
    return u32(clamp(floor((d - dmin) * scale), 0.0, 31.0));
}

// Scale of depth_cell for a tile: 32 / (dmax - dmin), or 0 for a flat tile (one cell).
fn depth_cell_scale(t: TileDepth) -> f32 {
    return select(0.0, 32.0 / (t.dmax - t.dmin), t.dmax > t.dmin);
}

// Bits lo..=hi of a 32-bit mask.
fn bit_range(lo: u32, hi: u32) -> u32 {
    return (0xffffffffu >> (31u - hi)) & (0xffffffffu << lo);
}

// The 2.5D mask of a light's depth extent in a tile.
fn light_depth_mask(l: CullLight, t: TileDepth) -> u32 {
    let scale = depth_cell_scale(t);
    let lo = depth_cell(-l.center.z - l.radius - l.slack, t.dmin, scale);
    let hi = depth_cell(-l.center.z + l.radius + l.slack, t.dmin, scale);
    return bit_range(lo, hi);
}

// The view-space box of tile `tile`'s frustum between its depth bounds: the bounds of its 8
// corners (each coordinate of a point of the frustum is bilinear in its NDC coordinate and its
// depth, so the corners bound it). (lo, hi).
fn tile_box(tile: vec2<u32>, t: TileDepth) -> array<vec3<f32>, 2> {
    let r = tile_ndc(tile);
    var lo = vec3<f32>(3.4e38);
    var hi = vec3<f32>(-3.4e38);
    for (var k = 0u; k < 8u; k++) {
        let ndc = vec2<f32>(select(r.x, r.z, (k & 1u) != 0u), select(r.y, r.w, (k & 2u) != 0u));
        let q = view_point(ndc, -select(t.dmin, t.dmax, (k & 4u) != 0u));
        lo = min(lo, q);
        hi = max(hi, q);
    }
    return array<vec3<f32>, 2>(lo, hi);
}

// Whether the sphere of centre c and radius r (slack included) meets the box: the distance from
// its centre to the box's nearest point.
fn sphere_meets_box(c: vec3<f32>, r: f32, b: array<vec3<f32>, 2>) -> bool {
    let d = clamp(c, b[0], b[1]) - c;
    return dot(d, d) <= r * r;
}

// Whether tile tests take the box test (CULL_FLAG_TILE_BOX).
fn tile_boxes() -> bool {
    return (cull.flags & CULL_FLAG_TILE_BOX) != 0u;
}

// The tile's box for the box test (tile_box) where it applies, a placeholder otherwise: computed
// once a tile, before its lights are tested.
fn tile_test_box(tile: vec2<u32>, t: TileDepth) -> array<vec3<f32>, 2> {
    if tile_boxes() && t.covered != 0u {
        return tile_box(tile, t);
    }
    return array<vec3<f32>, 2>(vec3<f32>(0.0), vec3<f32>(0.0));
}

// tile_keeps without its box test.
fn tile_keeps_planes(l: CullLight, planes: array<vec4<f32>, 4>, t: TileDepth) -> bool {
    if t.covered == 0u {
        return false;
    }
    // Written out, not a loop: a dynamically indexed array may go to local memory.
    if outside_plane(planes[0], l) || outside_plane(planes[1], l) || outside_plane(planes[2], l) || outside_plane(planes[3], l) {
        return false;
    }
    return depth_keeps(l, t);
}

// Whether a light may reach any covered pixel of a tile: the tile frustum between the tile's
// depth bounds, with CULL_FLAG_DEPTH_MASK the 2.5D masks, and with CULL_FLAG_TILE_BOX the light's
// sphere against the frustum's view-space box `b` (tile_test_box): the planes test a sphere as
// if it were a cube, and a tile's frustum is narrow beside a light, so the box test cuts the
// lights that reach only the cube's corners (decided last: only for the lights the planes keep).
fn tile_keeps(l: CullLight, planes: array<vec4<f32>, 4>, b: array<vec3<f32>, 2>, t: TileDepth) -> bool {
    return tile_keeps_planes(l, planes, t) && (!tile_boxes() || sphere_meets_box(l.center, l.radius + l.slack, b));
}

// tile_keeps with the box computed only where the planes keep the light (a thread testing one
// light against many tiles: tiled scatter).
fn tile_keeps_at(l: CullLight, tile: vec2<u32>, planes: array<vec4<f32>, 4>, t: TileDepth) -> bool {
    return tile_keeps_planes(l, planes, t) && (!tile_boxes() || sphere_meets_box(l.center, l.radius + l.slack, tile_box(tile, t)));
}

// The depth part of tile_keeps: the tile's depth bounds as planes (-z >= dmin and -z <= dmax),
// and with CULL_FLAG_DEPTH_MASK the 2.5D masks.
fn depth_keeps(l: CullLight, t: TileDepth) -> bool {
    if outside_plane(vec4<f32>(0.0, 0.0, -1.0, -t.dmin), l) || outside_plane(vec4<f32>(0.0, 0.0, 1.0, t.dmax), l) {
        return false;
    }
    if (cull.flags & CULL_FLAG_DEPTH_MASK) != 0u {
        return (light_depth_mask(l, t) & t.mask) != 0u;
    }
    return true;
}

// A light's depth extent for depth_keeps, computed once a light (gather's lines path):
// (lo, hi, sphere lo, sphere hi). A tile's depth planes keep the light when dmin <= hi and
// dmax >= lo: the sphere's extent along z, narrowed by the cone's for a spot (outside_plane with
// the planes' normals (0, 0, -1) and (0, 0, 1), solved for dmin and dmax). Only rounding
// differs from outside_plane's, far inside the slack's borderline band (cpu::BORDER). The
// sphere's extent, the same floats as light_depth_mask's, gives the 2.5D mask.
fn light_depth_extent(l: CullLight) -> vec4<f32> {
    let s_lo = -l.center.z - l.radius - l.slack;
    let s_hi = -l.center.z + l.radius + l.slack;
    var lo = s_lo;
    var hi = s_hi;
    if l.is_cone {
        let n_perp = length(vec3<f32>(0.0, 0.0, 1.0) - l.axis.z * l.axis);
        let spread = l.radius * l.tan_outer * n_perp;
        hi = min(hi, max(-l.center.z, -(l.center.z + l.axis.z * l.radius) + spread) + l.slack);
        lo = max(lo, -max(l.center.z, l.center.z + l.axis.z * l.radius + spread) - l.slack);
    }
    return vec4<f32>(lo, hi, s_lo, s_hi);
}

// depth_keeps over a light's depth extent (light_depth_extent).
fn extent_keeps(e: vec4<f32>, t: TileDepth) -> bool {
    if t.dmin > e.y || t.dmax < e.x {
        return false;
    }
    if (cull.flags & CULL_FLAG_DEPTH_MASK) != 0u {
        let scale = depth_cell_scale(t);
        return (bit_range(depth_cell(e.z, t.dmin, scale), depth_cell(e.w, t.dmin, scale)) & t.mask) != 0u;
    }
    return true;
}

// Depth bin of linear depth d (layout::ZBINS): monotone in d; every depth in bin 0 where the
// near plane is not in front of the eye.
fn zbin(d: f32) -> u32 {
    if !(cull.near > 0.0) {
        return 0u;
    }
    return min((bitcast<u32>(max(d, cull.near)) - bitcast<u32>(cull.near)) >> ZBIN_SHIFT, ZBINS - 1u);
}

// Tile lines (gather's and 2.5D's lines path): line c < tiles_x is column c of tiles, line
// tiles_x + r row r, and line tiles_x + tiles_y + b depth bin b (zbin). A tile's side planes
// 0 and 1 depend only on its column and 2 and 3 only on its row (tile_ndc), so a column's or
// row's two planes are those of each of its tiles, the same floats.
fn line_planes(line: u32) -> array<vec4<f32>, 2> {
    if line < cull.tiles_x {
        let p = tile_side_planes(vec2<u32>(line, 0u));
        return array<vec4<f32>, 2>(p[0], p[1]);
    }
    let p = tile_side_planes(vec2<u32>(0u, line - cull.tiles_x));
    return array<vec4<f32>, 2>(p[2], p[3]);
}

// Words of a tile's mask in the tile masks (tile_masks.wgsl): two a batch of 64 lights.
fn mask_words() -> u32 {
    return (cull.light_count + 63u) / 64u * 2u;
}

// A pixel's nearest and farthest covered depth (NDC) and how many of its samples are covered,
// as the depth input (depth_input*.wgsl) gives it (depth_span); (1, 0, 0) where none is.
struct DepthSpan {
    near: f32,
    far: f32,
    covered: u32,
}

// Depth slice in [0, slices - 1] of linear depth d.
fn depth_slice(d: f32) -> u32 {
    var s: f32;
    if cull.slicing == SLICING_EXPONENTIAL {
        s = floor(log(max(d, cull.near) / cull.near) * cull.slice_scale);
    } else {
        s = floor((d - cull.near) * cull.slice_scale);
    }
    return u32(clamp(s, 0.0, f32(cull.slices - 1u)));
}

// The near boundary (view depth) of slice s >= 1: where depth_slice starts placing depths in s.
fn slice_edge(s: u32) -> f32 {
    if cull.slicing == SLICING_EXPONENTIAL {
        return cull.near * exp(f32(s) / cull.slice_scale);
    }
    return cull.near + f32(s) / cull.slice_scale;
}

// The part of slice s (s0 <= s <= s1) a pixel holds whose covered samples lie between linear
// depths d0 <= d1, in slices s0 = depth_slice(d0) to s1 = depth_slice(d1): [d0, d1] within the
// slice. With MSAA a fragment is looked up at its centroid, whose depth lies between its covered
// samples' depths, so every slice from the nearest sample's to the farthest's may be looked up,
// over that part of the pixel's depths (the slice's boundaries widened by 1e-4 of their depth:
// depth_slice may place a depth a few ulps past one). With one sample, [d0, d1] is one depth.
fn pixel_slice_range(s: u32, s0: u32, s1: u32, d0: f32, d1: f32) -> vec2<f32> {
    var r = vec2<f32>(d0, d1);
    if s > s0 {
        r.x = max(d0, slice_edge(s) * (1.0 - 1e-4));
    }
    if s < s1 {
        r.y = min(d1, slice_edge(s + 1u) * (1.0 + 1e-4));
    }
    return r;
}

// The bin of pixel `pixel` whose depth buffer value is `z` (NDC): its tile, and for clusters
// the depth slice of its linear depth.
fn bin_of(pixel: vec2<u32>, z: f32) -> u32 {
    let tile = pixel / cull.tile_size;
    let t = tile.y * cull.tiles_x + tile.x;
    if cull.slices <= 1u {
        return t;
    }
    return depth_slice(linear_depth(z)) * cull.tiles_x * cull.tiles_y + t;
}

// Inclusive tile rectangle (x0, y0, x1, y1) that may hold the light, or x0 > x1 when none.
// Every covered pixel lies at least the near plane's depth away, so only the part of a light's
// view-space box beyond the near plane matters: a light wholly nearer reaches no visible pixel
// (none), and a box crossing the near plane is cut there (still a box). Its corners, all in
// front of the eye, are projected one by one; their rectangle contains the projection of the
// sphere's visible part. (Only a degenerate camera leaves a corner at w <= 0: then the whole
// screen is a candidate, and the plane tests decide.)
//
// With CULL_FLAG_SPHERE_BOUNDS and a perspective without skew (sphere_bounds_apply), the
// rectangle holds the exact projection of the sphere's part beyond the near plane instead
// (sphere_axis_bounds): a box's corners project up to 1.4 times as wide on each axis for a
// sphere near the camera or the screen's edge.
fn light_tiles(l: CullLight) -> vec4<i32> {
    let full = vec4<i32>(0, 0, i32(cull.tiles_x) - 1, i32(cull.tiles_y) - 1);
    let r = l.radius + l.slack;
    let near = linear_depth(0.0);
    if -l.center.z + r < near {
        return vec4<i32>(0, 0, -1, -1);
    }
    var lo = vec2<f32>(1e30);
    var hi = vec2<f32>(-1e30);
    if sphere_bounds_apply() {
        let bx = sphere_axis_bounds(l.center.x, l.center.z, r, -near);
        let by = sphere_axis_bounds(l.center.y, l.center.z, r, -near);
        let x0 = frame.clip_from_view * vec4<f32>(bx.x, 0.0, bx.y, 1.0);
        let x1 = frame.clip_from_view * vec4<f32>(bx.z, 0.0, bx.w, 1.0);
        let y0 = frame.clip_from_view * vec4<f32>(0.0, by.x, by.y, 1.0);
        let y1 = frame.clip_from_view * vec4<f32>(0.0, by.z, by.w, 1.0);
        if min(min(x0.w, x1.w), min(y0.w, y1.w)) <= 1e-6 {
            return full;
        }
        lo = vec2<f32>(min(x0.x / x0.w, x1.x / x1.w), min(y0.y / y0.w, y1.y / y1.w));
        hi = vec2<f32>(max(x0.x / x0.w, x1.x / x1.w), max(y0.y / y0.w, y1.y / y1.w));
        return tiles_of_ndc(lo, hi, full);
    }
    for (var k = 0u; k < 8u; k++) {
        var corner = l.center + r * vec3<f32>(select(-1.0, 1.0, (k & 1u) != 0u), select(-1.0, 1.0, (k & 2u) != 0u), select(-1.0, 1.0, (k & 4u) != 0u));
        corner.z = min(corner.z, -near);
        let c = frame.clip_from_view * vec4<f32>(corner, 1.0);
        if c.w <= 1e-6 {
            return full;
        }
        let ndc = c.xy / c.w;
        lo = min(lo, ndc);
        hi = max(hi, ndc);
    }
    return tiles_of_ndc(lo, hi, full);
}

// Whether light_tiles takes the sphere's exact bounds: CULL_FLAG_SPHERE_BOUNDS and a
// perspective whose NDC x depends on view x and z only, NDC y on y and z, and w = -z.
fn sphere_bounds_apply() -> bool {
    let m = frame.clip_from_view;
    return (cull.flags & CULL_FLAG_SPHERE_BOUNDS) != 0u && m[0][1] == 0.0 && m[1][0] == 0.0 && m[0][3] == 0.0 && m[1][3] == 0.0 && m[2][3] == -1.0 && m[3][3] == 0.0;
}

// Mara and McGuire, "2D Polyhedral Bounds of a Clipped, Perspective-Projected 3D Sphere"
// (JCGT 2013): in the plane of one view axis `a` and z, the two points of the sphere (center
// (a, z), radius r) whose projections bound it on that axis, its tangents from the eye or,
// where a tangent point lies nearer than the near plane (z = near_z < 0) or the eye is inside
// the sphere, the ends of its chord on the near plane. Returns (a0, z0, a1, z1).
fn sphere_axis_bounds(a: f32, z: f32, r: f32, near_z: f32) -> vec4<f32> {
    let c = vec2<f32>(a, z);
    let t2 = dot(c, c) - r * r;
    let inside = t2 <= 0.0;
    var v = vec2<f32>(0.0);
    if !inside {
        v = vec2<f32>(sqrt(t2), r) / length(c);
    }
    let clip = c.y + r >= near_z;
    // The first bound is the lower one (c turned by -θ, then the chord's lower end): the signs
    // of Mara and McGuire's listing, as a's projection a / -z grows with the angle from -z.
    var k = -sqrt(max(r * r - (c.y - near_z) * (c.y - near_z), 0.0));
    var b = array<vec2<f32>, 2>(c, c);
    for (var i = 0u; i < 2u; i++) {
        if !inside {
            b[i] = vec2<f32>(v.x * c.x + v.y * c.y, v.x * c.y - v.y * c.x) * v.x;
        }
        if clip && (inside || b[i].y > near_z) {
            b[i] = vec2<f32>(c.x + k, near_z);
        }
        v.y = -v.y;
        k = -k;
    }
    return vec4<f32>(b[0], b[1]);
}

// The inclusive tile rectangle of the NDC rectangle lo..hi, within `full`.
fn tiles_of_ndc(lo: vec2<f32>, hi: vec2<f32>, full: vec4<i32>) -> vec4<i32> {
    // NDC to pixels (y flips), one pixel of margin for rounding, then tiles.
    let px0 = (lo.x + 1.0) * 0.5 * frame.viewport.x - 1.0;
    let px1 = (hi.x + 1.0) * 0.5 * frame.viewport.x + 1.0;
    let py0 = (1.0 - hi.y) * 0.5 * frame.viewport.y - 1.0;
    let py1 = (1.0 - lo.y) * 0.5 * frame.viewport.y + 1.0;
    let ts = f32(cull.tile_size);
    let t0 = vec2<i32>(clamp(floor(vec2<f32>(px0, py0) / ts), vec2<f32>(-1.0), vec2<f32>(1e6)));
    let t1 = vec2<i32>(clamp(floor(vec2<f32>(px1, py1) / ts), vec2<f32>(-1.0), vec2<f32>(1e6)));
    return vec4<i32>(max(t0, full.xy), min(t1, full.zw));
}
