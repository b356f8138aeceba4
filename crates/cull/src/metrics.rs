//! The exact per-pixel oracle and the list metrics of every configuration.
//!
//! The *exact set* of a covered pixel is the lights with a non-zero contribution at its surface
//! point ([`manylights_scene::Light::reaches`]: inside the radius and, for a spot, strictly
//! inside the outer cone). The surface point is the one culling sees: reconstructed in f64 from
//! the pixel centre and the depth buffer value through the inverse of `clip_from_world`.
//! (Forward shading evaluates the interpolated vertex position instead, which differs by the
//! depth buffer's quantisation; that difference shows in the image metrics against the
//! reference, not here.)

use glam::{DMat4, DVec3, DVec4};
use manylights_gpu::layout::GpuFrame;
use manylights_scene::Light;

use crate::BinLists;
use crate::geometry::bin_of;
use crate::layout::GpuCullParams;

/// The metrics of one set of lists against the exact per-pixel sets.
#[derive(Clone, Debug, PartialEq)]
pub struct ListMetrics {
    /// Covered pixels (with MSAA, from the GPU oracle: covered samples; the means are per
    /// covered sample then, and false negatives are (sample, light) pairs).
    pub covered_pixels: u64,
    /// (pixel, light) pairs in a pixel's exact set but missing from its list. A conservative
    /// method must have 0.
    pub false_negatives: u64,
    /// Sum over covered pixels of the list lengths (lights evaluated).
    pub evaluated: u64,
    /// Sum over covered pixels of the exact set sizes (lights needed).
    pub needed: u64,
    /// `evaluated / needed` (1.0 is perfect); `None` when no pixel needs a light.
    pub false_positive_ratio: Option<f64>,
    /// Mean list length over covered pixels.
    pub lights_per_pixel_mean: f64,
    /// Mean exact set size over covered pixels: the lights a pixel needs.
    pub lights_needed_per_pixel_mean: f64,
    /// Longest list of any bin.
    pub max_lights_per_bin: u32,
    /// Histogram of list lengths over bins: bucket 0 holds empty lists, bucket k >= 1 lengths
    /// in [2^(k-1), 2^k).
    pub histogram: Vec<u64>,
    /// Lights dropped by a capacity (none of the current strategies has one).
    pub dropped_lights: u64,
}

/// World-space surface points of every pixel (None for background), in f64.
pub fn surface_points(frame: &GpuFrame, depth: &[f32], w: u32, h: u32) -> Vec<Option<DVec3>> {
    let world_from_clip: DMat4 = frame.clip_from_world.as_dmat4().inverse();
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let z = depth[(y * w + x) as usize];
            (z < 1.0).then(|| {
                let ndc = DVec4::new(
                    (f64::from(x) + 0.5) / f64::from(w) * 2.0 - 1.0,
                    1.0 - (f64::from(y) + 0.5) / f64::from(h) * 2.0,
                    f64::from(z),
                    1.0,
                );
                let p = world_from_clip * ndc;
                p.truncate() / p.w
            })
        })
        .collect()
}

/// The exact set of every pixel (None for background).
pub fn exact_sets(points: &[Option<DVec3>], lights: &[Light]) -> Vec<Option<Vec<u32>>> {
    points
        .iter()
        .map(|p| {
            p.map(|p| {
                (0..lights.len() as u32)
                    .filter(|&i| lights[i as usize].reaches(p))
                    .collect()
            })
        })
        .collect()
}

/// Compares `lists` with the exact sets: every pixel looks up its bin as the shaders do.
pub fn evaluate(
    frame: &GpuFrame,
    params: &GpuCullParams,
    depth: &[f32],
    w: u32,
    h: u32,
    exact: &[Option<Vec<u32>>],
    lists: &BinLists,
) -> ListMetrics {
    let sorted: Vec<Vec<u32>> = (0..lists.ranges.len()).map(|b| lists.sorted(b)).collect();
    let pixels = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter_map(|(x, y)| {
            let i = (y * w + x) as usize;
            let ex = exact[i].as_ref()?;
            let list = &sorted[bin_of(frame, params, [x, y], depth[i]) as usize];
            let missing = ex.iter().filter(|l| list.binary_search(l).is_err()).count() as u64;
            Some((list.len() as u64, ex.len() as u64, missing))
        });
    ListMetrics::from_pixels(pixels, lists.ranges.iter().map(|r| r[1]))
}

/// The same metrics from the GPU exact oracle's per-pixel `[evaluated, needed, found, covered]`
/// (`Culler::exact_counts`) and every bin's list length (`CullOutput::bin_lengths`).
pub fn from_gpu_counts(counts: &[[u32; 4]], bin_lengths: &[u32]) -> ListMetrics {
    let pixels = counts.iter().filter(|c| c[3] != 0).map(|c| {
        (
            u64::from(c[0]),
            u64::from(c[1]),
            u64::from(c[1] - c[2].min(c[1])),
        )
    });
    let mut m = ListMetrics::from_pixels(pixels, bin_lengths.iter().copied());
    // With MSAA a pixel's counts are sums over its covered samples (the fourth word says how
    // many): the means are per covered sample.
    let samples: u64 = counts.iter().map(|c| u64::from(c[3])).sum();
    if samples != m.covered_pixels && samples > 0 {
        m.covered_pixels = samples;
        m.lights_per_pixel_mean = m.evaluated as f64 / samples as f64;
        m.lights_needed_per_pixel_mean = m.needed as f64 / samples as f64;
    }
    m
}

impl ListMetrics {
    /// From per covered pixel (evaluated, needed, missing) and per bin list lengths.
    pub fn from_pixels(
        pixels: impl Iterator<Item = (u64, u64, u64)>,
        bin_lengths: impl Iterator<Item = u32>,
    ) -> Self {
        let mut m = ListMetrics {
            covered_pixels: 0,
            false_negatives: 0,
            evaluated: 0,
            needed: 0,
            false_positive_ratio: None,
            lights_per_pixel_mean: 0.0,
            lights_needed_per_pixel_mean: 0.0,
            max_lights_per_bin: 0,
            histogram: Vec::new(),
            dropped_lights: 0,
        };
        for (evaluated, needed, missing) in pixels {
            m.covered_pixels += 1;
            m.evaluated += evaluated;
            m.needed += needed;
            m.false_negatives += missing;
        }
        if m.needed > 0 {
            m.false_positive_ratio = Some(m.evaluated as f64 / m.needed as f64);
        }
        if m.covered_pixels > 0 {
            m.lights_per_pixel_mean = m.evaluated as f64 / m.covered_pixels as f64;
            m.lights_needed_per_pixel_mean = m.needed as f64 / m.covered_pixels as f64;
        }
        for n in bin_lengths {
            m.max_lights_per_bin = m.max_lights_per_bin.max(n);
            let bucket = if n == 0 {
                0
            } else {
                (32 - n.leading_zeros()) as usize
            };
            if m.histogram.len() <= bucket {
                m.histogram.resize(bucket + 1, 0);
            }
            m.histogram[bucket] += 1;
        }
        m
    }
}
