//! Moving lights: the GPU animation pass and the host upload against their oracle
//! (`manylights_scene::motion`), and runs of moving lights checked by the exact oracle at every
//! measured frame.

mod common;

use glam::Vec3;
use manylights_gpu::GpuScene;
use manylights_gpu::layout::GpuLight;
use manylights_gpu::motion::LightMotion;
use manylights_lab::Experiment;
use manylights_lab::runner::{RunOptions, run_parsed};
use manylights_scene::procedural::ProceduralScene;
use manylights_scene::{LightGenerator, LightSpec, Motion, RadiusRule, Scene};

/// The atrium with `n` lights on its surfaces (a third of them spots) after three of its own,
/// and every light's anchor normal.
fn scene(n: u32) -> (Scene, Vec<Vec3>) {
    let mut s = ProceduralScene::from_name("atrium")
        .unwrap()
        .build()
        .unwrap();
    let spec = LightSpec {
        generator: LightGenerator::OnSurfaces {
            offset: (0.05, 0.5),
        },
        count: n + 3,
        seed: 11,
        radius: RadiusRule::Fixed(1.5),
        spot_fraction: 0.3,
        ..LightSpec::default()
    };
    s.lights = spec.generate(&s).unwrap();
    let anchors = spec.anchors(&s).unwrap();
    (s, anchors)
}

fn read_lights(ctx: &manylights_gpu::GpuContext, gs: &GpuScene) -> Vec<GpuLight> {
    let bytes = manylights_gpu::readback::read_buffer(
        ctx,
        &gs.lights,
        0,
        u64::from(gs.light_count) * size_of::<GpuLight>() as u64,
    )
    .unwrap();
    bytemuck::pod_collect_to_vec(&bytes)
}

/// The animation pass moves every moving light where the oracle says (to `sin`/`cos`
/// rounding) and changes nothing else; the upload writes exactly the oracle's lights; lights
/// before `first` (the scene's own) stay where they are.
#[test]
fn animation_pass_and_upload_put_every_light_where_the_oracle_does() {
    let ctx = common::gpu();
    let (s, anchors) = scene(5000);
    let gs = GpuScene::upload(&ctx, &s, &s.camera, 32, 18).unwrap();
    let first = 3usize;
    let glide = Motion::Glide {
        speed: 1.0,
        extent: 0.4,
    };
    // A glide without its anchors is an error that says what it needs.
    let e = LightMotion::new(&ctx, &gs, &s.lights[first..], &[], first as u32, glide)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("anchor normal"), "{e}");
    for motion in [Motion::Orbit(3.0), Motion::Noise(2.0), glide] {
        let anchors = &anchors[first..];
        let mut m =
            LightMotion::new(&ctx, &gs, &s.lights[first..], anchors, first as u32, motion).unwrap();
        for frame in [0u32, 1, 37, 600] {
            let want: Vec<GpuLight> = s
                .lights
                .iter()
                .enumerate()
                .map(|(i, l)| {
                    let mut g = GpuLight::from(l);
                    if i >= first {
                        let n = anchors[i - first];
                        g.position = motion.position_on(i as u32, l.position, l.radius, n, frame);
                    }
                    g
                })
                .collect();
            m.animate(&ctx, frame).unwrap();
            let got = read_lights(&ctx, &gs);
            let mut moved = 0;
            for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                let d = (g.position - w.position).abs().max_element();
                assert!(
                    d < 1e-3,
                    "{motion:?} frame {frame} light {i}: {} vs {}",
                    g.position,
                    w.position
                );
                assert_eq!(
                    GpuLight {
                        position: w.position,
                        ..*g
                    },
                    *w,
                    "{motion:?} frame {frame} light {i}: only the position changes"
                );
                moved += usize::from(g.position != s.lights[i].position);
            }
            if frame > 0 {
                assert!(
                    moved > 4000,
                    "{motion:?} frame {frame}: {moved} lights moved"
                );
            }
            assert_eq!(&got[..first], &want[..first]);
            let cost = m.upload(&ctx, frame).unwrap();
            assert_eq!(
                read_lights(&ctx, &gs),
                want,
                "{motion:?} frame {frame}: upload"
            );
            assert!(cost.host_ms.is_some_and(|ms| ms >= 0.0));
        }
    }
}

