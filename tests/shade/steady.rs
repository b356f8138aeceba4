//! The frame's geometry back to back (`Renderer::geometry_repeated`, what the experiments'
//! `gpu_ms_geometry_steady` times, and with culling and shading `gpu_ms_frame_steady`).

use super::*;

/// Forward, deferred and naive forward, at one and 4 samples a pixel, over glass: each
/// repetition times exactly the single frame's geometry passes, in order (forward: the depth
/// prepass and the lookup bounds' passes; deferred: the G-buffer pass and the bounds; naive
/// forward: its whole frame), and naive forward's image is the single frame's.
#[test]
fn geometry_back_to_back_repeats_the_frames_geometry() {
    let ctx = common::gpu();
    let (w, h) = (64, 48);
    let s = transparent::glass_scene("pillars");
    let settings = CullSettings::for_camera(&s.camera);
    let strategy = Strategy::tiled_gather(16);
    let runs = 3;
    for samples in [1, 4] {
        let gpu_scene = GpuScene::upload(&ctx, &s, &s.camera, w, h).unwrap();
        let renderer = Renderer::with_samples(&ctx, &gpu_scene, samples).unwrap();
        for backend in [
            Backend::Forward,
            Backend::Deferred,
            Backend::NaiveForward,
            Backend::Visibility,
        ] {
            let what = format!("{samples}x {}", backend.name());
            let out = renderer
                .render(&ctx, &gpu_scene, backend, &strategy, &settings, (w, h))
                .unwrap();
            let single = out
                .timings
                .clone()
                .expect("this test needs timestamp queries (lavapipe has them)");
            let geometry: Vec<String> = single
                .iter()
                .map(|p| p.label.clone())
                .filter(|l| {
                    backend == Backend::NaiveForward
                        || l.starts_with("prepass.")
                        || l == "shade.gbuffer"
                        || l == "shade.visibility"
                })
                .collect();
            assert!(
                backend == Backend::NaiveForward
                    || geometry.iter().any(|l| l == "prepass.depth_bounds"),
                "{what}: the glass's lookup bounds: {geometry:?}"
            );
            let mut timer = GpuTimer::new(&ctx, 64);
            renderer
                .geometry_repeated(&ctx, &gpu_scene, &out, runs, &mut timer)
                .unwrap();
            let timed: Vec<String> = timer
                .read(&ctx)
                .unwrap()
                .unwrap()
                .into_iter()
                .map(|p| p.label)
                .collect();
            let repeated: Vec<String> = (0..runs).flat_map(|_| geometry.clone()).collect();
            assert_eq!(timed, repeated, "{what}");
            if backend == Backend::NaiveForward {
                assert!(
                    out.read_color(&ctx).unwrap().data == out.color.data,
                    "{what}: the image after the repetitions differs from the single frame's"
                );
            }
        }
    }
}
