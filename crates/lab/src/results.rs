//! Result rows: one per cell, persisted as `cells/<id>.json` when the cell finishes, and
//! gathered into `results.csv` and `results.json`.
//!
//! The columns named by the experiments issue are a public contract: keep them, add new ones
//! after them, never rename. GPU times are medians over the measured frames, with p10 and p90
//! beside them; `gpu_ms_prepass` counts `prepass.*`, `shade.gbuffer` and `shade.visibility` (the
//! geometry pass of each backend, and with MSAA forward `prepass.depth_bounds`), `gpu_ms_cull` every `cull.*`, `scan.*` and `sort.*` pass, `gpu_ms_shade`
//! every other `shade.*` pass. Values that were not measured are empty in the CSV and null in
//! the JSON.

use std::collections::BTreeMap;

use manylights_gpu::timing::Category;
use serde::{Deserialize, Serialize};

pub use crate::columns::COLUMNS;
pub use crate::old_rows::backfill;
pub use crate::result_files::{load_cells, load_rows, merge, save_cell, to_csv, write_results};

/// One cell's results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Experiment name.
    pub experiment: String,
    /// Cell name.
    pub cell: String,
    /// Scene name.
    pub scene: String,
    /// Number of lights.
    pub lights: u64,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Strategy name (`none` for naive forward).
    pub strategy: String,
    /// Backend name.
    pub backend: String,
    /// Strategy parameters.
    pub params: String,
    /// Median GPU time of all passes, ms.
    pub gpu_ms_total: Option<f64>,
    /// Median culling time, ms.
    pub gpu_ms_cull: Option<f64>,
    /// Median shading time, ms.
    pub gpu_ms_shade: Option<f64>,
    /// Median geometry-pass time (depth prepass or G-buffer), ms.
    pub gpu_ms_prepass: Option<f64>,
    /// Median CPU time recording command buffers, ms.
    pub cpu_ms_encode: f64,
    /// False negatives (pixel, light pairs) of the cell's lists against the exact oracle;
    /// empty where the oracle did not run (`exact_stride: 0`) and for naive forward, which has
    /// no lists.
    pub false_negatives: Option<u64>,
    /// Lights evaluated / lights needed.
    pub false_positive_ratio: Option<f64>,
    /// Mean lights evaluated per covered pixel.
    pub lights_per_pixel_mean: Option<f64>,
    /// Longest list of any tile or cluster.
    pub max_lights_per_tile: Option<u64>,
    /// Lights dropped by a capacity.
    pub dropped_lights: u64,
    /// Bytes of the lists.
    pub list_bytes: u64,
    /// Bytes of the G-buffer, or of the visibility buffer (with the compute rasteriser its keys
    /// too).
    pub gbuffer_bytes: u64,
    /// PSNR against the reference, dB (`"inf"` in JSON for identical images).
    #[serde(with = "inf_f64")]
    pub psnr_db: Option<f64>,
    /// Mean FLIP against the reference.
    pub flip_mean: Option<f64>,
    /// Maximum absolute error against the reference.
    pub max_abs_error: Option<f64>,
    /// Adapter name.
    pub adapter: String,
    /// Driver.
    pub driver: String,
    /// Commit of the binary.
    pub commit: String,
    /// p10 of `gpu_ms_total`.
    pub gpu_ms_total_p10: Option<f64>,
    /// p90 of `gpu_ms_total`.
    pub gpu_ms_total_p90: Option<f64>,
    /// p10 of `gpu_ms_cull`.
    pub gpu_ms_cull_p10: Option<f64>,
    /// p90 of `gpu_ms_cull`.
    pub gpu_ms_cull_p90: Option<f64>,
    /// p10 of `gpu_ms_shade`.
    pub gpu_ms_shade_p10: Option<f64>,
    /// p90 of `gpu_ms_shade`.
    pub gpu_ms_shade_p90: Option<f64>,
    /// p10 of `gpu_ms_prepass`.
    pub gpu_ms_prepass_p10: Option<f64>,
    /// p90 of `gpu_ms_prepass`.
    pub gpu_ms_prepass_p90: Option<f64>,
    /// Median GPU time of raster passes, ms.
    pub gpu_ms_raster: Option<f64>,
    /// Median GPU time of compute passes, ms.
    pub gpu_ms_compute: Option<f64>,
    /// PSNR against the infinite-range reference (the cost of the cut-off), dB.
    #[serde(with = "inf_f64")]
    pub psnr_db_infinite: Option<f64>,
    /// Mean FLIP against the infinite-range reference, both images tonemapped at the exposure
    /// adapted to the reference (`exposure_infinite`); stochastic cells: the mean over seeds.
    pub flip_mean_infinite: Option<f64>,
    /// Maximum absolute error against the infinite-range reference.
    pub max_abs_error_infinite: Option<f64>,
    /// Pixel stride of the exact oracle (1: every pixel).
    pub exact_stride: u32,
    /// Measured frames.
    pub frames: u32,
    /// Pixels of the backend's image with a NaN or infinite channel (the worst pose).
    #[serde(default)]
    pub nonfinite_pixels: u64,
    /// Camera poses measured (a path's length; 1 otherwise); with moving lights, the measured
    /// frames, each checked with its lights where that frame had them. Every list and accuracy
    /// column is the worst over them (false negatives: their sum).
    #[serde(default = "one")]
    pub poses: u32,
    /// Mean absolute frame-to-frame change of the image over the path (per RGB channel).
    #[serde(default)]
    pub temporal_change: Option<f64>,
    /// The same for the reference: the change the camera motion itself causes.
    #[serde(default)]
    pub temporal_change_reference: Option<f64>,
    /// Largest frame-to-frame change of the image's error against the reference, relative to
    /// the reference's peak: flicker that the reference does not have.
    #[serde(default)]
    pub temporal_flicker: Option<f64>,
    /// Whether the strategy kept its lists through tile masks (a bit per tile and light, where
    /// they fit the cell's `mask_budget`; clusters never do); empty for naive forward.
    #[serde(default)]
    pub tile_masks: Option<bool>,
    /// Culling in steady state: the median over back-to-back runs (as many as the measured
    /// frames, at the first pose) of a run's summed passes, ms, as the benches time it; lists
    /// sized from an earlier run, so no count pass where a single run needs one. Empty for naive
    /// forward and without timestamp queries.
    #[serde(default)]
    pub gpu_ms_cull_steady: Option<f64>,
    /// The same runs' median span, ms: one timestamp pair around each run's passes, so clears
    /// and the gaps between dependent passes count. Empty where the adapter cannot write
    /// timestamps between passes.
    #[serde(default)]
    pub gpu_ms_cull_span: Option<f64>,
    /// A frame's culling and the shading pass that reads its lists, in steady state: the
    /// median over back-to-back runs (as `gpu_ms_cull_steady`) of a run's culling passes and
    /// shading pass (`shade.forward` or `shade.deferred`), ms. What a loose list costs shows
    /// here, not in the culling time. Empty for naive forward and without timestamp queries.
    #[serde(default)]
    pub gpu_ms_cull_shade: Option<f64>,
    /// The same runs' median span (culling and shading within one timestamp pair), ms.
    #[serde(default)]
    pub gpu_ms_cull_shade_span: Option<f64>,
    /// Mean number of lights a covered pixel needs (its exact set), from the exact oracle over
    /// the same pixels as `false_positive_ratio` (the worst pose of a camera path). Lights
    /// evaluated per light needed is `lights_per_pixel_mean / lights_needed_per_pixel_mean`.
    #[serde(default)]
    pub lights_needed_per_pixel_mean: Option<f64>,
    /// Mean number of lights a covered pixel's shading walks (tests against its range), counted
    /// on the GPU in a frame of its own (`manylights_gpu::GpuScene::count_lights_walked`), the
    /// first pose: `lights_per_pixel_mean` less what a backend's loop skips before a pixel tests
    /// a light (deferred's and the visibility buffer's box of an 8 x 8 block's surface points
    /// over the clusters' lists), summed over every fragment or sample group a pixel shades.
    /// Lights walked per light needed is this over `lights_needed_per_pixel_mean`.
    #[serde(default)]
    pub lights_walked_per_pixel_mean: Option<f64>,
    /// Moving lights: the median GPU time of a frame's light update, ms: the animation pass
    /// (`lights.animate`, `light_update: Gpu`) or the copy of the uploaded lights
    /// (`lights.upload`, `light_update: Upload`; empty where the device cannot time it). It is
    /// part of `gpu_ms_total`. Empty for static lights.
    #[serde(default)]
    pub gpu_ms_light_update: Option<f64>,
    /// Moving lights uploaded from the host (`light_update: Upload`): the median host time of
    /// a frame's upload, ms (waiting for the staging buffer, computing every moving light on
    /// every core, writing them into it). Empty otherwise.
    #[serde(default)]
    pub cpu_ms_upload: Option<f64>,
    /// Samples a pixel (MSAA where more than one; the config's `msaa`). With MSAA, the list
    /// metrics (`false_negatives`, `false_positive_ratio`, the lights needed) count every
    /// covered sample; `lights_per_pixel_mean` is a pixel's longest list of its samples.
    #[serde(default = "one")]
    pub msaa: u32,
    /// Bytes of the frame's multisampled targets (depth, and the HDR colour it resolves from),
    /// 0 without MSAA.
    #[serde(default)]
    pub msaa_target_bytes: u64,
    /// Whether the scene has transparent surfaces (glass): its list metrics then also count
    /// every visible transparent fragment, and culling reaches to the nearest glass.
    #[serde(default)]
    pub transparent: bool,
    /// The frame's geometry in steady state: the median over back-to-back runs
    /// (`Renderer::geometry_repeated`) of its depth prepass or G-buffer pass and lookup bounds
    /// (naive forward: its whole frame), ms. Empty without timestamp queries.
    #[serde(default)]
    pub gpu_ms_geometry_steady: Option<f64>,
    /// The frame in steady state: `gpu_ms_geometry_steady` plus `gpu_ms_cull_shade` (naive
    /// forward: its geometry's, its whole frame), ms; each timed back to back after a warm-up,
    /// at the clock the GPU runs at under load. `gpu_ms_total` times frames one at a time,
    /// each rendered, read back and checked before the next, which leaves the GPU idle long
    /// enough for its clock to fall (an H200 sampled at 345-1,400 MHz through such frames,
    /// 1,980 MHz under load). Empty without timestamp queries.
    #[serde(default)]
    pub gpu_ms_frame_steady: Option<f64>,
    /// How the lights' ranges were set: `fixed`, `threshold` or `stochastic` (stochastic light
    /// culling, its ranges drawn each frame).
    #[serde(default)]
    pub radius_rule: String,
    /// The exposure `flip_mean_infinite` tonemaps both images with: adapted to the
    /// infinite-range reference (`manylights_shade::accuracy::exposure_of`, Reinhard's key).
    #[serde(default)]
    pub exposure_infinite: Option<f64>,
    /// RMSE against the infinite-range reference (the worst pose; stochastic cells: the mean
    /// over seeds).
    #[serde(default)]
    pub rmse_infinite: Option<f64>,
    /// The signed mean relative luminance error over lit pixels against the infinite-range
    /// reference: negative where the image is darker, as any radius cut-off makes it (the pose
    /// farthest from zero; stochastic cells: the mean over seeds).
    #[serde(default)]
    pub energy_error_infinite: Option<f64>,
    /// Stochastic cells: the seeds measured (each an independent image).
    #[serde(default)]
    pub seeds: Option<u32>,
    /// Stochastic cells: frames averaged into each image (1: none).
    #[serde(default)]
    pub accumulate: Option<u32>,
    /// Stochastic cells: each lit pixel's mean over the seeds less the infinite-range
    /// reference, as the root mean square over lit pixels with the noise's share taken out,
    /// relative to their mean reference luminance (`manylights_lab::noise`; zero within noise
    /// for an unbiased estimate; empty with one seed).
    #[serde(default)]
    pub bias_infinite: Option<f64>,
    /// Stochastic cells: the standard deviation across seeds of each lit pixel's luminance, as
    /// the root mean square over lit pixels relative to their mean reference luminance (empty
    /// with one seed).
    #[serde(default)]
    pub noise_infinite: Option<f64>,
    /// Stochastic cells: the mean absolute change of luminance from one seed's image to the
    /// next, relative to the mean reference luminance (empty with one seed).
    #[serde(default)]
    pub temporal_flicker_mean: Option<f64>,
    /// Whether the infinite-range reference came from the run folder's cache
    /// (`references/`): a sweep computes it once per view.
    #[serde(default)]
    pub reference_infinite_cached: Option<bool>,
    /// The material models of the frame's surfaces (the config's `materials`, or the scene's
    /// own), their names joined by `+` in the order of their ids (`blinn_phong+ggx+...`).
    #[serde(default)]
    pub materials: String,
    /// Covered pixels (samples with MSAA) of the first pose: with `lights_per_pixel_mean`,
    /// the lights the frame evaluates.
    #[serde(default)]
    pub covered_pixels: Option<u64>,
    /// The shading passes' time in steady state (`passes_steady`'s `shade.*` passes other
    /// than the G-buffer's and the MSAA expansion; naive forward's `shade.naive`) per light
    /// evaluated (`lights_per_pixel_mean` times `covered_pixels`), ns: what one evaluation of
    /// the frame's material models costs, the per-pixel reject included. Empty where the
    /// passes were not timed apart.
    #[serde(default)]
    pub ns_per_light_eval: Option<f64>,
    /// `radius: Hierarchy`: the median GPU time of a frame's build of the lighting grid
    /// hierarchy (the `lights.hierarchy.*` passes), ms; part of `gpu_ms_light_update` and
    /// `gpu_ms_total`, not of the steady-state culling and shading. Empty otherwise.
    #[serde(default)]
    pub gpu_ms_hierarchy: Option<f64>,
    /// `radius: Hierarchy`: the build timed in steady state, builds back to back in one
    /// submission after the warm-up (as `gpu_ms_cull_steady` times culling, right after it and
    /// before the accuracy work, at the clock the frame's passes ran at), ms: what a frame
    /// pays for it beside `gpu_ms_cull_shade`. `gpu_ms_hierarchy` times each frame's build
    /// after the GPU idled, at whatever clock it had fallen to. Empty otherwise, and in rows
    /// written before it.
    #[serde(default)]
    pub gpu_ms_hierarchy_steady: Option<f64>,
    /// `radius: Hierarchy`: the frame in steady state with the hierarchy's build timed in it:
    /// `gpu_ms_geometry_steady` plus culling, shading and the build back to back in one
    /// submission (each run's build writing the lights the next run culls, as an
    /// application's frames run), ms. Empty otherwise, and in rows written before it.
    #[serde(default)]
    pub gpu_ms_frame_build_steady: Option<f64>,
    /// The scene's lights where the cell shades others in their place (`radius: Hierarchy`,
    /// whose nodes of every level `lights` counts); empty otherwise. A report's settings
    /// group cells by `Row::setting_lights`.
    #[serde(default)]
    pub scene_lights: Option<u64>,
    /// Bytes a pixel of the opaque frame written by its raster pass and its shading (depth,
    /// G-buffer or visibility buffer, and the lit image, at every sample):
    /// `manylights_shade::Backend::bytes_per_pixel`, a model, not a measurement. Empty in rows
    /// written before it.
    #[serde(default)]
    pub bytes_written_per_pixel: Option<u64>,
    /// Bytes a pixel the shading reads of what the raster pass wrote (and the visibility
    /// buffer's triangle fetch), as `bytes_written_per_pixel` models it.
    #[serde(default)]
    pub bytes_read_per_pixel: Option<u64>,
    /// The cell's swept parameters and its light range's, as columns (flattened: each is a
    /// column of its own).
    #[serde(flatten)]
    pub sweep: SweepColumns,
    /// Shadows: the cell's mode, its rays and their cost, and its image against the shadowed
    /// light (flattened).
    #[serde(flatten)]
    pub shadow: ShadowColumns,
    /// Per-pass median GPU times, ms, by pass name.
    pub passes: BTreeMap<String, f64>,
    /// The same in steady state: the passes of `gpu_ms_geometry_steady`'s,
    /// `gpu_ms_cull_shade`'s and `gpu_ms_hierarchy_steady`'s back-to-back runs, each pass's
    /// median over the runs, ms (empty where they were not timed). JSON only.
    #[serde(default)]
    pub passes_steady: BTreeMap<String, f64>,
    /// The category of each pass of `passes` and `passes_steady` (`prepass`, `cull`, `shade`
    /// or `light_update`: the frame plan's and culling's), by name. JSON only; empty in rows
    /// written before it ([`Row::pass_category`]).
    #[serde(default)]
    pub pass_categories: BTreeMap<String, String>,
    /// Cell index in sweep order.
    pub index: usize,
    /// Cell id (hash of its configuration).
    pub id: String,
    /// UTC time the cell finished (seconds since 1970).
    pub finished_unix: u64,
    /// Why the cell failed, where it did (`cell N `name` failed: ...`): its row then holds its
    /// identity and parameters alone, the report lists it, and a rerun runs it again. Empty
    /// for a cell that ran.
    #[serde(default)]
    pub error: Option<String>,
}

