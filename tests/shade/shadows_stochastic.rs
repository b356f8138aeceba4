//! Stochastic shadows (`Shadows::Stochastic`): K rays a pixel to lights drawn in proportion to
//! their unshadowed luminance, the ratio estimator. Naive forward against its CPU twin
//! (`manylights_scene::shadow_estimate`) over the f64 model at the reference's surface points;
//! the mean over frames against the exact shadowed reference, its noise falling with K; every
//! backend over every strategy casting K rays a lit pixel, each frame number its own draws.

use glam::{DVec3, Vec3};
use manylights_cull::CullSettings;
use manylights_gpu::GpuScene;
use manylights_scene::light::{Range, shade};
use manylights_scene::ray::{Blocked, opaque_triangles, segment, shadow_origin};
use manylights_scene::shadow_estimate::Draws;
use manylights_shade::accuracy::compare;
use manylights_shade::image_out::ImageSum;
use manylights_shade::{Backend, HdrImage, ReferenceRenderer, Renderer, Shadows};

use super::{CULLED, common, scene, strategies};

/// Each light's f64 contribution at a reference texel, as f32, in the scene's order (the order
/// naive forward's loop offers them), the emission, and the f64 ray test of each.
struct Texel {
    emission: Vec3,
    lights: Vec<(Vec3, Vec3)>,
    origin: Vec3,
}

fn texel(s: &manylights_scene::Scene, (pos, nrm): ([f32; 4], [f32; 4])) -> Texel {
    let p32 = Vec3::new(pos[0], pos[1], pos[2]);
    let n32 = Vec3::new(nrm[0], nrm[1], nrm[2]);
    let (p, n) = (p32.as_dvec3(), n32.as_dvec3());
    let v = (s.camera.position.as_dvec3() - p).normalize();
    let m = &s.materials[nrm[3] as usize];
    let lights = s
        .lights
        .iter()
        .filter_map(|l| {
            let c = shade(p, n, v, m, std::slice::from_ref(l), Range::Windowed)
                - m.emissive.as_dvec3();
            (c != DVec3::ZERO).then(|| (c.as_vec3(), l.position))
        })
        .collect();
    Texel {
        emission: m.emissive,
        lights,
        origin: shadow_origin(p32, n32),
    }
}

/// Naive forward with eight rays a pixel in frame 3 against the CPU twin of its estimator, fed
/// the f64 model's contributions and rays at the shadowed reference's surface points: within
/// 1e-3 of the peak at 97% of the checked pixels at least (a contribution within f32 rounding
/// of a reservoir's threshold may draw another light), pixels with an undecided ray skipped.
/// At least one pixel in 25 draws both clear and blocked lights, where the estimate is neither
/// the unshadowed sum nor the emission alone, so the twin's draws are what is compared.
#[test]
fn naive_forward_draws_as_the_cpu_twin() {
    let ctx = common::gpu();
    let (w, h) = (48, 32);
    let rays = 8;
    let frame = 3;
    let (s, gpu_scene, reference) = atrium(&ctx, (w, h));
    gpu_scene.set_shadow_frame(&ctx, frame);
    let settings = CullSettings::for_camera(&s.camera);
    let out = Renderer::new(&ctx, &gpu_scene)
        .with_shadows(Shadows::stochastic(rays))
        .render(
            &ctx,
            &gpu_scene,
            Backend::NaiveForward,
            &strategies()[0],
            &settings,
            (w, h),
        )
        .unwrap();
    let tris = opaque_triangles(&s);
    let peak = reference.color.peak();
    let (mut checked, mut mixed, mut off) = (0, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let k = (y * w + x) as usize;
            let (pos, nrm) = (reference.position.data[k], reference.normal.data[k]);
            if pos[3] == 0.0 {
                continue;
            }
            let t = texel(&s, (pos, nrm));
            let mut draws = Draws::new(rays, (x, y), frame, 0);
            let mut sum = t.emission;
            for &(c, at) in &t.lights {
                sum += c;
                draws.offer(c, at);
            }
            let tests: Vec<Blocked> = draws
                .drawn()
                .iter()
                .map(|&at| segment(&tris, t.origin, at))
                .collect();
            if tests.contains(&Blocked::Ambiguous) {
                continue;
            }
            let mut ray = tests.iter();
            let want = draws.estimate(sum, |_| *ray.next().unwrap() == Blocked::Yes);
            checked += 1;
            if tests.contains(&Blocked::Yes) && tests.contains(&Blocked::No) {
                mixed += 1;
            }
            let got = out.color.data[k];
            let err = (Vec3::new(got[0], got[1], got[2]) - want)
                .abs()
                .max_element();
            if err > 1e-3 * peak {
                off += 1;
            }
        }
    }
    println!("{checked} pixels checked, {mixed} with clear and blocked draws, {off} off");
    assert!(checked > 600, "only {checked} pixels checked");
    assert!(mixed * 25 >= checked, "{mixed} mixed pixels of {checked}");
    assert!(
        off * 100 <= checked * 3,
        "{off} of {checked} pixels differ from the CPU twin"
    );
}

