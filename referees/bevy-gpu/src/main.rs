//! Bevy's GPU light clusters for a manylights export, in the format `manylights score` reads
//! (docs/EXPERIMENTS.md, "Scoring another engine's lists").
//!
//! Usage: `manylights-bevy-gpu-referee EXPORT OUT [grid options] [--clustering gpu|cpu]
//! [--frames N] [--z-slice-capacity N] [--index-capacity N]`. The grid options are the CPU
//! adapter's (`referees/bevy`): `--xyz`, `--total`, `--z-slices`, `--first-slice-depth`,
//! `--far-z`.
//!
//! Bevy runs headless with its renderer: `DefaultPlugins` (no window; synchronous pipeline
//! compilation, no pipelined rendering), a `Camera3d` with `RenderTarget::None` of the export's
//! size, and the export's point and spot lights. With `--clustering gpu` (the default) bevy_pbr's
//! GPU clusterer (`cluster/gpu.rs`: z slicing, a count raster pass, allocation, a populate
//! raster pass) makes the lists; with `cpu` Bevy's CPU clusterer does, and the same readback
//! checks this adapter against `referees/bevy`.
//!
//! The lists are read back every frame (readback.rs). Frames run until three in a row, with the
//! same lights in Bevy's light buffer and some (Bevy extracts them a few frames after they are
//! spawned, and leaves out those it finds invisible) and the far bound Bevy's next frame will
//! slice to (it reads the farthest light back from the GPU two frames late), give the
//! same lists with nothing dropped (at most `--frames`, 16 by default), as an application's
//! steady state; each frame's entries and drops are printed. Bevy sizes its GPU lists from the
//! previous frames (`GlobalClusterGpuSettings`): entries past the index list's capacity are
//! dropped, which the readback counts; slices past the z-slice list's capacity are dropped
//! without a trace in the lists, so `--z-slice-capacity` defaults to its bound (lights x z
//! slices) and no slice is ever dropped. Bevy's own initial capacities (1,024 slices, 65,536
//! indices) are `--z-slice-capacity 1024 --index-capacity 65536`.

mod lists;
mod readback;

use bevy::DefaultPlugins;
use bevy::app::{App, PluginGroup, PluginsState};
use bevy::camera::{Camera3d, Projection, RenderTarget};
use bevy::ecs::entity::Entity;
use bevy::light::cluster::{ClusterConfig, ClusterFarZMode, Clusters, GlobalClusterSettings};
use bevy::math::UVec2;
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::render::renderer::{RenderAdapterInfo, RenderDevice};
use bevy::render::view::Msaa;
use bevy::render::{RenderApp, RenderPlugin};
use bevy::transform::components::Transform;
use manylights_bevy_referee::{
    Export, GRID_OPTIONS, Result, args_from, config, number, spawn_lights, write_lists,
};

use crate::lists::{Frame, lists_of};
use crate::readback::{Capture, add_capture, read_words};

#[derive(Clone, Copy, PartialEq, Debug)]
enum Clustering {
    Gpu,
    Cpu,
}

/// This adapter's own options.
struct Options {
    clustering: Clustering,
    frames: u32,
    z_slice_capacity: Option<usize>,
    index_capacity: usize,
}

fn usage() -> String {
    format!(
        "usage: manylights-bevy-gpu-referee EXPORT OUT {GRID_OPTIONS} [--clustering gpu|cpu] \
         [--frames N] [--z-slice-capacity N] [--index-capacity N]"
    )
}

/// This adapter's options out of `a`; the rest is for `args_from`.
fn options(a: &[String]) -> Result<(Options, Vec<String>)> {
    let mut o = Options {
        clustering: Clustering::Gpu,
        frames: 16,
        z_slice_capacity: None,
        index_capacity: 65_536,
    };
    let (mut rest, mut it) = (Vec::new(), a.iter());
    while let Some(s) = it.next() {
        let mut value = || {
            it.next()
                .ok_or_else(|| format!("{s}: a value is missing; {}", usage()))
        };
        match s.as_str() {
            "--clustering" => {
                o.clustering = match value()?.as_str() {
                    "gpu" => Clustering::Gpu,
                    "cpu" => Clustering::Cpu,
                    v => return Err(format!("--clustering {v}: expected gpu or cpu")),
                }
            }
            "--frames" => {
                o.frames = number(s, value()?, |n: u32| n >= 2, "a frame count >= 2")?;
            }
            "--z-slice-capacity" => {
                o.z_slice_capacity =
                    Some(number(s, value()?, |n: usize| n >= 1, "a capacity >= 1")?);
            }
            "--index-capacity" => {
                o.index_capacity = number(s, value()?, |n: usize| n >= 1, "a capacity >= 1")?;
            }
            _ => rest.push(s.clone()),
        }
    }
    Ok((o, rest))
}

