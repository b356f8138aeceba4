// shade.visibility_resolve: the keys of shade.visibility_compute into an id (R32Uint) and an
// NDC depth (R32Float, 1 where nothing is drawn) a pixel.

// The keys as two words each (low word first): no 64-bit operation here.
@group(1) @binding(0) var<storage, read> vr_keys: array<vec2<u32>>;
@group(1) @binding(1) var vr_ids: texture_storage_2d<r32uint, write>;
@group(1) @binding(2) var vr_depth: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8)
fn vis_resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(gid.xy >= size) {
        return;
    }
    let k = vr_keys[gid.y * size.x + gid.x];
    var depth = 1.0;
    var id = 0u;
    if k.y != 0u {
        depth = bitcast<f32>(0xffffffffu - k.y);
        id = 0xffffffffu - k.x;
    }
    textureStore(vr_ids, gid.xy, vec4<u32>(id, 0u, 0u, 0u));
    textureStore(vr_depth, gid.xy, vec4<f32>(depth, 0.0, 0.0, 0.0));
}
