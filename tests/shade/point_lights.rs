//! Windowed point lights take the shading loops' short path (`FRAME_FLAG_POINT_LIGHTS`,
//! `shade_point_light` in shaders/common/shading.wgsl): the same image as the general model's
//! path, on every form of lists (a workgroup's tile list, a pixel's bin list, z-binning's masks
//! a workgroup and a pixel at a time) and every culled backend.

use manylights_gpu::layout::GpuLight;
use manylights_gpu::{LightModel, LightPath};

use super::*;

/// `scene(name)` with point lights only (the same generator, no spots).
fn point_scene(name: &str) -> Scene {
    let mut s = scene(name);
    for l in &mut s.lights {
        l.kind = manylights_scene::LightKind::Point;
    }
    s
}

/// Each culled backend's frame of `gpu_scene` with `strategy`, by `renderer`.
fn frames(
    ctx: &GpuContext,
    renderer: &Renderer,
    gpu_scene: &GpuScene,
    s: &Scene,
    strategy: &Strategy,
    size: (u32, u32),
) -> Vec<HdrImage> {
    let settings = CullSettings::for_camera(&s.camera);
    CULLED
        .into_iter()
        .map(|backend| {
            renderer
                .render(ctx, gpu_scene, backend, strategy, &settings, size)
                .unwrap()
                .color
        })
        .collect()
}

/// Every strategy's frames, each culled backend's, by the short path (`short`, a renderer and
/// its scene) and the general one: lit, and the same within 1e-5 of the peak.
fn same_frames(
    ctx: &GpuContext,
    short: (&Renderer, &GpuScene),
    general: (&Renderer, &GpuScene),
    s: &Scene,
    size: (u32, u32),
) {
    for strategy in strategies() {
        let a = frames(ctx, short.0, short.1, s, &strategy, size);
        let b = frames(ctx, general.0, general.1, s, &strategy, size);
        for (k, backend) in CULLED.into_iter().enumerate() {
            let what = format!("{} {}", strategy.name(), backend.name());
            assert!(a[k].peak() > 0.0, "{what}: black");
            let d = max_difference(&a[k], &b[k]);
            assert!(
                d <= 1e-5,
                "{what}: short and general paths differ by {d:e} of the peak"
            );
        }
    }
}

/// The largest difference of two images' colour channels, relative to the first one's peak.
fn max_difference(a: &HdrImage, b: &HdrImage) -> f32 {
    let d = a
        .data
        .iter()
        .zip(&b.data)
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0f32, f32::max);
    d / a.peak()
}

/// A scene of point lights takes the short path, one with spots does not, nor one uploaded for
/// the general model. A renderer built for the short path's scene shades with it, and its images
/// equal those of a renderer built for the general path within rounding; it refuses the
/// general scene. And the flag is what picks the path: spot lights written into a flagged scene's buffer are shaded as points (cones
/// ignored), so the flag must only be set where the lights allow it.
#[test]
fn point_lights_shade_as_the_general_model_does() {
    let ctx = common::gpu();
    let size = (70, 45);
    let spots = scene("atrium");
    let points = point_scene("atrium");
    let spot_gpu = GpuScene::upload(&ctx, &spots, &spots.camera, size.0, size.1).unwrap();
    assert_eq!(
        spot_gpu.light_path(),
        LightPath::General,
        "a scene with spots must not be flagged"
    );
    let fast = GpuScene::upload(&ctx, &points, &points.camera, size.0, size.1).unwrap();
    assert_eq!(
        fast.light_path(),
        LightPath::Points,
        "a scene of point lights is flagged"
    );
    let general = GpuScene::upload_with(
        &ctx,
        &points,
        LightModel::CUT_OFF.general(),
        &points.camera,
        size.0,
        size.1,
    )
    .unwrap();
    assert_eq!(general.light_path(), LightPath::General);
    let point_renderer = Renderer::new(&ctx, &fast);
    assert_eq!(point_renderer.light_path(), LightPath::Points);
    let general_renderer = Renderer::new(&ctx, &general);
    assert_eq!(general_renderer.light_path(), LightPath::General);
    let refused = point_renderer.render(
        &ctx,
        &general,
        Backend::Deferred,
        &Strategy::tiled_gather(16),
        &CullSettings::for_camera(&points.camera),
        size,
    );
    let message = refused
        .err()
        .expect("a point-light renderer over general lights")
        .to_string();
    assert!(message.contains("point lights"), "{message}");
    same_frames(
        &ctx,
        (&point_renderer, &fast),
        (&general_renderer, &general),
        &points,
        size,
    );
    // Spots in a flagged scene's buffer: the short path ignores their cones.
    let spot_lights: Vec<GpuLight> = spots.lights.iter().map(GpuLight::from).collect();
    ctx.queue
        .write_buffer(&fast.lights, 0, bytemuck::cast_slice(&spot_lights));
    let strategy = Strategy::tiled_gather(16);
    let flagged = frames(&ctx, &point_renderer, &fast, &spots, &strategy, size);
    let right = frames(&ctx, &general_renderer, &spot_gpu, &spots, &strategy, size);
    for (k, backend) in CULLED.into_iter().enumerate() {
        let d = max_difference(&right[k], &flagged[k]);
        assert!(
            d > 1e-2,
            "{}: the flag did not switch the path (cones shaded either way, difference {d:e})",
            backend.name()
        );
    }
}

