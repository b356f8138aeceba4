//! Reading Bevy's cluster lists back from the GPU, in the render world.
//!
//! `ViewClusterBindings` holds a view's lists in two storage buffers: per cluster two `uvec4`
//! (list offset, point, spot and rect light counts; probe, volume and decal counts, padding),
//! and the index lists (a cluster's point lights, then its spots, then its rect lights; an
//! index is the light's place in `GlobalClusterableObjectMeta`'s light buffer). Their usage is
//! STORAGE | COPY_DST, so a system of ours, after Bevy's clustering in the `Core3d` schedule,
//! copies them with a compute pass into buffers it can read, and records which entity each
//! index is.

use std::sync::{Arc, Mutex};

use bevy::core_pipeline::prepass::node::early_prepass;
use bevy::core_pipeline::{Core3d, Core3dSystems};
use bevy::ecs::entity::Entity;
use bevy::ecs::prelude::*;
use bevy::pbr::{GlobalClusterableObjectMeta, ViewClusterBindings};
use bevy::render::render_resource::BindingResource;
use bevy::render::renderer::{RenderContext, RenderDevice, ViewQuery};
use bevy::render::sync_world::MainEntity;

/// One frame's lists, in buffers the CPU can map once the frame is submitted.
pub struct Captured {
    pub offsets_and_counts: wgpu::Buffer,
    pub index_lists: wgpu::Buffer,
    /// The main-world entity of each light index (`Entity::PLACEHOLDER` where none).
    pub light_entities: Vec<Entity>,
}

/// The last frame's capture, shared between the render world and the adapter's loop.
#[derive(Resource, Clone, Default)]
pub struct Capture(pub Arc<Mutex<Option<Captured>>>);

/// The copy pass's pipeline.
#[derive(Resource)]
pub struct Copier {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl Copier {
    pub fn new(device: &wgpu::Device) -> Copier {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("bevy-gpu referee copy"),
            source: wgpu::ShaderSource::Wgsl(include_str!("copy.wgsl").into()),
        });
        let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("bevy-gpu referee copy"),
            entries: &[storage(0, true), storage(1, false)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("bevy-gpu referee copy"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("bevy-gpu referee copy"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        Copier { pipeline, layout }
    }

    /// Records a copy of `src` into a new mappable buffer of its size.
    fn copy(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        src: &wgpu::Buffer,
    ) -> wgpu::Buffer {
        let size = src.size();
        let buffer = |usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("bevy-gpu referee copy"),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let dst = buffer(wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
        let staging = buffer(wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ);
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("bevy-gpu referee copy"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: src.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: dst.as_entire_binding(),
                },
            ],
        });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &group, &[]);
            let groups = (size / 4).div_ceil(256).clamp(1, 65_535) as u32;
            pass.dispatch_workgroups(groups, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&dst, 0, &staging, 0, size);
        staging
    }
}

/// Adds the capture after Bevy's clustering (`cluster_on_gpu` runs before `early_prepass`;
/// CPU clustering fills the buffers before the schedule).
pub fn add_capture(render_app: &mut bevy::app::SubApp, capture: Capture) {
    let device = render_app
        .world()
        .resource::<RenderDevice>()
        .wgpu_device()
        .clone();
    render_app
        .insert_resource(Copier::new(&device))
        .insert_resource(capture)
        .add_systems(
            Core3d,
            capture_lists
                .after(early_prepass)
                .in_set(Core3dSystems::Prepass),
        );
}

fn capture_lists(
    view: ViewQuery<&ViewClusterBindings>,
    mut context: RenderContext,
    copier: Res<Copier>,
    capture: Res<Capture>,
    meta: Res<GlobalClusterableObjectMeta>,
    main_entities: Query<&MainEntity>,
) {
    let bindings = view.into_inner();
    let (Some(BindingResource::Buffer(counts)), Some(BindingResource::Buffer(lists))) = (
        bindings.offsets_and_counts_binding(),
        bindings.clusterable_object_index_lists_binding(),
    ) else {
        return;
    };
    let device = context.render_device().wgpu_device().clone();
    let encoder = context.command_encoder();
    let offsets_and_counts = copier.copy(&device, encoder, counts.buffer);
    let index_lists = copier.copy(&device, encoder, lists.buffer);
    let mut light_entities = vec![Entity::PLACEHOLDER; meta.entity_to_index.len()];
    for (render_entity, &index) in &meta.entity_to_index {
        if let (Ok(main), Some(slot)) = (
            main_entities.get(*render_entity),
            light_entities.get_mut(index),
        ) {
            *slot = main.id();
        }
    }
    *capture.0.lock().unwrap() = Some(Captured {
        offsets_and_counts,
        index_lists,
        light_entities,
    });
}

/// The words of a mapped-on-read buffer, once the device has finished the frame.
pub fn read_words(device: &wgpu::Device, buffer: &wgpu::Buffer) -> Result<Vec<u32>, String> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| format!("waiting for the GPU: {e}"))?;
    rx.recv()
        .map_err(|e| e.to_string())?
        .map_err(|e| format!("mapping Bevy's lists: {e}"))?;
    let words = {
        let view = slice
            .get_mapped_range()
            .map_err(|e| format!("reading Bevy's lists: {e}"))?;
        bytemuck_words(&view)
    };
    buffer.unmap();
    Ok(words)
}

fn bytemuck_words(bytes: &[u8]) -> Vec<u32> {
    bytes
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}