/// Bevy's app with its renderer, headless, and the capture of the lists.
fn bevy_app(capture: &Capture) -> App {
    let mut app = App::new();
    app.add_plugins(
        DefaultPlugins
            .set(RenderPlugin {
                synchronous_pipeline_compilation: true,
                ..Default::default()
            })
            .disable::<PipelinedRenderingPlugin>(),
    );
    while app.plugins_state() == PluginsState::Adding {
        bevy::tasks::tick_global_task_pools_on_main_thread();
    }
    app.finish();
    app.cleanup();
    add_capture(app.sub_app_mut(RenderApp), capture.clone());
    app
}

/// Frames alike that make a steady state. Bevy reads a frame's farthest light and list sizes
/// back from the GPU and slices by them two frames later (frame k's readback is extracted
/// after frame k + 1's update and used in frame k + 2's), so two frames alike can still change
/// (the export fixture's lists do, at frames 3 to 5); three alike cannot.
const SETTLED: usize = 3;

/// The far bound Bevy's next frame slices to (bevy_light 0.20.1, `assign_objects_to_clusters`;
/// 1,000 m, its `DEFAULT_FAR_DEPTH`, before any readback). At Bevy's first frames it reads back
/// no light, and the far bound falls to the first slice's depth: a grid of no depth, whose
/// lists are empty, three frames alike in the export's deep view.
fn next_far(mode: ClusterFarZMode, clusters: &Clusters) -> f32 {
    let far = match mode {
        ClusterFarZMode::MaxClusterableObjectRange => {
            clusters.last_frame_farthest_z.unwrap_or(1000.0)
        }
        ClusterFarZMode::Constant(far) => far,
    };
    far.max(clusters.near)
}

fn settled(frames: &[Frame]) -> bool {
    frames.len() >= SETTLED
        && frames[frames.len() - 1].dropped == 0
        && frames[frames.len() - 1].held > 0
        && frames[frames.len() - 1].steady_far
        && frames[frames.len() - SETTLED..]
            .windows(2)
            .all(|w| w[0].same_lists(&w[1]))
}

fn run() -> Result<()> {
    let (opts, rest) = options(&std::env::args().skip(1).collect::<Vec<_>>())?;
    let mut args = args_from(&rest, &usage())?;
    let export = Export::read(&args.export)?;
    if args.far_camera {
        args.z_config.far_z_mode = ClusterFarZMode::Constant(export.projection.far);
    }
    let (config, described) = config(&args);
    let far_mode = args.z_config.far_z_mode;
    let z_slices = match config {
        ClusterConfig::XYZ { dimensions, .. } => dimensions.z,
        ClusterConfig::FixedZ { z_slices, .. } => z_slices,
        _ => unreachable!("the adapter makes XYZ and FixedZ grids"),
    } as usize;

    let capture = Capture::default();
    let mut app = bevy_app(&capture);
    {
        let mut settings = app.world_mut().resource_mut::<GlobalClusterSettings>();
        settings.view_cluster_bindings_max_indices = 1 << 26;
        match opts.clustering {
            Clustering::Cpu => settings.gpu_clustering = None,
            Clustering::Gpu => {
                let Some(gpu) = settings.gpu_clustering.as_mut() else {
                    return Err("Bevy turned GPU clustering off on this adapter (it needs \
                                compute shaders and storage buffers); --clustering cpu runs \
                                its CPU clusterer"
                        .into());
                };
                gpu.initial_z_slice_list_capacity = opts
                    .z_slice_capacity
                    .unwrap_or((export.lights.len() * z_slices).max(1));
                gpu.initial_index_list_capacity = opts.index_capacity;
            }
        }
    }
    let (w, h) = (export.width, export.height);
    let camera = app
        .world_mut()
        .spawn((
            Camera3d::default(),
            RenderTarget::None {
                size: UVec2::new(w, h),
            },
            Projection::Perspective(export.projection.clone()),
            Transform::from_matrix(export.view_from_world.inverse()),
            config,
            Msaa::Off,
        ))
        .id();
    let index = spawn_lights(app.world_mut(), &export.lights);
    let render_world = app.sub_app(RenderApp).world();
    let device = render_world
        .resource::<RenderDevice>()
        .wgpu_device()
        .clone();
    let info: &wgpu::AdapterInfo = render_world.resource::<RenderAdapterInfo>();
    println!(
        "adapter: {} ({:?}, {} {})",
        info.name, info.backend, info.driver, info.driver_info
    );

    let mut frames: Vec<Frame> = Vec::new();
    let (mut settled_at, mut lights_from) = (None, None);
    for frame in 1..=opts.frames {
        app.update();
        let Some(captured) = capture.0.lock().unwrap().take() else {
            println!("frame {frame}: no lists yet");
            continue;
        };
        let counts = read_words(&device, &captured.offsets_and_counts)?;
        let indices = read_words(&device, &captured.index_lists)?;
        let ids: Vec<Option<u32>> = captured
            .light_entities
            .iter()
            .map(|e: &Entity| index.get(e).copied())
            .collect();
        let clusters = app
            .world()
            .get::<Clusters>(camera)
            .ok_or("the camera has no Clusters: LightPlugin did not run")?;
        let mut f = lists_of(&counts, &indices, &ids, clusters)?;
        f.steady_far = next_far(far_mode, clusters) == clusters.far;
        let held = f.held;
        println!(
            "frame {frame}: Bevy holds {held} of {} lights, {} x {} x {} clusters, slices \
             [0, {}) then to {}, {} entries, index list capacity {}, {} dropped",
            export.lights.len(),
            f.dims.x,
            f.dims.y,
            f.dims.z,
            f.near,
            f.far,
            f.entries,
            f.capacity,
            f.dropped
        );
        if held > 0 {
            lights_from.get_or_insert(frame);
        }
        frames.push(f);
        if settled(&frames) {
            settled_at = Some(frame);
            break;
        }
    }
    let (Some(settled_at), Some(lights_from)) = (settled_at, lights_from) else {
        return Err(format!(
            "Bevy's lists did not settle within {} frames ({SETTLED} frames alike, the same \
             lights in Bevy's buffer and some, nothing dropped); --frames runs more",
            opts.frames
        ));
    };
    let last = &frames[frames.len() - 1];
    let (offsets, indices) = last.csr();
    let source = match opts.clustering {
        Clustering::Gpu => format!("bevy_pbr 0.20.1, GPU clustering, {described}"),
        Clustering::Cpu => {
            format!("bevy_pbr 0.20.1, CPU clustering read back from the GPU, {described}")
        }
    };
    write_lists(
        &args.out, &source, &export, last.dims, last.near, last.far, &offsets, &indices,
    )?;
    let first = frames
        .iter()
        .find(|f| f.held > 0)
        .expect("a frame with lights");
    println!(
        "bevy ({:?} clustering): {} x {} x {} clusters, slices [0, {}) then to {}; {} lights, \
         {} entries; settled at frame {settled_at}; lights in Bevy's buffer from frame \
         {lights_from} (whose lists had {} entries, {} dropped)",
        opts.clustering,
        last.dims.x,
        last.dims.y,
        last.dims.z,
        last.near,
        last.far,
        export.lights.len(),
        indices.len(),
        first.entries - first.dropped,
        first.dropped
    );
    Ok(())
}

