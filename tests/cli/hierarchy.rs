//! The lighting grid hierarchy from the command line: `--hierarchy ALPHA` with `--spacing H`
//! on `render` (with `--compare`) and `cull`, and their bad values.

use super::*;

/// Bad values name the option and what it accepts.
#[test]
fn bad_hierarchy_options_name_the_option() {
    for bad in ["-0.5", "0", "nan", "inf"] {
        rejects(
            &["--hierarchy", bad],
            2,
            &["--hierarchy", "a finite accuracy parameter above 0"],
        );
    }
    rejects(
        &["--hierarchy", "1", "--threshold", "0.1"],
        2,
        &["--threshold", "cannot be used with"],
    );
    rejects(
        &["--hierarchy", "1", "--stochastic", "1"],
        2,
        &["cannot be used with"],
    );
    rejects(
        &["--hierarchy", "1", "--spacing", "0"],
        2,
        &["--spacing", "a finite number above 0"],
    );
    rejects(
        &["--spacing", "0.5"],
        1,
        &["--spacing 0.5 without --hierarchy"],
    );
    rejects_cmd("cull", &["--spacing", "0.5"], 1, &["without --hierarchy"]);
    rejects(&["--sample-from", "1"], 2, &["--hierarchy"]);
    rejects(
        &["--hierarchy", "1", "--finest-nodes", "0"],
        2,
        &["--finest-nodes", "a finite number above 0"],
    );
    rejects(
        &["--finest-nodes", "0.25"],
        1,
        &["--finest-nodes 0.25 without --hierarchy"],
    );
    rejects(
        &["--hierarchy", "1", "--growth", "0.5"],
        1,
        &["lights.radius.growth = 0.5", "from 1"],
    );
    rejects(
        &["--growth", "1.2"],
        1,
        &["--growth 1.2 without --hierarchy"],
    );
    rejects(
        &["--hierarchy", "1", "--ramp", "2.5"],
        1,
        &["lights.radius.ramp = 2.5", "above 1"],
    );
    rejects(&["--ramp", "1.5"], 1, &["--ramp 1.5 without --hierarchy"]);
    rejects(
        &["--hierarchy", "1", "--spot-bins", "17"],
        1,
        &["lights.radius.spot_bins = 17", "to 16"],
    );
    rejects(
        &["--spot-bins", "3"],
        1,
        &["--spot-bins 3 without --hierarchy"],
    );
}

/// `render --hierarchy`: forward and deferred shade the hierarchy's lights as the brute-force
/// reference of the same hierarchy does, and a larger alpha comes nearer infinite range; with
/// sampled bands too, and with the authors' finest grid (`--finest-nodes 0.25`).
#[test]
fn render_hierarchy_matches_its_reference_and_nears_infinite_range() {
    let tmp = tempfile::tempdir().unwrap();
    let run = |alpha: &str, backend: &str, extra: &[&str]| {
        let out = tmp.path().join(format!("r{alpha}{backend}{}", extra.len()));
        let mut args = vec![
            "render",
            "--scene",
            "atrium",
            "--lights",
            "600",
            "--intensity",
            "1",
            "--generator",
            "uniform",
            "--hierarchy",
            alpha,
            "--spacing",
            "0.25",
            "--backend",
            backend,
            "--width",
            "48",
            "--height",
            "32",
            "--compare",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let stdout = succeeds(&args, backend);
        assert!(
            stdout.contains(&format!(
                "lighting grid hierarchy: alpha {alpha}, finest spacing"
            )),
            "{stdout}"
        );
        // More than the point lights: at least one level of aggregates.
        let levels = number_after(&stdout, "lighting grid hierarchy", "m, ");
        assert!(levels >= 2.0, "{stdout}");
        let psnr = number_after(&stdout, "vs reference (same hierarchy)", "PSNR");
        assert!(psnr > 60.0, "{stdout}");
        (
            number_after(&stdout, "vs infinite-range reference", "RMSE"),
            stdout,
        )
    };
    let (coarse, _) = run("1", "forward", &[]);
    let (fine, _) = run("3", "deferred", &[]);
    assert!(
        fine < coarse,
        "RMSE against infinite range: alpha 1 {coarse}, alpha 3 {fine}"
    );
    // Sampled bands: the backend still equals the reference over the same draws.
    let (_, sampled) = run("1", "deferred", &["--sample-from", "0"]);
    assert!(sampled.contains("bands sampled from level 0"), "{sampled}");
    // The finest grid's rule: the default, and the authors' quarter.
    let (_, default) = run("1.5", "deferred", &[]);
    assert!(
        default.contains("the finest grid at most 2 nodes a point light"),
        "{default}"
    );
    // Spots, in the point lights' nodes (no bins) and in direction bins: still the reference.
    let (_, spots) = run("1.5", "deferred", &["--spot-fraction", "0.3"]);
    assert!(spots.contains("spots in 0 direction bins"), "{spots}");
    let (_, binned) = run(
        "1.5",
        "forward",
        &["--spot-fraction", "0.3", "--spot-bins", "3"],
    );
    let bins = number_after(&binned, "lighting grid hierarchy", "spots in");
    assert!(bins >= 2.0, "{binned}");
    let (_, quarter) = run("1.5", "deferred", &["--finest-nodes", "0.25"]);
    assert!(
        quarter.contains("the finest grid at most 0.25 nodes a point light"),
        "{quarter}"
    );
    // A quarter of a node a light keeps a coarser finest grid.
    let spacing = |out: &str| number_after(out, "lighting grid hierarchy", "finest spacing");
    assert!(
        spacing(&quarter) > spacing(&default),
        "finest spacing {} by the quarter rule, {} by default",
        spacing(&quarter),
        spacing(&default)
    );
}

/// `cull --hierarchy`: every level's lights, culled by each strategy, with no false negative
/// against their bands (cull fails on one).
#[test]
fn cull_hierarchy_has_no_false_negatives() {
    let tmp = tempfile::tempdir().unwrap();
    for strategy in ["tiled-scatter", "depth-mask", "clustered", "zbin"] {
        let out = tmp.path().join(strategy);
        let stdout = succeeds(
            &[
                "cull",
                "--scene",
                "atrium",
                "--lights",
                "600",
                "--generator",
                "uniform",
                "--hierarchy",
                "1",
                "--strategy",
                strategy,
                "--width",
                "48",
                "--height",
                "32",
                "--out",
                out.to_str().unwrap(),
            ],
            strategy,
        );
        assert!(stdout.contains("false negatives         0"), "{stdout}");
        assert!(
            stdout.contains("lighting grid hierarchy: alpha 1,"),
            "{stdout}"
        );
    }
}
