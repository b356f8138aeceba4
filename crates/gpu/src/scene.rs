//! The scene on the GPU: one vertex buffer and one index buffer for all primitives (the material
//! index travels per vertex), the lights and materials as storage buffers, and the frame uniform.
//! Group 0 of every pass binds: 0 = frame, 1 = lights, 2 = materials, 3 and 4 = the BVH of the
//! opaque triangles that shadow rays walk ([`GpuScene::build_bvh`]; until it is built, a BVH of
//! no triangle), 5 = the counters of the shadow rays shading casts ([`GpuScene::count_rays`])
//! or of the lights it walks ([`GpuScene::count_lights_walked`]), whichever a frame counts.

use bytemuck::cast_slice;
use glam::Vec3;
use manylights_scene::hierarchy::Band;
use manylights_scene::{Camera, Light, Scene};
use wgpu::util::DeviceExt;

use crate::bvh::{GpuBvh, SceneBvh};
use crate::layout::{GpuFrame, GpuLight, GpuMaterial, GpuVertex, LIGHT_KIND_POINT};
use crate::light_model::{LightModel, LightPath, Ranges};
use crate::{GpuContext, GpuError};

mod counts;

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
    /// How its lights are shaded, as uploaded ([`GpuScene::upload_with`]).
    model: LightModel,
    /// The path shading takes, from the model and the lights as uploaded.
    path: LightPath,
    /// Layout of group 0.
    pub layout: wgpu::BindGroupLayout,
    /// Group 0.
    pub bind_group: wgpu::BindGroup,
    /// The BVH group 0 binds: the scene's, once built ([`GpuScene::build_bvh`]), or one of no
    /// triangle.
    bvh: GpuBvh,
    /// Whether `bvh` is the scene's.
    has_bvh: bool,
    /// The frame number stochastic shadow rays draw by ([`GpuScene::set_shadow_frame`]).
    shadow_frame: std::sync::Arc<std::sync::atomic::AtomicU32>,
    /// [`RAY_COUNT_SLOTS`] counters of shadow rays or walked lights, group 0's binding 5.
    ray_counts: wgpu::Buffer,
}

/// Counters the shadow rays of a counted frame are spread over (a ray adds one to the slot its
/// surface point hashes to, so that a frame's millions of rays do not contend for one word), and
/// its pixels' walked lights (a pixel adds its count to the slot its colour hashes to).
pub const RAY_COUNT_SLOTS: u32 = 16_384;

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
            storage(3),
            storage(4),
            // The ray counters: written by shading only (no vertex stage writes storage).
            wgpu::BindGroupLayoutEntry {
                binding: 5,
                visibility: wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: false },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
        ],
    })
}

/// Group 0 over the frame uniform, the lights and the materials (`scene`), the BVH and the ray
/// counters.
fn group0(
    d: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    [frame, lights, materials]: [&wgpu::Buffer; 3],
    (bvh, ray_counts): (&GpuBvh, &wgpu::Buffer),
) -> wgpu::BindGroup {
    crate::pipeline::buffers_group(
        d,
        "scene.group0",
        layout,
        &[
            frame,
            lights,
            materials,
            &bvh.nodes,
            &bvh.triangles,
            ray_counts,
        ],
    )
}

