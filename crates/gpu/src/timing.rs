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
///
/// A timer made by [`GpuTimer::spans`] times spans of passes instead: no pass writes
/// timestamps, and [`GpuTimer::span_begin`] and [`GpuTimer::span_end`] write one pair between
/// passes around each span. A span also counts what per-pass timestamps leave out: transfers
/// between passes (buffer clears and copies) and the gaps between dependent passes.
pub struct GpuTimer {
    set: Option<wgpu::QuerySet>,
    resolve: Option<wgpu::Buffer>,
    passes: Vec<(String, PassKind)>,
    capacity: u32,
    spans: bool,
    open: Option<u32>,
}

impl GpuTimer {
    /// A timer for up to `capacity` passes (at most [`MAX_QUERIES`] / 2).
    pub fn new(ctx: &GpuContext, capacity: u32) -> Self {
        let capacity = capacity.clamp(1, MAX_QUERIES / 2);
        if !ctx.features.timestamps {
            return Self {
                capacity,
                ..Self::untimed()
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
            spans: false,
            open: None,
        }
    }

    /// A timer that times nothing (no queries are made): for passes encoded outside any
    /// measured frame.
    pub fn untimed() -> Self {
        Self {
            set: None,
            resolve: None,
            passes: Vec::new(),
            capacity: 1,
            spans: false,
            open: None,
        }
    }

    /// A timer for up to `capacity` spans of passes (see [`GpuTimer`]); `None` where the device
    /// cannot write timestamps between passes.
    pub fn spans(ctx: &GpuContext, capacity: u32) -> Option<Self> {
        ctx.features.encoder_timestamps.then(|| Self {
            spans: true,
            ..Self::new(ctx, capacity)
        })
    }

    /// Whether this timer times spans, not passes.
    pub fn times_spans(&self) -> bool {
        self.spans
    }

    /// Starts a span named `label` (a timer of spans only; ends any span still open).
    pub fn span_begin(&mut self, encoder: &mut wgpu::CommandEncoder, label: &str) {
        if !self.spans {
            return;
        }
        self.span_end(encoder);
        if let Some(q) = self.push(label, PassKind::Compute)
            && let Some(set) = &self.set
        {
            encoder.write_timestamp(set, q);
            self.open = Some(q + 1);
        }
    }

    /// Ends the open span, if any.
    pub fn span_end(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let (Some(q), Some(set)) = (self.open.take(), &self.set) {
            encoder.write_timestamp(set, q);
        }
    }

    /// Whether this timer records anything.
    pub fn enabled(&self) -> bool {
        self.set.is_some()
    }

    /// The first of the next pair of queries, recorded as `label`; none without timestamps.
    fn push(&mut self, label: &str, kind: PassKind) -> Option<u32> {
        self.set.as_ref()?;
        let i = self.passes.len() as u32;
        assert!(
            i < self.capacity,
            "GpuTimer: more than {} passes or spans in one timer",
            self.capacity
        );
        self.passes.push((label.to_owned(), kind));
        Some(i * 2)
    }

    /// The next pair of queries for a pass, or none for a pass of a timer of spans.
    fn next(&mut self, label: &str, kind: PassKind) -> Option<(&wgpu::QuerySet, u32)> {
        if self.spans {
            return None;
        }
        let q = self.push(label, kind)?;
        Some((self.set.as_ref()?, q))
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
