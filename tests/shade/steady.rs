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

/// A timer holds any number of passes and spans: past its first query set's room it starts
/// another, and every pass comes back, in order, with its kind.
#[test]
fn a_timer_grows_past_its_first_query_set() {
    use manylights_gpu::timing::{GpuTimer, PassKind};
    let ctx = common::gpu();
    let mut timer = GpuTimer::new(&ctx, 2);
    assert!(timer.enabled(), "{}: no timestamp queries", ctx.info.name);
    let mut enc = ctx.encoder("timer test");
    let labels: Vec<String> = (0..7).map(|k| format!("test.pass{k}")).collect();
    for label in &labels {
        let pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: timer.compute_pass(label),
        });
        drop(pass);
    }
    timer.resolve(&mut enc);
    ctx.submit_and_wait(enc, "timer test").unwrap();
    let t = timer.read(&ctx).unwrap().expect("timed");
    assert_eq!(
        t.iter().map(|p| p.label.clone()).collect::<Vec<_>>(),
        labels
    );
    assert!(
        t.iter()
            .all(|p| p.kind == PassKind::Compute && p.ms.is_finite() && p.ms >= 0.0),
        "{t:?}"
    );
    if let Some(mut spans) = GpuTimer::spans(&ctx, 1) {
        let mut enc = ctx.encoder("span test");
        for k in 0..3 {
            spans.span_begin(&mut enc, &format!("test.span{k}"));
        }
        spans.span_end(&mut enc);
        spans.resolve(&mut enc);
        ctx.submit_and_wait(enc, "span test").unwrap();
        assert_eq!(spans.read(&ctx).unwrap().expect("timed").len(), 3);
    }
}
