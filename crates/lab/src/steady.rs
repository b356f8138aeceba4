//! Culling timed in steady state, as the benches time it: runs back to back in one submission
//! (`Culler::run_repeated`, sized from an earlier run and checked against it), each pass's and
//! each run's median, and the median span (one timestamp pair around each run's passes, so
//! clears and the gaps between dependent passes count). `manylights cull --repeat` prints it;
//! experiments write its run median and span as `gpu_ms_cull_steady` and `gpu_ms_cull_span`.
//!
//! A single run (a frame of an experiment, `gpu_ms_cull`) also times what sizes its lists: the
//! count pass and the read-back between its two submissions. Back to back, the lists are
//! already sized and gather's lines path runs two passes, not three.
//!
//! The geometry of a frame (its depth prepass or G-buffer pass and lookup bounds) is timed the
//! same way ([`steady_geometry`]): with culling and shading back to back, the frame at the
//! clock the GPU runs at under load, where a frame of the experiments' loop (rendered, read
//! back and checked one at a time) leaves the GPU idle long enough for its clock to fall.
//!
//! The runs are repeated untimed for [`WARM_UP`] first (not on a CPU adapter), so that they
//! are timed at the clock the GPU runs at under load, not the lower one it falls to while the
//! host works between cells; the timed submission then holds as many runs as the warm-up's
//! last, and the fastest of [`TIMED_TRIES`] timed submissions (and of as many of spans) is
//! kept, since the clock can still be rising after the warm-up. The lighting grid hierarchy's
//! build is timed the same way ([`steady_build`]).

use manylights_cull::{CullError, CullOutput, CullSettings, Culler, ListPass, Strategy};
use manylights_gpu::hierarchy::GpuHierarchy;
use manylights_gpu::timing::{Category, GpuTimer, MAX_QUERIES, PassKind};
use manylights_gpu::{GpuContext, GpuScene};
use manylights_shade::{Renderer, ShadeOutput};

use crate::results::percentiles;

/// Steady-state culling times, ms.
#[derive(Clone, Debug, PartialEq)]
pub struct SteadyCull {
    /// Runs timed.
    pub runs: u32,
    /// Each pass of a run, with its median over the runs.
    pub passes: Vec<PassMedian>,
    /// Median over the runs of the sum of a run's passes.
    pub total_ms: f64,
    /// Median span of a run (one timestamp pair around its passes); `None` where the adapter
    /// cannot write timestamps between passes.
    pub span_ms: Option<f64>,
}

/// How long the runs are repeated, untimed, before the timed ones: long enough for the GPU's
/// clock to rise from idle (DVFS), short next to a cell's other work. Not on a CPU adapter
/// (lavapipe), which has no such clock ([`warm_up`]).
pub const WARM_UP: std::time::Duration = std::time::Duration::from_millis(200);

/// How long a warm-up submission should keep the GPU busy, at the least (its runs double until
/// it does).
const WARM_SUBMIT: std::time::Duration = std::time::Duration::from_millis(20);

/// Timed submissions (and as many of spans) a steady-state measurement takes on a GPU, the
/// fastest kept ([`timed_tries`]).
pub const TIMED_TRIES: u32 = 3;

/// Whether `ctx`'s adapter has a clock that rises under load: not a CPU adapter (lavapipe).
fn clocked(ctx: &GpuContext) -> bool {
    ctx.info.device_type != wgpu::DeviceType::Cpu
}

/// The warm-up on `ctx`'s adapter: [`WARM_UP`], or none on a CPU adapter.
pub fn warm_up(ctx: &GpuContext) -> std::time::Duration {
    if clocked(ctx) {
        WARM_UP
    } else {
        std::time::Duration::ZERO
    }
}

/// The most runs timed back to back in one submission for a strategy whose single run took
/// `passes` passes: as many as one query set holds.
pub fn max_runs(passes: u32) -> u32 {
    MAX_QUERIES / 2 / passes.max(1)
}

