//! Deferred lighting over clusters (and tiles) a workgroup at a time (`ListForm::Clusters`,
//! `shade_cluster_group` in shaders/render/deferred.wgsl) against the loop a pixel over the same
//! lists (`ListForm::Bins`, `shade_list`): the same image, bit for bit, with lists shorter and
//! longer than the workgroup's memory holds, and with a workgroup's pixels in several slices.

use manylights_cull::layout::{
    CLUSTER_GROUP_MIN_LIGHTS, CLUSTER_GROUP_SLICES, ZBIN_ROUNDS_MIN_LIGHTS,
};
use manylights_cull::{CullOutput, ListForm, ListPass};

use super::*;

/// A list consumer bound as if the lists were in `form`: the loop a pixel reads any lists a
/// bin, so binding clusters' lists as `Bins` runs it over them.
struct BoundAs<P>(P, ListForm);

impl<P: ListPass> ListPass for BoundAs<P> {
    fn bind(&mut self, ctx: &GpuContext, lists: [wgpu::BindingResource<'_>; 3], _: ListForm) {
        self.0.bind(ctx, lists, self.1);
    }

    fn record(&self, enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer) {
        self.0.record(enc, timer);
    }

    fn passes(&self) -> u32 {
        self.0.passes()
    }
}

/// The atrium with `count` lights of radius `radius` times its lights' bounds' diagonal.
pub(crate) fn atrium_lights(count: u32, radius: f32) -> Scene {
    let mut s = scene("atrium");
    s.lights = LightSpec {
        generator: LightGenerator::Uniform,
        count,
        seed: 9,
        radius: RadiusRule::Fixed(s.light_bounds.extent().length() * radius),
        intensity: 0.05,
        spot_fraction: 0.0,
        spot_outer_deg: 40.0,
        ..LightSpec::default()
    }
    .generate(&s)
    .unwrap();
    s
}

/// Clusters of `tile_size` pixels and `slices` exponential slices, ordered, skipping empty ones.
pub(crate) fn clusters(tile_size: u32, slices: u32) -> Strategy {
    Strategy::Clustered {
        tile_size,
        slices,
        slicing: Slicing::Exponential,
        skip_empty: true,
        ordered: true,
        cells: false,
    }
}

/// How many pixels of `out` differ from the image of the loop a pixel over the same lists
/// (`shade_list`, the lists bound as `Bins`).
fn differ_from_the_loop_a_pixel(
    ctx: &GpuContext,
    renderer: &Renderer,
    gpu_scene: &GpuScene,
    out: &ShadeOutput,
    strategy: &Strategy,
    settings: &CullSettings,
) -> usize {
    let mut per_pixel = BoundAs(
        renderer.shade_pass(ctx, gpu_scene, out).unwrap(),
        ListForm::Bins,
    );
    let again = shade_again(
        ctx,
        renderer,
        gpu_scene,
        out,
        strategy,
        settings,
        &mut per_pixel,
    );
    again
        .data
        .iter()
        .zip(&out.color.data)
        .filter(|(a, b)| a != b)
        .count()
}

#[test]
fn cluster_group_lighting_equals_the_loop_a_pixel() {
    let ctx = common::gpu();
    let (w, h) = (70, 45);
    // More lights than CLUSTER_GROUP_MIN_LIGHTS: small ones (lists of a few lights) and larger
    // ones (several loads of the workgroup's batch of lights a list, the last one partial).
    for s in [
        atrium_lights(CLUSTER_GROUP_MIN_LIGHTS + 1, 0.02),
        atrium_lights(CLUSTER_GROUP_MIN_LIGHTS + 500, 0.1),
    ] {
        let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
        let renderer = Renderer::new(&ctx, &gpu_scene);
        let settings = CullSettings::for_camera(&s.camera);
        for (tile_size, slices) in [(8, 32), (16, 16), (32, 256)] {
            let strategy = clusters(tile_size, slices);
            for backend in [Backend::Deferred, Backend::DeferredStoredPosition] {
                let what = format!(
                    "{} {} {} lights",
                    strategy.name(),
                    backend.name(),
                    s.lights.len()
                );
                let out = renderer
                    .render(&ctx, &gpu_scene, backend, &strategy, &settings, (w, h))
                    .unwrap();
                let lists: &CullOutput = out.lists.as_ref().unwrap();
                assert_eq!(lists.form(), ListForm::Clusters, "{what}");
                let covered = out.color.data.iter().filter(|p| p[3] > 0.0).count();
                assert!(
                    covered > w as usize * h as usize / 2,
                    "{what}: {covered} pixels covered"
                );
                let differ = differ_from_the_loop_a_pixel(
                    &ctx, &renderer, &gpu_scene, &out, &strategy, &settings,
                );
                assert_eq!(
                    differ, 0,
                    "{what}: pixels that differ from the loop a pixel"
                );
            }
        }
    }
}

/// Deferred lighting over a list a tile a workgroup at a time (`ListForm::Tiles`,
/// `shade_tile_group`; with point lights four at a time) against the loop a pixel over the same
/// lists: the same image, bit for bit, with lists shorter and longer than a batch.
#[test]
fn tile_group_lighting_equals_the_loop_a_pixel() {
    let ctx = common::gpu();
    let (w, h) = (70, 45);
    for s in [atrium_lights(300, 0.02), atrium_lights(700, 0.1)] {
        let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
        let renderer = Renderer::new(&ctx, &gpu_scene);
        assert!(renderer.light_path().point_lights());
        let settings = CullSettings::for_camera(&s.camera);
        for strategy in [Strategy::tiled_gather(8), Strategy::tiled_gather(16)] {
            let what = format!("{} {} lights", strategy.name(), s.lights.len());
            let out = renderer
                .render(
                    &ctx,
                    &gpu_scene,
                    Backend::Deferred,
                    &strategy,
                    &settings,
                    (w, h),
                )
                .unwrap();
            assert_eq!(
                out.lists.as_ref().unwrap().form(),
                ListForm::Tiles,
                "{what}"
            );
            let differ = differ_from_the_loop_a_pixel(
                &ctx, &renderer, &gpu_scene, &out, &strategy, &settings,
            );
            assert_eq!(
                differ, 0,
                "{what}: pixels that differ from the loop a pixel"
            );
        }
    }
}

/// The form follows the grid and the lights: a list a tile for one slice; a list a cluster taken
/// a workgroup at a time for 2 to CLUSTER_GROUP_SLICES slices in tiles of a multiple of 8 pixels
/// with more than CLUSTER_GROUP_MIN_LIGHTS lights; the loop a pixel otherwise.
#[test]
fn cluster_list_form_follows_the_grid_and_the_lights() {
    let ctx = common::gpu();
    let (w, h) = (40, 24);
    for count in [CLUSTER_GROUP_MIN_LIGHTS, CLUSTER_GROUP_MIN_LIGHTS + 1] {
        let s = atrium_lights(count, 0.02);
        let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
        let renderer = Renderer::new(&ctx, &gpu_scene);
        let settings = CullSettings::for_camera(&s.camera);
        let many = count > CLUSTER_GROUP_MIN_LIGHTS;
        let clusters_form = if many {
            ListForm::Clusters
        } else {
            ListForm::Bins
        };
        for (tile_size, slices, form) in [
            (16, 1, ListForm::Tiles),
            (16, 2, clusters_form),
            (8, CLUSTER_GROUP_SLICES, clusters_form),
            (8, CLUSTER_GROUP_SLICES + 1, ListForm::Bins),
            (12, 16, ListForm::Bins),
        ] {
            let strategy = clusters(tile_size, slices);
            let out = renderer
                .render(
                    &ctx,
                    &gpu_scene,
                    Backend::Deferred,
                    &strategy,
                    &settings,
                    (w, h),
                )
                .unwrap();
            assert_eq!(
                out.lists.as_ref().unwrap().form(),
                form,
                "{} with {count} lights",
                strategy.name()
            );
        }
    }
}

/// Deferred lighting over z-binning's lists a workgroup at a time in a point-light pipeline,
/// below `ZBIN_ROUNDS_MIN_LIGHTS` lights by the workgroup's one walk and from there in rounds
/// (`shade_zbin_rounds`: each thread walks its run of the mask's words and loads a light a
/// round), against gather's lists of the same tiles (`shade_tile_group`): both sum, at each
/// pixel, the lights within range, in other orders, so the images agree to rounding (a light
/// missed or shaded twice would not), with several rounds' worth of lights a workgroup.
#[test]
fn zbin_group_lighting_matches_the_tile_lists() {
    let ctx = common::gpu();
    let (w, h) = (70, 45);
    let many = ZBIN_ROUNDS_MIN_LIGHTS + 100;
    for s in [
        atrium_lights(700, 0.1),
        atrium_lights(many, 0.02),
        atrium_lights(many, 0.05),
    ] {
        let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
        let renderer = Renderer::new(&ctx, &gpu_scene);
        assert!(renderer.light_path().point_lights());
        let settings = CullSettings::for_camera(&s.camera);
        for tile_size in [8, 16] {
            let render = |strategy: Strategy| {
                renderer
                    .render(
                        &ctx,
                        &gpu_scene,
                        Backend::Deferred,
                        &strategy,
                        &settings,
                        (w, h),
                    )
                    .unwrap()
            };
            let zbin = render(Strategy::ZBin {
                tile_size,
                bins: 32,
                slicing: Slicing::Exponential,
            });
            assert_eq!(zbin.lists.as_ref().unwrap().form(), ListForm::ZBin);
            let gather = render(Strategy::tiled_gather(tile_size));
            let peak = gather
                .color
                .data
                .iter()
                .flat_map(|p| p[..3].iter().copied())
                .fold(0.0f32, f32::max);
            let what = format!("zbin {tile_size} px, {} lights", s.lights.len());
            let mut lit = 0;
            for (k, (a, b)) in zbin.color.data.iter().zip(&gather.color.data).enumerate() {
                for ch in 0..4 {
                    let (x, y) = (a[ch], b[ch]);
                    assert!(
                        (x - y).abs() <= 1e-4 * x.abs().max(y.abs()) + 1e-6 * peak,
                        "{what}: pixel {k} channel {ch}: {x} against {y}"
                    );
                }
                lit += usize::from(b[0] > 1e-3 * peak);
            }
            assert!(lit > (w * h) as usize / 4, "{what}: {lit} pixels lit");
        }
    }
}
