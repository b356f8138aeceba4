// The surface deferred lighting shades at a pixel (or a sample, with MSAA), and how the
// visibility buffer's lighting finds it: shared by shade.deferred over one sample a pixel
// (deferred.wgsl) and over several (deferred_msaa.wgsl).

// The scene's vertices (GpuVertex: position, normal, material; 7 words each) and indices, which
// the visibility buffer's lighting interpolates (bound, unread, for the G-buffer's).
@group(2) @binding(4) var<storage, read> vis_vertices: array<u32>;
@group(2) @binding(5) var<storage, read> vis_indices: array<u32>;

// VISIBILITY: lighting over a visibility buffer (visibility.wgsl) in place of a G-buffer:
// `gb_material` holds each pixel's (each sample's) triangle id (its index plus one, 0 for
// none), and a pixel's surface is its triangle's, interpolated at the pixel's ray
// (`visibility_surface`).
override VISIBILITY: bool = false;

// A covered pixel's surface point (rebuilt from the view depth, or stored), normal, view
// direction and material.
struct Surface {
    p: vec3<f32>,
    n: vec3<f32>,
    v: vec3<f32>,
    m: Material,
}

// Vertex i's position, normal and material (GpuVertex).
fn vis_position(i: u32) -> vec3<f32> {
    return bitcast<vec3<f32>>(vec3<u32>(vis_vertices[VERTEX_WORDS * i], vis_vertices[VERTEX_WORDS * i + 1u], vis_vertices[VERTEX_WORDS * i + 2u]));
}

fn vis_normal(i: u32) -> vec3<f32> {
    return bitcast<vec3<f32>>(vec3<u32>(vis_vertices[VERTEX_WORDS * i + 3u], vis_vertices[VERTEX_WORDS * i + 4u], vis_vertices[VERTEX_WORDS * i + 5u]));
}

fn vis_material(i: u32) -> u32 {
    return vis_vertices[VERTEX_WORDS * i + 6u];
}

// The surface of triangle `tri` seen through the point `ndc` of the image: the point where the
// pixel's ray meets the triangle's plane (Moller and Trumbore 1997), the normal interpolated
// there with the same barycentrics (what the rasteriser's perspective-correct interpolation
// computes at the pixel centre) and turned towards the viewer, and the material of its first
// vertex (the provoking vertex, whose flat attribute the G-buffer pass writes). The ray runs
// through the view-space points at z = -1 and -2, for either projection.
fn visibility_surface(ndc: vec2<f32>, tri: u32) -> Surface {
    let i0 = vis_indices[3u * tri];
    let i1 = vis_indices[3u * tri + 1u];
    let i2 = vis_indices[3u * tri + 2u];
    let p0 = vis_position(i0);
    let e1 = vis_position(i1) - p0;
    let e2 = vis_position(i2) - p0;
    let o = (frame.world_from_view * vec4<f32>(view_point(ndc, -1.0), 1.0)).xyz;
    let d = (frame.world_from_view * vec4<f32>(view_point(ndc, -2.0), 1.0)).xyz - o;
    let q = cross(d, e2);
    // A triangle the ray runs along (a sliver seen edge on, which the rasteriser can still
    // cover a pixel centre of) gives no intersection: its first vertex stands in.
    let det = dot(e1, q);
    let inv = select(0.0, 1.0 / det, det != 0.0);
    let s = o - p0;
    let b1 = dot(s, q) * inv;
    let r = cross(s, e1);
    let b2 = dot(d, r) * inv;
    let p = p0 + b1 * e1 + b2 * e2;
    let v = view_dir(p);
    let n = normalize((1.0 - b1 - b2) * vis_normal(i0) + b1 * vis_normal(i1) + b2 * vis_normal(i2));
    return Surface(p, facing_normal(n, v), v, materials[vis_material(i0)]);
}