/// Why steady-state timing failed.
#[derive(Debug, thiserror::Error)]
pub enum SteadyError {
    /// The culling itself.
    #[error(transparent)]
    Cull(#[from] CullError),
    /// A GPU error reading the timestamps.
    #[error(transparent)]
    Gpu(#[from] manylights_gpu::GpuError),
    /// The timed passes do not split evenly into the runs.
    #[error("{passes} timed passes do not split into {runs} runs")]
    Uneven {
        /// Passes timed.
        passes: usize,
        /// Runs.
        runs: u32,
    },
}

/// The culling run being repeated: its culler, scene, depth, strategy and settings, and the run
/// that sized its lists.
pub struct Repeated<'a> {
    /// The device.
    pub ctx: &'a GpuContext,
    /// The culler.
    pub culler: &'a Culler,
    /// The scene.
    pub scene: &'a GpuScene,
    /// The depth culled over.
    pub depth: &'a wgpu::Texture,
    /// The strategy.
    pub strategy: &'a Strategy,
    /// Its settings.
    pub settings: &'a CullSettings,
    /// The single run whose lists size the repeated runs'.
    pub first: &'a CullOutput,
}

/// `runs` runs (at least 1, at most [`max_runs`] of `passes`, the single run's passes) of
/// the run `r` back to back, sized from its first, timed per pass and then as spans. `None`
/// without timestamp queries.
pub fn steady_cull(
    r: &Repeated<'_>,
    passes: u32,
    runs: u32,
) -> Result<Option<SteadyCull>, SteadyError> {
    steady(r, passes, runs, None)
}

/// As [`steady_cull`], each run followed by `then` (the shading pass that reads its lists,
/// [`manylights_shade::Renderer::shade_pass`]) inside its span: culling and shading timed
/// together as a frame pays them, for `gpu_ms_cull_shade`. `passes` counts the culling passes
/// of a single run and the shading pass.
pub fn steady_cull_shade(
    r: &Repeated<'_>,
    passes: u32,
    runs: u32,
    then: &mut dyn ListPass,
) -> Result<Option<SteadyCull>, SteadyError> {
    steady(r, passes, runs, Some(then))
}

fn steady(
    r: &Repeated<'_>,
    passes: u32,
    runs: u32,
    mut then: Option<&mut dyn ListPass>,
) -> Result<Option<SteadyCull>, SteadyError> {
    let Repeated {
        ctx,
        culler,
        scene,
        depth,
        strategy,
        settings,
        first,
    } = *r;
    let n = runs.clamp(1, max_runs(passes));
    let mut repeat = |timer: &mut GpuTimer, n: u32| -> Result<(), SteadyError> {
        match then.as_deref_mut() {
            Some(pass) => {
                culler.run_repeated_with(
                    ctx, scene, depth, strategy, settings, first, n, timer, pass,
                )?;
            }
            None => {
                culler.run_repeated(ctx, scene, depth, strategy, settings, first, n, timer)?;
            }
        }
        Ok(())
    };
    timed_runs(ctx, passes, n, &mut repeat)
}

/// The geometry of the frame `out` rendered (the depth prepass or the G-buffer pass and the
/// lookup bounds; naive forward: its whole frame), `runs` times back to back
/// ([`Renderer::geometry_repeated`]), as [`steady_cull`] times culling: with
/// `gpu_ms_cull_shade`, the frame in steady state (`gpu_ms_frame_steady`). `passes`: the
/// geometry passes of the single frame. `None` without timestamp queries.
pub fn steady_geometry(
    ctx: &GpuContext,
    renderer: &Renderer,
    scene: &GpuScene,
    out: &ShadeOutput,
    passes: u32,
    runs: u32,
) -> Result<Option<SteadyCull>, SteadyError> {
    let n = runs.clamp(1, max_runs(passes));
    let mut repeat = |timer: &mut GpuTimer, n: u32| -> Result<(), SteadyError> {
        Ok(renderer.geometry_repeated(ctx, scene, out, n, timer)?)
    };
    timed_runs(ctx, passes, n, &mut repeat)
}

/// The lighting grid hierarchy's build (`passes` passes: the points pass and a pass a level)
/// `runs` times back to back ([`GpuHierarchy::build_repeated`]), as [`steady_cull`] times
/// culling: the build as a frame of static lights pays it in steady state, for
/// `gpu_ms_hierarchy_steady`. `None` without timestamp queries.
pub fn steady_build(
    ctx: &GpuContext,
    hierarchy: &GpuHierarchy,
    passes: u32,
    runs: u32,
) -> Result<Option<SteadyCull>, SteadyError> {
    let n = runs.clamp(1, max_runs(passes));
    let mut repeat = |timer: &mut GpuTimer, n: u32| -> Result<(), SteadyError> {
        Ok(hierarchy.build_repeated(ctx, n, timer)?)
    };
    timed_runs(ctx, passes, n, &mut repeat)
}

/// A frame's shading pass followed by the lighting grid hierarchy's build, for
/// [`steady_cull_shade`]: the build timed with the frame, back to back with its culling and
/// shading as an application's frames run them (each run's build writes the lights the next
/// run culls; every build of the same lights is the same hierarchy, so the lists keep their
/// size), for `gpu_ms_frame_build_steady`.
pub struct ThenBuild<'a, P: ListPass> {
    /// The shading pass.
    pub pass: P,
    /// The build after it.
    pub hierarchy: &'a GpuHierarchy,
}