/// The shader's own guard: a point-light renderer's shading pass run past the host's check
/// (`Renderer::shade_pass`, as the benches drive it) over a scene of the same lights uploaded
/// for the general model writes NaN at every covered pixel, for forward and deferred lighting
/// alike.
#[test]
fn point_light_pipelines_write_nan_over_general_lights() {
    let ctx = common::gpu();
    let (w, h) = (64, 48);
    let s = point_scene("atrium");
    let settings = CullSettings::for_camera(&s.camera);
    let strategy = Strategy::tiled_gather(16);
    for backend in [Backend::Forward, Backend::Deferred] {
        let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
        let renderer = Renderer::new(&ctx, &gpu_scene);
        let out = renderer
            .render(&ctx, &gpu_scene, backend, &strategy, &settings, (w, h))
            .unwrap();
        let covered = out.color.data.iter().filter(|p| p[3] > 0.0).count();
        assert!(
            covered > 0 && out.color.non_finite_count() == 0,
            "{}",
            backend.name()
        );
        let general =
            GpuScene::upload_with(&ctx, &s, LightModel::CUT_OFF.general(), &s.camera, w, h)
                .unwrap();
        let mut pass = renderer.shade_pass(&ctx, &general, &out).unwrap();
        let again = shade_again(
            &ctx, &renderer, &general, &out, &strategy, &settings, &mut pass,
        );
        let nan = again
            .data
            .iter()
            .filter(|p| p[3] > 0.0 && p[..3].iter().any(|c| c.is_nan()))
            .count();
        assert_eq!(nan, covered, "{}: every covered pixel NaN", backend.name());
    }
}