/// A row's parameters: its sweep's (`setting`, `parameters`) and its light range's.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SweepColumns {
    /// The `setting=` label of the sweep's setting the cell is in; empty outside settings.
    #[serde(default)]
    pub setting: String,
    /// The radius rule's value: the fixed radius, the cut-off threshold, stochastic culling's
    /// error bound, or the hierarchy's alpha (`radius_rule` says which).
    #[serde(default)]
    pub radius_value: Option<f64>,
    /// `radius: Hierarchy`: the finest grid's spacing, m.
    #[serde(default)]
    pub hierarchy_spacing: Option<f64>,
    /// `radius: Hierarchy`: the most nodes the finest grid may hold a point light.
    #[serde(default)]
    pub hierarchy_finest_nodes: Option<f64>,
    /// `radius: Hierarchy`: how much farther each level's band ends than the level below's.
    #[serde(default)]
    pub hierarchy_growth: Option<f64>,
    /// `radius: Hierarchy`: how far each level hands over to the next.
    #[serde(default)]
    pub hierarchy_ramp: Option<f64>,
    /// `radius: Hierarchy`: the first level whose bands are sampled; empty for none.
    #[serde(default)]
    pub hierarchy_sample_from: Option<u32>,
    /// `radius: Hierarchy`: cells along each side of the octahedral map of the spots' axes
    /// (their direction bins).
    #[serde(default)]
    pub hierarchy_spot_bins: Option<u32>,
    /// Stochastic cells: what the error bounds (`light` or `albedo`).
    #[serde(default)]
    pub stochastic_bound: Option<String>,
    /// Stochastic cells: how a frame's numbers are drawn (`stratified` or `independent`).
    #[serde(default)]
    pub stochastic_draw: Option<String>,
    /// Stochastic cells: the side of the interleaved pixel classes (1: none).
    #[serde(default)]
    pub interleave: Option<u32>,
    /// Stochastic cells: the exposure the error bound is taken at.
    #[serde(default)]
    pub stochastic_exposure: Option<f64>,
    /// The cell's swept parameters: each axis's name and the value's (`setting`, `scene`,
    /// `lights`, `threshold`, `strategy`, `variant`, ...), what its name is made of. JSON only.
    #[serde(default)]
    pub parameters: BTreeMap<String, String>,
}