fn main() -> std::process::ExitCode {
    manylights_bevy_referee::exit(run())
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy::math::UVec3;

    fn frame(far: f32, entries: u32, held: usize, steady_far: bool, dropped: u64) -> Frame {
        Frame {
            dims: UVec3::new(2, 1, 3),
            near: 5.0,
            far,
            lists: vec![vec![0; entries as usize]; 6],
            held,
            steady_far,
            entries: u64::from(entries) * 6,
            capacity: 1 << 16,
            dropped,
        }
    }

    /// Three frames alike are a steady state only with lights in Bevy's buffer, nothing
    /// dropped, and the far bound Bevy's next frame keeps: the empty lists of Bevy's first
    /// frames (no lights yet, or a far bound fallen to the first slice) are not.
    #[test]
    fn settling_needs_three_frames_alike_with_lights_and_a_steady_far_bound() {
        let empty = frame(5.0, 0, 10, false, 0);
        let real = frame(24.0, 3, 10, true, 0);
        assert!(settled(&[real.clone(), real.clone(), real.clone()]));
        assert!(!settled(&[real.clone(), real.clone()]));
        assert!(!settled(&[empty.clone(), empty.clone(), empty]));
        let none = frame(24.0, 0, 0, true, 0);
        assert!(!settled(&[none.clone(), none.clone(), none]));
        let dropped = frame(24.0, 3, 10, true, 7);
        assert!(!settled(&[real.clone(), real.clone(), dropped]));
        let other = frame(24.0, 2, 10, true, 0);
        assert!(!settled(&[other, real.clone(), real]));
    }

    #[test]
    fn the_options_are_this_adapters_and_the_rest_are_the_grids() {
        let a: Vec<String> = [
            "e",
            "o",
            "--clustering",
            "cpu",
            "--xyz",
            "4,4,4",
            "--frames",
            "5",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let (o, rest) = options(&a).unwrap();
        assert_eq!((o.clustering, o.frames), (Clustering::Cpu, 5));
        assert_eq!(rest, ["e", "o", "--xyz", "4,4,4"]);
        for (bad, says) in [
            (
                &["--clustering", "both"][..],
                "--clustering both: expected gpu or cpu",
            ),
            (
                &["--frames", "1"],
                "--frames 1: expected a frame count >= 2",
            ),
            (
                &["--index-capacity"],
                "--index-capacity: a value is missing",
            ),
        ] {
            let a: Vec<String> = bad.iter().map(|s| s.to_string()).collect();
            let e = options(&a).err().expect("refused");
            assert!(e.contains(says), "{bad:?}: {e}");
        }
    }
}
