//! The pipelines of every backend (`Renderer::build`) and the shaders they are made from.

use manylights_cull::Culler;
use manylights_cull::layout::CULL_CONSTS;
use manylights_cull::shaders::{GEOMETRY, LOOKUP};
use manylights_gpu::lookup_bounds::LookupBounds;
use manylights_gpu::pipeline;
use manylights_gpu::prepass::DepthPrepass;
use manylights_gpu::shaders::{BRDF, FRAME, LIGHT, SCENE, SHADING, ShaderDef, ShaderFile, VERTEX};
use manylights_gpu::{GpuContext, GpuScene, shader_file};

use crate::backends::{GB_MATERIAL, GB_NORMAL_DEPTH, GB_POSITION, HdrFormat, Renderer};

/// The loop over a pixel's list, with its per-pixel reject (forward and deferred).
pub const LIST_SHADING: ShaderFile = shader_file!("render/list_shading.wgsl");
/// `shade.forward` and `shade.naive`.
pub const FORWARD: ShaderDef = ShaderDef {
    name: "shade.forward",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        BRDF,
        SHADING,
        VERTEX,
        GEOMETRY,
        LOOKUP,
        LIST_SHADING,
        shader_file!("render/forward.wgsl"),
    ],
};
/// `shade.gbuffer`.
pub const GBUFFER: ShaderDef = ShaderDef {
    name: "shade.gbuffer",
    consts: &[],
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        BRDF,
        SHADING,
        VERTEX,
        shader_file!("render/gbuffer.wgsl"),
    ],
};
/// `shade.deferred`.
pub const DEFERRED: ShaderDef = ShaderDef {
    name: "shade.deferred",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        BRDF,
        SHADING,
        GEOMETRY,
        LOOKUP,
        LIST_SHADING,
        shader_file!("render/deferred.wgsl"),
    ],
};

/// `shade.deferred` over a multisampled G-buffer (MSAA): a pixel at once, or its samples apart
/// at edges.
pub const DEFERRED_MSAA: ShaderDef = ShaderDef {
    name: "shade.deferred",
    consts: CULL_CONSTS,
    files: &[
        FRAME,
        LIGHT,
        SCENE,
        BRDF,
        SHADING,
        GEOMETRY,
        LOOKUP,
        LIST_SHADING,
        shader_file!("render/deferred_msaa.wgsl"),
    ],
};

fn lists_entries(visibility: wgpu::ShaderStages) -> Vec<wgpu::BindGroupLayoutEntry> {
    vec![
        pipeline::entry(0, visibility, pipeline::UNIFORM),
        pipeline::entry(1, visibility, pipeline::storage(true)),
        pipeline::entry(2, visibility, pipeline::storage(true)),
    ]
}

fn texture(sample_type: wgpu::TextureSampleType, samples: u32) -> wgpu::BindingType {
    wgpu::BindingType::Texture {
        sample_type,
        view_dimension: wgpu::TextureViewDimension::D2,
        multisampled: samples > 1,
    }
}

