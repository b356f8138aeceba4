// occlusion.occluder_test: query i (a light in queries[9i].xyz, its cell's corners in the eight
// after it, the margin in queries[9i].w) against every occluder; hidden[i] = 1 + the first that
// hides the light from the cell, 0 where none does (manylights_cull::occlusion::OccluderTest).

@group(0) @binding(0) var<storage, read> queries: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> occluders: array<Occluder>;
@group(0) @binding(2) var<storage, read_write> hidden: array<u32>;
// x: queries; y: occluders.
@group(0) @binding(3) var<uniform> test_params: vec4<u32>;

@compute @workgroup_size(64)
fn occluder_test(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= test_params.x {
        return;
    }
    var cell: array<vec3<f32>, 8>;
    for (var c = 0u; c < 8u; c++) {
        cell[c] = queries[9u * i + 1u + c].xyz;
    }
    let light = queries[9u * i];
    var found = 0u;
    for (var k = 0u; k < test_params.y; k++) {
        if occluder_hides(occluders[k], light.xyz, cell, light.w) {
            found = k + 1u;
            break;
        }
    }
    hidden[i] = found;
}
