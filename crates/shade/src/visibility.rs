//! The visibility buffer's CPU oracle: a frame's surface buffers read back (the triangle ids of
//! [`Backend::Visibility`], or the G-buffer of the deferred backends) and, in f64, the surface a
//! triangle id stands for at a pixel, as `visibility_surface` (shaders/render/surface.wgsl)
//! computes it in f32: where the ray through the pixel centre meets the triangle's plane, the
//! normal interpolated there with the same barycentrics and turned towards the viewer, and the
//! material of the triangle's first vertex.

use glam::{DMat4, DVec3, DVec4};
use manylights_gpu::layout::{GpuFrame, GpuVertex};
use manylights_gpu::{GpuContext, GpuError, GpuScene, readback};

use crate::backends::{Backend, ShadeOutput};

/// One sample a pixel of a frame's surface buffers, rows from the top.
pub struct SurfaceTexels {
    /// Visibility: each pixel's triangle id (its index in the scene's index buffer plus one, 0
    /// for none). Deferred: each pixel's material index.
    pub ids: Vec<u32>,
    /// Deferred: the shading normal and view-space z (0 for none); empty for visibility.
    pub normal_depth: Vec<[f32; 4]>,
    /// `DeferredStoredPosition`: the interpolated world position; empty otherwise.
    pub position: Vec<[f32; 4]>,
}

/// Reads back the surface buffers of `out`, a frame of a deferred or visibility backend at one
/// sample a pixel (multisampled textures cannot be copied).
pub fn read_surfaces(ctx: &GpuContext, out: &ShadeOutput) -> Result<SurfaceTexels, GpuError> {
    let views = out.targets.gbuffer.as_ref().ok_or_else(|| {
        GpuError::Unsupported(format!(
            "backend {} has no surface buffers",
            out.backend.name()
        ))
    })?;
    if views[1].texture().sample_count() > 1 {
        return Err(GpuError::Unsupported(
            "surface buffers with MSAA cannot be read back".into(),
        ));
    }
    let read =
        |v: &wgpu::TextureView| readback::read_texture(ctx, v.texture(), wgpu::TextureAspect::All);
    let texels = |bytes: Vec<u8>| -> Vec<[f32; 4]> {
        bytemuck::cast_slice::<u8, f32>(&bytes)
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect()
    };
    let ids = bytemuck::cast_slice::<u8, u32>(&read(&views[1])?).to_vec();
    let (normal_depth, position) = match out.backend {
        Backend::Visibility => (Vec::new(), Vec::new()),
        Backend::DeferredStoredPosition => (texels(read(&views[0])?), texels(read(&views[2])?)),
        _ => (texels(read(&views[0])?), Vec::new()),
    };
    Ok(SurfaceTexels {
        ids,
        normal_depth,
        position,
    })
}

/// The scene's vertices and indices as the GPU holds them (the order triangle ids index).
pub fn read_geometry(
    ctx: &GpuContext,
    scene: &GpuScene,
) -> Result<(Vec<GpuVertex>, Vec<u32>), GpuError> {
    let v = readback::read_buffer(ctx, &scene.vertices, 0, scene.vertices.size())?;
    let i = readback::read_buffer(ctx, &scene.indices, 0, scene.indices.size())?;
    Ok((
        bytemuck::pod_collect_to_vec(&v),
        bytemuck::pod_collect_to_vec(&i),
    ))
}

/// What a triangle id stands for at a pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleSurface {
    /// The world point where the pixel centre's ray meets the triangle's plane.
    pub position: DVec3,
    /// The interpolated unit normal, turned towards the viewer.
    pub normal: DVec3,
    /// The material index of the triangle's first vertex.
    pub material: u32,
    /// The barycentrics of `position` (each in [0, 1] where the ray meets the triangle).
    pub barycentrics: DVec3,
}

/// The surface of triangle id `id` (index plus one; `None` for 0, or where the ray runs
/// parallel to the triangle) at the centre of pixel `(x, y)` of `frame`.
pub fn triangle_surface(
    vertices: &[GpuVertex],
    indices: &[u32],
    frame: &GpuFrame,
    (x, y): (u32, u32),
    id: u32,
) -> Option<TriangleSurface> {
    let t = id.checked_sub(1)? as usize;
    let i = [indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]].map(|i| i as usize);
    let p = i.map(|i| vertices[i].position.as_dvec3());
    let n = i.map(|i| vertices[i].normal.as_dvec3());
    let ndc = (
        (f64::from(x) + 0.5) * 2.0 / f64::from(frame.viewport.x) - 1.0,
        1.0 - (f64::from(y) + 0.5) * 2.0 / f64::from(frame.viewport.y),
    );
    let world_from_clip = frame.clip_from_world.as_dmat4().inverse();
    let at = |z: f64| {
        let h: DVec4 = DMat4::mul_vec4(&world_from_clip, DVec4::new(ndc.0, ndc.1, z, 1.0));
        h.truncate() / h.w
    };
    let o = at(0.0);
    let d = at(1.0) - o;
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let q = d.cross(e2);
    let det = e1.dot(q);
    if det.abs() < 1e-300 {
        return None;
    }
    let s = o - p[0];
    let b1 = s.dot(q) / det;
    let b2 = d.dot(s.cross(e1)) / det;
    let b = DVec3::new(1.0 - b1 - b2, b1, b2);
    let position = p[0] * b.x + p[1] * b.y + p[2] * b.z;
    let eye = frame.eye.as_dvec4();
    let v = (eye.truncate() - position * eye.w).normalize();
    let normal = (n[0] * b.x + n[1] * b.y + n[2] * b.z).normalize();
    Some(TriangleSurface {
        position,
        normal: if normal.dot(v) < 0.0 { -normal } else { normal },
        material: vertices[i[0]].material,
        barycentrics: b,
    })
}