/// A row's shadow columns: what the cell cast and what its image is worth against the light as
/// it arrives, shadowed.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ShadowColumns {
    /// The cell's `shadows`: `off` or `exact`.
    #[serde(default)]
    pub shadows: String,
    /// Mean FLIP against the shadowed infinite-range reference (a shadow ray from every covered
    /// pixel to every light that adds radiance there), both images tonemapped at the exposure
    /// adapted to it; stochastic cells: the mean over seeds. Unshadowed cells are scored
    /// against it too (with `shadowed_reference`): what light leaking through walls costs.
    /// Empty where it was not rendered.
    #[serde(default)]
    pub flip_mean_shadowed: Option<f64>,
    /// The signed mean relative luminance error over lit pixels against the same reference
    /// (as `energy_error_infinite`): positive where light leaks through walls.
    #[serde(default)]
    pub energy_error_shadowed: Option<f64>,
    /// Shadow rays the frame casts per covered pixel (counted on the GPU in a frame of its
    /// own, `manylights_gpu::GpuScene::count_rays`: one for every (pixel, light) pair the
    /// shading evaluates with a nonzero contribution); the first pose. Empty without shadows.
    #[serde(default)]
    pub rays_per_pixel: Option<f64>,
    /// What the rays cost: `gpu_ms_cull_shade` less the same culling and shading without
    /// shadow rays, timed back to back in the same cell, ms. Empty without shadows, for naive
    /// forward, and where it was not timed.
    #[serde(default)]
    pub gpu_ms_shadow: Option<f64>,
    /// Shadow rays a second the frame traces, billions: the frame's rays over
    /// `gpu_ms_shadow`.
    #[serde(default)]
    pub grays_per_s: Option<f64>,
    /// Whether the shadowed infinite-range reference came from the run folder's cache.
    #[serde(default)]
    pub reference_shadowed_cached: Option<bool>,
    /// Where the shadowed infinite-range reference is an estimate (`shadowed_reference_rays`):
    /// its standard error in mean FLIP, half the mean FLIP between the means of its two pairs
    /// of estimates (for small errors the FLIP of the mean of four against the truth); the
    /// worst pose's. Empty where it is exact or not rendered.
    #[serde(default)]
    pub shadowed_reference_se: Option<f64>,
    /// (Bin, light) pairs culling by visibility dropped from the lists
    /// (`manylights_cull::CullOutput::occluded`), the first pose. Empty without `occlusion`.
    #[serde(default)]
    pub occluded_pairs: Option<u64>,
}