/// The atrium of `scene` at `size` with its BVH, and its exact shadowed reference frame.
fn atrium(
    ctx: &manylights_gpu::GpuContext,
    (w, h): (u32, u32),
) -> (manylights_scene::Scene, GpuScene, manylights_shade::ReferenceFrame) {
    let s = scene("atrium");
    let mut gpu_scene = GpuScene::upload(ctx, &s, &s.camera, w, h).unwrap();
    gpu_scene.build_bvh(ctx, &s).unwrap();
    let reference = ReferenceRenderer::new(ctx, &gpu_scene)
        .with_shadows(ctx, &gpu_scene, Shadows::Exact)
        .render(ctx, &gpu_scene, w, h)
        .unwrap();
    (s, gpu_scene, reference)
}

/// The mean of `frames` frames of `render`, each with its own shadow frame.
fn mean_of(
    ctx: &manylights_gpu::GpuContext,
    gpu_scene: &GpuScene,
    frames: u32,
    render: impl Fn() -> HdrImage,
    like: &HdrImage,
) -> HdrImage {
    let mut sum = ImageSum::default();
    for f in 0..frames {
        gpu_scene.set_shadow_frame(ctx, f);
        sum.add(&render());
    }
    sum.mean_over(like).unwrap()
}

/// Deferred over tiled gather in the atrium, against the exact shadowed reference (errors as
/// the RMSE over 12 frames, the noise's tail being heavy): 16 rays a pixel are at least 1.6 times
/// closer than 1; the mean of 32 frames of 1 ray at least twice as close as one frame, its
/// energy within 2%; the mean of 16 frames of 16 rays closer than that of 1 ray (the ratio
/// estimator's bias falls with K). The rays counted are K for every pixel some light lights, as
/// the f64 model counts those pixels (within 0.5%).
#[test]
fn stochastic_shadows_converge_to_the_shadowed_reference() {
    let ctx = common::gpu();
    let (w, h) = (64, 48);
    let (s, gpu_scene, reference) = atrium(&ctx, (w, h));
    let lit = reference
        .position
        .data
        .iter()
        .zip(&reference.normal.data)
        .filter(|(p, _)| p[3] != 0.0)
        .filter(|&(p, n)| !texel(&s, (*p, *n)).lights.is_empty())
        .count() as u64;
    let settings = CullSettings::for_camera(&s.camera);
    let strategy = strategies()[0];
    let (mut single, mut means) = (Vec::new(), Vec::new());
    for rays in [1, 16] {
        let renderer = Renderer::new(&ctx, &gpu_scene).with_shadows(Shadows::stochastic(rays));
        let render = || {
            renderer
                .render(&ctx, &gpu_scene, Backend::Deferred, &strategy, &settings, (w, h))
                .unwrap()
                .color
        };
        let counted = gpu_scene
            .count_rays(&ctx, (&s.camera, w, h), || {
                Ok::<_, manylights_shade::ShadeError>(render()).map(|_| ())
            })
            .unwrap();
        let want = lit * u64::from(rays);
        assert!(
            counted.abs_diff(want) * 200 <= want,
            "{rays} rays: {counted} counted, {want} = K x {lit} lit pixels"
        );
        let mut mse = 0.0;
        for f in 0..12 {
            gpu_scene.set_shadow_frame(&ctx, 1000 + f);
            mse += compare(&render(), &reference.color, 1.0).rmse.powi(2) / 12.0;
        }
        single.push(mse.sqrt());
        let frames = if rays == 1 { 32 } else { 16 };
        let mean = mean_of(&ctx, &gpu_scene, frames, render, &reference.color);
        let e = compare(&mean, &reference.color, 1.0);
        println!(
            "{rays} rays: one frame RMSE {:.3e}, {frames} frames {:.3e}, energy {:+.4}",
            mse.sqrt(),
            e.rmse,
            e.energy_error
        );
        assert!(e.energy_error.abs() <= 0.02, "{rays} rays, {frames} frames: {e:?}");
        if rays == 1 {
            assert!(e.rmse * 2.0 <= mse.sqrt(), "32 frames {e:?} vs one {}", mse.sqrt());
        }
        means.push(e.rmse);
    }
    assert!(single[1] * 1.6 <= single[0], "16 rays {} vs 1 ray {}", single[1], single[0]);
    assert!(means[1] < means[0], "16 frames of 16 rays {} vs of 1 ray {}", means[1], means[0]);
}