impl<P: ListPass> ListPass for ThenBuild<'_, P> {
    fn bind(
        &mut self,
        ctx: &GpuContext,
        lists: [wgpu::BindingResource<'_>; 3],
        form: manylights_cull::ListForm,
    ) {
        self.pass.bind(ctx, lists, form);
    }

    fn record(&self, enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer) {
        self.pass.record(enc, timer);
        self.hierarchy.encode(enc, timer);
    }

    fn passes(&self) -> u32 {
        self.pass.passes() + self.hierarchy.pass_count()
    }
}

/// `repeat` (`n` runs of `passes` passes each, back to back into the timer it is given)
/// repeated untimed for [`warm_up`], then timed per pass and as spans.
fn timed_runs(
    ctx: &GpuContext,
    passes: u32,
    n: u32,
    repeat: &mut dyn FnMut(&mut GpuTimer, u32) -> Result<(), SteadyError>,
) -> Result<Option<SteadyCull>, SteadyError> {
    // Raise the clock first: the GPU idles while the host works between measurements, and an
    // idle GPU clocks down (an H100 sampled at 465-1,455 MHz between a tuner's cells, 1,980 MHz
    // under load), so that the first passes after the host's work measure slow. The warm-up's
    // submissions double their runs (up to what a timer holds) until one takes WARM_SUBMIT: a
    // submission of a few short runs leaves the GPU idle while the host records and waits, too
    // little load for its clock to rise (an H200 timed culling and lighting at the Forward+
    // configuration at 0.25 ms after ten runs a submission, 0.14 ms as criterion times them).
    let warm = std::time::Instant::now();
    let warm_up = warm_up(ctx);
    let mut busy = n;
    while warm.elapsed() < warm_up {
        let submitted = std::time::Instant::now();
        repeat(&mut GpuTimer::untimed(), busy)?;
        if submitted.elapsed() < WARM_SUBMIT {
            busy = (busy * 2).min(max_runs(passes)).max(busy);
        }
    }
    // The timed submission as long as the warm-up's last: a few short runs alone leave the
    // clock to fall back while the host waits (an H200 timed 5 builds of the 50,000-light
    // hall's hierarchy at 0.26 or 0.99 ms from cell to cell, every pass 3.8 times slower).
    let n = n.max(busy);
    // The fastest of a few timed submissions (and spans): the clock can still be rising after
    // the warm-up (an H200 timed every pass of two of the quickstart's eight cells twice as
    // slow as their neighbours, their spans right after at the neighbours' speed).
    let mut best: Option<Timed> = None;
    let mut span_ms: Option<f64> = None;
    let mut totals = Vec::new();
    for _ in 0..timed_tries(ctx) {
        let Some((run_passes, total_ms)) = timed_once(ctx, passes, n, repeat)? else {
            return Ok(None);
        };
        totals.push(total_ms);
        if best.as_ref().is_none_or(|b| total_ms < b.1) {
            best = Some((run_passes, total_ms));
        }
        if let Some(mut spans) = GpuTimer::spans(ctx, n) {
            repeat(&mut spans, n)?;
            if let Some(t) = spans.read(ctx)? {
                let ms = median(t.iter().map(|p| p.ms).collect());
                span_ms = Some(span_ms.map_or(ms, |s: f64| s.min(ms)));
            }
        }
    }
    let Some((passes, total_ms)) = best else {
        return Ok(None);
    };
    let slowest = totals.iter().copied().fold(total_ms, f64::max);
    if slowest > total_ms * 1.1 {
        tracing::info!(
            "steady timing: timed submissions of {n} runs read {totals:?} ms a run; kept {total_ms}"
        );
    }
    Ok(Some(SteadyCull {
        runs: n,
        passes,
        total_ms,
        span_ms,
    }))
}

