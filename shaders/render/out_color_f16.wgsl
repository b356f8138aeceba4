// Deferred lighting's image in 16-bit floats (HdrFormat::F16), in out_color.wgsl's place.
@group(2) @binding(2) var out_color: texture_storage_2d<rgba16float, write>;