impl Row {
    /// The category of the pass `label`: `pass_categories`', or in rows written before it
    /// the one its name implied then.
    pub fn pass_category(&self, label: &str) -> Option<Category> {
        match self.pass_categories.get(label) {
            Some(name) => Category::from_name(name),
            None => Some(crate::old_rows::category_before_plans(label)),
        }
    }

    /// The whole frame in steady state, a hierarchy's build included, ms:
    /// `gpu_ms_frame_build_steady` where it was timed, else `gpu_ms_frame_steady` plus
    /// [`Row::hierarchy_build_ms`].
    pub fn frame_with_build_ms(&self) -> Option<f64> {
        self.gpu_ms_frame_build_steady.or_else(|| {
            self.gpu_ms_frame_steady
                .map(|t| t + self.hierarchy_build_ms().unwrap_or(0.0))
        })
    }

    /// The hierarchy's build a frame pays, ms: `gpu_ms_hierarchy_steady` where it was timed,
    /// else `gpu_ms_hierarchy`; `None` without a hierarchy.
    pub fn hierarchy_build_ms(&self) -> Option<f64> {
        self.gpu_ms_hierarchy_steady.or(self.gpu_ms_hierarchy)
    }

    /// The lights of the setting the cell belongs to: the scene's (`scene_lights`) where the
    /// cell shades a hierarchy's nodes in their place, else `lights`.
    pub fn setting_lights(&self) -> u64 {
        self.scene_lights.unwrap_or(self.lights)
    }
}