/// Stochastic ranges on a scene of point lights, every light drawn and one range a light, keep
/// the short path (`FRAME_FLAG_STOCHASTIC_POINTS`, pipelines built with `STOCHASTIC_POINTS`,
/// which shade `max(1 / d^2, alpha)` inside the drawn range): the same image as the general
/// model's path over the same draws, on every form of lists and every culled backend. A
/// point-light renderer built without stochastic ranges refuses such a scene, and one built
/// with them a scene without; interleaving, or lights left undrawn, take the general path; draws
/// over a scene uploaded for other ranges are refused.
#[test]
fn stochastic_point_lights_shade_as_the_general_model_does() {
    use manylights_gpu::stochastic::StochasticRanges;
    use manylights_scene::stochastic::StochasticParams;
    let ctx = common::gpu();
    let size = (70, 45);
    let points = point_scene("atrium");
    let upload_for = |model| {
        GpuScene::upload_with(&ctx, &points, model, &points.camera, size.0, size.1).unwrap()
    };
    let upload = || upload_for(LightModel::stochastic(0, 1));
    let params = StochasticParams {
        error: 0.05,
        exposure: 1.0,
        scale: 1.0,
        seed: 3,
        interleave: 1,
        draw: manylights_scene::stochastic::StochasticDraw::Stratified,
    };
    let strata = manylights_scene::stochastic::strata(&points.lights);
    let fast = upload();
    let n = fast.light_count;
    let fast_draw = StochasticRanges::new(&ctx, &fast, 0, n, &params, &strata).unwrap();
    assert_eq!(fast.light_path(), LightPath::StochasticPoints);
    let general = upload_for(LightModel::stochastic(0, 1).general());
    let general_draw = StochasticRanges::new(&ctx, &general, 0, n, &params, &strata).unwrap();
    assert_eq!(general.light_path(), LightPath::General);
    let stochastic_renderer = Renderer::new(&ctx, &fast);
    assert_eq!(
        stochastic_renderer.light_path(),
        LightPath::StochasticPoints
    );
    let general_renderer = Renderer::new(&ctx, &general);
    assert_eq!(general_renderer.light_path(), LightPath::General);
    fast_draw.draw(&ctx, 2).unwrap();
    general_draw.draw(&ctx, 2).unwrap();
    // (The short path multiplies colour by intensity first: rounding apart.)
    same_frames(
        &ctx,
        (&stochastic_renderer, &fast),
        (&general_renderer, &general),
        &points,
        size,
    );
    // Each kind of point-light renderer refuses the other kind's scene.
    let windowed = upload_for(LightModel::CUT_OFF);
    let windowed_renderer = Renderer::new(&ctx, &windowed);
    assert_eq!(windowed_renderer.light_path(), LightPath::Points);
    let settings = CullSettings::for_camera(&points.camera);
    let strategy = Strategy::tiled_gather(16);
    for (renderer, scene) in [
        (&windowed_renderer, &fast),
        (&stochastic_renderer, &windowed),
    ] {
        let refused = renderer.render(&ctx, scene, Backend::Deferred, &strategy, &settings, size);
        let message = refused.err().expect("refused").to_string();
        assert!(message.contains("point lights"), "{message}");
    }
    // The flag picks the falloff: the same drawn lights in a scene flagged windowed are shaded
    // with the window over the drawn ranges and no reweighting, which loses energy.
    let drawn_lights = manylights_gpu::readback::read_buffer(
        &ctx,
        &fast.lights,
        0,
        u64::from(n) * std::mem::size_of::<GpuLight>() as u64,
    )
    .unwrap();
    ctx.queue.write_buffer(&windowed.lights, 0, &drawn_lights);
    let energy =
        |i: &HdrImage| -> f64 { i.data.iter().map(|p| f64::from(p[0] + p[1] + p[2])).sum() };
    let plain = frames(
        &ctx,
        &windowed_renderer,
        &windowed,
        &points,
        &strategy,
        size,
    );
    let drawn = frames(&ctx, &stochastic_renderer, &fast, &points, &strategy, size);
    for k in 0..CULLED.len() {
        let (w, d) = (energy(&plain[k]), energy(&drawn[k]));
        assert!(
            d > 1.02 * w,
            "{}: the stochastic path's energy {d} against the window's {w}",
            CULLED[k].name()
        );
    }
    // Interleaved classes, or lights left undrawn, are the general model's.
    let interleaved = upload_for(LightModel::stochastic(0, 2));
    let il = StochasticParams {
        interleave: 2,
        ..params
    };
    StochasticRanges::new(&ctx, &interleaved, 0, n, &il, &strata).unwrap();
    assert_eq!(interleaved.light_path(), LightPath::General);
    let part = upload_for(LightModel::stochastic(1, 1));
    StochasticRanges::new(&ctx, &part, 1, n - 1, &params, &strata[1..]).unwrap();
    // Draws that the scene was not uploaded for are refused: it would shade them as what it
    // was uploaded for.
    for (scene, first, p) in [
        (&windowed, 0, &params),
        (&fast, 0, &il),
        (&fast, 1, &params),
    ] {
        let message =
            StochasticRanges::new(&ctx, scene, first, n - first, p, &strata[first as usize..])
                .err()
                .expect("refused")
                .to_string();
        assert!(message.contains("LightModel::stochastic"), "{message}");
    }
    // Stratified draws need one stratum a drawn light.
    let short = StochasticRanges::new(&ctx, &upload(), 0, n, &params, &strata[1..]);
    let message = short.err().expect("refused").to_string();
    assert!(message.contains("strata"), "{message}");
    assert_eq!(part.light_path(), LightPath::General);
}
