//! Scoring light lists that another program wrote (`manylights score`): the lists, in the
//! format docs/EXPERIMENTS.md ("Scoring another engine's lists") describes (`grid.json`, CSR
//! arrays `offsets.npy` and `indices.npy`, an optional light-id map), are looked up at every
//! pixel of an export (`--export`: the depth buffer, the camera and the lights) as their grid
//! says, and compared with the exact per-pixel sets that this workbench's oracle uses
//! (`manylights_cull::metrics`): false negatives (with where they are), lights evaluated per
//! light needed, lights per pixel and the longest list.

pub mod grid;
pub(crate) mod npy;
pub mod on_grid;

/// Draws `dir/scores.csv` (one row a setting and list source, as scripts/referee-bevy.sh
/// writes it) as `dir/figures/scores.svg`: lights evaluated per light needed against the
/// lists' memory, a panel a setting, a red ring around sources that miss lights. Returns the
/// figure's path.
pub fn chart(dir: &Path) -> Result<std::path::PathBuf, LabError> {
    let rows = crate::figures::scores::read(&dir.join("scores.csv"))?;
    let out = dir.join("figures").join("scores.svg");
    std::fs::create_dir_all(dir.join("figures")).map_err(|e| LabError::Io {
        path: dir.join("figures").display().to_string(),
        message: e.to_string(),
    })?;
    crate::figures::scores::draw(&rows, &out)?;
    Ok(out)
}

use std::path::Path;

use glam::{DMat4, DVec3, DVec4, Vec3};
use manylights_cull::metrics::ListMetrics;

use crate::LabError;
pub use grid::Grid;

/// What an export holds that scoring reads: the depth buffer, the camera, the lights.
pub struct Frame {
    /// Image width in pixels.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// NDC depth a pixel, rows from the top; 1.0 where no surface is.
    pub depth: Vec<f32>,
    /// World to clip.
    pub clip_from_world: DMat4,
    /// World to view.
    pub view_from_world: DMat4,
    /// The lights as the export holds them.
    pub lights: Vec<LightShape>,
}

/// What decides where a light reaches ([`manylights_scene::light::reaches`]).
#[derive(Clone, Copy, Debug)]
pub struct LightShape {
    /// Position.
    pub position: Vec3,
    /// Radius.
    pub radius: f32,
    /// For a spot, its unit axis and the cosine of its outer half-angle.
    pub cone: Option<(Vec3, f32)>,
}

/// One covered pixel's counts.
#[derive(Clone, Copy)]
struct PixelScore {
    evaluated: u64,
    needed: u64,
    missed: u32,
    extra: u32,
    first_missed: Option<u32>,
}

fn matrix(dir: &Path, name: &str) -> Result<DMat4, LabError> {
    let (_, m) = npy::read::<f32>(&dir.join(name), &["<f4"], &[Some(4), Some(4)])?;
    // Row-major in the file.
    Ok(DMat4::from_cols_array(&std::array::from_fn(|k| f64::from(m[k]))).transpose())
}

