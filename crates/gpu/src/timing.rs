//! Per-pass GPU timing with timestamp queries written at pass boundaries.
//!
//! Each timed pass gets a begin and an end query; [`GpuTimer::resolve`] copies them into a
//! buffer in the same encoder, and [`GpuTimer::read`] turns them into milliseconds with the
//! queue's timestamp period. A query set holds at most 4,096 queries (2,048 passes); callers that
//! time more passes use several timers. Where the adapter has no timestamp queries the timer
//! records nothing and [`GpuTimer::read`] says so, so that no result ever shows a made-up time.

use crate::{GpuContext, GpuError, readback};

/// Whether a pass runs on the raster pipeline or as compute. Reported apart, because compute
/// chips such as the H100 rasterise slowly relative to their compute throughput.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PassKind {
    /// A render pass (vertex/fragment work).
    Raster,
    /// A compute pass.
    Compute,
}

impl PassKind {
    /// `raster` or `compute`.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Raster => "raster",
            Self::Compute => "compute",
        }
    }
}

/// One timed pass.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTiming {
    /// Profiler scope name, such as `prepass.depth` or `shade.reference`.
    pub label: String,
    /// Raster or compute.
    pub kind: PassKind,
    /// GPU time in milliseconds.
    pub ms: f64,
}

/// Most queries one set may hold (a WebGPU limit).
pub const MAX_QUERIES: u32 = 4096;

/// Timestamp queries for up to `capacity` passes of one submission.
pub struct GpuTimer {
    set: Option<wgpu::QuerySet>,
    resolve: Option<wgpu::Buffer>,
    passes: Vec<(String, PassKind)>,
    capacity: u32,
}

impl GpuTimer {
    /// A timer for up to `capacity` passes (at most [`MAX_QUERIES`] / 2).
    pub fn new(ctx: &GpuContext, capacity: u32) -> Self {
        let capacity = capacity.clamp(1, MAX_QUERIES / 2);
        if !ctx.features.timestamps {
            return Self {
                set: None,
                resolve: None,
                passes: Vec::new(),
                capacity,
            };
        }
        let set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("timer"),
            ty: wgpu::QueryType::Timestamp,
            count: capacity * 2,
        });
        let resolve = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timer.resolve"),
            size: u64::from(capacity) * 16,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Self {
            set: Some(set),
            resolve: Some(resolve),
            passes: Vec::new(),
            capacity,
        }
    }

    /// Whether this timer records anything.
    pub fn enabled(&self) -> bool {
        self.set.is_some()
    }

    fn next(&mut self, label: &str, kind: PassKind) -> Option<(&wgpu::QuerySet, u32)> {
        let set = self.set.as_ref()?;
        let i = self.passes.len() as u32;
        assert!(
            i < self.capacity,
            "GpuTimer: more than {} passes in one timer",
            self.capacity
        );
        self.passes.push((label.to_owned(), kind));
        Some((set, i * 2))
    }

    /// Timestamp writes for a render pass named `label`.
    pub fn render_pass(&mut self, label: &str) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        self.next(label, PassKind::Raster)
            .map(|(query_set, q)| wgpu::RenderPassTimestampWrites {
                query_set,
                beginning_of_pass_write_index: Some(q),
                end_of_pass_write_index: Some(q + 1),
            })
    }

    /// Timestamp writes for a compute pass named `label`.
    pub fn compute_pass(&mut self, label: &str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.next(label, PassKind::Compute)
            .map(|(query_set, q)| wgpu::ComputePassTimestampWrites {
                query_set,
                beginning_of_pass_write_index: Some(q),
                end_of_pass_write_index: Some(q + 1),
            })
    }

    /// Resolves the queries written so far; call once, at the end of the encoder.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        if let (Some(set), Some(buf)) = (&self.set, &self.resolve) {
            let n = self.passes.len() as u32 * 2;
            if n > 0 {
                encoder.resolve_query_set(set, 0..n, buf, 0);
            }
        }
    }

    /// Reads the timings back after the submission finished. `Ok(None)` when the adapter has no
    /// timestamp queries.
    pub fn read(&self, ctx: &GpuContext) -> Result<Option<Vec<PassTiming>>, GpuError> {
        let Some(buf) = &self.resolve else {
            return Ok(None);
        };
        if self.passes.is_empty() {
            return Ok(Some(Vec::new()));
        }
        let bytes = readback::read_buffer(ctx, buf, 0, self.passes.len() as u64 * 16)?;
        let ticks: &[u64] = bytemuck::cast_slice(&bytes);
        let period = f64::from(ctx.queue.get_timestamp_period());
        Ok(Some(
            self.passes
                .iter()
                .enumerate()
                .map(|(i, (label, kind))| {
                    let dt = ticks[2 * i + 1].wrapping_sub(ticks[2 * i]);
                    PassTiming {
                        label: label.clone(),
                        kind: *kind,
                        ms: dt as f64 * period * 1e-6,
                    }
                })
                .collect(),
        ))
    }
}
