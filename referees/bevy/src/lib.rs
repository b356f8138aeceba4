//! What Bevy's light-cluster adapters share: reading a manylights export, Bevy's knobs of the
//! cluster grid, the export's lights as Bevy's, and writing lists in the format `manylights
//! score` reads (docs/EXPERIMENTS.md, "Scoring another engine's lists"). Two adapters use it:
//! this crate's `manylights-bevy-referee` (Bevy's CPU clusterer, bevy_light alone) and
//! `referees/bevy-gpu` (Bevy's GPU clusterer, which needs Bevy's renderer).
//!
//! Conventions converted here: the export's camera is right-handed, looking down -z, as
//! Bevy's is; Bevy's projection is the reversed-z infinite perspective of the export's field of
//! view, aspect and near plane (its clusterer assumes reversed z), and its frustum's far plane
//! the export's far plane. A Bevy spot light points along its transform's forward (-z). Bevy's
//! shader looks a pixel's cluster up at `floor((px + 0.5) X / W)`, `floor((py + 0.5) Y / H)`
//! (rows from the top) and its slice from the view depth (slice 0 is `[0, near)`), cluster
//! `(y X + x) Z + z`: the grid written says so.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use bevy_camera::PerspectiveProjection;
use bevy_camera::visibility::ViewVisibility;
use bevy_ecs::entity::Entity;
use bevy_ecs::world::World;
use bevy_light::cluster::{ClusterConfig, ClusterFarZMode, ClusterZConfig};
use bevy_light::{PointLight, SpotLight};
use bevy_math::{Mat4, UVec3, Vec3};
use bevy_transform::components::Transform;
use npyz::WriterBuilder;

pub type Result<T> = std::result::Result<T, String>;

pub fn read<T: npyz::Deserialize>(dir: &Path, name: &str) -> Result<(Vec<u64>, Vec<T>)> {
    let path = dir.join(name);
    let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let npy = npyz::NpyFile::new(&bytes[..]).map_err(|e| format!("{}: {e}", path.display()))?;
    let shape = npy.shape().to_vec();
    let v = npy
        .into_vec()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok((shape, v))
}

pub fn write<T: npyz::AutoSerialize + Copy>(path: &Path, data: &[T]) -> Result<()> {
    let mut bytes = Vec::new();
    let mut w = npyz::WriteOptions::new()
        .default_dtype()
        .shape(&[data.len() as u64])
        .writer(&mut bytes)
        .begin_nd()
        .map_err(|e| e.to_string())?;
    w.extend(data.iter().copied()).map_err(|e| e.to_string())?;
    w.finish().map_err(|e| e.to_string())?;
    std::fs::write(path, bytes).map_err(|e| format!("{}: {e}", path.display()))
}

/// A row-major 4 x 4 matrix of the export.
pub fn matrix(dir: &Path, name: &str) -> Result<Mat4> {
    let (_, m) = read::<f32>(dir, name)?;
    let a: [f32; 16] = m.try_into().map_err(|_| format!("{name}: not 4 x 4"))?;
    Ok(Mat4::from_cols_array(&a).transpose())
}

/// One light of the export.
pub struct ExportLight {
    pub position: Vec3,
    pub radius: f32,
    /// For a spot: its axis and the cosines of its inner and outer half-angles.
    pub spot: Option<(Vec3, f32, f32)>,
}