/// The rows in the experiment file's order: a cell's index is its place in the file's sweep
/// (a cell run from another file of the same configurations, such as a part of the sweep
/// moved to a run of its own, keeps its id, not its index). Rows of no cell of the file keep
/// theirs.
pub fn in_experiment_order(exp: &crate::Experiment, rows: &mut [Row]) {
    let index: BTreeMap<String, usize> =
        exp.cells().into_iter().map(|c| (c.id(), c.index)).collect();
    for r in rows.iter_mut() {
        if let Some(i) = index.get(&r.id) {
            r.index = *i;
        }
    }
    rows.sort_by_key(|r| r.index);
}

/// JSON has no infinity: an infinite PSNR (identical images) is written as the string "inf",
/// and read back from it; null stays "not measured".
mod inf_f64 {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
        match v {
            Some(x) if x.is_infinite() => s.serialize_str(if *x > 0.0 { "inf" } else { "-inf" }),
            Some(x) => s.serialize_f64(*x),
            None => s.serialize_none(),
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum V {
            Num(f64),
            Text(String),
        }
        Ok(match Option::<V>::deserialize(d)? {
            None => None,
            Some(V::Num(x)) => Some(x),
            Some(V::Text(t)) => Some(match t.as_str() {
                "inf" => f64::INFINITY,
                "-inf" => f64::NEG_INFINITY,
                other => return Err(serde::de::Error::custom(format!("not a number: {other}"))),
            }),
        })
    }
}

