//! The culling geometry on the CPU: an f32 mirror of `shaders/cull/common/geometry.wgsl`, function for
//! function and in the same order of operations, used by the CPU oracles. GPUs may fuse
//! multiply-adds or round divisions differently, so a decision within a hair of its boundary can
//! differ; the oracles detect such borderline decisions (see [`crate::cpu`]) instead of hiding
//! them.

use glam::{Mat4, Vec2, Vec3, Vec4, Vec4Swizzles};
use manylights_gpu::layout::{GpuFrame, GpuLight, LIGHT_KIND_SPOT};

use crate::layout::{
    CONE_MIN_COS, CULL_FLAG_DEPTH_MASK, CULL_FLAG_SPHERE_BOUNDS, CULL_FLAG_TILE_BOX, GpuCullParams,
    GpuTileDepth, SLICING_EXPONENTIAL,
};

fn row(m: &Mat4, i: usize) -> Vec4 {
    m.row(i)
}

/// WGSL `ordered_bits`: a float's bits mapped so that unsigned order is the float order.
pub fn ordered_bits(x: f32) -> u32 {
    let b = x.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// WGSL `from_ordered_bits`.
pub fn from_ordered_bits(u: u32) -> f32 {
    f32::from_bits(if u & 0x8000_0000 != 0 {
        u & 0x7fff_ffff
    } else {
        !u
    })
}

/// WGSL `linear_depth`.
pub fn linear_depth(frame: &GpuFrame, z: f32) -> f32 {
    let m = &frame.clip_from_view;
    let (a, b, c, d) = (m.z_axis.z, m.w_axis.z, m.z_axis.w, m.w_axis.w);
    -(b - d * z) / (c * z - a)
}

/// WGSL `view_point`: the view-space point at NDC `ndc` and view-space z `z`.
pub fn view_point(frame: &GpuFrame, ndc: Vec2, z: f32) -> Vec3 {
    let m = &frame.clip_from_view;
    let w = m.z_axis.w * z + m.w_axis.w;
    Vec3::new(
        (ndc.x * w - m.z_axis.x * z - m.w_axis.x) / m.x_axis.x,
        (ndc.y * w - m.z_axis.y * z - m.w_axis.y) / m.y_axis.y,
        z,
    )
}

/// WGSL `tile_box`: the view-space box (lo, hi) of tile `tile`'s frustum between its depth
/// bounds.
pub fn tile_box(
    frame: &GpuFrame,
    p: &GpuCullParams,
    tile: [u32; 2],
    t: &GpuTileDepth,
) -> [Vec3; 2] {
    let r = tile_ndc(frame, p, tile);
    let (mut lo, mut hi) = (Vec3::splat(3.4e38), Vec3::splat(-3.4e38));
    for k in 0..8u32 {
        let x = if k & 1 != 0 { r.z } else { r.x };
        let y = if k & 2 != 0 { r.w } else { r.y };
        let d = if k & 4 != 0 { t.dmax } else { t.dmin };
        let q = view_point(frame, Vec2::new(x, y), -d);
        lo = lo.min(q);
        hi = hi.max(q);
    }
    [lo, hi]
}

/// WGSL `sphere_meets_box`.
pub fn sphere_meets_box(c: Vec3, r: f32, b: &[Vec3; 2]) -> bool {
    let d = c.clamp(b[0], b[1]) - c;
    d.dot(d) <= r * r
}

/// WGSL `tile_ndc`: the NDC rectangle of tile `tile`.
pub fn tile_ndc(frame: &GpuFrame, p: &GpuCullParams, tile: [u32; 2]) -> Vec4 {
    let size = p.tile_size;
    let (w, h) = (frame.viewport.x as u32, frame.viewport.y as u32);
    let px0 = (tile[0] * size) as f32;
    let px1 = ((tile[0] + 1) * size).min(w) as f32;
    let py0 = (tile[1] * size) as f32;
    let py1 = ((tile[1] + 1) * size).min(h) as f32;
    Vec4::new(
        px0 * frame.viewport.z * 2.0 - 1.0,
        1.0 - py1 * frame.viewport.w * 2.0,
        px1 * frame.viewport.z * 2.0 - 1.0,
        1.0 - py0 * frame.viewport.w * 2.0,
    )
}

fn normalize_plane(p: Vec4) -> Vec4 {
    p / p.xyz().length()
}

/// WGSL `tile_side_planes`.
pub fn tile_side_planes(frame: &GpuFrame, p: &GpuCullParams, tile: [u32; 2]) -> [Vec4; 4] {
    let r = tile_ndc(frame, p, tile);
    let m = &frame.clip_from_view;
    let (r0, r1, r3) = (row(m, 0), row(m, 1), row(m, 3));
    [
        normalize_plane(r0 - r.x * r3),
        normalize_plane(r.z * r3 - r0),
        normalize_plane(r1 - r.y * r3),
        normalize_plane(r.w * r3 - r1),
    ]
}

/// WGSL `light_depth_extent`: (lo, hi, sphere lo, sphere hi).
pub fn light_depth_extent(l: &CullLight) -> [f32; 4] {
    let s_lo = -l.center.z - l.radius - l.slack;
    let s_hi = -l.center.z + l.radius + l.slack;
    let (mut lo, mut hi) = (s_lo, s_hi);
    if l.is_cone {
        let n_perp = (Vec3::Z - l.axis.z * l.axis).length();
        let spread = l.radius * l.tan_outer * n_perp;
        hi = hi.min((-l.center.z).max(-(l.center.z + l.axis.z * l.radius) + spread) + l.slack);
        lo = lo.max(-(l.center.z.max(l.center.z + l.axis.z * l.radius + spread)) - l.slack);
    }
    [lo, hi, s_lo, s_hi]
}

/// WGSL `zbin`: the depth bin of linear depth `d` ([`crate::layout::ZBINS`]).
pub fn zbin(p: &GpuCullParams, d: f32) -> u32 {
    // A NaN near plane also gives bin 0, as in the WGSL.
    if p.near.is_nan() || p.near <= 0.0 {
        return 0;
    }
    ((d.max(p.near).to_bits() - p.near.to_bits()) >> crate::layout::ZBIN_SHIFT)
        .min(crate::layout::ZBINS - 1)
}

/// WGSL `line_planes`: the two side planes of tile line `line` (columns, then rows).
pub fn line_planes(frame: &GpuFrame, p: &GpuCullParams, line: u32) -> [Vec4; 2] {
    if line < p.tiles_x {
        let [a, b, _, _] = tile_side_planes(frame, p, [line, 0]);
        [a, b]
    } else {
        let [_, _, a, b] = tile_side_planes(frame, p, [0, line - p.tiles_x]);
        [a, b]
    }
}

/// WGSL `CullLight`.
#[derive(Clone, Copy, Debug)]
pub struct CullLight {
    /// View-space centre.
    pub center: Vec3,
    /// Radius.
    pub radius: f32,
    /// Slack in view-space units.
    pub slack: f32,
    /// Whether the cone test applies.
    pub is_cone: bool,
    /// View-space spot axis.
    pub axis: Vec3,
    /// tan of the outer half-angle.
    pub tan_outer: f32,
}

impl CullLight {
    /// WGSL `cull_light`, with the relative slack given explicitly.
    pub fn new(frame: &GpuFrame, l: &GpuLight, slack: f32) -> Self {
        let center = (frame.view_from_world * l.position.extend(1.0)).xyz();
        Self {
            center,
            radius: l.radius,
            slack: slack * (center.length() + l.radius),
            is_cone: l.shape() == LIGHT_KIND_SPOT && l.cos_outer > CONE_MIN_COS,
            axis: (frame.view_from_world * l.direction.extend(0.0)).xyz(),
            tan_outer: (1.0 - l.cos_outer * l.cos_outer).max(0.0).sqrt()
                / l.cos_outer.max(CONE_MIN_COS),
        }
    }
}

/// WGSL `outside_plane`.
pub fn outside_plane(p: Vec4, l: &CullLight) -> bool {
    let dc = p.xyz().dot(l.center) + p.w;
    if dc < -(l.radius + l.slack) {
        return true;
    }
    if l.is_cone {
        let base = p.xyz().dot(l.center + l.axis * l.radius) + p.w;
        let n_perp = p.xyz() - p.xyz().dot(l.axis) * l.axis;
        let reach = dc.max(base + l.radius * l.tan_outer * n_perp.length());
        return reach < -l.slack;
    }
    false
}

/// WGSL `depth_cell`.
pub fn depth_cell(d: f32, dmin: f32, scale: f32) -> u32 {
    ((d - dmin) * scale).floor().clamp(0.0, 31.0) as u32
}

/// WGSL `depth_cell_scale`.
pub fn depth_cell_scale(t: &GpuTileDepth) -> f32 {
    if t.dmax > t.dmin {
        32.0 / (t.dmax - t.dmin)
    } else {
        0.0
    }
}

/// WGSL `bit_range`.
pub fn bit_range(lo: u32, hi: u32) -> u32 {
    (u32::MAX >> (31 - hi)) & (u32::MAX << lo)
}

/// WGSL `light_depth_mask`.
pub fn light_depth_mask(l: &CullLight, t: &GpuTileDepth) -> u32 {
    let scale = depth_cell_scale(t);
    let lo = depth_cell(-l.center.z - l.radius - l.slack, t.dmin, scale);
    let hi = depth_cell(-l.center.z + l.radius + l.slack, t.dmin, scale);
    bit_range(lo, hi)
}

/// WGSL `tile_keeps`, with the tile's box ([`tile_box`]) computed by the caller.
pub fn tile_keeps(
    p: &GpuCullParams,
    l: &CullLight,
    planes: &[Vec4; 4],
    bx: &[Vec3; 2],
    t: &GpuTileDepth,
) -> bool {
    if t.covered == 0 || planes.iter().any(|&pl| outside_plane(pl, l)) {
        return false;
    }
    if !depth_keeps(p, l, t) {
        return false;
    }
    p.flags & CULL_FLAG_TILE_BOX == 0 || sphere_meets_box(l.center, l.radius + l.slack, bx)
}

/// WGSL `depth_keeps`: the depth part of [`tile_keeps`].
pub fn depth_keeps(p: &GpuCullParams, l: &CullLight, t: &GpuTileDepth) -> bool {
    if outside_plane(Vec4::new(0.0, 0.0, -1.0, -t.dmin), l)
        || outside_plane(Vec4::new(0.0, 0.0, 1.0, t.dmax), l)
    {
        return false;
    }
    if p.flags & CULL_FLAG_DEPTH_MASK != 0 {
        return light_depth_mask(l, t) & t.mask != 0;
    }
    true
}

/// WGSL `depth_slice`, and the unclamped, unfloored slice coordinate (for borderline checks).
pub fn depth_slice(p: &GpuCullParams, d: f32) -> u32 {
    slice_coord(p, d).floor().clamp(0.0, (p.slices - 1) as f32) as u32
}

/// The slice coordinate before `floor`.
pub fn slice_coord(p: &GpuCullParams, d: f32) -> f32 {
    if p.slicing == SLICING_EXPONENTIAL {
        (d.max(p.near) / p.near).ln() * p.slice_scale
    } else {
        (d - p.near) * p.slice_scale
    }
}

/// WGSL `slice_edge`: the near boundary of slice `s` >= 1.
pub fn slice_edge(p: &GpuCullParams, s: u32) -> f32 {
    if p.slicing == SLICING_EXPONENTIAL {
        p.near * (s as f32 / p.slice_scale).exp()
    } else {
        p.near + s as f32 / p.slice_scale
    }
}

/// WGSL `pixel_slice_range`: the part of slice `s` (`s0 <= s <= s1`) a pixel holds whose
/// covered samples lie between linear depths `d0 <= d1`, in slices `s0` to `s1`.
pub fn pixel_slice_range(
    p: &GpuCullParams,
    s: u32,
    [s0, s1]: [u32; 2],
    [d0, d1]: [f32; 2],
) -> [f32; 2] {
    let mut r = [d0, d1];
    if s > s0 {
        r[0] = d0.max(slice_edge(p, s) * (1.0 - 1e-4));
    }
    if s < s1 {
        r[1] = d1.min(slice_edge(p, s + 1) * (1.0 + 1e-4));
    }
    r
}

/// WGSL `bin_of`.
pub fn bin_of(frame: &GpuFrame, p: &GpuCullParams, pixel: [u32; 2], z: f32) -> u32 {
    let t = (pixel[1] / p.tile_size) * p.tiles_x + pixel[0] / p.tile_size;
    if p.slices <= 1 {
        return t;
    }
    depth_slice(p, linear_depth(frame, z)) * p.tiles_x * p.tiles_y + t
}

/// WGSL `light_tiles`: inclusive tile rectangle (x0, y0, x1, y1); empty when x0 > x1.
pub fn light_tiles(frame: &GpuFrame, p: &GpuCullParams, l: &CullLight) -> [i32; 4] {
    let full = [0, 0, p.tiles_x as i32 - 1, p.tiles_y as i32 - 1];
    let r = l.radius + l.slack;
    let near = linear_depth(frame, 0.0);
    if -l.center.z + r < near {
        return [0, 0, -1, -1];
    }
    if sphere_bounds_apply(frame, p) {
        let m = &frame.clip_from_view;
        let [ax0, az0, ax1, az1] = sphere_axis_bounds(l.center.x, l.center.z, r, -near);
        let [ay0, bz0, ay1, bz1] = sphere_axis_bounds(l.center.y, l.center.z, r, -near);
        let x0 = *m * Vec4::new(ax0, 0.0, az0, 1.0);
        let x1 = *m * Vec4::new(ax1, 0.0, az1, 1.0);
        let y0 = *m * Vec4::new(0.0, ay0, bz0, 1.0);
        let y1 = *m * Vec4::new(0.0, ay1, bz1, 1.0);
        if x0.w.min(x1.w).min(y0.w.min(y1.w)) <= 1e-6 {
            return full;
        }
        let lo = Vec2::new(
            (x0.x / x0.w).min(x1.x / x1.w),
            (y0.y / y0.w).min(y1.y / y1.w),
        );
        let hi = Vec2::new(
            (x0.x / x0.w).max(x1.x / x1.w),
            (y0.y / y0.w).max(y1.y / y1.w),
        );
        return tiles_of_ndc(frame, p, lo, hi, full);
    }
    let mut lo = Vec2::splat(1e30);
    let mut hi = Vec2::splat(-1e30);
    for k in 0..8u32 {
        let s = |bit: u32| if k & bit != 0 { 1.0 } else { -1.0 };
        let mut corner = l.center + r * Vec3::new(s(1), s(2), s(4));
        corner.z = corner.z.min(-near);
        let c = frame.clip_from_view * corner.extend(1.0);
        if c.w <= 1e-6 {
            return full;
        }
        let ndc = c.xy() / c.w;
        lo = lo.min(ndc);
        hi = hi.max(ndc);
    }
    tiles_of_ndc(frame, p, lo, hi, full)
}

/// WGSL `sphere_bounds_apply`: `CULL_FLAG_SPHERE_BOUNDS` and a perspective without skew.
pub fn sphere_bounds_apply(frame: &GpuFrame, p: &GpuCullParams) -> bool {
    let m = &frame.clip_from_view;
    p.flags & CULL_FLAG_SPHERE_BOUNDS != 0
        && m.x_axis.y == 0.0
        && m.y_axis.x == 0.0
        && m.x_axis.w == 0.0
        && m.y_axis.w == 0.0
        && m.z_axis.w == -1.0
        && m.w_axis.w == 0.0
}

/// WGSL `sphere_axis_bounds` (Mara and McGuire 2013): in the plane of view axis `a` and z, the
/// two points bounding the projection of the sphere's part beyond the near plane `near_z`:
/// (a0, z0, a1, z1).
pub fn sphere_axis_bounds(a: f32, z: f32, r: f32, near_z: f32) -> [f32; 4] {
    let c = Vec2::new(a, z);
    let t2 = c.dot(c) - r * r;
    let inside = t2 <= 0.0;
    let mut v = if inside {
        Vec2::ZERO
    } else {
        Vec2::new(t2.sqrt(), r) / c.length()
    };
    let clip = c.y + r >= near_z;
    let mut k = -(r * r - (c.y - near_z) * (c.y - near_z)).max(0.0).sqrt();
    let mut b = [c, c];
    for bound in &mut b {
        if !inside {
            *bound = Vec2::new(v.x * c.x + v.y * c.y, v.x * c.y - v.y * c.x) * v.x;
        }
        if clip && (inside || bound.y > near_z) {
            *bound = Vec2::new(c.x + k, near_z);
        }
        v.y = -v.y;
        k = -k;
    }
    [b[0].x, b[0].y, b[1].x, b[1].y]
}

/// WGSL `tiles_of_ndc`: the inclusive tile rectangle of the NDC rectangle `lo..hi`, within
/// `full`.
fn tiles_of_ndc(
    frame: &GpuFrame,
    p: &GpuCullParams,
    lo: Vec2,
    hi: Vec2,
    full: [i32; 4],
) -> [i32; 4] {
    let px0 = (lo.x + 1.0) * 0.5 * frame.viewport.x - 1.0;
    let px1 = (hi.x + 1.0) * 0.5 * frame.viewport.x + 1.0;
    let py0 = (1.0 - hi.y) * 0.5 * frame.viewport.y - 1.0;
    let py1 = (1.0 - lo.y) * 0.5 * frame.viewport.y + 1.0;
    let ts = p.tile_size as f32;
    let t = |v: f32| (v / ts).floor().clamp(-1.0, 1e6) as i32;
    [
        t(px0).max(full[0]),
        t(py0).max(full[1]),
        t(px1).min(full[2]),
        t(py1).min(full[3]),
    ]
}
