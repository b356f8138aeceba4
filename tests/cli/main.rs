//! The `manylights` binary: bad input gives a clear error, a non-zero exit code and no output;
//! good input writes its files.

use std::path::Path;
use std::process::{Command, Output};

mod hierarchy;
mod lights;
mod msaa;
mod outputs;
mod score;
mod stochastic;
mod transparent;
mod tune;

pub(crate) fn manylights(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_manylights"))
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("run manylights")
}

/// Runs `manylights` with `args`, which must succeed (a failure names `what` and shows the
/// run's stderr); its stdout.
pub(crate) fn succeeds(args: &[&str], what: &str) -> String {
    let o = manylights(args);
    assert!(
        o.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The number after `key` on the first line of `stdout` that holds `line`.
pub(crate) fn number_after(stdout: &str, line: &str, key: &str) -> f64 {
    let l = stdout
        .lines()
        .find(|l| l.contains(line))
        .unwrap_or_else(|| panic!("no `{line}` line in:\n{stdout}"));
    l.split(key)
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.trim_end_matches(',').parse().ok())
        .unwrap_or_else(|| panic!("no `{key}` in {l}"))
}

/// The PSNR of `render --compare`'s line against the reference, from its output.
pub(crate) fn psnr_vs_reference(stdout: &str) -> f64 {
    let line = stdout
        .lines()
        .find(|l| l.contains("vs reference "))
        .unwrap_or_else(|| panic!("no comparison with the reference in:\n{stdout}"));
    line.split("PSNR ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no PSNR in {line}"))
}

/// Runs `render` with `extra` options into a fresh directory and expects failure with `code`
/// and every string of `expect` in stderr, and no output directory.
pub(crate) fn rejects(extra: &[&str], code: i32, expect: &[&str]) {
    rejects_cmd("render", extra, code, expect);
}

pub(crate) fn rejects_cmd(cmd: &str, extra: &[&str], code: i32, expect: &[&str]) {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let mut args = vec![cmd, "--out", out.to_str().unwrap()];
    for (flag, value) in [("--width", "32"), ("--height", "16"), ("--lights", "4")] {
        if !extra.contains(&flag) {
            args.extend([flag, value]);
        }
    }
    args.extend_from_slice(extra);
    let o = manylights(&args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        o.status.code(),
        Some(code),
        "{extra:?}: exit code; stderr: {stderr}"
    );
    for e in expect {
        assert!(
            stderr.contains(e),
            "{extra:?}: `{e}` missing from stderr: {stderr}"
        );
    }
    assert!(!out.exists(), "{extra:?}: output written despite the error");
}

#[test]
fn unknown_scene_lists_the_accepted_names() {
    rejects(
        &["--scene", "sponsa"],
        1,
        &[
            "unknown scene `sponsa`",
            "atrium, pillars, topdown, city",
            "sponza, staircase",
        ],
    );
}

#[test]
fn bad_light_values_name_the_value() {
    rejects(&["--radius", "-1"], 1, &["radius = -1", "> 0"]);
    rejects(&["--radius", "NaN"], 1, &["radius = NaN"]);
    rejects(&["--intensity", "-2"], 1, &["intensity = -2", ">= 0"]);
    rejects(&["--intensity", "NaN"], 1, &["intensity = NaN"]);
    rejects(&["--threshold", "0"], 1, &["threshold = 0"]);
    rejects(
        &["--spot-fraction", "1.5"],
        1,
        &["spot_fraction = 1.5", "[0, 1]"],
    );
}

#[test]
fn bad_material_models_list_the_valid_ones() {
    rejects(
        &["--materials", "phong"],
        2,
        &[
            "'phong'",
            "blinn-phong",
            "ggx",
            "sheen",
            "clear-coat",
            "wrap",
        ],
    );
    rejects(
        &["--materials", "ggx,sheen,ggx"],
        1,
        &["--materials names ggx twice"],
    );
}

#[test]
fn bad_resolutions_name_the_value_and_the_limit() {
    rejects(&["--width", "0"], 2, &["'0'", "1..=65536"]);
    rejects(&["--height", "0"], 2, &["'0'", "1..=65536"]);
    // Over the device's limit (lavapipe allows 16,384, an H100 32,768).
    rejects(
        &["--width", "65536"],
        1,
        &["width = 65536", "max_texture_dimension_2d"],
    );
}

