//! A run's data for the researcher's own analysis (`--export DIR` on `cull` and `render`,
//! `export: true` in experiments): NumPy `.npy` files written by the program (no Python
//! needed) and a `manifest.json` naming their shapes and conventions. docs/EXPERIMENTS.md
//! ("Exports") shows how to load them and recompute the false negatives with NumPy alone.

use std::path::{Path, PathBuf};

use manylights_cull::layout::GpuCullParams;
use manylights_cull::{BinLists, CullOutput, Culler, geometry};
use manylights_gpu::layout::{GpuFrame, GpuLight, LIGHT_KIND_SPOT};
use manylights_gpu::{GpuContext, GpuScene, readback};
use serde_json::json;

use crate::{LabError, write_atomic};

/// A culling run to export, as cull, render and the runner hold it: the lists of `strategy`
/// over the depth buffer `depth` of `scene` seen as `frame` says, by `culler`.
pub struct RunToExport<'a> {
    /// The device.
    pub ctx: &'a GpuContext,
    /// The culler whose exact oracle checks the lists.
    pub culler: &'a Culler,
    /// The scene.
    pub scene: &'a GpuScene,
    /// The depth buffer.
    pub depth: &'a wgpu::Texture,
    /// The lists.
    pub lists: &'a CullOutput,
    /// The frame uniform the run was culled with.
    pub frame: &'a GpuFrame,
    /// The strategy's name.
    pub strategy: &'a str,
}

/// Exports the run `r` into `dir`: the depth read back, the exact oracle at every pixel, the
/// lists read back, and the lights as the GPU holds them. Returns the files.
pub fn export_run(r: &RunToExport<'_>, dir: &Path) -> Result<Vec<PathBuf>, LabError> {
    let RunToExport {
        ctx,
        culler,
        scene,
        depth,
        lists,
        frame,
        strategy,
    } = *r;
    let gpu = |e: manylights_gpu::GpuError| LabError::from(e).during("export");
    if scene.has_transparent() {
        // The arrays are a pixel's opaque surface; glass fragments lie elsewhere.
        return Err(LabError::refused(
            "export",
            "the scene has transparent surfaces (glass), which the arrays (one depth a pixel) \
             cannot hold: export a scene without glass",
        ));
    }
    let (w, h) = (depth.width(), depth.height());
    let depth_values: Vec<f32> = bytemuck::pod_collect_to_vec(
        &readback::read_texture(ctx, depth, wgpu::TextureAspect::DepthOnly).map_err(gpu)?,
    );
    // Per pixel [evaluated, needed, found, covered], every pixel.
    let counts = culler
        .exact_counts(ctx, scene, depth, lists, frame.clip_from_world.inverse(), 1)
        .map_err(|e| LabError::from(e).during("export"))?;
    let evaluated: Vec<u32> = counts.iter().map(|c| c[0]).collect();
    let needed: Vec<u32> = counts.iter().map(|c| c[1]).collect();
    let bins = lists
        .read(ctx)
        .map_err(|e| LabError::from(e).during("export"))?;
    let n = u64::from(scene.light_count);
    let lights: Vec<GpuLight> = bytemuck::pod_collect_to_vec(
        &readback::read_buffer(ctx, &scene.lights, 0, n * size_of::<GpuLight>() as u64)
            .map_err(gpu)?,
    );
    write(
        dir,
        &ExportData {
            frame,
            params: &lists.params,
            strategy,
            depth: &depth_values,
            size: (w, h),
            needed: &needed,
            evaluated: &evaluated,
            lists: &bins,
            lights: &lights,
        },
    )
}

/// What one run exports.
pub struct ExportData<'a> {
    /// The frame constants (camera matrices, viewport).
    pub frame: &'a GpuFrame,
    /// The culling run's parameters (bins, tiles, slices).
    pub params: &'a GpuCullParams,
    /// The strategy's name.
    pub strategy: &'a str,
    /// The depth buffer, `width * height` values, rows from the top.
    pub depth: &'a [f32],
    /// Its width and height.
    pub size: (u32, u32),
    /// Per pixel, the lights it needs (its exact set's size; 0 for background).
    pub needed: &'a [u32],
    /// Per pixel, the lights its list hands it (0 for background).
    pub evaluated: &'a [u32],
    /// The lists, a bin each (z-binning's expanded a (tile, depth bin) cell).
    pub lists: &'a BinLists,
    /// The lights as the GPU holds them.
    pub lights: &'a [GpuLight],
}

/// One exported array: its file name, shape, NumPy dtype and `.npy` bytes.
struct Array {
    name: &'static str,
    shape: Vec<u64>,
    dtype: &'static str,
    bytes: Vec<u8>,
}

