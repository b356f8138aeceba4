//! Experiments: the shipped files, tiny runs of each, durable and sharded runs, bad input, and
//! the HTML report in a headless browser.

#[path = "../common/mod.rs"]
mod common;
mod hierarchy;
mod msaa;
mod report;
mod shipped;
mod shadows;
mod stochastic;

use std::path::{Path, PathBuf};
use std::process::Command;

use manylights_lab::runner::{RunOptions, run_parsed};
use manylights_lab::{Experiment, Row};

fn shipped(name: &str) -> (Experiment, String, PathBuf) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("experiments")
        .join(format!("{name}.ron"));
    let (e, src) = Experiment::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    (e, src, path)
}

fn opts() -> RunOptions {
    RunOptions {
        commit: "test".into(),
        ..RunOptions::default()
    }
}

/// The annotated example in docs/EXPERIMENTS.md is a valid experiment with the values it shows.
#[test]
fn the_documented_example_parses() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/EXPERIMENTS.md");
    let doc = std::fs::read_to_string(&path).unwrap();
    let start = doc.find("```ron\n").expect("a ```ron block") + "```ron\n".len();
    let len = doc[start..].find("```").expect("the block's end");
    let e = Experiment::parse(&doc[start..start + len], &path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(e.config.capacity, Some(64));
    assert_eq!(e.config.mask_budget, Some(0));
    assert!(e.config.tile_boxes);
    let variants = e.sweep.variants.as_ref().unwrap();
    assert_eq!(variants[2].mask_budget, Some(0));
    assert_eq!(variants[3].tile_boxes, Some(false));
    let moving = &variants[4];
    assert_eq!(variants[5].msaa, Some(4));
    assert_eq!(e.config.msaa, 1);
    assert_eq!(moving.motion, Some(manylights_scene::Motion::Orbit(2.0)));
    assert_eq!(
        moving.light_update,
        Some(manylights_lab::experiment::LightUpdate::Upload)
    );
    assert_eq!(e.config.lights.motion, manylights_scene::Motion::Static);
    // Light counts x strategies x variants.
    let cells = e.cells();
    assert_eq!(cells.len(), 2 * 2 * 6);
    assert!(cells.iter().any(|c| c.name.contains("orbit+upload")
        && c.config.lights.motion == manylights_scene::Motion::Orbit(2.0)));
    assert!(
        cells
            .iter()
            .any(|c| !c.config.tile_boxes && c.name.contains("planes"))
    );
}

/// Every RON block of the docs and the README parses: a block fenced as `ron` as a whole
/// experiment; one fenced as `ron field=NAME` as the value of config field NAME, in an
/// experiment of its own. (The docs once showed a camera as `Pose((position: ...))`, which the
/// parser rejects.)
#[test]
fn every_documented_ron_example_parses() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![root.join("README.md")];
    for e in std::fs::read_dir(root.join("docs")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            files.push(p);
        }
    }
    let mut parsed = 0;
    for path in files {
        let doc = std::fs::read_to_string(&path).unwrap();
        let mut lines = doc.lines().enumerate();
        while let Some((at, line)) = lines.next() {
            let Some(info) = line.trim_start().strip_prefix("```ron") else {
                continue;
            };
            let block: Vec<&str> = lines
                .by_ref()
                .map(|(_, l)| l)
                .take_while(|l| !l.trim_start().starts_with("```"))
                .collect();
            let body = block.join("\n");
            let what = format!("{}:{}", path.display(), at + 1);
            let src = match info.trim().strip_prefix("field=") {
                Some("scene") => {
                    format!("Experiment(name: \"doc\", config: Config(scene: {body}))")
                }
                Some(field) => format!(
                    "Experiment(name: \"doc\", config: Config(scene: Pillars(), {field}: {body}))"
                ),
                None => {
                    assert!(info.trim().is_empty(), "{what}: unknown fence `ron{info}`");
                    body
                }
            };
            Experiment::parse(&src, &path).unwrap_or_else(|e| panic!("{what}: {e}\n{src}"));
            parsed += 1;
        }
    }
    assert!(parsed >= 19, "only {parsed} RON blocks found");
}

