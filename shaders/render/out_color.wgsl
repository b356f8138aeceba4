// Deferred lighting's image (deferred.wgsl, deferred_msaa.wgsl) in 32-bit floats;
// out_color_f16.wgsl takes this file's place for a renderer of HdrFormat::F16.
@group(2) @binding(2) var out_color: texture_storage_2d<rgba32float, write>;
