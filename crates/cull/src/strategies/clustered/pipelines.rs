//! The clusters' pipelines, built once from their program (`shaders/cull/clustered/`).

use crate::Kernel;
use crate::program::Program;

/// The clusters' pipelines.
pub(crate) struct Pipelines {
    /// The per-light passes, without the cells and (`CLUSTER_CELLS`) with them: a constant of
    /// each pipeline, so that the clusters without cells run the code they ran before them
    /// (testing the flag at every (light, cluster) took 1.2% longer a frame at 1M lights).
    pub(super) per_light: [PerLight; 2],
    pub(super) wide_args: Kernel,
    /// `cull.clustered.scatter`: the held pairs into their lists.
    pub(super) scatter: Kernel,
    pub(super) order: Kernel,
    /// `cull.clustered.order`'s lists by the bitmap's rank sort, run in its place with
    /// `CULL_FLAG_ORDER_BITS`.
    pub(super) order_bits: Kernel,
    pub(super) order_short: Kernel,
    pub(super) order_lists: Kernel,
    pub(super) order_args: Kernel,
    pub(super) occupancy: Kernel,
    pub(super) light_rects: Kernel,
    pub(super) boxes: Kernel,
    /// `cull.clustered.cells`: each cluster's 2.5D cells (`Strategy::Clustered::cells`).
    pub(super) cells: Kernel,
    pub(super) tiles_count: Kernel,
    /// The same, reading `cull.clustered.rects`' rectangles (`CLUSTER_TILE_RECTS`).
    pub(super) tiles_count_rects: Kernel,
    pub(super) masks_fill: Kernel,
    /// The same, its ranges from a cursor (`CLUSTER_FILL_CURSOR`: no scan).
    pub(super) masks_fill_cursor: Kernel,
}

/// `cull.clustered.count`, `.fill`, `.count_wide` and `.fill_wide`.
pub(crate) struct PerLight {
    pub(super) count: Kernel,
    pub(super) fill: Kernel,
    pub(super) count_wide: Kernel,
    pub(super) fill_wide: Kernel,
    /// The count passes holding their pairs for `cull.clustered.scatter` (`CLUSTER_PAIRS`).
    pub(super) count_pairs: Kernel,
    pub(super) count_wide_pairs: Kernel,
}

impl PerLight {
    fn new(d: &wgpu::Device, program: &Program, cells: bool) -> Self {
        let constants = [("CLUSTER_CELLS", f64::from(u8::from(cells)))];
        let [count, fill, count_wide, fill_wide] = [
            "clustered_count",
            "clustered_fill",
            "clustered_count_wide",
            "clustered_fill_wide",
        ]
        .map(|e| program.pipeline_with(d, e, &constants));
        let held = [constants[0], ("CLUSTER_PAIRS", 1.0)];
        let [count_pairs, count_wide_pairs] =
            ["clustered_count", "clustered_count_wide"].map(|e| program.pipeline_with(d, e, &held));
        Self {
            count,
            fill,
            count_wide,
            fill_wide,
            count_pairs,
            count_wide_pairs,
        }
    }
}

impl Pipelines {
    /// From the clusters' program.
    pub fn new(d: &wgpu::Device, program: &Program) -> Self {
        let [
            wide_args,
            order_short,
            order_lists,
            order_args,
            occupancy,
            light_rects,
            boxes,
            cells,
            tiles_count,
            masks_fill,
            scatter,
        ] = program.pipelines(
            d,
            [
                "clustered_wide_args",
                "cluster_order_short",
                "cluster_order_lists",
                "cluster_order_args",
                "cluster_occupancy",
                "cluster_light_rects",
                "cluster_boxes",
                "cluster_cells",
                "cluster_tiles_count",
                "cluster_masks_fill",
                "clustered_scatter",
            ],
        );
        Self {
            per_light: [false, true].map(|cells| PerLight::new(d, program, cells)),
            wide_args,
            scatter,
            order_short,
            order_lists,
            order_args,
            occupancy,
            light_rects,
            boxes,
            cells,
            tiles_count,
            tiles_count_rects: program.pipeline_with(
                d,
                "cluster_tiles_count",
                &[("CLUSTER_TILE_RECTS", 1.0)],
            ),
            masks_fill,
            order: order_pipeline(d, program, "cluster_order"),
            order_bits: order_pipeline(d, program, "cluster_order_bits"),
            masks_fill_cursor: program.pipeline_with(
                d,
                "cluster_masks_fill",
                &[("CLUSTER_FILL_CURSOR", 1.0)],
            ),
        }
    }
}

/// A long lists' order pass, with [`order_threads`] threads.
fn order_pipeline(d: &wgpu::Device, program: &Program, entry: &'static str) -> Kernel {
    program.pipeline_with(d, entry, &[("ORDER_THREADS", f64::from(order_threads(d)))])
}

/// The threads of the long lists' order pass (`cull.clustered.order`): 512 where the device
/// allows a workgroup that many, else 256.
fn order_threads(d: &wgpu::Device) -> u32 {
    if d.limits().max_compute_invocations_per_workgroup >= 512
        && d.limits().max_compute_workgroup_size_x >= 512
    {
        512
    } else {
        256
    }
}