/// Moving lights in an experiment, moved on the GPU and uploaded: zero false negatives at every
/// measured frame (the exact oracle runs at each), the update's GPU time as its own column and
/// inside the frame's, the host's upload time for uploads only, the motion named in `params`;
/// and the lights of later frames are not where the first frame had them (the frames' renders
/// differ from each other).
#[test]
fn moving_lights_stay_conservatively_culled_at_every_measured_frame() {
    let ctx = common::gpu();
    let tmp = tempfile::tempdir().unwrap();
    let src = r#"Experiment(
        name: "moving",
        config: Config(
            scene: Atrium(bays: 2),
            lights: (generator: OnSurfaces(offset: (0.05, 0.5)), count: 160, seed: 3, radius: Fixed(1.5), motion: Orbit(30.0)),
            resolution: (64, 36),
            strategy: TiledGather(tile_size: 8),
            frames: 3,
            warmup: 1,
            accuracy: true,
        ),
        sweep: (
            strategy: [TiledGather(tile_size: 8), Clustered(tile_size: 16, slices: 8), ZBin(tile_size: 8)],
            motion: [Orbit(30.0), Noise(30.0), Glide(speed: 30.0, extent: 0.5)],
            light_update: [Gpu, Upload],
        ),
    )"#;
    let path = tmp.path().join("moving.ron");
    let e = Experiment::parse(src, &path).unwrap();
    let s = run_parsed(
        &ctx,
        &e,
        src,
        tmp.path(),
        &tmp.path().join("out"),
        &RunOptions {
            commit: "test".into(),
            ..RunOptions::default()
        },
    )
    .unwrap();
    assert_eq!(s.rows.len(), 18);
    for r in &s.rows {
        assert_eq!(r.false_negatives, Some(0), "{}", r.cell);
        assert_eq!(r.dropped_lights, 0, "{}", r.cell);
        assert_eq!(r.poses, 3, "{}: every measured frame checked", r.cell);
        let upload = r.params.ends_with(";light_update=upload");
        assert!(r.params.contains(";motion="), "{}", r.params);
        assert_eq!(r.cpu_ms_upload.is_some(), upload, "{}", r.cell);
        if ctx.features.timestamps && (!upload || ctx.features.encoder_timestamps) {
            let t = r
                .gpu_ms_light_update
                .unwrap_or_else(|| panic!("{}: no update time", r.cell));
            let label = if upload {
                "lights.upload"
            } else {
                "lights.animate"
            };
            assert!(r.passes.contains_key(label), "{}: {:?}", r.cell, r.passes);
            assert!(r.gpu_ms_total.unwrap() >= t, "{}", r.cell);
        }
        // Three measured frames with lights at 30 units/s: they changed from frame to frame.
        assert!(
            r.temporal_change.is_some_and(|c| c > 0.0),
            "{}: {:?}",
            r.cell,
            r.temporal_change
        );
        assert!(
            r.psnr_db.is_some_and(|p| p > 40.0),
            "{}: {:?}",
            r.cell,
            r.psnr_db
        );
    }
    // Uploaded and animated lights render the same scene.
    for pair in s.rows.chunks(2) {
        let (gpu, up) = (&pair[0], &pair[1]);
        assert_eq!(gpu.strategy, up.strategy);
        let (a, b) = (
            gpu.lights_per_pixel_mean.unwrap(),
            up.lights_per_pixel_mean.unwrap(),
        );
        assert!(
            (a - b).abs() <= 0.01 * a.max(1.0),
            "{}: {a} vs {b}",
            gpu.cell
        );
    }
}

/// A bad speed is an error naming the field and what is accepted.
#[test]
fn a_negative_speed_is_rejected_with_the_field() {
    let src = r#"Experiment(
        name: "bad",
        config: Config(scene: Atrium(), lights: (motion: Orbit(-2.0))),
    )"#;
    let e = Experiment::parse(src, std::path::Path::new("bad.ron"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("bad.ron") && e.contains("lights.motion") && e.contains("speed >= 0"),
        "{e}"
    );
}
