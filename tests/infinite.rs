//! Accuracy against infinite range: the compute reference (`shade.reference_infinite`) against
//! the shading model in f64, and stochastic light culling (`lights.stochastic`), with and
//! without interleaved pixel classes: its draws against their host oracle, its estimate against
//! the f64 one, and its unbiasedness by a z-test that a deliberately biased variant fails.

mod common;

use glam::DVec3;
use manylights_gpu::GpuScene;
use manylights_gpu::layout::GpuLight;
use manylights_gpu::stochastic::StochasticRanges;
use manylights_scene::light::{Range, shade};
use manylights_scene::procedural::ProceduralScene;
use manylights_scene::{LightGenerator, LightSpec, RadiusRule, Scene, stochastic};
use manylights_shade::{HdrImage, InfiniteReference, ReferenceFrame, ReferenceRenderer};

/// `count` lights of the field generator in the atrium, with `radius`.
fn atrium(count: u32, radius: RadiusRule, spots: f32) -> Scene {
    let mut scene = ProceduralScene::from_name("atrium")
        .unwrap()
        .build()
        .unwrap();
    let spec = LightSpec {
        generator: LightGenerator::LightField,
        count,
        seed: 5,
        radius,
        intensity: 2.0,
        spot_fraction: spots,
        spot_outer_deg: 50.0,
        ..LightSpec::default()
    };
    scene.lights = spec.generate(&scene).unwrap();
    scene
}

/// `model(pixel, point, normal, view direction, material)` in f64 at each covered pixel's
/// stored surface point (position, shading normal, material index in the normal's w), the view
/// direction from the camera in f64; `pixel` is (x, y).
fn f64_at_surfaces(
    scene: &Scene,
    frame: &ReferenceFrame,
    model: impl Fn((u32, u32), DVec3, DVec3, DVec3, &manylights_scene::Material) -> DVec3,
) -> Vec<Option<DVec3>> {
    let eye = scene.camera.position.as_dvec3();
    let w = frame.position.width as usize;
    frame
        .position
        .data
        .iter()
        .zip(&frame.normal.data)
        .enumerate()
        .map(|(k, (p, n))| {
            (p[3] > 0.0).then(|| {
                let (pos, nrm) = (rgb(*p), rgb(*n));
                model(
                    ((k % w) as u32, (k / w) as u32),
                    pos,
                    nrm,
                    (eye - pos).normalize(),
                    &scene.materials[n[3] as usize],
                )
            })
        })
        .collect()
}

fn rgb(t: [f32; 4]) -> DVec3 {
    DVec3::new(t[0].into(), t[1].into(), t[2].into())
}