fn one() -> u32 {
    1
}

impl Row {
    /// A row of nothing measured: `identity`'s columns (a JSON object: at least the cell's
    /// experiment, name, scene, lights, size, strategy, backend, params, adapter, driver,
    /// commit, exact_stride, frames, index, id and finished_unix), every measurement empty (0
    /// where a column is a plain number), the rest at their defaults.
    pub(crate) fn unmeasured(identity: serde_json::Value) -> Row {
        let mut v = serde_json::json!({
            "gpu_ms_total": null, "gpu_ms_cull": null, "gpu_ms_shade": null,
            "gpu_ms_prepass": null, "cpu_ms_encode": 0.0, "false_negatives": null,
            "false_positive_ratio": null, "lights_per_pixel_mean": null,
            "max_lights_per_tile": null, "dropped_lights": 0, "list_bytes": 0, "gbuffer_bytes": 0,
            "psnr_db": null, "flip_mean": null, "max_abs_error": null,
            "gpu_ms_total_p10": null, "gpu_ms_total_p90": null,
            "gpu_ms_cull_p10": null, "gpu_ms_cull_p90": null, "gpu_ms_shade_p10": null,
            "gpu_ms_shade_p90": null, "gpu_ms_prepass_p10": null, "gpu_ms_prepass_p90": null,
            "gpu_ms_raster": null, "gpu_ms_compute": null, "psnr_db_infinite": null,
            "flip_mean_infinite": null, "max_abs_error_infinite": null, "passes": {},
        });
        v.as_object_mut()
            .expect("an object")
            .extend(identity.as_object().expect("identity is an object").clone());
        serde_json::from_value(v).expect("an unmeasured row's columns")
    }
}

