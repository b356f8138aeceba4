//! `tune`.

use super::*;

/// `tune` tries every candidate on this device, ranks the conservative ones by the whole frame
/// in steady state (with `--rank cull-shade` by culling and shading together, the same cells
/// ranked again), and writes the best as an experiment file that `run` reproduces; a budget
/// that leaves no candidate is an error that says so.
#[test]
fn tune_ranks_candidates_and_writes_the_best_as_an_experiment() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("tune");
    let small = [
        "--scene", "atrium", "--lights", "48", "--width", "48", "--height", "32", "--frames", "1",
        "--warmup", "0",
    ];
    let mut args = vec!["tune", "--out", out.to_str().unwrap(), "--budget-s", "600"];
    args.extend_from_slice(&small);
    let o = manylights(&args);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    // Every candidate finished (a generous budget) and none of them drops a light here.
    let ranked: Vec<&str> = stdout
        .lines()
        .filter(|l| l.trim_start().starts_with(|c: char| c.is_ascii_digit()))
        .collect();
    assert_eq!(
        ranked.len(),
        manylights_lab::tune::candidates().len(),
        "{stdout}"
    );
    assert!(!stdout.contains("untried"), "{stdout}");
    // Ranked by the frame (the first time), fastest first; with --rank cull-shade by culling
    // and shading (the second).
    let times = |stdout: &str, column: usize| -> Vec<f64> {
        stdout
            .lines()
            .filter(|l| l.trim_start().starts_with(|c: char| c.is_ascii_digit()))
            .map(|l| {
                let parts: Vec<&str> = l.split(" ms").collect();
                parts[column]
                    .split_whitespace()
                    .last()
                    .unwrap()
                    .parse()
                    .unwrap()
            })
            .collect()
    };
    let frames = times(&stdout, 0);
    assert!(frames.windows(2).all(|w| w[0] <= w[1]), "{stdout}");
    assert!(
        stdout.contains("best: deferred + ") && stdout.contains("gpu_ms_frame_steady"),
        "{stdout}"
    );
    let mut again_args = args.clone();
    again_args.extend_from_slice(&["--rank", "cull-shade"]);
    let o = manylights(&again_args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let by_cull = String::from_utf8_lossy(&o.stdout).into_owned();
    let cull_shade = times(&by_cull, 1);
    assert_eq!(cull_shade.len(), frames.len(), "{by_cull}");
    assert!(cull_shade.windows(2).all(|w| w[0] <= w[1]), "{by_cull}");
    assert!(by_cull.contains("gpu_ms_cull_shade"), "{by_cull}");
    let best = out.join("best.ron");
    let (e, _) = manylights_lab::Experiment::load(&best).unwrap();
    assert_eq!(e.cells().len(), 1);
    let again = tmp.path().join("again");
    let o = manylights(&[
        "run",
        best.to_str().unwrap(),
        "--out",
        again.to_str().unwrap(),
        "--no-report",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.join("report.html").is_file() && out.join("results.csv").is_file());
    // No time for any candidate.
    let none = tmp.path().join("none");
    let mut args = vec!["tune", "--out", none.to_str().unwrap(), "--budget-s", "0"];
    args.extend_from_slice(&small);
    let o = manylights(&args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("no candidate was eligible within the budget of 0 s")
            && stderr.contains("raise --budget-s"),
        "{stderr}"
    );
}

/// `tune --shadows exact --max-error F` (and `stochastic --shadow-rays 2`): every candidate
/// casts shadows and is held to mean FLIP against the shadowed infinite-range reference (the
/// table's last column is it), only those within F ranked; the best has the same shadows.
#[test]
fn tune_with_shadows_holds_candidates_to_the_shadowed_light() {
    for (mode, rays) in [("exact", None), ("stochastic", Some(2))] {
        tune_with_shadows(mode, rays);
    }
}

fn tune_with_shadows(mode: &str, rays: Option<u32>) {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("tune");
    let rays_arg = rays.map(|k| k.to_string());
    let mut args = vec![
        "tune",
        "--out",
        out.to_str().unwrap(),
        "--max-error",
        "0.6",
        "--shadows",
        mode,
        "--scene",
        "atrium",
        "--lights",
        "96",
        "--width",
        "40",
        "--height",
        "24",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--thresholds",
        "1",
        "--errors",
        "0.5",
        "--alphas",
        "1",
        "--spacing",
        "0.5",
    ];
    if let Some(k) = &rays_arg {
        args.extend(["--shadow-rays", k]);
    }
    let o = manylights(&args);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("FLIP shad"), "{stdout}");
    let rows = manylights_lab::results::load_rows(&out).unwrap();
    assert!(rows.iter().all(|r| r.shadow.shadows == mode), "{mode}");
    let ranked: Vec<f64> = stdout
        .lines()
        .filter(|l| l.trim_start().starts_with(|c: char| c.is_ascii_digit()))
        .map(|l| l.split_whitespace().last().unwrap().parse().unwrap())
        .collect();
    assert!(!ranked.is_empty(), "{stdout}");
    for flip in &ranked {
        assert!(*flip <= 0.6, "{stdout}");
        // Each printed error is a row's error against the shadowed light.
        assert!(
            rows.iter().any(|r| r
                .shadow
                .flip_mean_shadowed
                .is_some_and(|f| (f - flip).abs() < 1e-4)),
            "{flip} is no row's flip_mean_shadowed"
        );
    }
    let (e, _) = manylights_lab::Experiment::load(&out.join("best.ron")).unwrap();
    assert!(e.config.shadows.casts(), "the best casts shadows");
    assert_eq!(e.config.shadows.rays(), rays, "{mode}: the best's rays");
}