impl GpuScene {
    /// Uploads `scene` (which must validate) with each light's own radius
    /// ([`LightModel::CUT_OFF`]) and sets the frame for `camera` at `width` x `height`.
    pub fn upload(
        ctx: &GpuContext,
        scene: &Scene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<Self, GpuError> {
        Self::upload_with(ctx, scene, LightModel::CUT_OFF, camera, width, height)
    }

    /// Uploads `scene` (which must validate) for the light model `model` (the passes that write
    /// its lights check it: stochastic ranges, the hierarchy's build) and sets the frame for
    /// `camera` at `width` x `height`.
    pub fn upload_with(
        ctx: &GpuContext,
        scene: &Scene,
        model: LightModel,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<Self, GpuError> {
        check_model(&model, scene)?;
        let Geometry {
            vertices,
            indices,
            opaque_models,
            opaque_index_count,
            triangles,
            centroids,
        } = Geometry::of(scene, camera);
        let light_count = u32::try_from(scene.lights.len()).map_err(|_| GpuError::OverLimit {
            what: "light count".into(),
            value: scene.lights.len() as u64,
            limit: u32::MAX.into(),
            limit_name: "u32 light index",
        })?;
        let mut lights: Vec<GpuLight> = scene.lights.iter().map(GpuLight::from).collect();
        let path = model.path(
            lights.iter().all(|l| l.kind == LIGHT_KIND_POINT),
            light_count,
        );
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
        let frame = Self::frame(model, path, camera, (width, height), light_count, 0);
        let frame_buf = init(
            "scene.frame",
            bytemuck::bytes_of(&frame),
            wgpu::BufferUsages::UNIFORM | copy,
        );
        let layout = group0_layout(d);
        let bvh = GpuBvh::upload(ctx, &SceneBvh::of_triangles(&[])?)?;
        let ray_counts = init(
            "scene.ray_counts",
            &vec![0u8; RAY_COUNT_SLOTS as usize * 4],
            wgpu::BufferUsages::STORAGE | copy,
        );
        let bind_group = group0(
            d,
            &layout,
            [&frame_buf, &lights_buf, &materials_buf],
            (&bvh, &ray_counts),
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
            model,
            path,
            layout,
            bind_group,
            bvh,
            has_bvh: false,
            shadow_frame: Default::default(),
            ray_counts,
        })
    }

    /// Builds the BVH of `scene`'s opaque triangles (the scene this was uploaded from) on the
    /// CPU, uploads it and binds it in group 0, for shading with shadow rays; returns it. An
    /// error where its tree is deeper than the traversal's stack or a buffer exceeds the
    /// device's storage bindings.
    pub fn build_bvh(&mut self, ctx: &GpuContext, scene: &Scene) -> Result<SceneBvh, GpuError> {
        let built = SceneBvh::build(scene)?;
        self.bvh = GpuBvh::upload(ctx, &built)?;
        self.has_bvh = true;
        self.bind_group = group0(
            &ctx.device,
            &self.layout,
            [&self.frame, &self.lights, &self.materials],
            (&self.bvh, &self.ray_counts),
        );
        Ok(built)
    }

    /// Sets the frame number stochastic shadow rays draw their lights by (0 after the upload):
    /// the frame uniform's `shadow_frame`, kept by later [`GpuScene::set_view`]s. Frames of
    /// one number draw the same lights; a renderer that accumulates frames gives each its own.
    pub fn set_shadow_frame(&self, ctx: &GpuContext, frame: u32) {
        self.shadow_frames().set(ctx, frame);
    }

    /// What sets the scene's shadow frame ([`GpuScene::set_shadow_frame`]), for a holder that
    /// does not hold the scene.
    pub fn shadow_frames(&self) -> ShadowFrames {
        ShadowFrames {
            frame: self.frame.clone(),
            value: self.shadow_frame.clone(),
        }
    }

    /// Whether the scene's BVH is built and bound ([`GpuScene::build_bvh`]).
    pub fn has_bvh(&self) -> bool {
        self.has_bvh
    }

    /// The BVH group 0 binds (of no triangle until [`GpuScene::build_bvh`]).
    pub fn bvh(&self) -> &GpuBvh {
        &self.bvh
    }

    /// The frame uniform of `camera` rendering a `width` x `height` target with the view's
    /// `flags` (`FRAME_FLAG_*` but the light path's) for lights of `model` shaded by `path`.
    fn frame(
        model: LightModel,
        path: LightPath,
        camera: &Camera,
        (width, height): (u32, u32),
        light_count: u32,
        flags: u32,
    ) -> GpuFrame {
        let ramp = model.band_ramp();
        GpuFrame {
            flags: (flags & !LightPath::FLAGS) | path.frame_flags(),
            band_ramp: ramp,
            band_slope: 1.0 / (ramp - 1.0),
            ..GpuFrame::new(camera, width, height, light_count)
        }
    }

    /// Rewrites the frame uniform for another camera, resolution or flags (`FRAME_FLAG_*`; the
    /// light path's flags are the scene's own, whatever `flags` holds), and sorts the
    /// transparent triangles back to front for the camera.
    pub fn set_view(&self, ctx: &GpuContext, camera: &Camera, width: u32, height: u32, flags: u32) {
        let frame = GpuFrame {
            shadow_frame: self.shadow_frame.load(std::sync::atomic::Ordering::Relaxed),
            ..Self::frame(
                self.model,
                self.path,
                camera,
                (width, height),
                self.light_count,
                flags,
            )
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

    /// How its lights are shaded, as uploaded.
    pub fn light_model(&self) -> LightModel {
        self.model
    }

    /// The path shading takes over its lights: what its renderers' pipelines are built for.
    pub fn light_path(&self) -> LightPath {
        self.path
    }

    /// Uploads `lights` again (the scene's, the same count) with their hierarchy bands
    /// (`manylights_scene::hierarchy`, one a light: [`GpuLight::with_band`]), as a hierarchy's
    /// build writes them.
    ///
    /// # Panics
    /// Unless the scene was uploaded for the hierarchy with the bands' ramp, and there are as
    /// many lights and bands as the scene has lights.
    pub fn set_light_bands(&self, ctx: &GpuContext, lights: &[Light], bands: &[Band]) {
        assert!(
            lights.len() == self.light_count as usize && bands.len() == lights.len(),
            "{} lights and {} bands for a scene of {} lights",
            lights.len(),
            bands.len(),
            self.light_count
        );
        if let Some(b) = bands.first() {
            assert!(
                bands.iter().all(|c| c.ramp == b.ramp)
                    && self.model.ranges
                        == (Ranges::Hierarchy {
                            ramp: b.ramp as f32
                        }),
                "bands of ramp {} for a scene uploaded for {:?}: upload it with \
                 LightModel::hierarchy of the bands' one ramp",
                b.ramp,
                self.model.ranges
            );
        }
        let gpu: Vec<GpuLight> = lights
            .iter()
            .zip(bands)
            .map(|(l, b)| GpuLight::from(l).with_band(b))
            .collect();
        if !gpu.is_empty() {
            ctx.queue.write_buffer(&self.lights, 0, cast_slice(&gpu));
        }
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
/// Whether `model` is one `scene` can be uploaded for: its values, and its first drawn light
/// among the scene's.
fn check_model(model: &LightModel, scene: &Scene) -> Result<(), GpuError> {
    model.validate().map_err(GpuError::Unsupported)?;
    match model.ranges {
        Ranges::Stochastic { first, .. } if first as usize > scene.lights.len() => {
            Err(GpuError::OverLimit {
                what: "the first light with stochastic ranges".into(),
                value: u64::from(first),
                limit: scene.lights.len() as u64,
                limit_name: "the scene's light count",
            })
        }
        _ => Ok(()),
    }
}

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

/// A scene's triangles as uploaded: its vertices, the opaque triangles' indices first, a
/// material model at a time, then the transparent ones sorted back to front for the camera.
struct Geometry {
    vertices: Vec<GpuVertex>,
    indices: Vec<u32>,
    opaque_models: Vec<(u32, std::ops::Range<u32>)>,
    opaque_index_count: u32,
    /// The transparent triangles and their centroids.
    triangles: Vec<[u32; 3]>,
    centroids: Vec<Vec3>,
}

impl Geometry {
    fn of(scene: &Scene, camera: &Camera) -> Self {
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
        Self {
            vertices,
            indices,
            opaque_models,
            opaque_index_count,
            triangles,
            centroids,
        }
    }
}

/// Sets a scene's shadow frame ([`GpuScene::shadow_frames`]).
#[derive(Clone, Debug)]
pub struct ShadowFrames {
    frame: wgpu::Buffer,
    value: std::sync::Arc<std::sync::atomic::AtomicU32>,
}

impl ShadowFrames {
    /// As [`GpuScene::set_shadow_frame`].
    pub fn set(&self, ctx: &GpuContext, frame: u32) {
        self.value
            .store(frame, std::sync::atomic::Ordering::Relaxed);
        ctx.queue.write_buffer(
            &self.frame,
            std::mem::offset_of!(GpuFrame, shadow_frame) as u64,
            bytemuck::bytes_of(&frame),
        );
    }
}