impl Frame {
    /// Reads an export directory (`cull --export`, `render --export`, `export: true`).
    pub fn from_export(dir: &Path) -> Result<Self, LabError> {
        let (shape, depth) = npy::read::<f32>(&dir.join("depth.npy"), &["<f4"], &[None, None])?;
        let (h, w) = (shape[0] as u32, shape[1] as u32);
        let (s, position) =
            npy::read::<f32>(&dir.join("light_position.npy"), &["<f4"], &[None, Some(3)])?;
        let n = Some(s[0]);
        let (_, radius) = npy::read::<f32>(&dir.join("light_radius.npy"), &["<f4"], &[n])?;
        let (_, kind) = npy::read::<u32>(&dir.join("light_kind.npy"), &["<u4"], &[n])?;
        let (_, axis) =
            npy::read::<f32>(&dir.join("light_direction.npy"), &["<f4"], &[n, Some(3)])?;
        let (_, cos_outer) = npy::read::<f32>(&dir.join("light_cos_outer.npy"), &["<f4"], &[n])?;
        let v3 = |a: &[f32], i: usize| Vec3::new(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
        let lights = (0..radius.len())
            .map(|i| {
                let cone = (kind[i] == manylights_gpu::layout::LIGHT_KIND_SPOT)
                    .then(|| (v3(&axis, i), cos_outer[i]));
                LightShape {
                    position: v3(&position, i),
                    radius: radius[i],
                    cone,
                }
            })
            .collect();
        Ok(Self {
            width: w,
            height: h,
            depth,
            clip_from_world: matrix(dir, "clip_from_world.npy")?,
            view_from_world: matrix(dir, "view_from_world.npy")?,
            lights,
        })
    }

    /// The world point of pixel `(x, y)` (None for background), as the exact oracle
    /// reconstructs it (`manylights_cull::metrics::surface_points`).
    fn point(&self, world_from_clip: &DMat4, x: u32, y: u32) -> Option<DVec3> {
        let z = self.depth[(y * self.width + x) as usize];
        (z < 1.0).then(|| {
            let ndc = DVec4::new(
                (f64::from(x) + 0.5) / f64::from(self.width) * 2.0 - 1.0,
                1.0 - (f64::from(y) + 0.5) / f64::from(self.height) * 2.0,
                f64::from(z),
                1.0,
            );
            let p = *world_from_clip * ndc;
            p.truncate() / p.w
        })
    }
}

/// Another program's lists, read and checked against the frame they are scored on.
pub struct Lists {
    /// The grid.
    pub grid: Grid,
    /// Cell `c`'s lights are `indices[offsets[c]..offsets[c + 1]]`.
    pub offsets: Vec<u64>,
    /// The lists, as the scene's light indices (mapped through the light-id map where given).
    pub indices: Vec<u32>,
}

impl Lists {
    /// Reads `dir` (`grid.json`, `offsets.npy`, `indices.npy` and the light-id map it names)
    /// for a frame of `width` x `height` pixels and `lights` lights.
    pub fn load(dir: &Path, width: u32, height: u32, lights: usize) -> Result<Self, LabError> {
        let grid = Grid::load(&dir.join("grid.json"), width, height)?;
        let cells = grid.cells();
        let path = dir.join("offsets.npy");
        let (_, offsets) = match npy::read::<u32>(&path, &["<u4"], &[Some(cells + 1)]) {
            Ok((s, v)) => (s, v.into_iter().map(u64::from).collect::<Vec<u64>>()),
            Err(_) => npy::read::<u64>(&path, &["<u4", "<u8"], &[Some(cells + 1)])?,
        };
        let ipath = dir.join("indices.npy");
        let (_, mut indices) = npy::read::<u32>(&ipath, &["<u4"], &[None])?;
        let err = |path: &Path, message: String| LabError::Io {
            path: path.display().to_string(),
            message,
        };
        if offsets[0] != 0 || offsets.windows(2).any(|w| w[0] > w[1]) {
            return Err(err(
                &path,
                "offsets must start at 0 and never decrease".into(),
            ));
        }
        if offsets[cells as usize] != indices.len() as u64 {
            return Err(err(
                &path,
                format!(
                    "the last offset is {}, but indices.npy holds {} entries",
                    offsets[cells as usize],
                    indices.len()
                ),
            ));
        }
        // The ids the lists use, and how many there are.
        let (ids_path, map) = match &grid.light_ids {
            Some(name) => {
                let p = dir.join(name);
                let (_, map) = npy::read::<u32>(&p, &["<u4"], &[None])?;
                if let Some((k, &v)) = map.iter().enumerate().find(|(_, v)| **v as usize >= lights)
                {
                    return Err(err(
                        &p,
                        format!(
                            "entry {k} maps to light {v}; the scene has {lights} lights (0 to {})",
                            lights - 1
                        ),
                    ));
                }
                (p, Some(map))
            }
            None => (ipath.clone(), None),
        };
        let ids = map.as_ref().map_or(lights, Vec::len);
        if let Some((k, &v)) = indices
            .iter()
            .enumerate()
            .find(|(_, v)| **v as usize >= ids)
        {
            return Err(err(
                &ipath,
                format!(
                    "entry {k} is light id {v}; accepted: 0 to {} ({} in {})",
                    ids.saturating_sub(1),
                    ids,
                    ids_path.display()
                ),
            ));
        }
        if let Some(map) = map {
            for i in &mut indices {
                *i = map[*i as usize];
            }
        }
        Ok(Self {
            grid,
            offsets,
            indices,
        })
    }