/// Every strategy x backend and naive forward with 4 rays a pixel: a finite image whose mean
/// over 8 frames has the exact shadowed reference's energy within 3% and is closer to it than
/// the unshadowed frame; the same frame number renders the same image, another a different
/// one.
#[test]
fn every_strategy_and_backend_casts_stochastic_shadows() {
    let ctx = common::gpu();
    let (w, h) = (48, 32);
    let (s, gpu_scene, reference) = atrium(&ctx, (w, h));
    let reference = reference.color;
    let settings = CullSettings::for_camera(&s.camera);
    let renderer = Renderer::new(&ctx, &gpu_scene).with_shadows(Shadows::stochastic(4));
    let plain = Renderer::new(&ctx, &gpu_scene);
    let leak = compare(
        &plain
            .render(&ctx, &gpu_scene, Backend::Deferred, &strategies()[0], &settings, (w, h))
            .unwrap()
            .color,
        &reference,
        1.0,
    );
    let mut cases: Vec<(manylights_cull::Strategy, Backend)> = strategies()
        .into_iter()
        .flat_map(|st| CULLED.into_iter().map(move |b| (st, b)))
        .collect();
    cases.push((strategies()[0], Backend::NaiveForward));
    for (strategy, backend) in cases {
        let what = format!("{} {}", strategy.name(), backend.name());
        let render = || {
            renderer
                .render(&ctx, &gpu_scene, backend, &strategy, &settings, (w, h))
                .unwrap()
                .color
        };
        gpu_scene.set_shadow_frame(&ctx, 5);
        let a = render();
        assert_eq!(a.non_finite_count(), 0, "{what}");
        assert_eq!(a.data, render().data, "{what}: frame 5 twice");
        gpu_scene.set_shadow_frame(&ctx, 6);
        assert_ne!(a.data, render().data, "{what}: frames 5 and 6 draw alike");
        let mean = mean_of(&ctx, &gpu_scene, 8, render, &reference);
        let e = compare(&mean, &reference, 1.0);
        assert!(e.energy_error.abs() <= 0.03, "{what}: {e:?}");
        assert!(e.rmse < leak.rmse, "{what}: {e:?} vs the unshadowed frame {leak:?}");
    }
}