/// Median, p10 and p90 (nearest rank) of `v`.
pub fn percentiles(v: &[f64]) -> Option<(f64, f64, f64)> {
    if v.is_empty() {
        return None;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    // `+ 0.0` turns the -0.0 of an empty sum into 0.0.
    let at = |q: f64| s[((q * (s.len() - 1) as f64).round() as usize).min(s.len() - 1)] + 0.0;
    Some((at(0.5), at(0.1), at(0.9)))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::{Row, in_experiment_order};
    use std::path::Path;

    /// A row with every column the JSON requires, the rest at their defaults.
    pub(crate) fn sample_row() -> Row {
        Row::unmeasured(serde_json::json!({
            "experiment": "e", "cell": "", "scene": "s", "lights": 1, "width": 1, "height": 1,
            "strategy": "x", "backend": "forward", "params": "", "adapter": "", "driver": "",
            "commit": "", "exact_stride": 1, "frames": 1, "index": 0, "id": "",
            "finished_unix": 0,
        }))
    }

    #[test]
    fn rows_take_their_place_in_the_experiment_file() {
        let exp = crate::Experiment::parse(
            r#"Experiment(name: "e", config: Config(scene: Atrium(), lights: (count: 64), resolution: (16, 8)), sweep: (radius: [Threshold(1.0), Threshold(0.1), Threshold(0.01)]))"#,
            Path::new("e.ron"),
        )
        .unwrap();
        let cells = exp.cells();
        // Rows run from other files: right ids, wrong indices; and one of no cell of the file.
        let mut rows: Vec<Row> = cells
            .iter()
            .rev()
            .enumerate()
            .map(|(i, c)| {
                let mut r = sample_row();
                r.id = c.id();
                r.cell = c.name.clone();
                r.index = i;
                r
            })
            .collect();
        let mut stray = sample_row();
        stray.id = "elsewhere".into();
        stray.index = 7;
        rows.push(stray);
        in_experiment_order(&exp, &mut rows);
        let names: Vec<&str> = rows.iter().map(|r| r.cell.as_str()).collect();
        assert_eq!(
            names[..3],
            ["threshold=1", "threshold=0.1", "threshold=0.01"]
        );
        assert_eq!(
            rows.iter().map(|r| r.index).collect::<Vec<_>>(),
            [0, 1, 2, 7]
        );
    }
}
