//! The scene on the GPU: one vertex buffer and one index buffer for all primitives (the material
//! index travels per vertex), the lights and materials as storage buffers, and the frame uniform.
//! Group 0 of every pass binds: 0 = frame, 1 = lights, 2 = materials.

use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use bytemuck::cast_slice;
use glam::Vec3;
use manylights_scene::hierarchy::Band;
use manylights_scene::{Camera, Light, Scene};
use wgpu::util::DeviceExt;

use crate::layout::{
    FRAME_FLAG_BAND_POINTS, FRAME_FLAG_POINT_LIGHTS, FRAME_FLAG_STOCHASTIC_POINTS, GpuFrame,
    GpuLight, GpuMaterial, GpuVertex, LIGHT_KIND_POINT,
};
use crate::{GpuContext, GpuError};

/// A scene uploaded for rendering.
pub struct GpuScene {
    /// All vertices.
    pub vertices: wgpu::Buffer,
    /// All triangle indices.
    pub indices: wgpu::Buffer,
    /// Number of indices: the opaque triangles', then the transparent ones'.
    pub index_count: u32,
    /// Indices of the opaque triangles (the first ones).
    pub opaque_index_count: u32,
    /// The opaque triangles grouped by material model: each group's model id
    /// (`manylights_scene::Model::id`) and its range of indices, in the order of the ids.
    pub opaque_models: Vec<(u32, std::ops::Range<u32>)>,
    /// The transparent triangles (materials with opacity below 1), as uploaded, and their
    /// centroids, for sorting them for each view.
    transparent: Vec<[u32; 3]>,
    centroids: Vec<Vec3>,
    /// Lights (at least one element is allocated; `light_count` says how many are real).
    pub lights: wgpu::Buffer,
    /// Number of lights.
    pub light_count: u32,
    /// Materials.
    pub materials: wgpu::Buffer,
    /// The frame uniform.
    pub frame: wgpu::Buffer,
    /// Whether every light is a point light with the windowed falloff (`FRAME_FLAG_POINT_LIGHTS`):
    /// as uploaded, until [`GpuScene::mark_general_lights`].
    point_lights: AtomicBool,
    /// With `point_lights`, the flag of their kind on the short path: 0 (windowed),
    /// `FRAME_FLAG_STOCHASTIC_POINTS` (stochastic ranges without interleaving, from
    /// [`GpuScene::mark_stochastic_points`]) or `FRAME_FLAG_BAND_POINTS` (the lighting grid
    /// hierarchy's, with bands, from [`GpuScene::mark_band_points`]).
    point_kind: AtomicU32,
    /// The flags of the last [`GpuScene::set_view`], without `FRAME_FLAG_POINT_LIGHTS`.
    view_flags: AtomicU32,
    /// The hierarchy bands' ramp the frame carries (the bits of an f32;
    /// [`GpuScene::set_band_ramp`]).
    band_ramp: AtomicU32,
    /// Layout of group 0.
    pub layout: wgpu::BindGroupLayout,
    /// Group 0.
    pub bind_group: wgpu::BindGroup,
}

/// The layout of group 0, which every pass binds: the frame uniform, the lights and the
/// materials, seen by every stage.
fn group0_layout(d: &wgpu::Device) -> wgpu::BindGroupLayout {
    let vis =
        wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
    let storage = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: vis,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("scene.group0"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: vis,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            storage(1),
            storage(2),
        ],
    })
}

