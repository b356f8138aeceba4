//! What both bench targets share: the quick switch, the device and criterion's sampling.

use std::time::Duration;

use manylights_gpu::{GpuContext, GpuOptions};

/// `MANYLIGHTS_BENCH_QUICK=1` (anything but `0`) shrinks the sizes for a smoke run.
pub fn quick() -> bool {
    std::env::var("MANYLIGHTS_BENCH_QUICK").is_ok_and(|v| v != "0")
}

/// The default adapter, printed, or a panic saying the benchmarks need one.
pub fn gpu() -> GpuContext {
    let ctx = GpuContext::new(&GpuOptions::default())
        .unwrap_or_else(|e| panic!("these benchmarks need a Vulkan adapter: {e}"));
    eprintln!("adapter: {}", ctx.summary());
    ctx
}

/// Flat sampling: ten samples of equal iteration counts, so the slowest cases (a million
/// lights at 4K) need ten iterations, not the fifty-five of linear sampling.
pub fn configure(g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>) {
    g.sample_size(10)
        .sampling_mode(criterion::SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
}
