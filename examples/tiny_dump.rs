//! Two builds side by side, part 1: runs the tiny variant of every experiment file
//! (`Experiment::tiny`, as the suite's smoke test: 48 x 27 at most, one frame, at most 256
//! lights) with every cell exported (but for experiments with MSAA or glass, which exports
//! cannot hold), into OUT/<file stem>. `compare_dumps` then compares two
//! builds' dumps (docs/bench/frame-as-data-done has the method and a run):
//!
//!     cargo run --release --example tiny_dump -- OUT
//!
//! `DUMP_ONLY=a,b` runs only those files; `DUMP_VIS_RASTER=1` gives the visibility backend the
//! raster pass. An experiment that fails is reported and the rest run.

use std::path::Path;

use manylights_gpu::{GpuContext, GpuOptions};
use manylights_lab::Experiment;
use manylights_lab::runner::{RunOptions, run_parsed};

fn main() {
    let out = std::env::args()
        .nth(1)
        .expect("usage: tiny_dump OUT (a directory for the runs)");
    let ctx = GpuContext::new(&GpuOptions::default()).unwrap_or_else(|e| {
        panic!(
            "needs a Vulkan adapter (lavapipe: apt-get install mesa-vulkan-drivers libvulkan1): {e}"
        )
    });
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    files.sort();
    let only = std::env::var("DUMP_ONLY").ok();
    for path in &files {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        if only
            .as_ref()
            .is_some_and(|o| !o.split(',').any(|x| x == name))
        {
            continue;
        }
        let (e, src) = match Experiment::load(path) {
            Ok(x) => x,
            Err(err) => {
                eprintln!("{name}: load: {err}");
                continue;
            }
        };
        let mut tiny = e.tiny();
        // Exports hold one depth a pixel and no glass: an experiment with MSAA or glass
        // cells is compared by its rows and images alone.
        tiny.config.export = tiny
            .cells()
            .iter()
            .all(|c| c.config.msaa == 1 && !c.config.scene.label().ends_with("+glass"));
        if std::env::var("DUMP_VIS_RASTER").is_ok() {
            tiny.config.visibility_pass = manylights_shade::VisibilityPass::Raster;
        }
        let t = std::time::Instant::now();
        let options = RunOptions {
            commit: "dump".into(),
            ..RunOptions::default()
        };
        let r = run_parsed(
            &ctx,
            &tiny,
            &src,
            &dir,
            &Path::new(&out).join(&name),
            &options,
        );
        eprintln!(
            "{name}: {} in {:.0} s",
            match &r {
                Ok(s) => format!("{} rows", s.rows.len()),
                Err(e) => format!("error {e}"),
            },
            t.elapsed().as_secs_f64()
        );
    }
}