#[test]
fn missing_and_malformed_gltf_are_errors() {
    rejects(
        &["--scene", "/nonexistent/model.glb"],
        1,
        &["/nonexistent/model.glb", "no such file"],
    );
    let bad = "/usr/share/assimp/models/glTF2/RecursiveNodes/RecursiveNodes.gltf";
    assert!(Path::new(bad).exists(), "install assimp-testmodels");
    rejects(&["--scene", bad], 1, &[bad, "cycle"]);
}

/// `--scene sponza` renders the vendored scene by name, and its compressed file by path, within
/// forward's tolerance of the reference.
#[test]
fn real_scenes_render_by_name_and_by_path() {
    let tmp = tempfile::tempdir().unwrap();
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/sponza.glb.xz");
    for scene in ["sponza", file] {
        let out = tmp.path().join("render");
        let stdout = succeeds(
            &[
                "render",
                "--scene",
                scene,
                "--backend",
                "forward",
                "--lights",
                "64",
                "--radius",
                "4",
                "--width",
                "64",
                "--height",
                "36",
                "--compare",
                "--out",
                out.to_str().unwrap(),
            ],
            scene,
        );
        assert!(psnr_vs_reference(&stdout) > 80.0, "{scene}: {stdout}");
        assert!(out.join("forward.png").is_file(), "{scene}");
    }
}

#[test]
fn render_writes_png_and_exr() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("render");
    let o = manylights(&[
        "render",
        "--scene",
        "pillars",
        "--lights",
        "32",
        "--width",
        "48",
        "--height",
        "27",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        o.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let png = image::open(out.join("reference.png"))
        .expect("a readable PNG")
        .to_rgb8();
    assert_eq!(png.dimensions(), (48, 27));
    assert!(png.pixels().any(|p| p.0 != [0, 0, 0]), "the PNG is black");
    let exr = image::open(out.join("reference.exr"))
        .expect("a readable EXR")
        .to_rgb32f();
    assert_eq!(exr.dimensions(), (48, 27));
    let names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names.len(),
        2,
        "only the two images, no temporary files: {names:?}"
    );
}

#[test]
fn help_explains_each_subcommand() {
    let o = manylights(&["--help"]);
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success() && s.contains("render") && s.contains("reference renderer"),
        "{s}"
    );
    let o = manylights(&["render", "--help"]);
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(
        s.contains("--scene") && s.contains("--adapter") && s.contains("MANYLIGHTS_ADAPTER"),
        "{s}"
    );
}

#[test]
fn unknown_adapter_lists_the_adapters_found() {
    rejects(
        &["--adapter", "no-such-gpu"],
        1,
        &["no adapter matches `no-such-gpu`", "adapters found", "[0]"],
    );
}

#[test]
fn cull_reports_metrics_and_writes_heatmaps() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("cull");
    for strategy in [
        "tiled-gather",
        "tiled-scatter",
        "depth-mask",
        "clustered",
        "zbin",
    ] {
        let stdout = succeeds(
            &[
                "cull",
                "--scene",
                "pillars",
                "--lights",
                "64",
                "--radius",
                "1.5",
                "--strategy",
                strategy,
                "--width",
                "40",
                "--height",
                "23",
                "--tile-size",
                "8",
                "--out",
                out.to_str().unwrap(),
            ],
            strategy,
        );
        assert!(
            stdout.contains("false negatives         0"),
            "{strategy}: {stdout}"
        );
        assert!(
            stdout.contains("false-positive ratio") && stdout.contains("list entries / bytes"),
            "{stdout}"
        );
        // Deferred shading walks each pixel's whole list at 64 lights: the lights walked a
        // covered point are the lights a pixel's list holds.
        let field = |label: &str| -> f64 {
            let line = stdout
                .lines()
                .find(|l| l.trim_start().starts_with(label))
                .unwrap_or_else(|| panic!("{strategy}: no `{label}` in {stdout}"));
            let rest = line.trim_start()[label.len()..].trim_start();
            let rest = rest.split_once('(').map_or(rest, |(_, r)| r);
            rest.split_whitespace().next().unwrap().parse().unwrap()
        };
        assert_eq!(
            format!("{:.2}", field("lights walked")),
            format!("{:.2}", field("lights per pixel")),
            "{strategy}: {stdout}"
        );
        let name = strategy.replace('-', "_");
        for kind in ["tiles", "pixels"] {
            let img = image::open(out.join(format!("heatmap_{kind}_{name}.png")))
                .expect("a heatmap PNG")
                .to_rgb8();
            assert_eq!(img.dimensions(), (40 + manylights_cull::heatmap::BAR, 23));
        }
    }
}

