//! Where the device puts a pixel's samples, as a pass shaded at every sample sees them: for
//! each sample count it has (of 2, 4 and 8), one pixel drawn by a triangle over a sloped depth,
//! each sample writing its `@builtin(position)` (its x and y within the pixel, its depth) and
//! its index; a compute pass reads the samples back. Printed beside the standard sample
//! positions (Vulkan's standardSampleLocations) and the plane's depth there, which deferred
//! lighting, the visibility buffer and the exact oracle assume (`standard_sample_position`,
//! shaders/common/frame.wgsl):
//!
//!     cargo run --release --example sample_positions

use manylights_gpu::{GpuContext, GpuOptions, pipeline};

const SHADER: &str = r#"
// The plane's depth: z = 0.25 + 0.125 x_ndc + 0.0625 y_ndc (NDC y up), affine in screen space.
@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let xy = vec2<f32>(f32(i & 1u) * 4.0 - 1.0, f32(i >> 1u) * 4.0 - 1.0);
    return vec4<f32>(xy, 0.25 + 0.125 * xy.x + 0.0625 * xy.y, 1.0);
}

@fragment
fn fs(@builtin(position) p: vec4<f32>, @builtin(sample_index) k: u32) -> @location(0) vec4<f32> {
    return vec4<f32>(fract(p.x), fract(p.y), p.z, f32(k));
}

@group(0) @binding(0) var samples: texture_multisampled_2d<f32>;
@group(0) @binding(1) var<storage, read_write> out: array<vec4<f32>>;

@compute @workgroup_size(1)
fn read_back() {
    for (var k = 0u; k < textureNumSamples(samples); k++) {
        out[k] = textureLoad(samples, vec2<u32>(0u), k);
    }
}
"#;

/// Vulkan's standard sample positions for `n` samples.
fn standard(n: u32) -> Vec<(f32, f32)> {
    match n {
        2 => vec![(0.75, 0.75), (0.25, 0.25)],
        4 => vec![
            (0.375, 0.125),
            (0.875, 0.375),
            (0.125, 0.625),
            (0.625, 0.875),
        ],
        8 => vec![
            (0.5625, 0.3125),
            (0.4375, 0.6875),
            (0.8125, 0.5625),
            (0.3125, 0.1875),
            (0.1875, 0.8125),
            (0.0625, 0.4375),
            (0.6875, 0.9375),
            (0.9375, 0.0625),
        ],
        _ => vec![(0.5, 0.5)],
    }
}

fn main() {
    let ctx = GpuContext::new(&GpuOptions::default()).unwrap_or_else(|e| {
        panic!(
            "needs a Vulkan adapter (lavapipe: apt-get install mesa-vulkan-drivers libvulkan1): {e}"
        )
    });
    let format = wgpu::TextureFormat::Rgba32Float;
    let d = &ctx.device;
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("sample_positions"),
        source: wgpu::ShaderSource::Wgsl(SHADER.into()),
    });
    println!("{}", ctx.info.name);
    for n in [2, 4, 8] {
        if !ctx.msaa_counts_of(&[format]).contains(&n) {
            println!("{n} samples: not offered");
            continue;
        }
        let target = pipeline::texture_2d_msaa(
            d,
            "sample_positions.target",
            (1, 1),
            format,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            n,
        );
        let view = target.create_view(&Default::default());
        let raster = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("sample_positions.raster"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState {
                count: n,
                ..Default::default()
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[pipeline::target(format)],
            }),
            multiview_mask: None,
            cache: None,
        });
        let read = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("sample_positions.read_back"),
            layout: None,
            module: &module,
            entry_point: Some("read_back"),
            compilation_options: Default::default(),
            cache: None,
        });
        let out = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("sample_positions.out"),
            size: 16 * 8,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let group = pipeline::group(
            d,
            "sample_positions.read_back",
            &read.get_bind_group_layout(0),
            &[
                wgpu::BindingResource::TextureView(&view),
                out.as_entire_binding(),
            ],
        );
        let mut enc = d.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("sample_positions.raster"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&raster);
            pass.draw(0..3, 0..1);
        }
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&read);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        ctx.submit_and_wait(enc, "sample positions")
            .expect("the passes run");
        let bytes = manylights_gpu::readback::read_buffer(&ctx, &out, 0, 16 * u64::from(n))
            .expect("the samples read back");
        let v: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        println!("{n} samples: k  x      y      depth     | standard x, y, plane depth there");
        for (k, (s, (sx, sy))) in v.iter().zip(standard(n)).enumerate() {
            // The pixel spans NDC x in [-1, 1] and y in [1, -1] (y down in the framebuffer).
            let plane = 0.25 + 0.125 * (2.0 * sx - 1.0) + 0.0625 * (1.0 - 2.0 * sy);
            println!(
                "           {k}  {:.4} {:.4} {:.6}  | {sx:.4} {sy:.4} {plane:.6}   (index {})",
                s[0], s[1], s[2], s[3]
            );
        }
    }
}
