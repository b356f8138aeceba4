//! Bevy's CPU light clusters for a manylights export, in the format `manylights score` reads
//! (docs/EXPERIMENTS.md, "Scoring another engine's lists").
//!
//! Usage: `manylights-bevy-referee EXPORT OUT [--xyz X,Y,Z | --total N --z-slices N]
//! [--first-slice-depth D] [--far-z max-light-range|F]`. EXPORT is a directory written by
//! `manylights cull --export` (or `render --export`, or `export: true`); OUT receives
//! `grid.json`, `offsets.npy` and `indices.npy`. By default Bevy's default grid
//! (`ClusterConfig::FixedZ`: 4,096 clusters, 24 slices, dynamic resizing); `--total` and
//! `--z-slices` change its counts, `--xyz` makes it a fixed X x Y x Z grid. Bevy's own knobs of
//! the slicing (`ClusterZConfig`) for either: `--first-slice-depth` (5 m by default) and
//! `--far-z` (`max-light-range`, the default, `ClusterFarZMode::MaxClusterableObjectRange`: the
//! previous frame's farthest light; `camera`, a constant at the export's far plane; or a
//! constant depth in metres). `grid.json`'s `source`
//! names every setting.
//!
//! Bevy runs headless: a plain ECS `App` with the task pool, assets, transforms and
//! `LightPlugin`, CPU clustering (`GlobalClusterSettings::gpu_clustering: None`), a `Camera3d`
//! whose projection and render-target size are set by hand, and the export's point and spot
//! lights, all visible. Two frames run (the second slices to the first's farthest light, as an
//! application's steady state does); then the camera's `Clusters` are written out.
//!
//!
//! The conventions converted, and what the GPU adapter shares, are in the library (lib.rs).

use bevy_app::{App, TaskPoolPlugin};
use bevy_asset::{AssetApp, AssetPlugin};
use bevy_camera::{Camera, Camera3d, CameraProjection, ComputedCameraValues, RenderTargetInfo};
use bevy_image::Image;
use bevy_light::LightPlugin;
use bevy_light::cluster::{ClusterFarZMode, ClusterableObjects, Clusters, GlobalClusterSettings};
use bevy_math::UVec2;
use bevy_transform::TransformPlugin;
use bevy_transform::components::{GlobalTransform, Transform};
use manylights_bevy_referee::{
    Export, GRID_OPTIONS, Result, args_from, config, spawn_lights, write_lists,
};

fn run() -> Result<()> {
    let usage = format!("usage: manylights-bevy-referee EXPORT OUT {GRID_OPTIONS}");
    let mut args = args_from(&std::env::args().skip(1).collect::<Vec<_>>(), &usage)?;
    let export = Export::read(&args.export)?;
    let (w, h) = (export.width, export.height);
    let projection = export.projection.clone();
    if args.far_camera {
        args.z_config.far_z_mode = ClusterFarZMode::Constant(projection.far);
    }
    let lights = &export.lights;

    let mut app = App::new();
    app.add_plugins((
        TaskPoolPlugin::default(),
        AssetPlugin::default(),
        TransformPlugin,
    ));
    app.init_asset::<Image>();
    app.add_plugins(LightPlugin);
    app.insert_resource(GlobalClusterSettings {
        supports_storage_buffers: true,
        clustered_decals_are_usable: false,
        gpu_clustering: None,
        max_uniform_buffer_clusterable_objects: 256,
        view_cluster_bindings_max_indices: 1 << 24,
    });
    let world_from_view = export.view_from_world.inverse();
    let frustum = projection.compute_frustum(&GlobalTransform::from(Transform::from_matrix(
        world_from_view,
    )));
    let camera = Camera {
        computed: ComputedCameraValues {
            clip_from_view: projection.get_clip_from_view(),
            target_info: Some(RenderTargetInfo {
                physical_size: UVec2::new(w, h),
                scale_factor: 1.0,
            }),
            ..Default::default()
        },
        ..Default::default()
    };
    let (config, described) = config(&args);
    let view = app
        .world_mut()
        .spawn((
            Camera3d::default(),
            camera,
            Transform::from_matrix(world_from_view),
            frustum,
            config,
        ))
        .id();
    let index = spawn_lights(app.world_mut(), lights);
    // Two frames: the second slices to the first's farthest light.
    app.update();
    app.update();
    let clusters = app
        .world()
        .get::<Clusters>(view)
        .ok_or("the camera has no Clusters: LightPlugin did not run")?;
    let ClusterableObjects::Cpu(cells) = &clusters.clusterable_objects else {
        return Err("Bevy clustered on the GPU; the adapter asked for the CPU".into());
    };
    let d = clusters.dimensions;
    if cells.len() != (d.x * d.y * d.z) as usize {
        return Err(format!(
            "{} cluster lists for {} x {} x {} clusters",
            cells.len(),
            d.x,
            d.y,
            d.z
        ));
    }
    let mut offsets = vec![0u32];
    let mut indices = Vec::new();
    for c in cells {
        indices.extend(c.iter().filter_map(|e| index.get(e).copied()));
        offsets.push(indices.len() as u32);
    }
    write_lists(
        &args.out,
        &format!("bevy_light 0.20.1, CPU clustering, {described}"),
        &export,
        d,
        clusters.near,
        clusters.far,
        &offsets,
        &indices,
    )?;
    println!(
        "bevy: {} x {} x {} clusters (tiles of {} x {} px), slices [0, {}) then to {}; {} lights, {} entries",
        d.x,
        d.y,
        d.z,
        clusters.tile_size.x,
        clusters.tile_size.y,
        clusters.near,
        clusters.far,
        lights.len(),
        indices.len()
    );
    Ok(())
}

fn main() -> std::process::ExitCode {
    manylights_bevy_referee::exit(run())
}