#[test]
fn cull_repeat_times_runs_back_to_back() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("cull");
    // Tiled scatter with its pairs and radix sort (without tile masks, or with a budget they
    // do not fit), then with tile masks (the default where they fit, or a budget they fit):
    // each prints its passes' medians and whether it used masks. The sort is the onesweep path
    // (lavapipe has subgroups of 8).
    let pairs = &["cull.tiled_scatter.count", "sort.radix.onesweep"][..];
    let masked = &["cull.tiled_scatter.count", "cull.tiled_scatter.fill"][..];
    for (flags, passes, absent, masks) in [
        (
            &["--no-tile-masks"][..],
            pairs,
            "cull.tiled_scatter.fill",
            "not used",
        ),
        (
            &["--mask-budget", "0"][..],
            pairs,
            "cull.tiled_scatter.fill",
            "not used",
        ),
        // 3 x 2 tiles of 16 pixels, 64 lights: 6 x 2 words of 4 bytes.
        (
            &["--mask-budget", "47"][..],
            pairs,
            "cull.tiled_scatter.fill",
            "not used",
        ),
        (
            &["--mask-budget", "48"][..],
            masked,
            "sort.radix",
            "used (48 bytes)",
        ),
        (&[][..], masked, "sort.radix", "used (48 bytes)"),
    ] {
        let mut args = vec![
            "cull",
            "--scene",
            "pillars",
            "--lights",
            "64",
            "--strategy",
            "tiled-scatter",
            "--width",
            "40",
            "--height",
            "23",
            "--repeat",
            "3",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(flags);
        let stdout = succeeds(&args, "cull --repeat");
        let after = stdout
            .split("3 runs back to back (median per pass):")
            .nth(1)
            .unwrap_or_else(|| panic!("no back-to-back timings: {stdout}"));
        for pass in passes.iter().chain(&["total (median run)"]) {
            assert!(after.contains(pass), "{flags:?}: {pass} missing: {stdout}");
        }
        assert!(
            !stdout.contains(absent),
            "{flags:?}: {absent} ran: {stdout}"
        );
        assert!(
            stdout.contains(&format!("tile masks              {masks}\n")),
            "{flags:?}: tile masks {masks}: {stdout}"
        );
    }
}

/// `cull --repeat N` with gather's lines path: the single run counts, then fills; back to back
/// a run is `cull.tile_lines` and the fill, no count pass, and each pass's median is over the
/// N runs (the timed passes split by runs, not by the first run's passes).
#[test]
fn cull_repeat_times_gathers_lines_path_in_two_passes() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("cull");
    let stdout = succeeds(
        &[
            "cull",
            "--scene",
            "pillars",
            "--lights",
            "64",
            "--strategy",
            "tiled-gather",
            "--width",
            "40",
            "--height",
            "23",
            "--repeat",
            "3",
            "--out",
            out.to_str().unwrap(),
        ],
        "cull --repeat",
    );
    assert!(
        stdout.contains("tile masks              used as tile lines ("),
        "{stdout}"
    );
    let (single, after) = stdout
        .split_once("3 runs back to back (median per pass):")
        .unwrap_or_else(|| panic!("no back-to-back timings: {stdout}"));
    assert!(single.contains("cull.tiled_gather.count"), "{stdout}");
    let runs: Vec<&str> = after
        .lines()
        .take_while(|l| !l.contains("total (median run)"))
        .filter(|l| l.trim_start().starts_with("cull."))
        .map(|l| l.split_whitespace().next().unwrap())
        .collect();
    assert_eq!(
        runs,
        ["cull.tile_lines", "cull.tiled_gather.fill"],
        "{stdout}"
    );
}

