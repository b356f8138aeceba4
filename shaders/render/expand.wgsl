// shade.deferred_expand: with MSAA over transparent surfaces, deferred lighting's image (one
// value a pixel, each pixel's samples already averaged) written to every sample of a
// multisampled target, one triangle over the screen, so that shade.forward_transparent can blend
// the glass sample by sample and resolve. Where a pixel holds both a glass edge and an opaque
// edge, its opaque samples are blended as their average (the reference blends each its own).
@group(0) @binding(0) var lit: texture_2d<f32>;

@fragment
fn fs_expand(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(lit, vec2<u32>(pos.xy), 0);
}
