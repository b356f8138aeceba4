//! Pipeline and bind-group-layout construction shared by every pass, so that each pass states
//! only what is its own: its shader, entry point, groups, targets and depth test.

use crate::layout::VERTEX_LAYOUT;
use crate::prepass::{DEPTH_FORMAT, PRIMITIVE};

/// How a raster pass uses the depth buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthTest {
    /// Writes depth, keeping the nearest (`Less`): the depth prepass and the G-buffer pass.
    WriteLess,
    /// Reads the prepass depth and shades only where it is equal: each pixel shaded once.
    Equal,
    /// Reads the opaque depth without writing it and shades what lies nearer (`Less`):
    /// transparent surfaces, blended over what is behind them.
    Less,
    /// Writes depth, keeping the farthest (`Greater`, over a target cleared to 0).
    WriteGreater,
}

/// A uniform buffer holding `contents`.
pub fn uniform_buffer(device: &wgpu::Device, label: &str, contents: &[u8]) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents,
        usage: wgpu::BufferUsages::UNIFORM,
    })
}

/// A pipeline layout over `groups` (group 0 first), with no immediates.
pub fn layout(
    device: &wgpu::Device,
    label: &str,
    groups: &[&wgpu::BindGroupLayout],
) -> wgpu::PipelineLayout {
    let groups: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().copied().map(Some).collect();
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &groups,
        immediate_size: 0,
    })
}

/// A raster pipeline over the shared vertex stage (`vs_main`, the scene's vertex layout, the
/// common primitive state); `fragment` is the entry point and its targets, or none for a
/// depth-only pass.
pub fn raster(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    groups: &[&wgpu::BindGroupLayout],
    fragment: Option<(&str, &[Option<wgpu::ColorTargetState>])>,
    depth: DepthTest,
) -> wgpu::RenderPipeline {
    raster_msaa(device, label, module, groups, fragment, depth, 1)
}

/// [`raster`] into targets of `samples` samples a pixel (MSAA).
pub fn raster_msaa(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    groups: &[&wgpu::BindGroupLayout],
    fragment: Option<(&str, &[Option<wgpu::ColorTargetState>])>,
    depth: DepthTest,
    samples: u32,
) -> wgpu::RenderPipeline {
    raster_with(device, label, module, groups, fragment, depth, samples, &[])
}

/// [`raster_msaa`] with values of the fragment stage's `override` constants.
#[allow(
    clippy::too_many_arguments,
    reason = "raster_msaa's arguments and the constants"
)]
pub fn raster_with(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    groups: &[&wgpu::BindGroupLayout],
    fragment: Option<(&str, &[Option<wgpu::ColorTargetState>])>,
    depth: DepthTest,
    samples: u32,
    constants: &[(&str, f64)],
) -> wgpu::RenderPipeline {
    let layout = layout(device, label, groups);
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(VERTEX_LAYOUT)],
        },
        primitive: PRIMITIVE,
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(matches!(
                depth,
                DepthTest::WriteLess | DepthTest::WriteGreater
            )),
            depth_compare: Some(match depth {
                DepthTest::WriteLess | DepthTest::Less => wgpu::CompareFunction::Less,
                DepthTest::Equal => wgpu::CompareFunction::Equal,
                DepthTest::WriteGreater => wgpu::CompareFunction::Greater,
            }),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState {
            count: samples,
            ..Default::default()
        },
        fragment: fragment.map(|(entry, targets)| wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// A colour target of `format` blending what a transparent surface draws over what is there:
/// colour `src * a + dst * (1 - a)`, alpha (coverage) `a + dst * (1 - a)`, `a` the fragment's
/// alpha (its opacity).
pub fn blended_target(format: wgpu::TextureFormat) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend: Some(wgpu::BlendState::ALPHA_BLENDING),
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// A colour target of `format` that keeps what is blended over it as a layer: colour blended
/// as [`blended_target`] does, alpha the product of one minus each source's (cleared to black
/// with alpha 1, it holds the layer's own contribution and its transmittance, to composite
/// over what lies behind it later).
pub fn layer_target(format: wgpu::TextureFormat) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend: Some(wgpu::BlendState {
            color: wgpu::BlendState::ALPHA_BLENDING.color,
            alpha: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Zero,
                dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
                operation: wgpu::BlendOperation::Add,
            },
        }),
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// An opaque colour target of `format`.
pub fn target(format: wgpu::TextureFormat) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// A compute pipeline for entry point `entry` of `module` over `layout`.
pub fn compute(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    entry: &str,
) -> wgpu::ComputePipeline {
    compute_with(
        device,
        module,
        layout,
        entry,
        &wgpu::PipelineCompilationOptions::default(),
    )
}