impl Renderer {
    pub(crate) fn build(ctx: &GpuContext, scene: &GpuScene, samples: u32, hdr: HdrFormat) -> Self {
        let d = &ctx.device;
        let color = hdr.texture_format();
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries,
            })
        };
        let compute = wgpu::ShaderStages::COMPUTE;
        let forward_lists = layout(
            "shade.forward.lists",
            &lists_entries(wgpu::ShaderStages::FRAGMENT),
        );
        let mut entries = lists_entries(compute);
        entries.push(pipeline::entry(
            3,
            compute,
            pipeline::depth_texture(samples),
        ));
        let deferred_lists = layout("shade.deferred.lists", &entries);
        let deferred_gbuffer = layout(
            "shade.deferred.gbuffer",
            &[
                pipeline::entry(
                    0,
                    compute,
                    texture(
                        wgpu::TextureSampleType::Float { filterable: false },
                        samples,
                    ),
                ),
                pipeline::entry(1, compute, texture(wgpu::TextureSampleType::Uint, samples)),
                pipeline::entry(
                    2,
                    compute,
                    wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: color,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                ),
                // The stored position; with MSAA, the glass layer lighting composites.
                pipeline::entry(
                    3,
                    compute,
                    texture(
                        wgpu::TextureSampleType::Float { filterable: false },
                        samples,
                    ),
                ),
            ],
        );
        use pipeline::{DepthTest, raster, raster_msaa, raster_with, target};
        let fwd = FORWARD.create_samples(d, samples);
        let gb = GBUFFER.create(d);
        let g0 = &scene.layout;
        // Forward: a pipeline a material model of the opaque triangles, each shading its model
        // alone (MATERIAL_MODELS, brdf.wgsl), drawn a model at a time.
        // A POINT_LIGHTS pipeline where every light is a windowed point light (shading.wgsl).
        let point_lights = scene.point_lights();
        let point = ("POINT_LIGHTS", f64::from(u8::from(point_lights)));
        // STOCHASTIC_POINTS: those point lights with stochastic ranges (shading.wgsl).
        let stochastic_points = point_lights && scene.stochastic_points();
        let stochastic = ("STOCHASTIC_POINTS", f64::from(u8::from(stochastic_points)));
        // BAND_POINTS: those point lights the lighting grid hierarchy's, with bands.
        let band_points = point_lights && scene.band_points();
        let band = ("BAND_POINTS", f64::from(u8::from(band_points)));
        let forward_with = |entry| {
            scene
                .opaque_models
                .iter()
                .map(|&(model, _)| {
                    raster_with(
                        d,
                        "shade.forward",
                        &fwd,
                        &[g0, &forward_lists],
                        Some((entry, &[target(color)])),
                        DepthTest::Equal,
                        samples,
                        &[
                            ("MATERIAL_MODELS", f64::from(1u32 << model)),
                            point,
                            stochastic,
                            band,
                        ],
                    )
                })
                .collect::<Vec<_>>()
        };
        let forward = forward_with("fs_forward");
        let forward_zbin = forward_with("fs_forward_zbin");
        let transparent_with = |target: Option<wgpu::ColorTargetState>| {
            ["fs_forward_transparent", "fs_forward_transparent_zbin"].map(|entry| {
                raster_with(
                    d,
                    "shade.forward_transparent",
                    &fwd,
                    &[g0, &forward_lists],
                    Some((entry, std::slice::from_ref(&target))),
                    DepthTest::Less,
                    samples,
                    &[point, stochastic, band],
                )
            })
        };
        let forward_transparent = transparent_with(pipeline::blended_target(color));
        let transparent = scene.has_transparent();
        let glass_layer =
            (samples > 1 && transparent).then(|| transparent_with(pipeline::layer_target(color)));
        let naive = raster_msaa(
            d,
            "shade.naive",
            &fwd,
            &[g0],
            Some(("fs_naive", &[target(color)])),
            DepthTest::Equal,
            samples,
        );
        let naive_transparent = raster_msaa(
            d,
            "shade.naive_transparent",
            &fwd,
            &[g0],
            Some(("fs_naive_transparent", &[pipeline::blended_target(color)])),
            DepthTest::Less,
            samples,
        );
        let gbuffer = raster_msaa(
            d,
            "shade.gbuffer",
            &gb,
            &[g0],
            Some((
                "fs_gbuffer",
                &[target(GB_NORMAL_DEPTH), target(GB_MATERIAL)],
            )),
            DepthTest::WriteLess,
            samples,
        );
        let gbuffer_stored = raster(
            d,
            "shade.gbuffer",
            &gb,
            &[g0],
            Some((
                "fs_gbuffer_stored",
                &[
                    target(GB_NORMAL_DEPTH),
                    target(GB_MATERIAL),
                    target(GB_POSITION),
                ],
            )),
            DepthTest::WriteLess,
        );
        let def_layout = pipeline::layout(
            d,
            "shade.deferred",
            &[g0, &deferred_lists, &deferred_gbuffer],
        );
        // Deferred: one lighting pass over every model of the opaque triangles, branching on
        // each pixel's.
        // With MSAA, GLASS: the lighting composites the glass layer over each sample.
        let models = [
            ("MATERIAL_MODELS", f64::from(scene.opaque_model_mask())),
            point,
            stochastic,
            band,
            ("GLASS", f64::from(u8::from(glass_layer.is_some()))),
        ];
        let models = if samples > 1 {
            &models[..]
        } else {
            &models[..4]
        };
        let models = wgpu::PipelineCompilationOptions {
            constants: models,
            ..Default::default()
        };
        let compute = |def: &wgpu::ShaderModule, entry| {
            pipeline::compute_with(d, def, &def_layout, entry, &models)
        };
        // With MSAA, one pass for the lists a bin (a tile's or a cluster's too) and one for
        // z-binning's, the position rebuilt; the stored position takes no MSAA (`render` says
        // so).
        let (deferred, deferred_stored, deferred_zbin, deferred_tiles, deferred_clusters) =
            if samples > 1 {
                let def = DEFERRED_MSAA.create_edited(d, samples, &|s| hdr_storage(s, hdr));
                let bins = compute(&def, "deferred_shade_msaa");
                let zbin = compute(&def, "deferred_shade_msaa_zbin");
                (
                    bins.clone(),
                    bins.clone(),
                    [zbin.clone(), zbin.clone(), zbin.clone(), zbin],
                    [bins.clone(), bins.clone()],
                    [bins.clone(), bins],
                )
            } else {
                let def = DEFERRED.create_edited(d, 1, &|s| hdr_storage(s, hdr));
                (
                    compute(&def, "deferred_shade"),
                    compute(&def, "deferred_shade_stored"),
                    [
                        "deferred_shade_zbin",
                        "deferred_shade_stored_zbin",
                        "deferred_shade_zbin_rounds",
                        "deferred_shade_stored_zbin_rounds",
                    ]
                    .map(|entry| compute(&def, entry)),
                    ["deferred_shade_tiles", "deferred_shade_stored_tiles"]
                        .map(|entry| compute(&def, entry)),
                    ["deferred_shade_clusters", "deferred_shade_stored_clusters"]
                        .map(|entry| compute(&def, entry)),
                )
            };
        let lookup_bounds =
            (samples > 1 || transparent).then(|| LookupBounds::new(ctx, scene, samples));
        Self {
            culler: if lookup_bounds.is_some() {
                Culler::with_bounds(ctx, scene, samples)
            } else {
                Culler::with_samples(ctx, scene, samples)
            },
            samples,
            hdr,
            point_lights,
            stochastic_points,
            band_points,
            prepass: DepthPrepass::with_samples(ctx, scene, samples),
            transparent,
            lookup_bounds,
            glass_layer,
            forward,
            forward_zbin,
            forward_transparent,
            naive,
            naive_transparent,
            gbuffer,
            gbuffer_stored,
            deferred,
            deferred_stored,
            deferred_zbin,
            deferred_tiles,
            deferred_clusters,
            forward_lists,
            deferred_lists,
            deferred_gbuffer,
        }
    }
}

/// The deferred lighting passes' image (`out_color`, declared `rgba32float`) in format `hdr`.
fn hdr_storage(source: String, hdr: HdrFormat) -> String {
    const DECLARED: &str = "var out_color: texture_storage_2d<rgba32float, write>;";
    assert!(
        source.contains(DECLARED),
        "out_color is declared as {DECLARED}"
    );
    source.replace(
        DECLARED,
        &format!("var out_color: texture_storage_2d<{}, write>;", hdr.wgsl()),
    )
}