/// The NumPy dtype of an exported element type.
trait Dtype: npyz::AutoSerialize + Copy {
    const NAME: &'static str;
}
impl Dtype for f32 {
    const NAME: &'static str = "float32";
}
impl Dtype for u32 {
    const NAME: &'static str = "uint32";
}
impl Dtype for i32 {
    const NAME: &'static str = "int32";
}

/// `data` as array `name` of `shape` (C order, little-endian).
fn npy<T: Dtype>(name: &'static str, shape: &[u64], data: &[T]) -> Result<Array, LabError> {
    let bytes = crate::score::npy::encode(shape, data)
        .map_err(|e| LabError::refused(format!("encoding {name}"), e.to_string()))?;
    Ok(Array {
        name,
        shape: shape.to_vec(),
        dtype: T::NAME,
        bytes,
    })
}

/// A matrix as 16 values in row-major order (NumPy's `M` with `p' = M @ p`).
fn rows(m: &glam::Mat4) -> [f32; 16] {
    m.transpose().to_cols_array()
}

/// Writes the export of one run into `dir` (each file whole or not at all); returns the files.
pub fn write(dir: &Path, d: &ExportData<'_>) -> Result<Vec<PathBuf>, LabError> {
    let (w, h) = d.size;
    let pixels = (w * h) as usize;
    for (name, len) in [
        ("depth", d.depth.len()),
        ("needed", d.needed.len()),
        ("evaluated", d.evaluated.len()),
    ] {
        if len != pixels {
            return Err(LabError::refused(
                "export",
                format!("{name} holds {len} values for {w} x {h} pixels"),
            ));
        }
    }
    let hw = [u64::from(h), u64::from(w)];
    // The bin each covered pixel reads (-1: background), as the shading lookup finds it.
    let pixel_bin: Vec<i32> = (0..pixels)
        .map(|i| {
            let z = d.depth[i];
            if z < 1.0 {
                let (x, y) = (i as u32 % w, i as u32 / w);
                geometry::bin_of(d.frame, d.params, [x, y], z) as i32
            } else {
                -1
            }
        })
        .collect();
    let n = d.lights.len() as u64;
    let bins = d.lists.ranges.len() as u64;
    let vec3 = |f: fn(&GpuLight) -> glam::Vec3| -> Vec<f32> {
        d.lights.iter().flat_map(|l| f(l).to_array()).collect()
    };
    let scalar = |f: fn(&GpuLight) -> f32| -> Vec<f32> { d.lights.iter().map(f).collect() };
    let offsets: Vec<u32> = d.lists.ranges.iter().map(|r| r[0]).collect();
    let counts: Vec<u32> = d.lists.ranges.iter().map(|r| r[1]).collect();
    // The shape alone: the export format predates the falloff bits of `GpuLight::kind`.
    let kinds: Vec<u32> = d.lights.iter().map(GpuLight::shape).collect();
    let m = |m: &glam::Mat4| rows(m);
    let files = vec![
        npy("depth.npy", &hw, d.depth)?,
        npy("needed.npy", &hw, d.needed)?,
        npy("evaluated.npy", &hw, d.evaluated)?,
        npy("pixel_bin.npy", &hw, &pixel_bin)?,
        npy("bin_offsets.npy", &[bins], &offsets)?,
        npy("bin_counts.npy", &[bins], &counts)?,
        npy(
            "light_indices.npy",
            &[d.lists.indices.len() as u64],
            &d.lists.indices,
        )?,
        npy("light_position.npy", &[n, 3], &vec3(|l| l.position))?,
        npy("light_radius.npy", &[n], &scalar(|l| l.radius))?,
        npy("light_color.npy", &[n, 3], &vec3(|l| l.color))?,
        npy("light_intensity.npy", &[n], &scalar(|l| l.intensity))?,
        npy("light_kind.npy", &[n], &kinds)?,
        npy("light_direction.npy", &[n, 3], &vec3(|l| l.direction))?,
        npy("light_cos_inner.npy", &[n], &scalar(|l| l.cos_inner))?,
        npy("light_cos_outer.npy", &[n], &scalar(|l| l.cos_outer))?,
        npy("clip_from_world.npy", &[4, 4], &m(&d.frame.clip_from_world))?,
        npy("view_from_world.npy", &[4, 4], &m(&d.frame.view_from_world))?,
        npy("clip_from_view.npy", &[4, 4], &m(&d.frame.clip_from_view))?,
    ];
    let manifest = manifest(d, &files);
    let mut written = Vec::with_capacity(files.len() + 4);
    for a in files {
        let path = dir.join(a.name);
        write_atomic(&path, &a.bytes)?;
        written.push(path);
    }
    written.extend(write_lists(&dir.join("lists"), d)?);
    let path = dir.join("manifest.json");
    let text = serde_json::to_string_pretty(&manifest)
        .map_err(|e| LabError::refused("export manifest", e.to_string()))?;
    write_atomic(&path, text.as_bytes())?;
    written.push(path);
    Ok(written)
}