pub fn lights(dir: &Path) -> Result<Vec<ExportLight>> {
    let (_, p) = read::<f32>(dir, "light_position.npy")?;
    let (_, r) = read::<f32>(dir, "light_radius.npy")?;
    let (_, k) = read::<u32>(dir, "light_kind.npy")?;
    let (_, d) = read::<f32>(dir, "light_direction.npy")?;
    let (_, ci) = read::<f32>(dir, "light_cos_inner.npy")?;
    let (_, co) = read::<f32>(dir, "light_cos_outer.npy")?;
    let v = |a: &[f32], i: usize| Vec3::new(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
    Ok((0..r.len())
        .map(|i| ExportLight {
            position: v(&p, i),
            radius: r[i],
            spot: (k[i] == 1).then(|| (v(&d, i), ci[i], co[i])),
        })
        .collect())
}

/// Bevy's projection of the export's field of view, aspect and near and far planes (Bevy's
/// own `PerspectiveProjection`: reversed z, infinite, the far plane bounding its frustum).
pub fn projection(clip_from_view: &Mat4) -> Result<PerspectiveProjection> {
    let m = clip_from_view;
    if m.w_axis.w != 0.0 {
        return Err("orthographic cameras are not supported by this adapter".into());
    }
    // The export's projection maps view z = -near to NDC z 0 and -far to 1:
    // z_ndc = (a z + b) / -z, so near = b / a and far = b / (a + 1).
    let (a, b) = (m.z_axis.z, m.w_axis.z);
    Ok(PerspectiveProjection {
        fov: 2.0 * (1.0 / m.y_axis.y).atan(),
        aspect_ratio: m.y_axis.y / m.x_axis.x,
        near: b / a,
        far: b / (a + 1.0),
        ..Default::default()
    })
}

pub struct Args {
    pub export: PathBuf,
    pub out: PathBuf,
    /// A fixed X x Y x Z grid (`ClusterConfig::XYZ`); otherwise `FixedZ` of `total` clusters
    /// over `z_slices` slices.
    pub xyz: Option<UVec3>,
    pub total: u32,
    pub z_slices: u32,
    pub z_config: ClusterZConfig,
    /// `--far-z camera`: the last slice ends at the export's far plane.
    pub far_camera: bool,
}

/// The options every adapter takes, after its name and `EXPORT OUT`.
pub const GRID_OPTIONS: &str = "[--xyz X,Y,Z | --total N --z-slices N] \
                                [--first-slice-depth D] [--far-z max-light-range|camera|F]";

/// A number of `T` for `option`, or an error naming the option, the value and what it accepts.
pub fn number<T: std::str::FromStr + PartialOrd + Copy>(
    option: &str,
    value: &str,
    ok: impl Fn(T) -> bool,
    accepted: &str,
) -> Result<T> {
    match value.trim().parse::<T>() {
        Ok(v) if ok(v) => Ok(v),
        _ => Err(format!("{option} {value}: expected {accepted}")),
    }
}

/// The grid options and `EXPORT OUT` of `a`; errors end with `usage`.
pub fn args_from(a: &[String], usage: &str) -> Result<Args> {
    let (mut pos, mut xyz) = (Vec::new(), None);
    let (mut total, mut z_slices) = (None, None);
    let mut z_config = ClusterZConfig::default();
    let mut far_camera = false;
    let mut it = a.iter();
    while let Some(s) = it.next() {
        let mut value = || {
            it.next()
                .ok_or_else(|| format!("{s}: a value is missing; {usage}"))
        };
        match s.as_str() {
            "--xyz" => {
                let v = value()?;
                let n: Vec<u32> = v
                    .split(',')
                    .map(|x| x.trim().parse::<u32>())
                    .collect::<std::result::Result<_, _>>()
                    .map_err(|_| format!("--xyz {v}: expected three counts, X,Y,Z"))?;
                if n.len() != 3 || n.contains(&0) {
                    return Err(format!("--xyz {v}: expected three counts >= 1, X,Y,Z"));
                }
                xyz = Some(UVec3::new(n[0], n[1], n[2]));
            }
            "--total" => {
                total = Some(number(
                    s,
                    value()?,
                    |n: u32| n >= 1,
                    "a cluster count >= 1",
                )?);
            }
            "--z-slices" => {
                z_slices = Some(number(s, value()?, |n: u32| n >= 1, "a slice count >= 1")?);
            }
            "--first-slice-depth" => {
                z_config.first_slice_depth = number(
                    s,
                    value()?,
                    |d: f32| d.is_finite() && d > 0.0,
                    "a finite depth > 0 (metres)",
                )?;
            }
            "--far-z" => {
                let v = value()?;
                far_camera = v == "camera";
                z_config.far_z_mode = match v.as_str() {
                    "max-light-range" => ClusterFarZMode::MaxClusterableObjectRange,
                    // Set to the export's far plane once it is read.
                    "camera" => ClusterFarZMode::Constant(f32::INFINITY),
                    _ => ClusterFarZMode::Constant(number(
                        s,
                        v,
                        |d: f32| d.is_finite() && d > 0.0,
                        "max-light-range, camera (the export's far plane) or a finite depth > 0 (metres)",
                    )?),
                };
            }
            o if o.starts_with("--") => return Err(format!("unknown option {o}; {usage}")),
            _ => pos.push(PathBuf::from(s)),
        }
    }
    if xyz.is_some() && (total.is_some() || z_slices.is_some()) {
        return Err(format!(
            "--xyz fixes every count: --total and --z-slices are for Bevy's FixedZ grid; {usage}"
        ));
    }
    let [export, out] = <[PathBuf; 2]>::try_from(pos).map_err(|_| usage.to_string())?;
    Ok(Args {
        export,
        out,
        xyz,
        total: total.unwrap_or(4096),
        z_slices: z_slices.unwrap_or(24),
        z_config,
        far_camera,
    })
}

/// The cluster configuration `args` ask for, and its description for `grid.json`'s source.
pub fn config(args: &Args) -> (ClusterConfig, String) {
    let z = &args.z_config;
    let far = match z.far_z_mode {
        ClusterFarZMode::MaxClusterableObjectRange => "MaxClusterableObjectRange".to_string(),
        ClusterFarZMode::Constant(f) => format!("Constant({f})"),
    };
    let z_text = format!(
        "first_slice_depth {}, far_z_mode {far}",
        z.first_slice_depth
    );
    match args.xyz {
        Some(dimensions) => (
            ClusterConfig::XYZ {
                dimensions,
                z_config: *z,
                dynamic_resizing: false,
            },
            format!(
                "ClusterConfig::XYZ {} x {} x {}, {z_text}",
                dimensions.x, dimensions.y, dimensions.z
            ),
        ),
        None => (
            ClusterConfig::FixedZ {
                total: args.total,
                z_slices: args.z_slices,
                z_config: *z,
                dynamic_resizing: true,
            },
            format!(
                "ClusterConfig::FixedZ {} clusters, {} slices, {z_text}",
                args.total, args.z_slices
            ),
        ),
    }
}

/// Spawns the export's lights as Bevy's point and spot lights, all visible; returns each
/// entity's index among the export's lights.
pub fn spawn_lights(world: &mut World, lights: &[ExportLight]) -> HashMap<Entity, u32> {
    let mut index: HashMap<Entity, u32> = HashMap::new();
    for (i, l) in lights.iter().enumerate() {
        let at = Transform::from_translation(l.position);
        let e = match l.spot {
            None => world
                .spawn((
                    PointLight {
                        range: l.radius,
                        radius: 0.0,
                        shadow_maps_enabled: false,
                        ..Default::default()
                    },
                    at,
                    ViewVisibility::VISIBLE,
                ))
                .id(),
            Some((axis, cos_inner, cos_outer)) => {
                let up = if axis.normalize().dot(Vec3::Y).abs() > 0.99 {
                    Vec3::X
                } else {
                    Vec3::Y
                };
                world
                    .spawn((
                        SpotLight {
                            range: l.radius,
                            radius: 0.0,
                            inner_angle: cos_inner.clamp(-1.0, 1.0).acos(),
                            outer_angle: cos_outer.clamp(-1.0, 1.0).acos(),
                            shadow_maps_enabled: false,
                            ..Default::default()
                        },
                        at.looking_to(axis, up),
                        ViewVisibility::VISIBLE,
                    ))
                    .id()
            }
        };
        index.insert(e, i as u32);
    }
    index
}

/// An adapter's exit: success, or the error on stderr and failure.
pub fn exit(result: Result<()>) -> std::process::ExitCode {
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// What the adapters read of an export: the image size, the camera and the lights.
pub struct Export {
    pub width: u32,
    pub height: u32,
    pub view_from_world: Mat4,
    pub projection: PerspectiveProjection,
    pub lights: Vec<ExportLight>,
}

impl Export {
    pub fn read(dir: &Path) -> Result<Export> {
        let (shape, _) = read::<f32>(dir, "depth.npy")?;
        if shape.len() != 2 {
            return Err(format!(
                "{}: expected a 2-D depth image, found shape {shape:?}",
                dir.join("depth.npy").display()
            ));
        }
        Ok(Export {
            width: shape[1] as u32,
            height: shape[0] as u32,
            view_from_world: matrix(dir, "view_from_world.npy")?,
            projection: projection(&matrix(dir, "clip_from_view.npy")?)?,
            lights: lights(dir)?,
        })
    }
}

/// Writes `grid.json`, `offsets.npy` and `indices.npy` into `out`: lists of `dims` clusters,
/// cluster `(y X + x) Z + z`, Bevy's proportional lookup and its near slice `[0, near)`.
#[allow(clippy::too_many_arguments)]
pub fn write_lists(
    out: &Path,
    source: &str,
    export: &Export,
    dims: UVec3,
    near: f32,
    far: f32,
    offsets: &[u32],
    indices: &[u32],
) -> Result<()> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    write(&out.join("offsets.npy"), offsets)?;
    write(&out.join("indices.npy"), indices)?;
    let grid = serde_json::json!({
        "format": "manylights-lists/1",
        "source": source,
        "width": export.width,
        "height": export.height,
        "dims": [dims.x, dims.y, dims.z],
        "screen": {"kind": "proportional"},
        "slicing": {"kind": "near_slice", "near": near, "far": far},
        "order": "z_fastest",
    });
    std::fs::write(
        out.join("grid.json"),
        serde_json::to_string_pretty(&grid).map_err(|e| e.to_string())?,
    )
    .map_err(|e| format!("{}: {e}", out.join("grid.json").display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy_camera::CameraProjection;

    fn parse(a: &[&str]) -> Result<Args> {
        args_from(
            &a.iter().map(|s| s.to_string()).collect::<Vec<_>>(),
            "usage: test",
        )
    }

    /// Bevy's knobs parse into its configuration, named in the source; bad values name the
    /// option and what it accepts.
    #[test]
    fn the_knobs_become_bevys_configuration() {
        let a = parse(&["e", "o"]).unwrap();
        let (c, text) = config(&a);
        assert!(matches!(
            c,
            ClusterConfig::FixedZ {
                total: 4096,
                z_slices: 24,
                dynamic_resizing: true,
                ..
            }
        ));
        assert_eq!(
            text,
            "ClusterConfig::FixedZ 4096 clusters, 24 slices, first_slice_depth 5, far_z_mode MaxClusterableObjectRange"
        );
        let a = parse(&[
            "e",
            "o",
            "--z-slices",
            "48",
            "--first-slice-depth",
            "0.5",
            "--far-z",
            "60",
        ])
        .unwrap();
        let (c, text) = config(&a);
        let ClusterConfig::FixedZ {
            z_slices, z_config, ..
        } = c
        else {
            panic!("{c:?}")
        };
        assert_eq!((z_slices, z_config.first_slice_depth), (48, 0.5));
        assert!(matches!(z_config.far_z_mode, ClusterFarZMode::Constant(f) if f == 60.0));
        assert!(
            text.contains("48 slices, first_slice_depth 0.5, far_z_mode Constant(60)"),
            "{text}"
        );
        assert!(parse(&["e", "o", "--far-z", "camera"]).unwrap().far_camera);
        let a = parse(&["e", "o", "--xyz", "20,12,32", "--first-slice-depth", "1"]).unwrap();
        assert!(
            config(&a)
                .1
                .starts_with("ClusterConfig::XYZ 20 x 12 x 32, first_slice_depth 1,")
        );
        for (bad, says) in [
            (
                &["e", "o", "--z-slices", "0"][..],
                "--z-slices 0: expected a slice count >= 1",
            ),
            (
                &["e", "o", "--first-slice-depth", "-1"],
                "--first-slice-depth -1: expected a finite depth",
            ),
            (
                &["e", "o", "--far-z", "far"],
                "--far-z far: expected max-light-range, camera (the export's far plane) or",
            ),
            (
                &["e", "o", "--xyz", "4,4,4", "--total", "64"],
                "--xyz fixes every count",
            ),
            (&["e", "o", "--total"], "--total: a value is missing"),
            (&["e", "o", "--tiles", "4"], "unknown option --tiles"),
            (&["e"], "usage:"),
        ] {
            let e = parse(bad).err().expect("refused");
            assert!(e.contains(says), "{bad:?}: {e}");
        }
    }

    /// The export's projection (glam's right-handed, depth in [0, 1]) gives back its field of
    /// view, aspect and planes, and Bevy's matrix of them maps the near plane to NDC z 1.
    #[test]
    fn the_projection_converts_to_bevys() {
        let m = Mat4::from_cols_array(&[
            1.0 / (0.6f32.tan() * 1.5),
            0.0,
            0.0,
            0.0,
            0.0,
            1.0 / 0.6f32.tan(),
            0.0,
            0.0,
            0.0,
            0.0,
            80.0 / (0.1 - 80.0),
            -1.0,
            0.0,
            0.0,
            0.1 * 80.0 / (0.1 - 80.0),
            0.0,
        ]);
        let p = projection(&m).unwrap();
        assert!((p.fov - 1.2).abs() < 1e-5 && (p.aspect_ratio - 1.5).abs() < 1e-5);
        assert!(
            (p.near - 0.1).abs() < 1e-5 && (p.far - 80.0).abs() < 1e-2,
            "{p:?}"
        );
        let c = p.get_clip_from_view() * bevy_math::Vec4::new(0.0, 0.0, -0.1, 1.0);
        assert!(
            (c.z / c.w - 1.0).abs() < 1e-5,
            "reversed z: the near plane at 1"
        );
        // An orthographic matrix keeps w = 1.
        assert!(
            projection(&Mat4::IDENTITY)
                .unwrap_err()
                .contains("orthographic")
        );
    }
}