/// The compute reference, over many dispatches (64 lights each), against the f64 sum at the
/// same surface points. Tolerance: 2e-5 of each pixel's value (relative, per channel) plus
/// 1e-7 of the image's mean. f32 evaluation of one term errs by a few ulps (the exponent-32
/// lobe multiplies the half vector's rounding by 32); compensated summation keeps the sum's
/// error at that level over 4,000 terms whose sizes span eight decades. The raster reference
/// with the infinite-range flag (a plain f32 sum) is checked against the same sums, to 1e-3.
#[test]
fn compute_reference_matches_f64_over_many_chunks() {
    let ctx = common::gpu();
    let scene = atrium(4000, RadiusRule::Fixed(3.0), 0.3);
    let (w, h) = (40, 24);
    let gpu_scene = GpuScene::upload(&ctx, &scene, &scene.camera, w, h).unwrap();
    let rr = ReferenceRenderer::new(&ctx, &gpu_scene);
    let surfaces = rr.surfaces(&ctx, &gpu_scene, w, h).unwrap();
    let inf = InfiniteReference::new(&ctx, &gpu_scene).with_chunk(64);
    let image = inf.render(&ctx, &gpu_scene, &surfaces).unwrap();
    let raster = rr
        .render_infinite(&ctx, &gpu_scene, &scene.camera, w, h)
        .unwrap();
    let want = f64_at_surfaces(&scene, &surfaces, |_, p, n, v, m| {
        shade(p, n, v, m, &scene.lights, Range::Infinite)
    });
    let covered: Vec<DVec3> = want.iter().flatten().copied().collect();
    assert!(
        covered.len() > (w * h / 2) as usize,
        "the atrium fills the view"
    );
    let mean = covered.iter().map(|c| c.element_sum()).sum::<f64>() / (3 * covered.len()) as f64;
    let (mut worst, mut worst_raster) = (0.0f64, 0.0f64);
    for (k, e) in want.iter().enumerate() {
        let (g, r) = (image.data[k], raster.color.data[k]);
        let Some(e) = e else {
            assert_eq!(g[3], 0.0, "pixel {k}: not covered");
            continue;
        };
        assert_eq!(g[3], 1.0, "pixel {k}: covered");
        for c in 0..3 {
            let err = (f64::from(g[c]) - e[c]).abs();
            assert!(
                err <= 2e-5 * e[c] + 1e-7 * mean,
                "pixel {k} channel {c}: compute {} vs f64 {}",
                g[c],
                e[c]
            );
            worst = worst.max(err / e[c].max(1e-30));
            let err_r = (f64::from(r[c]) - e[c]).abs();
            assert!(
                err_r <= 1e-3 * e[c] + 1e-6 * mean,
                "pixel {k}: raster {} vs {}",
                r[c],
                e[c]
            );
            worst_raster = worst_raster.max(err_r / e[c].max(1e-30));
        }
    }
    println!(
        "largest relative error: compute {worst:.2e}, raster (plain f32 sum) {worst_raster:.2e}"
    );
    // The same result in one dispatch as in 63.
    let one = InfiniteReference::new(&ctx, &gpu_scene)
        .render(&ctx, &gpu_scene, &surfaces)
        .unwrap();
    for (a, b) in one.data.iter().zip(&image.data) {
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() <= 1e-5 * a[c].abs() + 1e-7 * mean as f32);
        }
    }
}

/// A scene with stochastic ranges uploaded, the draw pass for its lights, and the host's
/// parameters.
struct Stochastic {
    scene: Scene,
    gpu: GpuScene,
    params: stochastic::StochasticParams,
    /// The lights' strata (stratified draws).
    strata: Vec<u32>,
}

impl Stochastic {
    /// The draw pass over every light.
    fn ranges(&self, ctx: &manylights_gpu::GpuContext) -> StochasticRanges {
        let n = self.gpu.light_count;
        StochasticRanges::new(ctx, &self.gpu, 0, n, &self.params, &self.strata).unwrap()
    }

    /// The same scene drawn with `draw`.
    fn with_draw(self, draw: stochastic::StochasticDraw) -> Self {
        let params = stochastic::StochasticParams {
            draw,
            ..self.params
        };
        Self { params, ..self }
    }
}

fn stochastic_scene(
    ctx: &manylights_gpu::GpuContext,
    count: u32,
    error: f32,
    interleave: u32,
    (w, h): (u32, u32),
) -> Stochastic {
    stochastic_scene_in(
        ctx,
        atrium_with(count, error, interleave, false),
        error,
        interleave,
        (w, h),
    )
}

/// The atrium of [`stochastic_scene`] with `count` lights, its surfaces glTF's GGX where
/// `glossy`: every third material a mirror-like metal at the roughness floor (roughness 0),
/// every third a dielectric at roughness 0.05, the rest as their Blinn-Phong weight maps.
fn atrium_with(count: u32, error: f32, interleave: u32, glossy: bool) -> Scene {
    let mut scene = atrium(count, stochastic_rule(error, interleave), 0.25);
    if glossy {
        scene.assign_models(&[manylights_scene::Model::Ggx]);
        for (k, m) in scene.materials.iter_mut().enumerate() {
            m.brdf = match k % 3 {
                0 => manylights_scene::Brdf::Ggx {
                    metallic: 1.0,
                    roughness: 0.0,
                },
                1 => manylights_scene::Brdf::Ggx {
                    metallic: 0.0,
                    roughness: 0.05,
                },
                _ => m.brdf,
            };
        }
    }
    scene
}

fn stochastic_rule(error: f32, interleave: u32) -> RadiusRule {
    RadiusRule::Stochastic {
        error,
        bound: stochastic::StochasticBound::Light,
        exposure: 1.0,
        accumulate: 0,
        seeds: 1,
        interleave,
        draw: stochastic::StochasticDraw::Stratified,
    }
}