    /// Writes the lists in the scoring format into `dir` (`grid.json`, `offsets.npy` as
    /// uint32, `indices.npy`), each file whole or not at all; returns the files.
    pub fn write(&self, dir: &Path) -> Result<Vec<std::path::PathBuf>, LabError> {
        std::fs::create_dir_all(dir).map_err(|e| LabError::Io {
            path: dir.display().to_string(),
            message: e.to_string(),
        })?;
        let (g, o, i) = (
            dir.join("grid.json"),
            dir.join("offsets.npy"),
            dir.join("indices.npy"),
        );
        let too_many = |path: &Path| LabError::Io {
            path: path.display().to_string(),
            message: format!("{} entries do not fit uint32 offsets", self.indices.len()),
        };
        let offsets: Vec<u32> = self
            .offsets
            .iter()
            .map(|&v| u32::try_from(v).map_err(|_| too_many(&o)))
            .collect::<Result<_, _>>()?;
        crate::write_atomic(
            &g,
            serde_json::to_string_pretty(&self.grid)
                .expect("a grid serialises")
                .as_bytes(),
        )?;
        npy::write_u32(&o, &[offsets.len() as u64], &offsets)?;
        npy::write_u32(&i, &[self.indices.len() as u64], &self.indices)?;
        Ok(vec![g, o, i])
    }

    /// The lists' size in the scoring format: 4 bytes an entry and 4 bytes a cell's offset
    /// (`indices.npy` and `offsets.npy` as 32-bit words; an engine may pack its own tighter).
    pub fn bytes(&self) -> u64 {
        4 * (self.indices.len() as u64 + self.offsets.len() as u64)
    }

    /// Cell `c`'s lights, sorted.
    fn sorted(&self, c: u64) -> Vec<u32> {
        let (a, b) = (self.offsets[c as usize], self.offsets[c as usize + 1]);
        let mut v = self.indices[a as usize..b as usize].to_vec();
        v.sort_unstable();
        v
    }
}

/// The score of a set of lists over a frame.
pub struct Score {
    /// The metrics every strategy of this workbench reports.
    pub metrics: ListMetrics,
    /// Per pixel (rows from the top): lights it needs that its list lacks.
    pub missed: Vec<u32>,
    /// Per pixel: lights its list hands it that it does not need.
    pub extra: Vec<u32>,
    /// The first few false negatives: (x, y, light).
    pub first_misses: Vec<(u32, u32, u32)>,
}

impl Score {
    /// Writes `dir/score.json` ([`Score::to_json`]) and the per-pixel counts as NumPy arrays,
    /// `false_negatives.npy` and `extra.npy` (uint32, (H, W), rows from the top); returns the
    /// files.
    pub fn write(
        &self,
        dir: &Path,
        frame: &Frame,
        lists: &Lists,
    ) -> Result<Vec<std::path::PathBuf>, LabError> {
        std::fs::create_dir_all(dir).map_err(|e| LabError::Io {
            path: dir.display().to_string(),
            message: e.to_string(),
        })?;
        let hw = [u64::from(frame.height), u64::from(frame.width)];
        let (missed, extra, json) = (
            dir.join("false_negatives.npy"),
            dir.join("extra.npy"),
            dir.join("score.json"),
        );
        npy::write_u32(&missed, &hw, &self.missed)?;
        npy::write_u32(&extra, &hw, &self.extra)?;
        crate::write_atomic(&json, self.to_json(frame, lists).as_bytes())?;
        Ok(vec![json, missed, extra])
    }