#[test]
fn cull_rejects_bad_parameters() {
    rejects_cmd(
        "cull",
        &["--tile-size", "2"],
        1,
        &["tile_size = 2", "4..=256"],
    );
    rejects_cmd(
        "cull",
        &["--strategy", "clustered", "--slices", "0"],
        1,
        &["slices = 0"],
    );
    rejects_cmd(
        "cull",
        &["--strategy", "zbin", "--bins", "0"],
        1,
        &["bins = 0", "1..=1024"],
    );
    // An option the strategy does not read is an error, not ignored.
    for (extra, option, readers) in [
        (&["--slices", "32"][..], "--slices", "clustered"),
        (
            &["--strategy", "zbin", "--cells"][..],
            "--cells",
            "clustered",
        ),
        (
            &["--strategy", "tiled-scatter", "--coarse", "0"][..],
            "--coarse",
            "tiled-gather and depth-mask",
        ),
        (
            &["--strategy", "clustered", "--bins", "64"][..],
            "--bins",
            "zbin",
        ),
        (
            &["--strategy", "depth-mask", "--slicing", "linear"][..],
            "--slicing",
            "clustered and zbin",
        ),
        (&["--unordered"][..], "--unordered", "clustered"),
        (&["--skip-empty"][..], "--skip-empty", "clustered"),
    ] {
        for cmd in ["cull", "render"] {
            rejects_cmd(cmd, extra, 1, &[option, readers, "would ignore it"]);
        }
    }
    // Culling's options where nothing culls, and the visibility buffer's elsewhere.
    for (extra, option, why) in [
        (
            &["--backend", "reference", "--strategy", "clustered"][..],
            "--strategy",
            "--backend reference culls nothing",
        ),
        (
            &["--backend", "naive-forward", "--tile-size", "8"][..],
            "--tile-size",
            "--backend naive-forward culls nothing",
        ),
        (
            &["--capacity", "4"][..],
            "--capacity",
            "--backend reference culls nothing",
        ),
        (
            &["--backend", "forward", "--visibility-pass", "raster"][..],
            "--visibility-pass",
            "--backend forward would ignore it",
        ),
    ] {
        rejects_cmd("render", extra, 1, &[option, why]);
    }
    rejects_cmd(
        "cull",
        &["--strategy", "zbin", "--capacity", "4"],
        1,
        &["capacity = 4", "zbin"],
    );
    rejects_cmd(
        "cull",
        &["--strategy", "forward-plus"],
        2,
        &["forward-plus", "tiled-gather"],
    );
    rejects_cmd("cull", &["--slack", "-1"], 1, &["slack = -1", ">= 0"]);
    rejects_cmd(
        "cull",
        &["--repeat", "5000"],
        1,
        &["--repeat 5000", "at most"],
    );
    rejects_cmd(
        "render",
        &["--backend", "forward", "--capacity", "0"],
        1,
        &["capacity = 0"],
    );
}

#[test]
fn render_with_a_backend_compares_and_writes_heatmap_and_flip_map() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("r");
    for backend in ["forward", "deferred", "naive-forward", "visibility"] {
        // Naive forward culls nothing: a strategy for it is an error.
        let (strategy, value) = if backend == "naive-forward" {
            ("--exposure", "1")
        } else {
            ("--strategy", "depth-mask")
        };
        let stdout = succeeds(
            &[
                "render",
                "--scene",
                "atrium",
                "--lights",
                "64",
                "--backend",
                backend,
                strategy,
                value,
                "--width",
                "40",
                "--height",
                "24",
                "--compare",
                "--flip-map",
                "--out",
                out.to_str().unwrap(),
            ],
            backend,
        );
        assert!(
            stdout.contains("vs reference")
                && stdout.contains("vs infinite-range reference")
                && stdout.contains("mean FLIP"),
            "{stdout}"
        );
        assert!(
            (backend != "visibility")
                || (stdout.contains("visibility buffer bytes")
                    && stdout.contains("shade.visibility_compute.blocks")),
            "{stdout}"
        );
        let name = backend.replace('-', "_");
        for file in [
            format!("{name}.png"),
            format!("{name}.exr"),
            format!("heatmap_lights_per_pixel_{name}.png"),
            format!("flip_{name}.png"),
        ] {
            assert!(out.join(&file).is_file(), "{backend}: {file} missing");
        }
    }
}