/// The tile-mask budget as an experiment parameter: swept over the default and 0 for gather,
/// 2.5D and tiled scatter, the `tile_masks` column says which cells used masks (the default
/// budget at this size: all three; 0: none), their lists are the same (the list metrics equal,
/// no false negatives), and `params` names the budget where one is set.
#[test]
fn mask_budget_sweeps_tile_masks_on_and_off_with_the_same_lists() {
    let ctx = common::gpu();
    let tmp = tempfile::tempdir().unwrap();
    let src = r#"Experiment(
        name: "masks",
        config: Config(
            scene: Atrium(bays: 2),
            lights: (generator: Uniform, count: 96, seed: 5, radius: Fixed(1.5)),
            resolution: (64, 40),
            frames: 1,
            warmup: 0,
            accuracy: false,
        ),
        sweep: (
            strategy: [TiledGather(tile_size: 8), DepthMask(tile_size: 8), TiledScatter(tile_size: 8)],
            mask_budget: [None, Some(0)],
        ),
    )"#;
    let path = tmp.path().join("masks.ron");
    let e = Experiment::parse(src, &path).unwrap();
    assert_eq!(e.cells().len(), 6);
    let s = run_parsed(&ctx, &e, src, tmp.path(), &tmp.path().join("out"), &opts()).unwrap();
    assert_eq!(s.rows.len(), 6);
    for pair in s.rows.chunks(2) {
        let (on, off) = (&pair[0], &pair[1]);
        assert_eq!(on.strategy, off.strategy);
        assert_eq!(on.tile_masks, Some(true), "{}: masks fit", on.cell);
        assert_eq!(off.tile_masks, Some(false), "{}: budget 0", off.cell);
        assert!(!on.params.contains("mask_budget"), "{}", on.params);
        assert!(off.params.ends_with(";mask_budget=0"), "{}", off.params);
        assert!(off.cell.contains("mask_budget=0"), "{}", off.cell);
        for r in [on, off] {
            assert_eq!(r.false_negatives, Some(0), "{}", r.cell);
        }
        assert_eq!(on.list_bytes, off.list_bytes, "{}", on.cell);
        assert_eq!(
            on.max_lights_per_tile, off.max_lights_per_tile,
            "{}",
            on.cell
        );
        assert_eq!(
            on.lights_per_pixel_mean, off.lights_per_pixel_mean,
            "{}",
            on.cell
        );
        assert_eq!(
            on.false_positive_ratio, off.false_positive_ratio,
            "{}",
            on.cell
        );
    }
    let csv = std::fs::read_to_string(tmp.path().join("out/results.csv")).unwrap();
    assert!(csv.lines().next().unwrap().ends_with(
        ",tile_masks,gpu_ms_cull_steady,gpu_ms_cull_span,gpu_ms_cull_shade,\
                 gpu_ms_cull_shade_span,lights_needed_per_pixel_mean,gpu_ms_light_update,cpu_ms_upload,\
                 msaa,msaa_target_bytes,transparent,gpu_ms_geometry_steady,gpu_ms_frame_steady,\
                 radius_rule,exposure_infinite,rmse_infinite,energy_error_infinite,seeds,accumulate,\
                 bias_infinite,noise_infinite,temporal_flicker_mean,reference_infinite_cached,\
                 materials,covered_pixels,ns_per_light_eval,gpu_ms_hierarchy,scene_lights,\
                 bytes_written_per_pixel,bytes_read_per_pixel,gpu_ms_hierarchy_steady,setting,\
                 radius_value,hierarchy_spacing,hierarchy_finest_nodes,hierarchy_growth,\
                 hierarchy_ramp,hierarchy_sample_from,stochastic_bound,stochastic_draw,interleave,\
                 stochastic_exposure,shadows,flip_mean_shadowed,energy_error_shadowed,\
                 rays_per_pixel,gpu_ms_shadow,grays_per_s,reference_shadowed_cached,occluded_pairs,\
                 hierarchy_spot_bins,gpu_ms_frame_build_steady,shadowed_reference_se,\
                 lights_walked_per_pixel_mean,error"
    ));
}

/// The columns of a row that do not depend on timing, and its image error rounded. The order of
/// lights within a list depends on the GPU's atomics (fills append), so the float sum of a
/// pixel's lights may differ in its last bits between runs: PSNR of identical images is infinite
/// in one run and 210 dB in the next. Image error is compared to within that rounding.
fn deterministic(
    r: &Row,
) -> (
    String,
    String,
    Option<u64>,
    Option<String>,
    u64,
    Option<u64>,
    String,
) {
    (
        r.id.clone(),
        r.cell.clone(),
        r.false_negatives,
        r.false_positive_ratio.map(|v| format!("{v:.9}")),
        r.list_bytes,
        r.max_lights_per_tile,
        r.max_abs_error
            .map_or(String::new(), |v| format!("{:.4}", v + 1e-3)),
    )
}