/// `tune --max-error F`: light ranges are candidates too, every candidate is scored against
/// the infinite-range reference, and only those within mean FLIP F are ranked; the best is
/// written with its radius rule; the lighting grid hierarchy is among them (--alphas, with
/// --growths and --ramps). A budget none reaches is an error naming the lowest error; a budget
/// that is not a positive number is a usage error, a growth or ramp out of range an error
/// naming it before any GPU work.
#[test]
fn tune_max_error_ranks_only_what_is_accurate_enough_against_infinite_range() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("tune");
    let small = [
        "--scene",
        "atrium",
        "--lights",
        "96",
        "--width",
        "48",
        "--height",
        "32",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--thresholds",
        "1",
        "--errors",
        "0.5",
        "--alphas",
        "1",
        "--growths",
        "1.15",
        "--ramps",
        "1.25",
        "--spacing",
        "0.5",
    ];
    let mut args = vec!["tune", "--out", out.to_str().unwrap(), "--max-error", "0.6"];
    args.extend_from_slice(&small);
    let o = manylights(&args);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ranked: Vec<&str> = stdout
        .lines()
        .filter(|l| l.trim_start().starts_with(|c: char| c.is_ascii_digit()))
        .collect();
    assert!(!ranked.is_empty(), "{stdout}");
    for l in &ranked {
        let flip: f64 = l.split_whitespace().last().unwrap().parse().unwrap();
        assert!(flip <= 0.6, "{l}");
    }
    // The radius cut-off of threshold 1 keeps a fraction of the light: rejected for its error.
    assert!(
        stdout
            .lines()
            .any(|l| l.starts_with("rejected:") && l.contains("above --max-error 0.6")),
        "{stdout}"
    );
    let (e, _) = manylights_lab::Experiment::load(&out.join("best.ron")).unwrap();
    let rows = manylights_lab::results::load_rows(&out).unwrap();
    let best = rows.iter().find(|r| r.id == e.cells()[0].id()).unwrap();
    assert!(best.flip_mean_infinite.unwrap() <= 0.6);
    assert!(
        ["stochastic", "hierarchy"].contains(&best.radius_rule.as_str()),
        "{stdout}"
    );
    // The lighting grid hierarchy is a candidate with every strategy, built on the GPU and
    // scored against infinite range, its build counted in its time.
    let hier: Vec<_> = rows
        .iter()
        .filter(|r| r.radius_rule == "hierarchy")
        .collect();
    assert_eq!(
        hier.len(),
        rows.len() / 3,
        "one candidate in three is the hierarchy's: {stdout}"
    );
    for r in &hier {
        assert!(r.gpu_ms_hierarchy.is_some_and(|t| t > 0.0), "{}", r.cell);
        assert!(r.flip_mean_infinite.is_some(), "{}", r.cell);
        assert_eq!(r.false_negatives, Some(0), "{}", r.cell);
    }
    assert!(
        stdout
            .lines()
            .any(|l| l.contains(" hierarchy=1/h0.5/g1.15/c1.25")),
        "{stdout}"
    );
    // None within a budget no candidate reaches (the same cells, resumed).
    let mut args = vec![
        "tune",
        "--out",
        out.to_str().unwrap(),
        "--max-error",
        "0.001",
    ];
    args.extend_from_slice(&small);
    let o = manylights(&args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("the lowest mean FLIP against infinite range was")
            && stderr.contains("--max-error 0.001"),
        "{stderr}"
    );
    for (option, bad, field) in [("--growths", "1.15,5", "growth"), ("--ramps", "1", "ramp")] {
        let o = manylights(&[
            "tune",
            "--scene",
            "atrium",
            "--max-error",
            "0.5",
            option,
            bad,
        ]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{option} {bad}: {stderr}");
        assert!(
            stderr.contains(option) && stderr.contains(&format!("lights.radius.{field}")),
            "{stderr}"
        );
        assert!(
            !stderr.contains("adapter:"),
            "checked before the GPU: {stderr}"
        );
    }
    for bad in ["0", "-1", "nan"] {
        let o = manylights(&["tune", "--scene", "atrium", "--max-error", bad]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{bad}: {stderr}");
        assert!(
            stderr.contains("--max-error") && stderr.contains("above 0"),
            "{stderr}"
        );
    }
}