/// `--visibility-pass raster` draws the visibility buffer with the raster pass, `compute` (the
/// default) with the compute rasteriser: the printed passes say which ran.
#[test]
fn render_visibility_pass_picks_the_raster_or_the_compute_pass() {
    let tmp = tempfile::tempdir().unwrap();
    for (pass, drawn, not) in [
        ("raster", "shade.visibility ", "shade.visibility_compute"),
        (
            "compute",
            "shade.visibility_compute.triangles",
            "shade.visibility ",
        ),
    ] {
        let out = tmp.path().join(pass);
        let stdout = succeeds(
            &[
                "render",
                "--scene",
                "pillars",
                "--lights",
                "32",
                "--backend",
                "visibility",
                "--visibility-pass",
                pass,
                "--width",
                "32",
                "--height",
                "24",
                "--out",
                out.to_str().unwrap(),
            ],
            pass,
        );
        assert!(
            stdout.contains(drawn) && !stdout.contains(not),
            "{pass}: {stdout}"
        );
    }
}

/// `render --shadows exact` builds the BVH, shades with shadow rays (darker than `off` against
/// the unshadowed infinite-range reference, and within tolerance of its own shadowed reference);
/// a value it does not take is an error naming the option and the values it takes.
#[test]
fn render_shadows_exact_casts_shadow_rays() {
    let tmp = tempfile::tempdir().unwrap();
    let mut energy = Vec::new();
    for shadows in ["off", "exact"] {
        let out = tmp.path().join(shadows);
        let stdout = succeeds(
            &[
                "render",
                "--scene",
                "pillars",
                "--lights",
                "64",
                "--radius",
                "4",
                "--backend",
                "deferred",
                "--shadows",
                shadows,
                "--compare",
                "--width",
                "48",
                "--height",
                "32",
                "--out",
                out.to_str().unwrap(),
            ],
            shadows,
        );
        assert_eq!(
            stdout.contains("BVH of"),
            shadows == "exact",
            "{shadows}: {stdout}"
        );
        assert!(psnr_vs_reference(&stdout) > 60.0, "{shadows}: {stdout}");
        assert_eq!(
            stdout.contains("shadow rays"),
            shadows == "exact",
            "{shadows}: {stdout}"
        );
        if shadows == "exact" {
            // `cull --shadows exact` counts the rays that deferred shading of its lists casts:
            // the same rays as the render's.
            let rays = number_after(&stdout, "shadow rays", "shadow rays");
            let culled = succeeds(
                &[
                    "cull",
                    "--scene",
                    "pillars",
                    "--lights",
                    "64",
                    "--radius",
                    "4",
                    "--shadows",
                    "exact",
                    "--width",
                    "48",
                    "--height",
                    "32",
                    "--out",
                    out.join("cull").to_str().unwrap(),
                ],
                "cull --shadows exact",
            );
            assert!(rays > 100.0, "{stdout}");
            assert_eq!(
                number_after(&culled, "shadow rays", "shadow rays"),
                rays,
                "{culled}"
            );
        }
        energy.push(number_after(
            &stdout,
            "vs infinite-range reference",
            "energy ",
        ));
    }
    assert!(
        energy[1] < energy[0] - 1e-3,
        "shadows must take light away: {energy:?}"
    );
    rejects(
        &["--shadows", "soft"],
        2,
        &["--shadows", "off", "exact", "stochastic"],
    );
    rejects_cmd(
        "cull",
        &["--shadows", "soft"],
        2,
        &["--shadows", "off", "exact", "stochastic"],
    );
}

/// `render --shadows stochastic --shadow-rays 3` casts three rays a lit pixel (at most three a
/// covered pixel), and `cull` counts the same; its image is scored
/// against the exact shadowed reference, near it but not equal. --shadow-rays out of 1 to 16,
/// or without --shadows stochastic, is an error naming the option.
#[test]
fn render_shadows_stochastic_casts_k_rays_a_pixel() {
    let tmp = tempfile::tempdir().unwrap();
    let args = |cmd: &'static str, out: &str| -> Vec<String> {
        let mut v: Vec<String> = [
            cmd,
            "--scene",
            "pillars",
            "--lights",
            "64",
            "--radius",
            "4",
            "--shadows",
            "stochastic",
            "--shadow-rays",
            "3",
            "--width",
            "48",
            "--height",
            "32",
            "--out",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        v.push(tmp.path().join(out).to_str().unwrap().to_owned());
        v
    };
    let mut render = args("render", "render");
    render.extend(["--backend", "deferred", "--compare"].map(String::from));
    let render: Vec<&str> = render.iter().map(String::as_str).collect();
    let stdout = succeeds(&render, "render --shadows stochastic");
    let per_pixel = number_after(&stdout, "shadow rays", "(");
    let rays = number_after(&stdout, "shadow rays", "shadow rays");
    assert!(
        per_pixel > 0.5 && per_pixel <= 3.0 && rays % 3.0 == 0.0,
        "{stdout}"
    );
    let flip = number_after(&stdout, "vs reference", "mean FLIP");
    assert!(
        flip > 1e-3 && flip < 0.2,
        "noisy but near the exact shadows: {stdout}"
    );
    let cull = args("cull", "cull");
    let cull: Vec<&str> = cull.iter().map(String::as_str).collect();
    let culled = succeeds(&cull, "cull --shadows stochastic");
    assert_eq!(
        number_after(&culled, "shadow rays", "shadow rays"),
        number_after(&stdout, "shadow rays", "shadow rays"),
        "{culled}"
    );
    rejects(
        &["--shadows", "stochastic", "--shadow-rays", "17"],
        2,
        &["--shadow-rays", "17"],
    );
    rejects(
        &["--shadows", "exact", "--shadow-rays", "4"],
        1,
        &["--shadow-rays 4", "--shadows stochastic"],
    );
    rejects_cmd("cull", &["--shadow-rays", "0"], 2, &["--shadow-rays", "0"]);
    rejects_cmd(
        "tune",
        &["--shadow-rays", "2"],
        1,
        &["--shadow-rays 2", "--shadows stochastic"],
    );
}

