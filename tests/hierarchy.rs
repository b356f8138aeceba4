//! The lighting grid hierarchy (issue 48) on the GPU: its lights flattened with their bands
//! (`manylights_scene::hierarchy`), uploaded with `GpuScene::set_light_bands` and shaded by
//! the brute-force reference, against the hierarchy's shading in f64 at the same surface points.

mod common;

use glam::DVec3;
use manylights_gpu::GpuScene;
use manylights_scene::hierarchy::{self, Hierarchy, HierarchyParams};
use manylights_scene::light::{Range, shade};
use manylights_scene::procedural::ProceduralScene;
use manylights_scene::{LightGenerator, LightSpec, RadiusRule, Scene};
use manylights_shade::ReferenceRenderer;

fn atrium(count: u32, spots: f32) -> Scene {
    let mut scene = ProceduralScene::from_name("atrium")
        .unwrap()
        .build()
        .unwrap();
    let spec = LightSpec {
        generator: LightGenerator::Uniform,
        count,
        seed: 48,
        radius: RadiusRule::Fixed(3.0),
        intensity: 2.0,
        spot_fraction: spots,
        spot_outer_deg: 50.0,
        ..LightSpec::default()
    };
    scene.lights = spec.generate(&scene).unwrap();
    scene
}

fn rgb(t: [f32; 4]) -> DVec3 {
    DVec3::new(t[0].into(), t[1].into(), t[2].into())
}

/// Every level's light and every spot, shaded on the GPU with its band, against
/// `hierarchy::shade` in f64. The bands are continuous (0 at both ends), so f32 rounding of a
/// distance moves a term by a rounding, not by a step: 1e-4 of each pixel plus 1e-6 of the
/// image's mean. The hierarchy's image also differs from the lights' own at infinite range by
/// its bias, which is small at this alpha but not zero (the hierarchy is in effect).
#[test]
fn hierarchy_lights_shade_as_their_oracle() {
    let ctx = common::gpu();
    let (w, h) = (40, 24);
    let original = atrium(1500, 0.2);
    let hier = Hierarchy::build(
        &original.lights,
        HierarchyParams {
            alpha: 2.0,
            spacing: 0.75,
            top_lights: 16,
        },
    );
    assert!(hier.levels.len() >= 4, "{} levels", hier.levels.len());
    let (flat, bands) = hier.flatten(hierarchy::reach(&original));
    let scene = Scene {
        lights: flat.clone(),
        ..original.clone()
    };
    let gpu = GpuScene::upload(&ctx, &scene, &scene.camera, w, h).unwrap();
    gpu.set_light_bands(&ctx, &flat, &bands);
    let rr = ReferenceRenderer::new(&ctx, &gpu);
    let got = rr.render(&ctx, &gpu, w, h).unwrap();
    let eye = scene.camera.position.as_dvec3();
    let (mut checked, mut biased) = (0, 0);
    let mut mean = 0.0;
    let mut pairs = Vec::new();
    for (k, (p, n)) in got.position.data.iter().zip(&got.normal.data).enumerate() {
        if p[3] == 0.0 {
            continue;
        }
        let (pos, nrm) = (rgb(*p), rgb(*n));
        let v = (eye - pos).normalize();
        let m = &scene.materials[n[3] as usize];
        let want = hierarchy::shade(pos, nrm, v, m, &flat, &bands);
        let exact = shade(pos, nrm, v, m, &original.lights, Range::Infinite);
        if (want - exact).abs().max_element() > 1e-3 * exact.max_element() {
            biased += 1;
        }
        mean += want.element_sum() / 3.0;
        pairs.push((k, rgb(got.color.data[k]), want));
    }
    mean /= pairs.len() as f64;
    for (k, g, want) in &pairs {
        assert!(
            (*g - *want).abs().max_element() <= 1e-4 * want.max_element() + 1e-6 * mean,
            "pixel {k}: gpu {g} vs f64 {want}"
        );
        checked += 1;
    }
    assert!(checked > (w * h / 2) as usize, "{checked} pixels");
    assert!(
        biased > 0,
        "the hierarchy's estimate is the lights' own everywhere"
    );
}
