//! Several material models in one frame: every backend against the reference with the five
//! models mixed (forward drawing a pipeline a model, deferred branching on the pixel's model)
//! and with GGX alone, at the tolerances of every other backend test; and no non-finite pixel
//! at the models' edges (grazing views, lights at the surface, roughness and metalness 0 and 1).

use glam::Vec3;
use manylights_cull::{CullSettings, Strategy};
use manylights_gpu::GpuScene;
use manylights_scene::{Aabb, Brdf, Camera, Light, Material, Model, Primitive, Scene};
use manylights_shade::accuracy::compare;
use manylights_shade::{Backend, ReferenceRenderer, Renderer};

use super::{common, naive_against, scene, strategies, within_tolerance};

/// Forward, deferred and the stored-position deferred over every strategy (deferred's tile path,
/// clusters' list a bin, z-binning's workgroup walk), and naive forward: within tolerance of the
/// reference, with every model in the frame and with GGX alone.
#[test]
fn every_material_model_and_backend_matches_the_reference() {
    let ctx = common::gpu();
    let (w, h) = (64, 48);
    let strategies = strategies();
    for models in [Model::ALL.to_vec(), vec![Model::Ggx]] {
        let mut s = scene("atrium");
        s.assign_models(&models);
        s.validate().unwrap();
        let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
        assert_eq!(
            gpu_scene.opaque_models.len(),
            models.len(),
            "{models:?}: a draw a model"
        );
        let reference = ReferenceRenderer::new(&ctx, &gpu_scene)
            .render(&ctx, &gpu_scene, w, h)
            .unwrap()
            .color;
        assert!(reference.peak() > 0.0);
        let renderer = Renderer::new(&ctx, &gpu_scene);
        let settings = CullSettings::for_camera(&s.camera);
        let (_, e) = naive_against(&ctx, &renderer, &gpu_scene, &settings, (w, h), &reference);
        assert!(
            within_tolerance(&e, Backend::NaiveForward),
            "{models:?} naive: {e:?}"
        );
        for strategy in &strategies {
            for backend in [
                Backend::Forward,
                Backend::Deferred,
                Backend::DeferredStoredPosition,
                Backend::Visibility,
            ] {
                let what = format!("{models:?} {} {}", strategy.name(), backend.name());
                let out = renderer
                    .render(&ctx, &gpu_scene, backend, strategy, &settings, (w, h))
                    .unwrap();
                let e = compare(&out.color, &reference, 1.0);
                assert!(within_tolerance(&e, backend), "{what}: {e:?}");
                assert_eq!(out.color.non_finite_count(), 0, "{what}");
            }
        }
    }
}

/// A plane in strips, a material each at the edges of its model's parameters, seen at grazing
/// angles and lit by lights at and just above its surface (down to the falloff's 1 cm floor):
/// no backend and no reference writes a non-finite pixel, and forward agrees with the reference.
#[test]
fn material_edges_render_finite_pixels() {
    let ctx = common::gpu();
    let brdfs = [
        Brdf::Ggx {
            metallic: 0.0,
            roughness: 0.0,
        },
        Brdf::Ggx {
            metallic: 1.0,
            roughness: 0.0,
        },
        Brdf::Ggx {
            metallic: 0.0,
            roughness: 1.0,
        },
        Brdf::Ggx {
            metallic: 1.0,
            roughness: 1.0,
        },
        Brdf::ClearCoat {
            metallic: 1.0,
            roughness: 0.0,
            coat: 1.0,
            coat_roughness: 0.0,
        },
        Brdf::Sheen {
            roughness: 0.0,
            sheen: Vec3::ONE,
        },
        Brdf::Sheen {
            roughness: 1.0,
            sheen: Vec3::ONE,
        },
        Brdf::Wrap { wrap: 0.0 },
        Brdf::Wrap { wrap: 1.0 },
        Brdf::BlinnPhong { specular: 1.0 },
    ];
    let strip = 2.0;
    let mut primitives = Vec::new();
    let mut materials = Vec::new();
    for (k, brdf) in brdfs.iter().enumerate() {
        let x0 = k as f32 * strip - 10.0;
        primitives.push(Primitive {
            positions: vec![
                Vec3::new(x0, 0.0, -10.0),
                Vec3::new(x0 + strip, 0.0, -10.0),
                Vec3::new(x0 + strip, 0.0, 10.0),
                Vec3::new(x0, 0.0, 10.0),
            ],
            normals: vec![Vec3::Y; 4],
            indices: vec![0, 2, 1, 0, 3, 2],
            material: k as u32,
        });
        for base in [Vec3::ZERO, Vec3::ONE] {
            // Two materials a model (black and white); the strips use the white ones.
            materials.push(Material {
                base_color: base,
                brdf: *brdf,
                opacity: 1.0,
                emissive: Vec3::ZERO,
            });
        }
    }
    for (k, p) in primitives.iter_mut().enumerate() {
        p.material = 2 * k as u32 + 1;
    }
    let mut lights = Vec::new();
    for k in 0..brdfs.len() {
        let x = k as f32 * strip - 10.0 + strip / 2.0;
        for (y, z) in [(0.0, 8.0), (0.005, 6.0), (0.3, 4.0), (1.0, 2.0)] {
            lights.push(Light::point(Vec3::new(x, y, z), 3.0, Vec3::ONE, 2.0));
        }
    }
    // Grazing: the eye 2 cm above the plane (inside its edge), looking along it.
    let camera = Camera::perspective(
        Vec3::new(0.0, 0.02, 9.5),
        Vec3::new(0.0, 0.0, -10.0),
        60.0,
        0.01,
        50.0,
    );
    let s = Scene {
        name: "edges".into(),
        primitives,
        materials,
        lights,
        camera,
        light_bounds: Aabb::new(Vec3::splat(-10.0), Vec3::splat(10.0)),
    };
    s.validate().unwrap();
    let (w, h) = (96, 32);
    let gpu_scene = GpuScene::upload(&ctx, &s, &camera, w, h).unwrap();
    let reference = ReferenceRenderer::new(&ctx, &gpu_scene)
        .render(&ctx, &gpu_scene, w, h)
        .unwrap()
        .color;
    assert_eq!(reference.non_finite_count(), 0, "reference");
    assert!(reference.peak() > 0.0);
    let renderer = Renderer::new(&ctx, &gpu_scene);
    let settings = CullSettings::for_camera(&camera);
    for backend in [
        Backend::Forward,
        Backend::Deferred,
        Backend::NaiveForward,
        Backend::Visibility,
    ] {
        let out = renderer
            .render(
                &ctx,
                &gpu_scene,
                backend,
                &Strategy::tiled_gather(16),
                &settings,
                (w, h),
            )
            .unwrap();
        assert_eq!(out.color.non_finite_count(), 0, "{}", backend.name());
        if backend != Backend::Deferred {
            let e = compare(&out.color, &reference, 1.0);
            assert!(within_tolerance(&e, backend), "{}: {e:?}", backend.name());
        }
    }
}