/// A run stopped after some cells and run again yields the same rows as a clean run, none
/// duplicated; a temporary file left by an interrupted write is ignored; shards merged give the
/// same rows too.
#[test]
fn resumed_and_sharded_runs_equal_a_clean_run() {
    let ctx = common::gpu();
    let (e, src, path) = shipped("quickstart");
    let tiny = e.tiny();
    let base = path.parent().unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let clean = run_parsed(&ctx, &tiny, &src, base, &tmp.path().join("clean"), &opts())
        .unwrap()
        .rows;

    let resumed_dir = tmp.path().join("resumed");
    let first = run_parsed(
        &ctx,
        &tiny,
        &src,
        base,
        &resumed_dir,
        &RunOptions {
            max_cells: Some(2),
            ..opts()
        },
    )
    .unwrap();
    assert_eq!(
        (first.ran, first.rows.len()),
        (2, 2),
        "the interrupted run persisted its finished cells"
    );
    // The interrupted run's report names the cells it has not run.
    manylights_lab::report::write_report(&resumed_dir).unwrap();
    let md = std::fs::read_to_string(resumed_dir.join("report.md")).unwrap();
    // (The report reads the experiment file, `e`; `tiny` shrinks its cells, not their number.)
    let missing = &e.cells()[2..];
    let line = format!("- cells: 2 of {} ({} not run: ", clean.len(), missing.len());
    assert!(md.contains(&line), "{line} not in the report");
    assert!(missing.iter().all(|c| md.contains(&c.name)));
    std::fs::write(resumed_dir.join("cells").join(".tmpXYZ123"), b"{\"half\": ").unwrap();
    let second = run_parsed(&ctx, &tiny, &src, base, &resumed_dir, &opts()).unwrap();
    assert_eq!((second.ran, second.skipped), (clean.len() - 2, 2));
    let a: Vec<_> = clean.iter().map(deterministic).collect();
    let b: Vec<_> = second.rows.iter().map(deterministic).collect();
    assert_eq!(a, b, "resumed rows differ from a clean run's");

    let shards: Vec<PathBuf> = (0..2)
        .map(|i| tmp.path().join(format!("shard{i}")))
        .collect();
    for (i, dir) in shards.iter().enumerate() {
        let s = run_parsed(
            &ctx,
            &tiny,
            &src,
            base,
            dir,
            &RunOptions {
                shard: Some((i, 2)),
                ..opts()
            },
        )
        .unwrap();
        assert!(
            s.rows.iter().all(|r| r.index % 2 == i),
            "shard {i} ran a cell of another shard"
        );
        // A finished shard misses none of its own cells.
        manylights_lab::report::write_report(dir).unwrap();
        let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
        assert!(
            md.contains(&format!("- cells: {}\n", s.rows.len())),
            "shard {i}'s report counts cells it was not given"
        );
    }
    let inputs: Vec<&Path> = shards.iter().map(PathBuf::as_path).collect();
    let merged = manylights_lab::results::merge(&inputs, &tmp.path().join("merged")).unwrap();
    let m: Vec<_> = merged.iter().map(deterministic).collect();
    assert_eq!(a, m, "merged shards differ from a clean run");
    let meta: serde_json::Value = serde_json::from_slice(
        &std::fs::read(tmp.path().join("merged").join("meta.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(meta["merged_shards"], serde_json::json!(["0/2", "1/2"]));
    assert!(meta.get("shard").is_none(), "{meta}");
}

fn manylights(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_manylights"))
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap()
}

/// `run --time-limit`: no cell starts after the limit, the cells left are counted with how to
/// resume them, and a bad limit names the option.
#[test]
fn time_limit_leaves_the_cells_after_it_for_a_resumed_run() {
    common::gpu();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let exp = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quickstart.ron");
    let cells = manylights_lab::Experiment::load(&exp)
        .unwrap()
        .0
        .cells()
        .len();
    let o = manylights(&[
        "run",
        exp.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--time-limit",
        "0.000001",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains(&format!("{cells} cells not run (--time-limit reached); run the same command again to resume them")),
        "{err}"
    );
    assert!(!out.join("report.md").exists(), "a report of no cells");
    for bad in ["0", "-3", "soon"] {
        let limit = format!("--time-limit={bad}");
        let o = manylights(&["run", exp.to_str().unwrap(), &limit]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success()
                && err.contains("--time-limit")
                && err.contains("positive number of seconds"),
            "{bad}: {err}"
        );
    }
}

/// Bad experiment files: an error with the file, line and column, exit code 1, and no output.
#[test]
fn bad_ron_gives_its_location_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let good = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quickstart.ron"),
    )
    .unwrap();
    let cases = [
        (
            "syntax",
            good.replace("frames: 3,", "frames: 3,,"),
            vec!["syntax.ron:11:19"],
        ),
        (
            "unknown-strategy",
            good.replace("DepthMask(tile_size: 16)", "ForwardPlus(tile_size: 16)"),
            vec!["unknown-strategy.ron:", "ForwardPlus", "TiledGather"],
        ),
        (
            "negative-count",
            good.replace("count: 256", "count: -5"),
            vec!["negative-count.ron:9:"],
        ),
        (
            "empty-sweep",
            good.replace("backend: [Forward, Deferred, Visibility]", "backend: []"),
            vec!["empty-sweep.ron:", "sweep.backend is empty"],
        ),
        (
            "unknown-field",
            good.replace("warmup: 1,", "warmup: 1, colour: 3,"),
            vec!["unknown-field.ron:", "colour"],
        ),
        (
            "bad-value",
            good.replace("resolution: (320, 180)", "resolution: (0, 180)"),
            vec!["bad-value.ron:", "resolution (0, 180)"],
        ),
    ];
    for (name, text, expect) in cases {
        let file = tmp.path().join(format!("{name}.ron"));
        std::fs::write(&file, text).unwrap();
        let out = tmp.path().join(format!("out-{name}"));
        let o = manylights(&[
            "run",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{name}: {stderr}");
        for e in expect {
            assert!(stderr.contains(e), "{name}: `{e}` missing from: {stderr}");
        }
        assert!(!out.exists(), "{name}: output written for a bad file");
        println!("{name}: {}", stderr.trim());
    }
}

/// Chromium's DOM of `page` after its scripts ran, and its log (headless, no network, a fresh
/// profile under `tmp`).
fn chromium_dom(page: &Path, tmp: &Path) -> (String, String) {
    let chromium = ["/usr/bin/chromium", "/usr/bin/chromium-browser"]
        .into_iter()
        .find(|p| Path::new(p).exists())
        .unwrap_or_else(|| {
            panic!("this test needs Chromium: `apt-get install chromium` (as .ci/run does)")
        });
    let profile = tmp.join("profile");
    let o = Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--allow-file-access-from-files",
            "--enable-logging=stderr",
            "--v=0",
            "--virtual-time-budget=5000",
            &format!("--user-data-dir={}", profile.display()),
            "--dump-dom",
            &format!("file://{}", page.display()),
        ])
        .output()
        .unwrap();
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Every figure of every committed report (docs/reports/*/figures), laid out by Chromium: no
/// text reaches past the figure's edges (a title cut off, a label off the canvas), and no
/// legend holds more than 12 entries (the text inside each figure's `legend-box`).
#[test]
fn committed_figures_have_no_clipped_text_and_short_legends_in_chromium() {
    let reports = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/reports");
    let mut page = String::from("<!doctype html><html><body>\n");
    let mut count = 0;
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&reports)
        .unwrap()
        .map(|e| e.unwrap().path().join("figures"))
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    for dir in dirs {
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "svg"))
            .collect();
        files.sort();
        for f in files {
            let svg = std::fs::read_to_string(&f).unwrap();
            let svg = svg.find("<svg").map_or(svg.as_str(), |i| &svg[i..]);
            let name = f.strip_prefix(&reports).unwrap().display().to_string();
            page += &format!("<div class=\"fig\" data-name=\"{name}\">{svg}</div>\n");
            count += 1;
        }
    }
    assert!(count >= 40, "only {count} committed figures");
    page += r#"<script>
const out = [];
for (const div of document.querySelectorAll('div.fig')) {
  const svg = div.querySelector('svg');
  const s = svg.getBoundingClientRect();
  const texts = [...svg.querySelectorAll('text')].filter(t => t.textContent.trim() !== '');
  const clipped = texts.filter(t => {
    const b = t.getBoundingClientRect();
    return b.left < s.left - 1 || b.top < s.top - 1 || b.right > s.right + 1 || b.bottom > s.bottom + 1;
  }).map(t => t.textContent);
  let legend = -1;
  for (const box of svg.querySelectorAll('rect.legend-box')) {
    const l = box.getBoundingClientRect();
    legend = Math.max(legend, texts.filter(t => {
      const b = t.getBoundingClientRect();
      const x = (b.left + b.right) / 2, y = (b.top + b.bottom) / 2;
      return x >= l.left && x <= l.right && y >= l.top && y <= l.bottom;
    }).length);
  }
  out.push(encodeURIComponent(div.dataset.name) + ' ' + legend + ' ' + clipped.length + ' ' + encodeURIComponent(clipped.slice(0, 3).join(' | ')));
}
document.body.setAttribute('data-result', out.join(';'));
</script></body></html>
"#;
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("figures.html");
    std::fs::write(&file, page).unwrap();
    let (dom, _) = chromium_dom(&file, tmp.path());
    let result = dom
        .split("data-result=\"")
        .nth(1)
        .and_then(|s| s.split('"').next())
        .unwrap_or_else(|| panic!("no result; DOM: {}", &dom[..dom.len().min(300)]));
    let decode = |s: &str| {
        let mut out = Vec::new();
        let b = s.as_bytes();
        let mut i = 0;
        while i < b.len() {
            if b[i] == b'%' && i + 2 < b.len() {
                out.push(u8::from_str_radix(&s[i + 1..i + 3], 16).unwrap());
                i += 3;
            } else {
                out.push(b[i]);
                i += 1;
            }
        }
        String::from_utf8_lossy(&out).into_owned()
    };
    let mut problems = Vec::new();
    let mut seen = 0;
    for entry in result.split(';') {
        let parts: Vec<&str> = entry.split(' ').collect();
        let (name, legend, clipped) = (decode(parts[0]), parts[1], parts[2]);
        let legend: i64 = legend.parse().unwrap();
        if legend > 12 {
            problems.push(format!("{name}: {legend} legend entries"));
        }
        if legend < 1 {
            // Every figure has a legend, marked where the figures module drew it.
            problems.push(format!(
                "{name}: no legend box, or nothing in it ({legend})"
            ));
        }
        if clipped != "0" {
            problems.push(format!(
                "{name}: {clipped} texts past the edges ({})",
                decode(parts.get(3).unwrap_or(&""))
            ));
        }
        seen += 1;
    }
    assert_eq!(seen, count, "Chromium measured {seen} of {count} figures");
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The HTML report opens in headless Chromium with no console errors and every figure loaded.
#[test]
fn html_report_loads_in_headless_chromium() {
    let ctx = common::gpu();
    let (e, src, path) = shipped("quickstart");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    run_parsed(&ctx, &e.tiny(), &src, path.parent().unwrap(), &out, &opts()).unwrap();
    let html = manylights_lab::report::write_report(&out).unwrap();
    let (dom, log) = chromium_dom(&html, tmp.path());
    assert!(
        dom.contains("data-figures=\"loaded\""),
        "not every figure loaded; DOM: {}",
        &dom[..dom.len().min(500)]
    );
    let count: usize = dom
        .split("data-figure-count=\"")
        .nth(1)
        .and_then(|s| s.split('"').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    assert!(count >= 3, "only {count} figures on the page");
    for line in log.lines() {
        let l = line.to_lowercase();
        assert!(
            !(l.contains("console") && (l.contains("error") || l.contains("uncaught"))),
            "console error: {line}"
        );
        assert!(
            !l.contains("failed to load resource"),
            "a resource failed to load: {line}"
        );
    }
}

/// The stability suite: every case parses, a tiny variant of each runs for every configuration,
/// and no configuration fails in any case (false negatives without a capacity, NaN/Inf pixels).
#[test]
fn stability_suite_has_no_failures() {
    use manylights_lab::stability::{Verdict, verdict, write_report};
    let ctx = common::gpu();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/stability");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    files.sort();
    assert!(files.len() >= 15, "only {} stability cases", files.len());
    let tmp = tempfile::tempdir().unwrap();
    let mut cases = Vec::new();
    for f in &files {
        let (e, src) = Experiment::load(f).unwrap_or_else(|e| panic!("{e}"));
        let out = tmp.path().join(&e.name);
        let rows = run_parsed(&ctx, &e.tiny(), &src, &dir, &out, &opts())
            .unwrap_or_else(|err| panic!("{}: {err}", e.name))
            .rows;
        for r in &rows {
            assert!(
                !matches!(verdict(r), Verdict::Fail(_)),
                "{} {}: {:?}",
                e.name,
                r.cell,
                verdict(r)
            );
        }
        if e.name == "15-jittered-camera" {
            // Every pose is measured, and flicker caused by culling is zero: the forward
            // backend, exact up to float rounding, changes from pose to pose exactly as the
            // reference does (1e-4 of the peak: forward's stated tolerance).
            for r in &rows {
                assert_eq!(r.poses, 4, "{}", r.cell);
                let f = r.temporal_flicker.expect("a path measures flicker");
                assert!(
                    r.temporal_change_reference.unwrap() > 0.0,
                    "{}: the path must move the image",
                    r.cell
                );
                if r.backend == "forward" || r.backend == "naive_forward" {
                    assert!(f <= 1e-4, "{}: flicker {f}", r.cell);
                }
            }
        }
        if e.name == "14-device-limits" {
            let ctx_max = manylights_cull::max_lights(&ctx);
            let dim = ctx.limits.max_texture_dimension_2d;
            assert!(rows.iter().any(|r| r.width == dim) && rows.iter().any(|r| r.height == dim));
            assert!(rows.iter().any(|r| r.lights == u64::from(ctx_max)));
        }
        if e.name == "18-glossy-stochastic" {
            // The lists of the default bound do not depend on the materials: under GGX (from
            // the roughness floor) and the clear coat as long as under Blinn-Phong, for the
            // same scene and configuration; the noise is measured for every model.
            let per_pixel = |scene: &str, materials: &str| {
                rows.iter()
                    .find(|r| {
                        r.scene == scene
                            && r.materials == materials
                            && r.backend == "deferred"
                            && r.strategy == "tiled_gather"
                    })
                    .and_then(|r| r.lights_per_pixel_mean)
                    .unwrap_or_else(|| panic!("{scene} {materials}: no deferred gather row"))
            };
            for scene in ["glossy-boxes", "atrium"] {
                let blinn = per_pixel(scene, "blinn_phong");
                for m in ["ggx", "clear_coat"] {
                    let glossy = per_pixel(scene, m);
                    assert!(
                        glossy <= 2.0 * blinn,
                        "{scene} {m}: {glossy} lights a pixel against Blinn-Phong's {blinn}"
                    );
                }
            }
            for r in rows.iter().filter(|r| r.backend != "naive_forward") {
                assert!(
                    r.noise_infinite.is_some() && r.flip_mean_infinite.is_some(),
                    "{}: the noise is reported",
                    r.cell
                );
                let needed = r
                    .lights_needed_per_pixel_mean
                    .expect("the exact set's size");
                assert!(
                    needed < 0.25 * r.lights as f64,
                    "{}: {needed} lights needed a pixel",
                    r.cell
                );
                // The rule that fails ranges spanning the scene fires where they would.
                let mut spanning = r.clone();
                spanning.lights_needed_per_pixel_mean = Some(r.lights as f64 * 0.6);
                assert!(
                    matches!(verdict(&spanning), Verdict::Fail(_)),
                    "{}: {:?}",
                    r.cell,
                    verdict(&spanning)
                );
            }
        }
        if e.name == "05-overflow-pressure" {
            assert!(
                rows.iter().any(|r| r.dropped_lights > 0),
                "the capacity cells must drop lights"
            );
            assert!(
                rows.iter()
                    .any(|r| matches!(verdict(r), Verdict::Degraded(_))),
                "a counted loss is degraded"
            );
        }
        cases.push((e.name.clone(), Ok(rows)));
    }
    cases.push(("broken".into(), Err("cell 3 `x` failed: a reason".into())));
    let fails = write_report(tmp.path(), &cases).unwrap();
    let md = std::fs::read_to_string(tmp.path().join("stability.md")).unwrap();
    assert!(
        md.contains("| 01-depth-discontinuity |") && md.contains("pass"),
        "{md}"
    );
    assert!(
        fails > 0
            && md.contains("| broken | - | - | **fail** (did not run: see below the table)")
            && md.contains("- `broken`: cell 3 `x` failed: a reason"),
        "a case that did not run must fail"
    );
}

/// The tuner leaves out the candidates the device cannot hold, with why, instead of failing on
/// them: z-binning's masks at 1080p and 4M lights (1 bit a tile and light, 4 GB), not at 256.
#[test]
fn tune_leaves_out_what_the_device_cannot_hold() {
    let ctx = common::gpu();
    let (e, _, _) = shipped("quickstart");
    let mut base = e.config.clone();
    base.resolution = (1920, 1080);
    base.lights.count = 256;
    let (fit, left_out) = manylights_lab::tune::fitting(&ctx, &base);
    assert!(left_out.is_empty(), "{left_out:?}");
    assert_eq!(fit.len(), manylights_lab::tune::candidates().len());
    base.lights.count = 4 << 20;
    let (fit, left_out) = manylights_lab::tune::fitting(&ctx, &base);
    assert_eq!(
        left_out.len(),
        3,
        "z-binning at 8, 16 and 32 pixels: {left_out:?}"
    );
    assert!(left_out.iter().all(
        |(s, why)| matches!(s, manylights_cull::Strategy::ZBin { .. })
            && why.contains("zbin masks")
            && why.contains("max_storage_buffer_binding_size")
    ));
    assert_eq!(fit.len() + 3, manylights_lab::tune::candidates().len());
}

/// The lit image's format as an experiment parameter: swept over F32 and F16, each cell with
/// its accuracy against the 32-bit reference; `params` names `hdr=f16`, the 16-bit image is
/// finite and as accurate as the 32-bit one within half's rounding, and the lists are the same.
#[test]
fn hdr_sweeps_the_lit_image_format() {
    let ctx = common::gpu();
    let tmp = tempfile::tempdir().unwrap();
    let src = r#"Experiment(
        name: "hdr",
        config: Config(
            scene: Atrium(bays: 2),
            lights: (generator: Uniform, count: 96, seed: 5, radius: Fixed(1.5)),
            resolution: (64, 40),
            backend: Deferred,
            frames: 1,
            warmup: 0,
        ),
        sweep: (
            strategy: [TiledGather(tile_size: 8)],
            hdr: [F32, F16],
        ),
    )"#;
    let path = tmp.path().join("hdr.ron");
    let e = Experiment::parse(src, &path).unwrap();
    assert_eq!(e.cells().len(), 2);
    let s = run_parsed(&ctx, &e, src, tmp.path(), &tmp.path().join("out"), &opts()).unwrap();
    let (full, half) = (&s.rows[0], &s.rows[1]);
    assert!(!full.params.contains("hdr"), "{}", full.params);
    assert!(half.params.ends_with(";hdr=f16"), "{}", half.params);
    assert!(half.cell.contains("hdr=f16"), "{}", half.cell);
    assert_eq!(half.nonfinite_pixels, 0);
    assert_eq!(full.lights_per_pixel_mean, half.lights_per_pixel_mean);
    let (a, b) = (full.max_abs_error.unwrap(), half.max_abs_error.unwrap());
    println!(
        "max_abs_error: f32 {a:e}, f16 {b:e}; flip_mean {:?} {:?}; psnr {:?} {:?}",
        full.flip_mean, half.flip_mean, full.psnr_db, half.psnr_db
    );
    assert!(
        b > a,
        "the 16-bit image carries its rounding: {b} against {a}"
    );
    assert!(half.flip_mean.unwrap() < 1e-3, "{:?}", half.flip_mean);
    // A mean FLIP bound at 64 x 40 lets two wholly wrong pixels through; PSNR does not: one
    // pixel off by a thousandth of the peak at 2,560 pixels is 94 dB (f16's rounding: 103).
    assert!(half.psnr_db.unwrap() >= 95.0, "{:?}", half.psnr_db);
}

/// A real scene by name (`Real("sponza")`) lit by fixtures: its camera, no false negatives, the
/// image within forward's tolerance of the reference, and its name in the rows.
#[test]
fn a_real_scene_runs_by_name() {
    let ctx = common::gpu();
    let tmp = tempfile::tempdir().unwrap();
    let src = r#"Experiment(
        name: "real",
        config: Config(
            scene: Real("sponza"),
            lights: (generator: Fixtures(drop: 0.15, on_walls: 0.5), count: 64, seed: 3, radius: Fixed(4.0), spot_fraction: 0.5),
            resolution: (64, 36),
            frames: 1,
            warmup: 0,
        ),
        sweep: (
            variants: [
                (label: "forward+gather", backend: Forward, strategy: TiledGather(tile_size: 8)),
                (label: "visibility+clusters", backend: Visibility, strategy: Clustered(tile_size: 16, slices: 16)),
            ],
        ),
    )"#;
    let path = tmp.path().join("real.ron");
    // An unknown name is an error at its place, naming the scenes there are.
    let bad = src.replace("Real(\"sponza\")", "Real(\"sponsa\")");
    let err = Experiment::parse(&bad, &path).unwrap_err().to_string();
    assert!(
        err.contains("real.ron:")
            && err.contains("Real(\"sponsa\")")
            && err.contains("sponza, staircase"),
        "{err}"
    );
    let e = Experiment::parse(src, &path).unwrap();
    let s = run_parsed(&ctx, &e, src, tmp.path(), &tmp.path().join("out"), &opts()).unwrap();
    assert_eq!(s.rows.len(), 2);
    for r in &s.rows {
        assert_eq!(r.scene, "sponza", "{}", r.cell);
        assert_eq!(r.false_negatives, Some(0), "{}", r.cell);
        assert!(
            r.lights_needed_per_pixel_mean.is_some_and(|n| n > 0.0),
            "{}: no light reaches the view",
            r.cell
        );
        assert_eq!(r.nonfinite_pixels, 0, "{}", r.cell);
        let bound = if r.backend == "forward" { 1e-6 } else { 1e-3 };
        assert!(
            r.flip_mean.is_some_and(|f| f <= bound),
            "{}: {:?}",
            r.cell,
            r.flip_mean
        );
    }
}

/// A cell that fails (here a glTF file that is not there) is recorded with its error in the
/// results and the report, the sweep goes on, the run says which failed, and a rerun runs that
/// cell alone again.
#[test]
fn a_failed_cell_is_recorded_and_the_sweep_goes_on() {
    let ctx = common::gpu();
    let tmp = tempfile::tempdir().unwrap();
    let src = r#"Experiment(
        name: "fails",
        config: Config(
            scene: Pillars(),
            lights: (count: 16, radius: Fixed(2.0)),
            resolution: (32, 18),
            frames: 1,
            warmup: 0,
        ),
        sweep: (scene: [Gltf("nope.glb"), Pillars()]),
    )"#;
    let path = tmp.path().join("fails.ron");
    let e = Experiment::parse(src, &path).unwrap();
    let out = tmp.path().join("out");
    let s = run_parsed(&ctx, &e, src, tmp.path(), &out, &opts()).unwrap();
    assert_eq!((s.ran, s.rows.len()), (2, 2));
    let failed = s.failed();
    assert_eq!(failed.len(), 1);
    let error = failed[0].error.as_deref().unwrap();
    assert!(
        error.contains("cell 0") && error.contains("nope.glb") && error.contains("no such file"),
        "{error}"
    );
    assert!(failed[0].gpu_ms_total.is_none() && failed[0].scene == "nope");
    let ran = s.rows.iter().find(|r| r.error.is_none()).unwrap();
    assert_eq!(ran.scene, "pillars");
    assert!(ran.gpu_ms_total.is_some() || ran.flip_mean.is_some());
    let checked = s.check().unwrap_err().to_string();
    assert!(
        checked.contains("1 cells failed") && checked.contains("nope.glb"),
        "{checked}"
    );
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert!(csv.lines().next().unwrap().ends_with(",error"), "{csv}");
    assert!(csv.contains("no such file"), "{csv}");
    let json = std::fs::read_to_string(out.join("results.json")).unwrap();
    assert!(json.contains("\"error\": \"cell 0"), "{json}");
    manylights_lab::report::write_report(&out).unwrap();
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("1 of 2 (1 failed: cell 0"), "{md}");
    // A rerun runs the failed cell again, and only it.
    let again = run_parsed(&ctx, &e, src, tmp.path(), &out, &opts()).unwrap();
    assert_eq!((again.ran, again.skipped), (1, 1));
    assert_eq!(again.failed().len(), 1);
}

/// A walkthrough of Sponza from its own camera (`camera: Walkthrough(...)`): every pose checked
/// (no false negatives at any), the path's temporal change measured, the cell named for it.
#[test]
fn a_walkthrough_checks_every_pose_of_a_real_scene() {
    let ctx = common::gpu();
    let tmp = tempfile::tempdir().unwrap();
    let src = r#"Experiment(
        name: "walk",
        config: Config(
            scene: Real("sponza"),
            lights: (generator: OnSurfaces(offset: (0.1, 1.0)), count: 128, seed: 4, radius: Fixed(4.0)),
            resolution: (48, 27),
            frames: 3,
            warmup: 0,
            strategy: Clustered(tile_size: 16, slices: 16),
        ),
        sweep: (camera: [Walkthrough(poses: 3, toward: 0.5, pan_deg: 20.0)]),
    )"#;
    let path = tmp.path().join("walk.ron");
    let e = Experiment::parse(src, &path).unwrap();
    let s = run_parsed(&ctx, &e, src, tmp.path(), &tmp.path().join("out"), &opts()).unwrap();
    let r = &s.rows[0];
    assert!(r.cell.contains("camera=walk3"), "{}", r.cell);
    assert_eq!(r.poses, 3);
    assert_eq!(r.false_negatives, Some(0));
    assert!(
        r.temporal_change.is_some_and(|t| t > 0.0),
        "{:?}",
        r.temporal_change
    );
    // A bad walk is an error at its place.
    let bad = src.replace("poses: 3", "poses: 1");
    let err = Experiment::parse(&bad, &path).unwrap_err().to_string();
    assert!(
        err.contains("walk.ron:") && err.contains("at least 2 poses"),
        "{err}"
    );
}