fn stochastic_scene_in(
    ctx: &manylights_gpu::GpuContext,
    scene: Scene,
    error: f32,
    interleave: u32,
    (w, h): (u32, u32),
) -> Stochastic {
    let rule = stochastic_rule(error, interleave);
    let spec = LightSpec {
        radius: rule,
        seed: 5,
        ..LightSpec::default()
    };
    let params = spec.stochastic(&scene).unwrap();
    let model = manylights_gpu::LightModel::of_rule(&rule, 0);
    let gpu = GpuScene::upload_with(ctx, &scene, model, &scene.camera, w, h).unwrap();
    let strata = stochastic::strata(&scene.lights);
    Stochastic {
        scene,
        gpu,
        params,
        strata,
    }
}

/// The GPU's draws (range, alpha and interleave word of every light, at several frames) against
/// the host's, without interleaving and over 3 x 3 classes (the range: the longest class's).
/// Both compute `1 / sqrt(alpha * xi)` from the same 24-bit xi and alpha in f32; the GPU's
/// square root may differ by an ulp or two.
#[test]
fn stochastic_draws_match_their_oracle() {
    let ctx = common::gpu();
    use stochastic::StochasticDraw::{Independent, Stratified};
    for (interleave, kind) in [(1, Independent), (1, Stratified), (3, Stratified)] {
        let s = stochastic_scene(&ctx, 3000, 0.01, interleave, (16, 16)).with_draw(kind);
        let draw = s.ranges(&ctx);
        for frame in [0, 1, 17] {
            draw.draw(&ctx, frame).unwrap();
            let bytes = manylights_gpu::readback::read_buffer(
                &ctx,
                &s.gpu.lights,
                0,
                u64::from(s.gpu.light_count) * 64,
            )
            .unwrap();
            let gpu: &[GpuLight] = bytemuck::cast_slice(&bytes);
            let mut longest = 0.0f32;
            for (i, (g, l)) in gpu.iter().zip(&s.scene.lights).enumerate() {
                let at = format!("{kind:?}, interleave {interleave} frame {frame} light {i}");
                let (want, alpha) = s.params.at_frame(l, i as u32, s.strata[i], frame);
                assert_eq!(g.alpha, alpha, "{at}: alpha");
                // Stochastic culling's falloff (a biased draw's would be the windowed one),
                // the light's shape kept.
                assert_eq!(
                    g.kind,
                    GpuLight::from(l).shape() | manylights_gpu::layout::LIGHT_FALLOFF_STOCHASTIC,
                    "{at}: kind"
                );
                assert_eq!(
                    g.interleave,
                    s.params.interleave_word(i as u32, frame),
                    "{at}: interleave word"
                );
                assert!(
                    (g.radius - want.radius).abs() <= 4.0 * f32::EPSILON * want.radius,
                    "{at}: range {} vs {}",
                    g.radius,
                    want.radius
                );
                assert_eq!(g.position, l.position, "only radius and alpha change");
                let shortest = stochastic::StochasticParams::range(s.params.alpha(l), 1.0);
                longest = longest.max(g.radius / shortest);
            }
            assert!(
                longest > 10.0,
                "some ranges are long ({longest}x the shortest)"
            );
        }
    }
}

/// Renders the brute-force reference (every light, shaded with its drawn range and alpha: the
/// stochastic estimate with no culling) at frames `0..frames`, and returns each image.
fn stochastic_frames(
    ctx: &manylights_gpu::GpuContext,
    s: &Stochastic,
    draw: &StochasticRanges,
    frames: u32,
    (w, h): (u32, u32),
) -> Vec<HdrImage> {
    let rr = ReferenceRenderer::new(ctx, &s.gpu);
    (0..frames)
        .map(|f| {
            draw.draw(ctx, f).unwrap();
            rr.render(ctx, &s.gpu, w, h).unwrap().color
        })
        .collect()
}

