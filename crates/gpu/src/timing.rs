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

/// What part of a frame a pass belongs to: the result columns `gpu_ms_prepass`, `gpu_ms_cull`,
/// `gpu_ms_shade` and `gpu_ms_light_update` sum the passes of each. A pass takes the category
/// its timer holds when it is timed ([`GpuTimer::set_category`]), which the recorder of its
/// plan sets: a frame plan's entry's, culling's, a light update's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Category {
    /// The frame's geometry: a depth prepass, a G-buffer or visibility buffer (raster or
    /// compute), the lookup bounds.
    Prepass,
    /// Culling: the lists from the depth.
    Cull,
    /// Shading, and any pass that is none of the others (a reference's).
    #[default]
    Shade,
    /// Moving the lights, drawing their ranges, building a hierarchy over them.
    LightUpdate,
}

impl Category {
    /// Every category, in a frame's order (the light update first).
    pub const ALL: [Category; 4] = [
        Category::LightUpdate,
        Category::Prepass,
        Category::Cull,
        Category::Shade,
    ];

    /// `prepass`, `cull`, `shade` or `light_update`: the result columns' part of the name.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Prepass => "prepass",
            Self::Cull => "cull",
            Self::Shade => "shade",
            Self::LightUpdate => "light_update",
        }
    }

    /// The category named `name` ([`Category::as_str`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.as_str() == name)
    }
}

/// One timed pass.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTiming {
    /// Profiler scope name, such as `prepass.depth` or `shade.reference`.
    pub label: String,
    /// Raster or compute.
    pub kind: PassKind,
    /// The part of the frame it belongs to.
    pub category: Category,
    /// GPU time in milliseconds.
    pub ms: f64,
}

/// Most queries one set may hold (a WebGPU limit).
pub const MAX_QUERIES: u32 = 4096;

/// Timestamp queries for the passes of one submission.
///
/// The queries live in sets of `capacity` passes (the first made with the timer, at most
/// [`MAX_QUERIES`] / 2 a set); a pass past the last set's room starts another set, so a frame
/// of any number of passes is timed whole.
///
/// A timer made by [`GpuTimer::spans`] times spans of passes instead: no pass writes
/// timestamps, and [`GpuTimer::span_begin`] and [`GpuTimer::span_end`] write one pair between
/// passes around each span. A span also counts what per-pass timestamps leave out: transfers
/// between passes (buffer clears and copies) and the gaps between dependent passes.
pub struct GpuTimer {
    /// Where more sets come from; `None` without timestamp queries.
    device: Option<wgpu::Device>,
    /// Each set of queries and the buffer it resolves into.
    sets: Vec<(wgpu::QuerySet, wgpu::Buffer)>,
    passes: Vec<(String, PassKind, Category)>,
    /// The category of the passes timed from now on.
    category: Category,
    /// Passes a set.
    capacity: u32,
    spans: bool,
    /// The open span's end query: its set and index.
    open: Option<(usize, u32)>,
}

impl GpuTimer {
    /// A timer whose query sets hold `capacity` passes each (at most [`MAX_QUERIES`] / 2).
    pub fn new(ctx: &GpuContext, capacity: u32) -> Self {
        Self {
            device: ctx.features.timestamps.then(|| ctx.device.clone()),
            capacity: capacity.clamp(1, MAX_QUERIES / 2),
            ..Self::untimed()
        }
    }

    /// A timer that times nothing (no queries are made): for passes encoded outside any
    /// measured frame.
    pub fn untimed() -> Self {
        Self {
            device: None,
            sets: Vec::new(),
            passes: Vec::new(),
            category: Category::default(),
            capacity: 1,
            spans: false,
            open: None,
        }
    }

    /// A timer for spans of passes (see [`GpuTimer`]), its query sets of `capacity` spans each;
    /// `None` where the device cannot write timestamps between passes.
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
        if let Some((set, q)) = self.push(label, PassKind::Compute) {
            encoder.write_timestamp(&self.sets[set].0, q);
            self.open = Some((set, q + 1));
        }
    }

    /// Ends the open span, if any.
    pub fn span_end(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let Some((set, q)) = self.open.take() {
            encoder.write_timestamp(&self.sets[set].0, q);
        }
    }

    /// Times the passes (and spans) that follow as `category`, until it is set again; returns
    /// the category it held, for the caller to restore.
    pub fn set_category(&mut self, category: Category) -> Category {
        std::mem::replace(&mut self.category, category)
    }

    /// Whether this timer records anything.
    pub fn enabled(&self) -> bool {
        self.device.is_some()
    }

    /// The set and first query of the next pair, recorded as `label` (a new set where the last
    /// one is full); none without timestamps.
    fn push(&mut self, label: &str, kind: PassKind) -> Option<(usize, u32)> {
        let device = self.device.as_ref()?;
        let i = self.passes.len() as u32;
        let (set, slot) = ((i / self.capacity) as usize, i % self.capacity);
        if set == self.sets.len() {
            let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("timer"),
                ty: wgpu::QueryType::Timestamp,
                count: self.capacity * 2,
            });
            let resolve = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timer.resolve"),
                size: u64::from(self.capacity) * 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            self.sets.push((queries, resolve));
        }
        self.passes.push((label.to_owned(), kind, self.category));
        Some((set, slot * 2))
    }

    /// The next pair of queries for a pass, or none for a pass of a timer of spans.
    fn next(&mut self, label: &str, kind: PassKind) -> Option<(&wgpu::QuerySet, u32)> {
        if self.spans {
            return None;
        }
        let (set, q) = self.push(label, kind)?;
        Some((&self.sets[set].0, q))
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
        let mut left = self.passes.len() as u32;
        for (set, buf) in &self.sets {
            let n = left.min(self.capacity);
            if n > 0 {
                encoder.resolve_query_set(set, 0..n * 2, buf, 0);
            }
            left -= n;
        }
    }

    /// Reads the timings back after the submission finished. `Ok(None)` when the adapter has no
    /// timestamp queries.
    pub fn read(&self, ctx: &GpuContext) -> Result<Option<Vec<PassTiming>>, GpuError> {
        if self.device.is_none() {
            return Ok(None);
        }
        let mut ticks: Vec<u64> = Vec::with_capacity(self.passes.len() * 2);
        let mut left = self.passes.len() as u64;
        for (_, buf) in &self.sets {
            let n = left.min(u64::from(self.capacity));
            if n > 0 {
                let bytes = readback::read_buffer(ctx, buf, 0, n * 16)?;
                ticks.extend_from_slice(bytemuck::cast_slice(&bytes));
            }
            left -= n;
        }
        let period = f64::from(ctx.queue.get_timestamp_period());
        Ok(Some(
            self.passes
                .iter()
                .enumerate()
                .map(|(i, (label, kind, category))| {
                    let dt = ticks[2 * i + 1].wrapping_sub(ticks[2 * i]);
                    PassTiming {
                        label: label.clone(),
                        kind: *kind,
                        category: *category,
                        ms: dt as f64 * period * 1e-6,
                    }
                })
                .collect(),
        ))
    }
}