    /// `score.json`: the metrics, where the false negatives are, and what was scored.
    pub fn to_json(&self, frame: &Frame, lists: &Lists) -> String {
        let m = &self.metrics;
        let v = serde_json::json!({
            "source": lists.grid.source,
            "width": frame.width,
            "height": frame.height,
            "lights": frame.lights.len(),
            "cells": lists.grid.cells(),
            "covered_pixels": m.covered_pixels,
            "false_negatives": m.false_negatives,
            "pixels_with_false_negatives": self.missed.iter().filter(|&&n| n > 0).count(),
            "first_false_negatives": self.first_misses.iter()
                .map(|&(x, y, l)| serde_json::json!({"x": x, "y": y, "light": l}))
                .collect::<Vec<_>>(),
            "evaluated": m.evaluated,
            "needed": m.needed,
            "false_positive_ratio": m.false_positive_ratio,
            "lights_per_pixel_mean": m.lights_per_pixel_mean,
            "lights_needed_per_pixel_mean": m.lights_needed_per_pixel_mean,
            "max_lights_per_cell": m.max_lights_per_bin,
            "list_bytes": lists.bytes(),
        });
        serde_json::to_string_pretty(&v).expect("JSON of numbers and strings")
    }
}

/// Scores `lists` over `frame`: every covered pixel looks its cell up as the grid says (at its
/// view depth) and its list is compared with its exact set. Rows are spread over the cores.
pub fn score(frame: &Frame, lists: &Lists) -> Score {
    let (w, h) = (frame.width, frame.height);
    let world_from_clip = frame.clip_from_world.inverse();
    let sorted: Vec<Vec<u32>> = (0..lists.grid.cells()).map(|c| lists.sorted(c)).collect();
    let row = |y: u32| -> Vec<Option<PixelScore>> {
        (0..w)
            .map(|x| {
                let p = frame.point(&world_from_clip, x, y)?;
                let d = -(frame.view_from_world * p.extend(1.0)).z;
                let list = &sorted[lists.grid.cell(x, y, d) as usize];
                let mut needed = 0u64;
                let mut missed = 0u32;
                let mut first = None;
                for (i, l) in frame.lights.iter().enumerate() {
                    if manylights_scene::light::reaches(l.position, l.radius, l.cone, p) {
                        needed += 1;
                        if list.binary_search(&(i as u32)).is_err() {
                            missed += 1;
                            first.get_or_insert(i as u32);
                        }
                    }
                }
                let found = needed - u64::from(missed);
                let extra = (list.len() as u64 - found) as u32;
                Some(PixelScore {
                    evaluated: list.len() as u64,
                    needed,
                    missed,
                    extra,
                    first_missed: first,
                })
            })
            .collect()
    };
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()) as u32;
    let mut rows: Vec<Vec<_>> = Vec::with_capacity(h as usize);
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                s.spawn(move || {
                    (t..h)
                        .step_by(threads as usize)
                        .map(|y| (y, row(y)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        let mut all: Vec<(u32, Vec<_>)> = handles
            .into_iter()
            .flat_map(|h| h.join().expect("a scoring thread"))
            .collect();
        all.sort_by_key(|(y, _)| *y);
        rows = all.into_iter().map(|(_, r)| r).collect();
    });
    let pixels: Vec<_> = rows.iter().flatten().collect();
    let metrics = ListMetrics::from_pixels(
        pixels
            .iter()
            .filter_map(|p| p.map(|p| (p.evaluated, p.needed, u64::from(p.missed)))),
        sorted.iter().map(|l| l.len() as u32),
    );
    let first_misses = pixels
        .iter()
        .enumerate()
        .filter_map(|(k, p)| {
            let light = p.and_then(|p| p.first_missed)?;
            Some(((k as u32) % w, (k as u32) / w, light))
        })
        .take(10)
        .collect();
    Score {
        metrics,
        missed: pixels.iter().map(|p| p.map_or(0, |p| p.missed)).collect(),
        extra: pixels.iter().map(|p| p.map_or(0, |p| p.extra)).collect(),
        first_misses,
    }
}
