//! Every WGSL shader, composed as the crates compose it, parses and validates with naga (no GPU
//! needed); every `.wgsl` file under `shaders/` belongs to some shader; and the host mirrors of
//! the WGSL structs have the same size and member offsets as naga's layout.

use std::collections::BTreeSet;
use std::path::Path;

use std::mem::offset_of;

use manylights_cull::layout::{GpuCullParams, GpuTileDepth};
use manylights_gpu::layout::{GpuFrame, GpuLight, GpuMaterial, GpuVertex};
use manylights_gpu::motion::MotionParams;
use manylights_gpu::shaders::ShaderDef;
use manylights_gpu::stochastic::GpuStochasticParams;

fn all_shaders() -> Vec<ShaderDef> {
    manylights_gpu::shaders::SHADERS
        .iter()
        .chain(manylights_shade::SHADERS)
        .chain(manylights_cull::shaders::SHADERS)
        .copied()
        .collect()
}

fn validate(def: &ShaderDef) -> naga::Module {
    validate_source(def.name, &def.compose())
}

/// The WGSL `src` of shader `name`, parsed and validated.
fn validate_source(name: &str, src: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(src)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(src)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(src)));
    module
}

#[test]
fn every_shader_validates_with_naga() {
    for def in all_shaders() {
        let m = validate(&def);
        assert!(
            !m.entry_points.is_empty(),
            "{} has no entry point",
            def.name
        );
    }
}

/// Every shader that reads the depth buffer also over a multisampled one (MSAA 2, 4, 8), as
/// `Culler::with_samples` and the backends' pipelines build it: `MSAA_SWAPS` in place of the
/// single-sample files, `DEPTH_SAMPLES` an override constant, no single-sample texture left.
#[test]
fn every_depth_reading_shader_validates_over_multisampled_depth() {
    use manylights_cull::shaders::{reads_depth, sample_swaps};
    let mut over_msaa = 0;
    for def in all_shaders() {
        if !reads_depth(&def) {
            assert!(
                !def.compose().contains("DEPTH_SAMPLES") || def.name == "prepass.depth_bounds",
                "{}: reads DEPTH_SAMPLES but composes no depth input",
                def.name
            );
            continue;
        }
        assert!(sample_swaps(1).is_empty());
        for samples in [2, 4, 8] {
            let src = def.compose_swapped(sample_swaps(samples));
            assert!(
                src.contains("override DEPTH_SAMPLES: u32;")
                    && src.contains("var depth_tex: texture_depth_multisampled_2d;")
                    && !src.contains("texture_depth_2d"),
                "{}: not multisampled at {samples} samples",
                def.name
            );
            let module = validate_source(def.name, &src);
            assert!(
                module
                    .overrides
                    .iter()
                    .any(|(_, o)| o.name.as_deref() == Some("DEPTH_SAMPLES")),
                "{}: no DEPTH_SAMPLES override",
                def.name
            );
        }
        over_msaa += 1;
    }
    // The culling strategies' five modules, the per-pixel consumers and the backends'.
    assert!(over_msaa >= 10, "{over_msaa} shaders read the depth buffer");
}

/// Every culling shader that reads depth also over lookup bounds, as `Culler::with_bounds`
/// builds it: `depth_input_bounds.wgsl` in place of `depth_input.wgsl`, two "samples" a pixel.
#[test]
fn every_culling_shader_validates_over_lookup_bounds() {
    use manylights_cull::shaders::{BOUNDS_SWAPS, DEPTH_INPUT};
    let mut over_bounds = 0;
    for def in manylights_cull::shaders::SHADERS {
        if !def.has_file(DEPTH_INPUT) {
            continue;
        }
        let src = def.compose_swapped(BOUNDS_SWAPS);
        assert!(
            src.contains("var depth_tex: texture_2d<f32>;") && !src.contains("texture_depth"),
            "{}: still reads a depth texture",
            def.name
        );
        validate_source(def.name, &src);
        over_bounds += 1;
    }
    assert!(over_bounds >= 3, "{over_bounds} culling shaders read depth");
}

/// Every culling shader that reads depth also over a float depth, as
/// a culler's pipelines over an `R32Float` depth build it: `depth_input_float.wgsl` in place of
/// `depth_input.wgsl`, one sample a pixel.
#[test]
fn every_culling_shader_validates_over_a_float_depth() {
    use manylights_cull::shaders::{DEPTH_INPUT, FLOAT_SWAPS};
    let mut over_float = 0;
    for def in manylights_cull::shaders::SHADERS {
        if !def.has_file(DEPTH_INPUT) {
            continue;
        }
        let src = def.compose_swapped(FLOAT_SWAPS);
        assert!(
            src.contains("var depth_tex: texture_2d<f32>;") && !src.contains("texture_depth"),
            "{}: still reads a depth texture",
            def.name
        );
        validate_source(def.name, &src);
        over_float += 1;
    }
    assert!(over_float >= 3, "{over_float} culling shaders read depth");
}