/// The GPU's stochastic estimate at a frame against the same estimate in f64 at the stored
/// surface points (the lights with the ranges and alphas the host draws for that frame, for
/// the pixel's class where 2 x 2 classes interleave).
#[test]
fn stochastic_estimate_matches_f64() {
    let ctx = common::gpu();
    let (w, h) = (32, 20);
    for interleave in [1, 2] {
        let s = stochastic_scene(&ctx, 800, 0.02, interleave, (w, h));
        let draw = s.ranges(&ctx);
        let frame = 3;
        draw.draw(&ctx, frame).unwrap();
        let rr = ReferenceRenderer::new(&ctx, &s.gpu);
        let got = rr.render(&ctx, &s.gpu, w, h).unwrap();
        // The lights each class shades with.
        let classes: Vec<(Vec<_>, Vec<_>)> = (0..interleave * interleave)
            .map(|c| {
                s.scene
                    .lights
                    .iter()
                    .enumerate()
                    .map(|(i, l)| s.params.at_pixel(l, i as u32, s.strata[i], frame, c))
                    .unzip()
            })
            .collect();
        let want = f64_at_surfaces(&s.scene, &got, |(x, y), p, n, v, m| {
            let (lights, alphas) = &classes[stochastic::pixel_class(x, y, interleave) as usize];
            stochastic::shade(p, n, v, m, lights, alphas)
        });
        // A light within f32 rounding of its range may be in on one side and out on the
        // other: the tolerance admits one such light's largest term, alpha times the BRDF.
        let one = classes[0].1.iter().fold(0.0f32, |a, &b| a.max(b)) as f64 * 2.0 * 6.0;
        let mut checked = 0;
        for (k, want) in want.iter().enumerate() {
            let Some(want) = want else { continue };
            let g = rgb(got.color.data[k]);
            assert!(
                (g - *want).abs().max_element() <= 1e-4 * want.max_element() + one,
                "interleave {interleave} pixel {k}: gpu {g} vs f64 {want}"
            );
            checked += 1;
        }
        assert!(checked > 200);
        if interleave > 1 {
            // The classes differ: the same pixels shaded with class 0's ranges everywhere
            // would not match.
            let plain = f64_at_surfaces(&s.scene, &got, |_, p, n, v, m| {
                stochastic::shade(p, n, v, m, &classes[0].0, &classes[0].1)
            });
            let differ = plain
                .iter()
                .zip(&want)
                .filter(|(a, b)| matches!((a, b), (Some(a), Some(b)) if (*a - *b).abs().max_element() > 1e-3 * b.max_element()))
                .count();
            assert!(differ > 50, "only {differ} pixels see their class's draws");
        }
    }
}

/// Per-pixel z statistics of the mean of `images` against `reference` (luminance): the largest
/// |z| and the mean z over covered pixels with noise, and how many pixels had none.
fn z_stats(images: &[HdrImage], reference: &HdrImage) -> (f64, f64, usize) {
    let lum = manylights_shade::accuracy::luminance;
    let m = images.len() as f64;
    let (mut zmax, mut zsum, mut n, mut quiet) = (0.0f64, 0.0f64, 0usize, 0usize);
    for k in 0..reference.data.len() {
        if reference.data[k][3] == 0.0 {
            continue;
        }
        let xs: Vec<f64> = images.iter().map(|i| lum(i.data[k])).collect();
        let mean = xs.iter().sum::<f64>() / m;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (m - 1.0);
        let r = lum(reference.data[k]);
        if var <= (1e-6 * r).powi(2) {
            // Every draw alike: every light always in range; the mean is the reference.
            assert!(
                (mean - r).abs() <= 1e-4 * r,
                "pixel {k}: no noise, yet {mean} vs {r}"
            );
            quiet += 1;
            continue;
        }
        let z = (mean - r) / (var / m).sqrt();
        zmax = zmax.max(z.abs());
        zsum += z;
        n += 1;
    }
    (zmax, zsum / n.max(1) as f64, quiet)
}

