// shadow_rays.trace: one any-hit shadow ray a thread through the scene's BVH (common/bvh.wgsl,
// BVH_GROUP 1): segment i from rays[2i] to rays[2i + 1] (xyz), its answer in blocked[i]
// (1: blocked). manylights_gpu::bvh::ShadowRays runs it: the BVH's test against its f64
// oracle, and the rate of shadow rays a second.

@group(0) @binding(0) var<storage, read> rays: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> blocked: array<u32>;
// x: rays; y: threads in one row of the dispatch grid.
@group(0) @binding(2) var<uniform> ray_params: vec4<u32>;

@compute @workgroup_size(64)
fn trace(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * ray_params.y;
    if i >= ray_params.x {
        return;
    }
    blocked[i] = u32(bvh_blocked(rays[2u * i].xyz, rays[2u * i + 1u].xyz));
}
