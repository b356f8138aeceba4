//! The raster passes of the backends: what a pass keeps of its targets and draws ([`Loads`]),
//! a pass as data ([`Draw`]) and [`draw`], which draws the scene into its targets (the G-buffer
//! and visibility passes, forward shading, the glass, naive forward).

use manylights_gpu::GpuScene;
use manylights_gpu::timing::GpuTimer;

/// What a raster pass keeps of its targets, and what it draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Loads {
    /// Clears colour and depth, draws the opaque surfaces (the G-buffer pass).
    Clear,
    /// Clears colour, keeps the prepass depth, draws the opaque surfaces (tested `Equal`).
    Depth,
    /// Keeps colour and depth, draws the transparent surfaces (blended over the opaque ones).
    Transparent,
    /// Clears colour to no glass (black, transmittance 1 in alpha), keeps depth, draws the
    /// transparent surfaces: their own contribution and transmittance, a layer that deferred
    /// lighting with MSAA composites over each sample.
    GlassLayer,
}

/// A raster pass drawing the scene: into which targets (each with the single-sample texture it
/// resolves into where it is multisampled and this pass is the frame's last, then discarded),
/// over which depth, with which pipelines and lists; what it keeps of them and what it draws
/// as `loads` says.
pub(crate) struct Draw<'a> {
    /// One pipeline draws every triangle; several (forward's, a material model each) draw the
    /// opaque triangles of a model each.
    pub pipelines: &'a [wgpu::RenderPipeline],
    /// The colour targets and where each resolves.
    pub targets: Vec<(&'a wgpu::TextureView, Option<&'a wgpu::TextureView>)>,
    /// The depth buffer.
    pub depth: &'a wgpu::TextureView,
    /// What it keeps and draws.
    pub loads: Loads,
    /// Bind group 1: the lists a forward pass reads.
    pub lists: Option<&'a wgpu::BindGroup>,
}

/// Encodes `d` as the render pass `label`, timed.
pub(crate) fn draw(
    enc: &mut wgpu::CommandEncoder,
    timer: &mut GpuTimer,
    label: &str,
    scene: &GpuScene,
    d: &Draw<'_>,
) {
    let loads = d.loads;
    let attachments: Vec<Option<wgpu::RenderPassColorAttachment<'_>>> = d
        .targets
        .iter()
        .map(|&(view, resolve_target)| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target,
                ops: wgpu::Operations {
                    load: match loads {
                        Loads::Transparent => wgpu::LoadOp::Load,
                        Loads::GlassLayer => wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        Loads::Clear | Loads::Depth => {
                            wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
                        }
                    },
                    store: if resolve_target.is_some() {
                        wgpu::StoreOp::Discard
                    } else {
                        wgpu::StoreOp::Store
                    },
                },
            })
        })
        .collect();
    let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &attachments,
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: d.depth,
            depth_ops: Some(wgpu::Operations {
                load: if loads == Loads::Clear {
                    wgpu::LoadOp::Clear(1.0)
                } else {
                    wgpu::LoadOp::Load
                },
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: timer.render_pass(label),
        occlusion_query_set: None,
        multiview_mask: None,
    });
    if let Some(group) = d.lists {
        pass.set_bind_group(1, group, &[]);
    }
    match d.pipelines {
        [one] => {
            pass.set_pipeline(one);
            if matches!(loads, Loads::Transparent | Loads::GlassLayer) {
                scene.draw_transparent(&mut pass);
            } else {
                scene.draw(&mut pass);
            }
        }
        by_model => {
            for (group, pipeline) in by_model.iter().enumerate() {
                pass.set_pipeline(pipeline);
                scene.draw_model(&mut pass, group);
            }
        }
    }
}