/// More lights than the device holds: an error stating the limit. On lavapipe the limit is its
/// loop limit (llvmpipe ends loops silently after 65,535 iterations per invocation, so it holds
/// 32,767 lights for the exact oracle's two loops); elsewhere the storage binding (64 bytes a
/// light). The storage check is also run on lavapipe with its loop limit set aside.
#[test]
fn more_lights_than_the_device_holds_is_an_error_stating_the_limit() {
    let mut ctx = manylights_gpu::GpuContext::new(&manylights_gpu::GpuOptions::default())
        .expect("a Vulkan adapter (lavapipe is enough)");
    let max = manylights_cull::max_lights(&ctx);
    let binding = ctx
        .limits
        .max_storage_buffer_binding_size
        .min(ctx.limits.max_buffer_size);
    let too_many = (u64::from(max) + 1).to_string();
    let expected: &[&str] = if ctx.loop_limit.is_some() {
        &[
            "light count",
            "exceeds the device limit",
            &max.to_string(),
            "llvmpipe",
        ]
    } else {
        &["light buffer bytes", "exceeds the device limit"]
    };
    rejects(&["--lights", &too_many], 1, expected);
    // The storage binding, through the library (a CLI run would hit the loop limit first).
    ctx.loop_limit = None;
    let mut scene = manylights_scene::procedural::ProceduralScene::from_name("atrium")
        .unwrap()
        .build()
        .unwrap();
    let light = manylights_scene::Light::point(glam::Vec3::ZERO, 1.0, glam::Vec3::ONE, 1.0);
    scene.lights = vec![light; (binding / 64 + 1) as usize];
    let err = manylights_gpu::GpuScene::upload(&ctx, &scene, &scene.camera, 8, 8)
        .err()
        .expect("over the binding limit");
    let msg = err.to_string();
    assert!(
        msg.contains("light buffer bytes") && msg.contains(&binding.to_string()),
        "{msg}"
    );
}