/// The lists again in the format `manylights score` reads (`lists/grid.json`, `offsets.npy`,
/// `indices.npy`; docs/EXPERIMENTS.md, "Scoring another engine's lists"): the bins as a grid
/// of tiles, x fastest, slices outermost, sliced as the run sliced them. Scoring them gives
/// back the run's own figures; they are also a template for another engine's lists.
fn write_lists(dir: &Path, d: &ExportData<'_>) -> Result<Vec<PathBuf>, LabError> {
    use crate::score::grid::{CellOrder, FORMAT, Grid, ScreenMapping, Slicing};
    let p = d.params;
    let slices = p.slices.max(1);
    let cells = u64::from(p.tiles_x) * u64::from(p.tiles_y) * u64::from(slices);
    if d.lists.ranges.len() as u64 != cells {
        return Ok(Vec::new());
    }
    let (near, z) = (f64::from(p.near), f64::from(slices));
    let slicing = if slices == 1 {
        Slicing::None
    } else if p.slicing == manylights_cull::layout::SLICING_EXPONENTIAL {
        Slicing::Exponential {
            near,
            far: near * (z / f64::from(p.slice_scale)).exp(),
        }
    } else {
        Slicing::Linear {
            near,
            far: near + z / f64::from(p.slice_scale),
        }
    };
    let grid = Grid {
        format: FORMAT.into(),
        source: format!("manylights {}", d.strategy),
        width: d.size.0,
        height: d.size.1,
        dims: [p.tiles_x, p.tiles_y, slices],
        screen: ScreenMapping::Tiles {
            tile_size: [p.tile_size, p.tile_size],
        },
        slicing,
        order: CellOrder::XFastest,
        light_ids: None,
    };
    let mut offsets = vec![0u32];
    let mut indices = Vec::new();
    for r in &d.lists.ranges {
        indices.extend_from_slice(&d.lists.indices[r[0] as usize..(r[0] + r[1]) as usize]);
        offsets.push(indices.len() as u32);
    }
    std::fs::create_dir_all(dir).map_err(|e| LabError::Io {
        path: dir.display().to_string(),
        message: e.to_string(),
    })?;
    let mut written = Vec::new();
    for a in [
        npy("offsets.npy", &[offsets.len() as u64], &offsets)?,
        npy("indices.npy", &[indices.len() as u64], &indices)?,
    ] {
        let path = dir.join(a.name);
        write_atomic(&path, &a.bytes)?;
        written.push(path);
    }
    let path = dir.join("grid.json");
    let text = serde_json::to_string_pretty(&grid)
        .map_err(|e| LabError::refused("export lists", e.to_string()))?;
    write_atomic(&path, text.as_bytes())?;
    written.push(path);
    Ok(written)
}

/// The manifest: every array's shape and dtype, and the conventions that read them.
fn manifest(d: &ExportData<'_>, files: &[Array]) -> serde_json::Value {
    let (w, h) = d.size;
    let p = d.params;
    let arrays: serde_json::Map<String, serde_json::Value> = files
        .iter()
        .map(|a| {
            (
                a.name.to_owned(),
                json!({ "shape": a.shape, "dtype": a.dtype }),
            )
        })
        .collect();
    json!({
        "format": "manylights export 1",
        "width": w,
        "height": h,
        "lights": d.lights.len(),
        "strategy": d.strategy,
        "bins": d.lists.ranges.len(),
        "tile_size": p.tile_size,
        "tiles": [p.tiles_x, p.tiles_y],
        "slices": p.slices,
        "arrays": arrays,
        "conventions": {
            "pixels": "row y from the top, column x from the left; arrays are [y, x]",
            "depth": "the depth buffer's value, NDC z in [0, 1]; 1.0 is background (no surface)",
            "ndc": "pixel (x, y) is at NDC ((x + 0.5) / width * 2 - 1, 1 - (y + 0.5) / height * 2, depth)",
            "world_position": "p = inv(clip_from_world) @ (ndc_x, ndc_y, depth, 1); world = p[:3] / p[3]",
            "matrices": "row-major, acting on column vectors: clip = clip_from_world @ (x, y, z, 1)",
            "lists": "the lights of bin b are light_indices[bin_offsets[b] : bin_offsets[b] + bin_counts[b]]; a pixel reads bin pixel_bin[y, x] (-1: background)",
            "light_kind": format!("0: point; {LIGHT_KIND_SPOT}: spot"),
            "exact_set": "light i reaches world point q when |q - position_i| < radius_i and, for a spot, dot(q - position_i, direction_i) / |q - position_i| > cos_outer_i",
            "needed": "the size of each pixel's exact set",
            "evaluated": "the length of the list each pixel reads",
            "scoring": "lists/ holds the same lists in the format manylights score reads (grid.json, offsets.npy, indices.npy), where the bins form a grid of tiles and slices",
        },
    })
}
