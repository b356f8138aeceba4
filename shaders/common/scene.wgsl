// The scene's storage buffers, group 0 of every pass (binding 0 is the frame, frame.wgsl).
// Host side: manylights_gpu::GpuScene.

// What the shading model reads of a material. Host mirror: manylights_gpu::layout::GpuMaterial.
struct Material {
    base_color: vec3<f32>,
    // MODEL_* (brdf.wgsl).
    model: u32,
    // Added once a pixel to what the lights reflect.
    emissive: vec3<f32>,
    // 1: opaque; below 1 a transparent surface's blend weight.
    opacity: f32,
    // The model's parameters (manylights_scene::Brdf::params): Blinn-Phong (specular); GGX
    // (metallic, roughness); sheen (sheen colour, roughness); clear coat (metallic, roughness,
    // coat, coat roughness); wrap (w).
    params: vec4<f32>,
}

@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var<storage, read> materials: array<Material>;
// Bindings 3 and 4: the BVH of the opaque triangles that shadow rays walk (bvh.wgsl; a BVH of
// one empty leaf where the scene has none built).
const BVH_GROUP: u32 = 0u;
const BVH_BINDING: u32 = 3u;