/// Unbiasedness: over 128 frames of fresh draws, each pixel's mean estimate against the
/// compute infinite-range reference, by a z-test with the variance measured across the frames.
/// With about 500 covered pixels tested at once, |z| <= 5 for every pixel holds for an
/// unbiased estimate with probability above 0.999 (a normal tail of 5.7e-7 a pixel, and the
/// frame means of bounded terms are close to normal at 128 frames); the test is deterministic
/// (fixed seeds). The same test on a deliberately biased variant (Russian roulette without the
/// reweighting: the windowed falloff over the drawn ranges) must fail it by far.
#[test]
fn stochastic_estimate_is_unbiased_by_a_z_test_that_a_biased_variant_fails() {
    let ctx = common::gpu();
    let (w, h) = (32, 20);
    let s = stochastic_scene(&ctx, 400, 0.05, 1, (w, h));
    let rr = ReferenceRenderer::new(&ctx, &s.gpu);
    let surfaces = rr.surfaces(&ctx, &s.gpu, w, h).unwrap();
    let reference = InfiniteReference::new(&ctx, &s.gpu)
        .render(&ctx, &s.gpu, &surfaces)
        .unwrap();
    // 128 frames: a z of 5 over 640 pixels is a one-in-3,000 event for an unbiased estimate,
    // and the biased variant lands hundreds of standard errors away.
    let frames = 128;
    let draw = s.ranges(&ctx);
    let images = stochastic_frames(&ctx, &s, &draw, frames, (w, h));
    let (zmax, zmean, quiet) = z_stats(&images, &reference);
    println!("unbiased: max |z| {zmax:.2}, mean z {zmean:.2}, {quiet} pixels without noise");
    assert!(
        zmax <= 5.0,
        "the stochastic estimate is biased: max |z| = {zmax}"
    );
    // Independent draws (one hash a light): unbiased too.
    let ind = stochastic_scene(&ctx, 400, 0.05, 1, (w, h))
        .with_draw(stochastic::StochasticDraw::Independent);
    let images = stochastic_frames(&ctx, &ind, &ind.ranges(&ctx), frames, (w, h));
    let (zmax_ind, zmean_ind, _) = z_stats(&images, &reference);
    println!("independent draws: max |z| {zmax_ind:.2}, mean z {zmean_ind:.2}");
    assert!(
        zmax_ind <= 5.0,
        "the estimate with independent draws is biased: max |z| = {zmax_ind}"
    );
    // Interleaved over 2 x 2 pixel classes: unbiased at every pixel too.
    let il = stochastic_scene(&ctx, 400, 0.05, 2, (w, h));
    let draw_il = il.ranges(&ctx);
    let images = stochastic_frames(&ctx, &il, &draw_il, frames, (w, h));
    let (zmax_il, zmean_il, _) = z_stats(&images, &reference);
    println!("interleaved 2 x 2: max |z| {zmax_il:.2}, mean z {zmean_il:.2}");
    assert!(
        zmax_il <= 5.0,
        "the interleaved estimate is biased: max |z| = {zmax_il}"
    );
    // On glTF's GGX, mirror-like metal at the roughness floor among it: the same lists (the
    // bound is the light's own contribution) and unbiased too.
    let g = stochastic_scene_in(&ctx, atrium_with(400, 0.05, 1, true), 0.05, 1, (w, h));
    assert_eq!(
        g.params, s.params,
        "the default bound does not depend on the materials"
    );
    let rr_g = ReferenceRenderer::new(&ctx, &g.gpu);
    let surfaces_g = rr_g.surfaces(&ctx, &g.gpu, w, h).unwrap();
    let reference_g = InfiniteReference::new(&ctx, &g.gpu)
        .render(&ctx, &g.gpu, &surfaces_g)
        .unwrap();
    let draw_g = g.ranges(&ctx);
    let images = stochastic_frames(&ctx, &g, &draw_g, frames, (w, h));
    let (zmax_g, zmean_g, _) = z_stats(&images, &reference_g);
    println!("GGX: max |z| {zmax_g:.2}, mean z {zmean_g:.2}");
    assert!(
        zmax_g <= 5.0,
        "the estimate on GGX is biased: max |z| = {zmax_g}"
    );
    let biased = draw.biased(&ctx);
    let images = stochastic_frames(&ctx, &s, &biased, frames, (w, h));
    let (zmax_b, zmean_b, _) = z_stats(&images, &reference);
    println!("biased: max |z| {zmax_b:.2}, mean z {zmean_b:.2}");
    assert!(
        zmax_b > 10.0 && zmean_b < -3.0,
        "the z-test must catch the biased variant: max |z| = {zmax_b}, mean z = {zmean_b}"
    );
}
