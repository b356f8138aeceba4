// shade.reference_samples, with MSAA after shade.reference (tested `Equal`, shaded at every
// sample: it reads `sample_index`): the reference's image at each sample. A pixel one fragment
// covers entirely (every sample holds the same stored point) keeps that fragment's radiance,
// shaded once at the pixel centre (the centroid of a fragment covering every sample);
// elsewhere (an edge) each sample is lit at its own standard position on its own triangle
// (surface.wgsl's visibility_surface: where the ray through the sample meets the triangle, the
// normal interpolated there). This is what deferred lighting and the visibility buffer compute
// from their surface buffers, and needs no choice the implementation makes: where a
// `centroid` input is evaluated within a partly covered pixel and how a rasteriser splits an
// edge pixel into fragments (llvmpipe shades some edge samples one by one) differ between
// GPUs, and so does a per-sample invocation's `@builtin(position).z` (the H200's is the pixel
// centre's depth: examples/sample_positions.rs) and its `sample` interpolation (llvmpipe's is
// up to a tenth of a pixel off).
// (ShaderDef puts the enable directive before the composed text: a directive comes first.)
enable primitive_index;

@group(1) @binding(0) var fragment_color: texture_multisampled_2d<f32>;
@group(1) @binding(1) var fragment_position: texture_multisampled_2d<f32>;

@fragment @early_depth_test(force)
fn fs_reference_samples(in: VertexOut, @builtin(sample_index) k: u32, @builtin(primitive_index) triangle: u32) -> @location(0) vec4<f32> {
    let pixel = vec2<u32>(in.clip.xy);
    shading_pixel = pixel;
    let samples = textureNumSamples(fragment_position);
    let p0 = textureLoad(fragment_position, pixel, 0);
    var one = p0.w > 0.0;
    for (var j = 1u; j < samples; j++) {
        one = one && all(textureLoad(fragment_position, pixel, j) == p0);
    }
    if one {
        return textureLoad(fragment_color, pixel, k);
    }
    let s = visibility_surface(screen_ndc(vec2<f32>(pixel) + standard_sample_position(samples, k)), triangle);
    return vec4<f32>(shade_all(s.p, s.n, s.v, s.m), 1.0);
}