/// Deferred lighting in every variant `Pipelines` builds: its image in 16-bit floats
/// (`out_color_f16.wgsl`) or 32, its depth the compute rasteriser's `R32Float`
/// (`lookup_depth_float.wgsl`) or the depth buffer, and with MSAA.
#[test]
fn deferred_lighting_validates_in_every_variant() {
    use manylights_cull::shaders::sample_swaps;
    use manylights_shade::HdrFormat;
    use manylights_shade::shaders::{DEFERRED, DEFERRED_MSAA, deferred_swaps};
    for (def, samples, float) in [
        (DEFERRED, 1, false),
        (DEFERRED, 1, true),
        (DEFERRED_MSAA, 4, false),
    ] {
        for hdr in [HdrFormat::F32, HdrFormat::F16] {
            let what = format!("{} {samples}x {hdr:?} float depth {float}", def.name);
            let swaps = [&deferred_swaps(hdr, float), sample_swaps(samples)].concat();
            let src = def.compose_swapped(&swaps);
            assert_eq!(
                src.contains("texture_storage_2d<rgba16float, write>"),
                hdr == HdrFormat::F16,
                "{what}: the image's format"
            );
            assert_eq!(
                src.contains("var depth_tex: texture_2d<f32>;"),
                float,
                "{what}: the depth's type"
            );
            validate_source(&what, &src);
        }
    }
}

#[test]
fn every_wgsl_file_is_used_by_a_shader() {
    let mut used: BTreeSet<String> = all_shaders()
        .iter()
        .flat_map(|d| d.files.iter().map(|f| f.path.to_owned()))
        .collect();
    // Files built in place of others: validated in those builds.
    used.extend(
        manylights_cull::shaders::BOUNDS_SWAPS
            .iter()
            .chain(manylights_cull::shaders::FLOAT_SWAPS)
            .chain(manylights_cull::shaders::LOOKUP_FLOAT_SWAPS)
            .chain(manylights_cull::shaders::MSAA_SWAPS)
            .chain(&manylights_shade::shaders::deferred_swaps(
                manylights_shade::HdrFormat::F16,
                true,
            ))
            .map(|(_, to)| to.path.to_owned()),
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let mut stack = vec![root.clone()];
    let mut found = Vec::new();
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "wgsl") {
                found.push(
                    p.strip_prefix(&root)
                        .unwrap()
                        .to_string_lossy()
                        .replace('\\', "/"),
                );
            }
        }
    }
    assert!(!found.is_empty());
    for f in found {
        assert!(
            used.contains(&f),
            "shaders/{f} is not part of any ShaderDef, so nothing validates it"
        );
    }
}

/// naga's (size, [(member, offset)]) of the struct `name` in `module`.
fn wgsl_layout(module: &naga::Module, name: &str) -> (u32, Vec<(String, u32)>) {
    let ty = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name}"))
        .1;
    match &ty.inner {
        naga::TypeInner::Struct { members, span } => (
            *span,
            members
                .iter()
                .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                .collect(),
        ),
        other => panic!("{name} is not a struct: {other:?}"),
    }
}