/// As [`compute`], with compilation options (values of the shader's `override` constants;
/// whether workgroup memory starts zeroed).
pub fn compute_with(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    entry: &str,
    options: &wgpu::PipelineCompilationOptions<'_>,
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: Some(layout),
        module,
        entry_point: Some(entry),
        compilation_options: options.clone(),
        cache: None,
    })
}

/// A bind-group-layout entry.
pub fn entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BindingType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty,
        count: None,
    }
}

/// A uniform buffer binding.
pub const UNIFORM: wgpu::BindingType = wgpu::BindingType::Buffer {
    ty: wgpu::BufferBindingType::Uniform,
    has_dynamic_offset: false,
    min_binding_size: None,
};

/// A storage buffer binding.
pub const fn storage(read_only: bool) -> wgpu::BindingType {
    wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Storage { read_only },
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

/// A 2D depth texture binding.
pub const DEPTH_TEXTURE: wgpu::BindingType = depth_texture(1);

/// A 2D depth texture binding of `samples` samples a pixel (`texture_depth_multisampled_2d`
/// in WGSL where more than one).
pub const fn depth_texture(samples: u32) -> wgpu::BindingType {
    wgpu::BindingType::Texture {
        sample_type: wgpu::TextureSampleType::Depth,
        view_dimension: wgpu::TextureViewDimension::D2,
        multisampled: samples > 1,
    }
}

/// A 2D texture of one mip level and one sample.
pub fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    size: (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    texture_2d_msaa(device, label, size, format, usage, 1)
}

/// [`texture_2d`] of `samples` samples a pixel (MSAA where more than one).
pub fn texture_2d_msaa(
    device: &wgpu::Device,
    label: &str,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
    samples: u32,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: samples,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// A bind group of `resources` at bindings 0, 1, 2, ... in order.
pub fn group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    resources: &[wgpu::BindingResource<'_>],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry<'_>> = resources
        .iter()
        .enumerate()
        .map(|(i, r)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: r.clone(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// A bind group of whole buffers at bindings 0, 1, 2, ... in order.
pub fn buffers_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let resources: Vec<wgpu::BindingResource<'_>> =
        buffers.iter().map(|b| b.as_entire_binding()).collect();
    group(device, label, layout, &resources)
}

/// A timed compute pass `label` dispatching `groups` workgroups of `pipeline` with bind groups
/// 0, 1, ... set from `bind`.
pub fn dispatch(
    encoder: &mut wgpu::CommandEncoder,
    timer: &mut crate::timing::GpuTimer,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    bind: &[&wgpu::BindGroup],
    groups: (u32, u32),
) {
    dispatch_3d(
        encoder,
        timer,
        label,
        pipeline,
        bind,
        [groups.0, groups.1, 1],
    );
}

/// [`dispatch`] over a three-dimensional grid of workgroups.
pub fn dispatch_3d(
    encoder: &mut wgpu::CommandEncoder,
    timer: &mut crate::timing::GpuTimer,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    bind: &[&wgpu::BindGroup],
    groups: [u32; 3],
) {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: timer.compute_pass(label),
    });
    pass.set_pipeline(pipeline);
    for (i, g) in bind.iter().enumerate() {
        pass.set_bind_group(i as u32, *g, &[]);
    }
    pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
}