/// Timed submissions a steady-state measurement takes, the fastest kept: [`TIMED_TRIES`] on a
/// GPU, one on a CPU adapter (lavapipe), which has no clock to rise.
pub fn timed_tries(ctx: &GpuContext) -> u32 {
    if clocked(ctx) { TIMED_TRIES } else { 1 }
}

/// The experiments' median (nearest rank).
fn median(v: Vec<f64>) -> f64 {
    percentiles(&v).map_or(0.0, |p| p.0)
}

/// A pass of back-to-back runs: what it is and its median time over the runs.
#[derive(Clone, Debug, PartialEq)]
pub struct PassMedian {
    /// Its name.
    pub label: String,
    /// Raster or compute.
    pub kind: PassKind,
    /// The part of the frame it belongs to.
    pub category: Category,
    /// Its median over the runs, ms.
    pub ms: f64,
}

/// A timed submission's passes and its median run, ms.
type Timed = (Vec<PassMedian>, f64);

/// One timed submission of `n` runs: each pass's median over the runs and the median run.
/// `None` without timestamp queries.
fn timed_once(
    ctx: &GpuContext,
    passes: u32,
    n: u32,
    repeat: &mut dyn FnMut(&mut GpuTimer, u32) -> Result<(), SteadyError>,
) -> Result<Option<Timed>, SteadyError> {
    let mut timer = GpuTimer::new(ctx, n * passes.max(1));
    repeat(&mut timer, n)?;
    let Some(t) = timer.read(ctx)? else {
        return Ok(None);
    };
    // Passes a run: back to back, a run may take fewer than `first` did.
    let k = t.len() / n as usize;
    if k == 0 || t.len() != k * n as usize {
        return Err(SteadyError::Uneven {
            passes: t.len(),
            runs: n,
        });
    }
    let passes = (0..k)
        .map(|j| {
            let ms = median((0..n as usize).map(|r| t[r * k + j].ms).collect());
            PassMedian {
                label: t[j].label.clone(),
                kind: t[j].kind,
                category: t[j].category,
                ms,
            }
        })
        .collect();
    let total_ms = median(
        (0..n as usize)
            .map(|r| t[r * k..(r + 1) * k].iter().map(|p| p.ms).sum())
            .collect(),
    );
    Ok(Some((passes, total_ms)))
}