impl GpuScene {
    /// Uploads `scene` (which must validate) and sets the frame for `camera` at `width` x `height`.
    pub fn upload(
        ctx: &GpuContext,
        scene: &Scene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<Self, GpuError> {
        let mut vertices = Vec::with_capacity(scene.vertex_count());
        let mut by_model: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
        let mut transparent: Vec<u32> = Vec::new();
        for p in &scene.primitives {
            let base = vertices.len() as u32;
            let material = &scene.materials[p.material as usize];
            let out = if material.is_transparent() {
                &mut transparent
            } else {
                by_model.entry(material.brdf.model().id()).or_default()
            };
            out.extend(p.indices.iter().map(|i| base + i));
            vertices.extend(
                p.positions
                    .iter()
                    .zip(&p.normals)
                    .map(|(&position, &normal)| GpuVertex {
                        position,
                        normal,
                        material: p.material,
                    }),
            );
        }
        // Opaque triangles first, a model at a time, then the transparent ones, sorted for the
        // camera.
        let mut indices = Vec::with_capacity(scene.triangle_count() * 3);
        let mut opaque_models = Vec::new();
        for (model, ix) in by_model {
            let start = indices.len() as u32;
            indices.extend(ix);
            opaque_models.push((model, start..indices.len() as u32));
        }
        let opaque_index_count = indices.len() as u32;
        let centroids: Vec<Vec3> = transparent
            .chunks(3)
            .map(|t| {
                t.iter()
                    .map(|&i| vertices[i as usize].position)
                    .sum::<Vec3>()
                    / 3.0
            })
            .collect();
        let triangles: Vec<[u32; 3]> = transparent.chunks(3).map(|t| [t[0], t[1], t[2]]).collect();
        indices.extend(
            back_to_front(&triangles, &centroids, camera)
                .into_iter()
                .flatten(),
        );
        let light_count = u32::try_from(scene.lights.len()).map_err(|_| GpuError::OverLimit {
            what: "light count".into(),
            value: scene.lights.len() as u64,
            limit: u32::MAX.into(),
            limit_name: "u32 light index",
        })?;
        let mut lights: Vec<GpuLight> = scene.lights.iter().map(GpuLight::from).collect();
        let point_lights = lights
            .iter()
            .all(|l| l.kind == LIGHT_KIND_POINT && l.alpha == 0.0);
        if lights.is_empty() {
            lights.push(bytemuck::Zeroable::zeroed());
        }
        ctx.check_loop_count("light count", u64::from(light_count))?;
        ctx.check_storage(
            "light buffer bytes",
            (lights.len() * size_of::<GpuLight>()) as u64,
        )?;
        ctx.check_storage(
            "vertex buffer bytes",
            (vertices.len().max(1) * size_of::<GpuVertex>()) as u64,
        )?;
        let materials: Vec<GpuMaterial> = scene.materials.iter().map(GpuMaterial::from).collect();
        let d = &ctx.device;
        let init = |label, contents: &[u8], usage| {
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let copy = wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        let vertices_buf = init(
            "scene.vertices",
            cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE | copy,
        );
        let indices_buf = init(
            "scene.indices",
            cast_slice(&indices),
            wgpu::BufferUsages::INDEX | wgpu::BufferUsages::STORAGE | copy,
        );
        let lights_buf = init(
            "scene.lights",
            cast_slice(&lights),
            wgpu::BufferUsages::STORAGE | copy,
        );
        let materials_buf = init(
            "scene.materials",
            cast_slice(&materials),
            wgpu::BufferUsages::STORAGE | copy,
        );
        let frame = GpuFrame {
            flags: if point_lights {
                FRAME_FLAG_POINT_LIGHTS
            } else {
                0
            },
            ..GpuFrame::new(camera, width, height, light_count)
        };
        let frame_buf = init(
            "scene.frame",
            bytemuck::bytes_of(&frame),
            wgpu::BufferUsages::UNIFORM | copy,
        );
        let layout = group0_layout(d);
        let bind_group = crate::pipeline::buffers_group(
            d,
            "scene.group0",
            &layout,
            &[&frame_buf, &lights_buf, &materials_buf],
        );
        Ok(Self {
            vertices: vertices_buf,
            indices: indices_buf,
            index_count: indices.len() as u32,
            opaque_index_count,
            opaque_models,
            transparent: triangles,
            centroids,
            lights: lights_buf,
            light_count,
            materials: materials_buf,
            frame: frame_buf,
            point_lights: AtomicBool::new(point_lights),
            point_kind: AtomicU32::new(0),
            view_flags: AtomicU32::new(0),
            band_ramp: AtomicU32::new(frame.band_ramp.to_bits()),
            layout,
            bind_group,
        })
    }

    /// Rewrites the frame uniform for another camera, resolution or flags (`FRAME_FLAG_*`; the
    /// scene adds `FRAME_FLAG_POINT_LIGHTS` where its lights allow it), and sorts the
    /// transparent triangles back to front for the camera.
    pub fn set_view(&self, ctx: &GpuContext, camera: &Camera, width: u32, height: u32, flags: u32) {
        let flags = flags
            & !(FRAME_FLAG_POINT_LIGHTS | FRAME_FLAG_STOCHASTIC_POINTS | FRAME_FLAG_BAND_POINTS);
        self.view_flags.store(flags, Ordering::Relaxed);
        let ramp = f32::from_bits(self.band_ramp.load(Ordering::Relaxed));
        let frame = GpuFrame {
            flags: self.frame_flags(flags),
            band_ramp: ramp,
            band_slope: 1.0 / (ramp - 1.0),
            ..GpuFrame::new(camera, width, height, self.light_count)
        };
        ctx.queue
            .write_buffer(&self.frame, 0, bytemuck::bytes_of(&frame));
        if !self.transparent.is_empty() {
            let sorted = back_to_front(&self.transparent, &self.centroids, camera);
            ctx.queue.write_buffer(
                &self.indices,
                u64::from(self.opaque_index_count) * 4,
                cast_slice(&sorted),
            );
        }
    }

    /// `flags` with `FRAME_FLAG_POINT_LIGHTS` where every light is a point light on the short
    /// path, and with the flag of its kind (stochastic ranges, hierarchy bands).
    fn frame_flags(&self, flags: u32) -> u32 {
        if !self.point_lights.load(Ordering::Relaxed) {
            return flags;
        }
        flags | FRAME_FLAG_POINT_LIGHTS | self.point_kind.load(Ordering::Relaxed)
    }

    /// Whether the frame tells shading that every light is a windowed point light
    /// (`FRAME_FLAG_POINT_LIGHTS`).
    pub fn point_lights(&self) -> bool {
        self.point_lights.load(Ordering::Relaxed)
    }

    /// From now on the lights may be anything the general model shades (stochastic alphas
    /// written on the GPU): the frame drops `FRAME_FLAG_POINT_LIGHTS`, so every light is shaded
    /// with its spot cone and alpha read.
    pub fn mark_general_lights(&self, ctx: &GpuContext) {
        self.point_lights.store(false, Ordering::Relaxed);
        self.point_kind.store(0, Ordering::Relaxed);
        self.write_flags(ctx);
    }

    /// Whether the frame tells shading that the point lights are the lighting grid hierarchy's,
    /// each with its band (`FRAME_FLAG_BAND_POINTS`, with `FRAME_FLAG_POINT_LIGHTS`).
    pub fn band_points(&self) -> bool {
        self.point_kind.load(Ordering::Relaxed) == FRAME_FLAG_BAND_POINTS
    }

    /// From now on every light carries a hierarchy band ([`GpuLight::with_band`], written on
    /// the GPU by `lights.hierarchy` or by [`GpuScene::set_light_bands`]): a scene of point lights
    /// stays on the short path, shaded with the band times `1 / d^2`
    /// (`FRAME_FLAG_BAND_POINTS`); any other scene (spots among the lights) is marked general
    /// ([`GpuScene::mark_general_lights`]).
    pub fn mark_band_points(&self, ctx: &GpuContext) {
        self.mark_point_kind(ctx, FRAME_FLAG_BAND_POINTS);
    }

    /// Uploads `lights` again (the scene's, the same count) with their hierarchy bands
    /// (`manylights_scene::hierarchy`, one a light: [`GpuLight::with_band`]), and marks them
    /// band points ([`GpuScene::mark_band_points`]: general where a spot is among them).
    /// Panics unless there are as many lights and bands as the scene has lights.
    pub fn set_light_bands(&self, ctx: &GpuContext, lights: &[Light], bands: &[Band]) {
        assert!(
            lights.len() == self.light_count as usize && bands.len() == lights.len(),
            "{} lights and {} bands for a scene of {} lights",
            lights.len(),
            bands.len(),
            self.light_count
        );
        let gpu: Vec<GpuLight> = lights
            .iter()
            .zip(bands)
            .map(|(l, b)| GpuLight::from(l).with_band(b))
            .collect();
        if !gpu.is_empty() {
            ctx.queue.write_buffer(&self.lights, 0, cast_slice(&gpu));
        }
        if let Some(b) = bands.first() {
            assert!(
                bands.iter().all(|c| c.ramp == b.ramp),
                "one hierarchy's bands share their ramp"
            );
            self.set_band_ramp(ctx, b.ramp as f32);
        }
        self.mark_band_points(ctx);
    }

    /// The ramps of the hierarchy's bands the frame carries from now on (`light_band`: a band
    /// rises from its inner distance to `ramp` times it and falls from its r to `ramp` times r;
    /// above 1 and at most 2, the papers' and the default).
    pub fn set_band_ramp(&self, ctx: &GpuContext, ramp: f32) {
        assert!(ramp > 1.0 && ramp <= 2.0, "a band ramp of {ramp}");
        self.band_ramp.store(ramp.to_bits(), Ordering::Relaxed);
        ctx.queue.write_buffer(
            &self.frame,
            std::mem::offset_of!(GpuFrame, band_ramp) as u64,
            bytemuck::cast_slice(&[ramp, 1.0 / (ramp - 1.0)]),
        );
    }

    /// Whether the frame tells shading that the point lights carry stochastic ranges without
    /// interleaving (`FRAME_FLAG_STOCHASTIC_POINTS`, with `FRAME_FLAG_POINT_LIGHTS`).
    pub fn stochastic_points(&self) -> bool {
        self.point_kind.load(Ordering::Relaxed) == FRAME_FLAG_STOCHASTIC_POINTS
    }

    /// From now on every light carries a stochastic range and alpha drawn for each frame, one
    /// range a light (no interleaving): a scene of windowed point lights stays on the short
    /// path, shaded `max(1 / d^2, alpha)` inside the ranges (`FRAME_FLAG_STOCHASTIC_POINTS`);
    /// any other scene is marked general ([`GpuScene::mark_general_lights`]).
    pub fn mark_stochastic_points(&self, ctx: &GpuContext) {
        self.mark_point_kind(ctx, FRAME_FLAG_STOCHASTIC_POINTS);
    }

    /// Point lights stay on the short path as `kind` (a `FRAME_FLAG_*_POINTS` flag); any other
    /// lights are marked general.
    fn mark_point_kind(&self, ctx: &GpuContext, kind: u32) {
        if self.point_lights.load(Ordering::Relaxed) {
            self.point_kind.store(kind, Ordering::Relaxed);
            self.write_flags(ctx);
        } else {
            self.mark_general_lights(ctx);
        }
    }

    /// Writes the frame's flags again from the last view's and the lights' state.
    fn write_flags(&self, ctx: &GpuContext) {
        let flags = self.frame_flags(self.view_flags.load(Ordering::Relaxed));
        ctx.queue.write_buffer(
            &self.frame,
            std::mem::offset_of!(GpuFrame, flags) as u64,
            bytemuck::bytes_of(&flags),
        );
    }

    /// Whether the scene has transparent triangles.
    pub fn has_transparent(&self) -> bool {
        !self.transparent.is_empty()
    }

    /// Binds group 0 and the geometry, and draws every opaque triangle.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        self.bind_geometry(pass);
        pass.draw_indexed(0..self.opaque_index_count, 0, 0..1);
    }

    /// The material models of the opaque triangles, a bit each (`1 << Model::id`): the
    /// `MATERIAL_MODELS` of a pass that shades them all (`shaders/common/brdf.wgsl`).
    pub fn opaque_model_mask(&self) -> u32 {
        self.opaque_models.iter().fold(0, |m, (id, _)| m | 1 << id)
    }

    /// Binds group 0 and the geometry, and draws the opaque triangles of
    /// `opaque_models[group]`.
    pub fn draw_model(&self, pass: &mut wgpu::RenderPass<'_>, group: usize) {
        self.bind_geometry(pass);
        pass.draw_indexed(self.opaque_models[group].1.clone(), 0, 0..1);
    }

    /// Binds group 0 and the geometry, and draws the transparent triangles, back to front for
    /// the camera of the last [`GpuScene::set_view`] (or of the upload).
    pub fn draw_transparent(&self, pass: &mut wgpu::RenderPass<'_>) {
        self.bind_geometry(pass);
        pass.draw_indexed(self.opaque_index_count..self.index_count, 0, 0..1);
    }

    fn bind_geometry(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
    }
}

/// The triangles ordered farthest first from the camera, by their centroids' distance along
/// the view direction (a painter's order: exact for panes that do not overlap in depth
/// within a pixel's view; intersecting transparent triangles are not split). Ties keep the
/// scene's order.
fn back_to_front(triangles: &[[u32; 3]], centroids: &[Vec3], camera: &Camera) -> Vec<[u32; 3]> {
    let view = camera.view_from_world();
    let mut order: Vec<(f32, usize)> = centroids
        .iter()
        .enumerate()
        .map(|(k, &c)| (view.transform_point3(c).z, k))
        .collect();
    // View space looks down -Z: the most negative z is the farthest.
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    order.into_iter().map(|(_, k)| triangles[k]).collect()
}