/// An output directory that cannot be written: a clear error naming it, exit code 1.
#[test]
fn unwritable_output_is_an_error() {
    let o = manylights(&[
        "render",
        "--lights",
        "4",
        "--width",
        "8",
        "--height",
        "8",
        "--out",
        "/proc/manylights-test/out",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("/proc/manylights-test/out"), "{stderr}");
    let exp = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quickstart.ron");
    let o = manylights(&[
        "run",
        exp.to_str().unwrap(),
        "--out",
        "/proc/manylights-test/run",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("/proc/manylights-test/run")
            && stderr.contains("cannot create the output directory"),
        "{stderr}"
    );
}

/// `-vv run` logs each stage of each cell and each GPU submission to stderr, and the run still
/// writes its results.
#[test]
fn verbose_run_logs_stages() {
    let tmp = tempfile::tempdir().unwrap();
    let exp = tmp.path().join("tiny.ron");
    std::fs::write(
        &exp,
        r#"Experiment(
    name: "tiny",
    description: "one deferred cell, for the log",
    config: Config(
        scene: Atrium(),
        lights: (generator: Uniform, count: 16, radius: Fixed(1.0), intensity: 1.0),
        resolution: (16, 8),
        frames: 1,
        warmup: 0,
        backend: Deferred,
    ),
)"#,
    )
    .unwrap();
    let out = tmp.path().join("out");
    let o = manylights(&[
        "-vv",
        "run",
        exp.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--no-report",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    for stage in [
        "scene built",
        "scene uploaded",
        "frame 0 rendered",
        "exact oracle",
        "reference rendered",
        "during=\"deferred lighting\"",
    ] {
        assert!(stderr.contains(stage), "no `{stage}` in the log:\n{stderr}");
    }
    assert!(out.join("results.csv").is_file());
}

#[test]
fn a_shader_dir_that_is_not_a_directory_is_a_clean_error() {
    let tmp = tempfile::tempdir().unwrap();
    let missing = tmp.path().join("no-such-shaders");
    let o = Command::new(env!("CARGO_BIN_EXE_manylights"))
        .args(["cull", "--width", "32", "--height", "16", "--lights", "4"])
        .arg("--out")
        .arg(tmp.path().join("out"))
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .env("MANYLIGHTS_SHADER_DIR", &missing)
        .output()
        .expect("run manylights");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "stderr: {stderr}");
    assert!(
        stderr.contains("MANYLIGHTS_SHADER_DIR") && stderr.contains("not a directory"),
        "{stderr}"
    );
    assert!(!tmp.path().join("out").exists());
}

/// `run` over a sweep with a cell that fails: every other cell runs, the results and the
/// report are written, and the command fails naming the cell and why.
#[test]
fn run_goes_on_past_a_failed_cell_and_exits_non_zero() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("fails.ron");
    std::fs::write(
        &file,
        r#"Experiment(name: "fails", config: Config(scene: Pillars(), lights: (count: 16, radius: Fixed(2.0)),
            resolution: (32, 18), frames: 1, warmup: 0),
            sweep: (scene: [Gltf("nope.glb"), Pillars()]))"#,
    )
    .unwrap();
    let out = tmp.path().join("out");
    let o = manylights(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("1 cells failed") && stderr.contains("nope.glb"),
        "{stderr}"
    );
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");
    assert!(out.join("report.md").is_file());
}

/// The bathroom of scenes/ at 1080p with the visibility buffer, with each of its passes: no NaN
/// pixel (a pixel's ray that ran along a sliver triangle the rasteriser covered met the
/// triangle's plane nowhere: `visibility_surface` divided by zero; before its fix one pixel with
/// the compute rasteriser, two with the raster pass, on lavapipe).
#[test]
fn the_bathroom_renders_no_nan_with_the_visibility_buffer() {
    let tmp = tempfile::tempdir().unwrap();
    for pass in ["compute", "raster"] {
        let out = tmp.path().join(pass);
        succeeds(
            &[
                "render",
                "--scene",
                "bathroom",
                "--backend",
                "visibility",
                "--visibility-pass",
                pass,
                "--strategy",
                "tiled-gather",
                "--lights",
                "100",
                "--radius",
                "1",
                "--width",
                "1920",
                "--height",
                "1080",
                "--out",
                out.to_str().unwrap(),
            ],
            pass,
        );
        assert!(out.join("visibility.png").is_file(), "{pass}");
    }
}

/// `cull --occlusion`: culling by visibility drops (bin, light) pairs in the city (lights of
/// 60 m among its buildings) and none the shadowed exact set needs; with z-binning it is an
/// error naming the option's field.
#[test]
fn cull_occlusion_drops_hidden_pairs_and_misses_none() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("cull");
    let base = [
        "cull",
        "--scene",
        "city",
        "--lights",
        "200",
        "--radius",
        "60",
        "--width",
        "96",
        "--height",
        "64",
        "--occlusion",
        "--out",
        out.to_str().unwrap(),
    ];
    let stdout = succeeds(&base, "cull --occlusion");
    let dropped = number_after(&stdout, "occluded pairs", "occluded pairs");
    assert!(dropped > 50.0, "{stdout}");
    assert_eq!(
        number_after(&stdout, "false negatives", "false negatives"),
        0.0,
        "{stdout}"
    );
    let mut zbin = base.to_vec();
    zbin.extend(["--strategy", "zbin"]);
    let o = manylights(&zbin);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && stderr.contains("occlusion") && stderr.contains("z-binning"),
        "{stderr}"
    );
}