#[test]
fn host_structs_match_wgsl_layout() {
    let reference = validate(&manylights_shade::reference::SHADER);
    macro_rules! check {
        ($ty:ty, $wgsl:literal, [$($field:ident => $member:literal),* $(,)?]) => {
            check!(&reference, $ty, $wgsl, [$($field => $member),*])
        };
        ($module:expr, $ty:ty, $wgsl:literal, [$($field:ident => $member:literal),* $(,)?]) => {{
            let (size, members) = wgsl_layout($module, $wgsl);
            assert_eq!(size as usize, size_of::<$ty>(), "size of {} vs {}", $wgsl, stringify!($ty));
            // Every member but padding (`_` names) is checked: a field added to both sides
            // must join the list.
            let listed = [$($member),*];
            for (name, _) in members.iter().filter(|(n, _)| !n.starts_with('_')) {
                assert!(listed.contains(&name.as_str()), "{}.{} is not checked", $wgsl, name);
            }
            $(
                let off = members.iter().find(|(n, _)| n == $member).unwrap_or_else(|| panic!("{}.{} missing", $wgsl, $member)).1;
                assert_eq!(off as usize, std::mem::offset_of!($ty, $field), "{}.{} offset", $wgsl, $member);
            )*
        }};
    }
    check!(GpuFrame, "Frame", [clip_from_world => "clip_from_world", view_from_world => "view_from_world",
        clip_from_view => "clip_from_view", world_from_view => "world_from_view", eye => "eye", viewport => "viewport", light_count => "light_count", flags => "flags",
        band_ramp => "band_ramp", band_slope => "band_slope", shadow_frame => "shadow_frame"]);
    check!(GpuLight, "Light", [position => "position", radius => "radius", color => "color", intensity => "intensity",
        direction => "direction", kind => "kind", cos_inner => "cos_inner", cos_outer => "cos_outer", alpha => "alpha", interleave => "interleave"]);
    check!(GpuMaterial, "Material", [base_color => "base_color", model => "model", emissive => "emissive", opacity => "opacity", params => "params"]);
    let cull = validate(&manylights_cull::shaders::DEPTH_BOUNDS);
    check!(&cull, GpuCullParams, "CullParams", [tiles_x => "tiles_x", tiles_y => "tiles_y",
        tile_size => "tile_size", light_count => "light_count", slices => "slices",
        slicing => "slicing", flags => "flags", bins => "bins", near => "near", far => "far",
        slack => "slack", slice_scale => "slice_scale", capacity => "capacity",
        coarse => "coarse", coarse_x => "coarse_x", chunk => "chunk"]);
    check!(&cull, GpuTileDepth, "TileDepth", [dmin => "dmin", dmax => "dmax", mask => "mask",
        covered => "covered"]);
    let motion = validate(&manylights_gpu::motion::MOTION);
    check!(&motion, MotionParams, "MotionParams", [kind => "kind", first => "first", count => "count",
        row => "row", speed => "speed", time => "time", extent => "extent"]);
    let rays = validate(&manylights_gpu::bvh::SHADOW_RAYS);
    check!(&rays, manylights_gpu::bvh::BvhNode, "BvhNode", [lo => "lo", count => "count",
        hi => "hi", first => "first"]);
    check!(&rays, manylights_gpu::bvh::BvhTriangle, "BvhTriangle", [v0 => "v0", v1 => "v1", v2 => "v2"]);
    let occlusion = validate(&manylights_cull::occlusion::OCCLUDER_TEST);
    check!(&occlusion, manylights_cull::occlusion::GpuOccluder, "Occluder", [corners => "corners",
        normal => "normal"]);
    let stochastic = validate(&manylights_gpu::stochastic::STOCHASTIC);
    check!(&stochastic, GpuStochasticParams, "StochasticParams", [first => "first", count => "count",
        row => "row", seed => "seed", frame => "frame", biased => "biased", error => "error",
        exposure => "exposure", scale => "scale", interleave => "interleave",
        stratified => "stratified"]);
    for def in [
        &manylights_gpu::hierarchy::HIERARCHY,
        &manylights_gpu::hierarchy::HIERARCHY64,
    ] {
        let hierarchy = validate(def);
        check!(&hierarchy, manylights_gpu::hierarchy::Step, "Step", [a => "a", b => "b", c => "c", d => "d",
            e => "e", g => "g", h => "h", far => "far", s => "s", o => "o"]);
    }
    // VertexIn is a vertex-input struct (no host-shareable layout); check its attribute
    // locations and formats against VERTEX_LAYOUT instead.
    let (_, members) = wgsl_layout(&reference, "VertexIn");
    let attrs = manylights_gpu::layout::VERTEX_LAYOUT.attributes;
    assert_eq!(members.len(), attrs.len());
    assert_eq!(
        attrs[0].offset as usize,
        std::mem::offset_of!(GpuVertex, position)
    );
    assert_eq!(
        attrs[1].offset as usize,
        std::mem::offset_of!(GpuVertex, normal)
    );
    assert_eq!(
        attrs[2].offset as usize,
        std::mem::offset_of!(GpuVertex, material)
    );
    // The storage passes read a vertex as VERTEX_WORDS words: the position from word 0, the
    // normal from word 3, the material from word 6 (shaders/render/surface.wgsl,
    // visibility_compute.wgsl).
    assert!(manylights_gpu::layout::wgsl_prelude().contains(&format!(
        "const VERTEX_WORDS: u32 = {}u;",
        size_of::<GpuVertex>() / 4
    )));
    assert_eq!(
        [
            offset_of!(GpuVertex, position),
            offset_of!(GpuVertex, normal),
            offset_of!(GpuVertex, material)
        ],
        [0, 12, 24]
    );
}
