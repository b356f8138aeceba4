//! MSAA in experiments (`msaa`): cells at 1 and 4 samples a pixel, forward over clusters and
//! gather and naive forward, end to end: the references at the same count, list metrics over
//! every covered sample, the targets' bytes; and the values an experiment cannot have.

use std::path::Path;

use manylights_lab::Experiment;
use manylights_lab::runner::run_parsed;

use super::{common, opts};

#[test]
fn msaa_cells_resolve_match_their_reference_and_count_every_sample() {
    let ctx = common::gpu();
    let src = r#"Experiment(
        name: "msaa",
        config: Config(
            scene: Pillars(),
            lights: (count: 128, radius: Fixed(2.0), intensity: 2.0),
            resolution: (64, 36),
            frames: 1,
            warmup: 0,
        ),
        sweep: (
            msaa: [1, 4],
            variants: [
                (label: "clusters", backend: Forward, strategy: Clustered(tile_size: 16, slices: 16)),
                (label: "deferred", backend: Deferred, strategy: ZBin(tile_size: 16)),
                (label: "gather", backend: Forward, strategy: TiledGather(tile_size: 8)),
                (label: "deferred-gather", backend: Deferred, strategy: TiledGather(tile_size: 8)),
                (label: "naive", backend: NaiveForward),
            ],
        ),
    )"#;
    let e = Experiment::parse(src, Path::new("msaa.ron")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let s = run_parsed(&ctx, &e, src, Path::new("."), tmp.path(), &opts()).unwrap();
    assert_eq!(s.rows.len(), 10);
    let pixels = 64 * 36;
    let mut needed = Vec::new();
    for r in &s.rows {
        let what = &r.cell;
        assert_eq!(
            r.false_negatives,
            (r.backend != "naive_forward").then_some(0),
            "{what}"
        );
        assert_eq!(r.dropped_lights, 0, "{what}");
        // Against the reference at the same sample count: forward's tolerance (tests/shade), as
        // PSNR over this scene's peak, but for forward and naive forward with MSAA, which light
        // an edge's fragments at their centroids where the reference lights each sample
        // (tests/shade/msaa.rs): a looser bound there.
        let forward = r.backend == "forward";
        if r.backend != "deferred" && r.msaa > 1 {
            assert!(
                r.flip_mean.is_some_and(|f| f < 0.05),
                "{what}: {:?}",
                r.flip_mean
            );
        } else {
            assert!(
                r.psnr_db.is_some_and(|p| p > 80.0),
                "{what}: {:?}",
                r.psnr_db
            );
        }
        let bytes = match (r.msaa, r.backend.as_str()) {
            (1, _) => 0,
            // Forward and deferred with MSAA also the lookup bounds culling reads: two f32 a
            // pixel.
            (4, "forward") => pixels * 4 * (4 + 16 + 8) + pixels * 8,
            (4, "deferred") => pixels * 4 * 24 + pixels * 8,
            (4, _) => pixels * 4 * (4 + 16),
            (n, _) => panic!("{what}: msaa {n}"),
        };
        assert_eq!(r.msaa_target_bytes, bytes, "{what}");
        assert_eq!(
            r.params.ends_with(";msaa=4"),
            r.msaa == 4,
            "{what}: {}",
            r.params
        );
        if forward {
            let passes: Vec<&String> = r.passes.keys().collect();
            assert_eq!(
                r.passes.contains_key("prepass.depth_bounds"),
                r.msaa == 4,
                "{what}: {passes:?}"
            );
            assert!(r.gpu_ms_cull_shade.is_some(), "{what}");
        }
        needed.push((r.msaa, r.lights_needed_per_pixel_mean.unwrap()));
    }
    // The report compares forward with deferred at 4 samples over the strategy they share.
    manylights_lab::report::write_report(tmp.path()).unwrap();
    let report = std::fs::read_to_string(tmp.path().join("report.md")).unwrap();
    assert!(
        report.contains("MSAA 4 without glass, tiled_gather:")
            && report.contains("One sample without glass, tiled_gather:")
            && report.contains("Multisampled targets")
            && report.contains("in steady state (`gpu_ms_frame_steady`)"),
        "{report}"
    );
    // The exact sets are the samples', whatever the strategy: one mean a sample count.
    for &(n, m) in &needed {
        let first = needed.iter().find(|x| x.0 == n).unwrap().1;
        assert!(
            (m - first).abs() <= 1e-9 * first.max(1.0),
            "msaa {n}: {needed:?}"
        );
    }
}

#[test]
fn msaa_values_an_experiment_cannot_have_are_errors() {
    let base = |extra: &str| {
        format!(
            "Experiment(name: \"bad\", config: Config(scene: Pillars(), resolution: (32, 18), {extra}))"
        )
    };
    for (extra, expect) in [
        ("msaa: 3", "msaa = 3: 1, 2, 4, 8 or 16"),
        ("msaa: 0", "msaa = 0"),
        (
            "backend: DeferredStoredPosition, msaa: 2",
            "deferred_stored_position: the stored position takes no MSAA",
        ),
        ("export: true, msaa: 4", "exports hold one depth a pixel"),
    ] {
        let src = base(extra);
        let e = Experiment::parse(&src, Path::new("bad.ron"))
            .err()
            .unwrap_or_else(|| panic!("{extra} accepted"))
            .to_string();
        assert!(
            e.contains("bad.ron:1:") && e.contains(expect),
            "{extra}: {e}"
        );
    }
    // Exports hold one depth a pixel: not glass.
    let src =
        "Experiment(name: \"bad\", config: Config(scene: Pillars(glass: true), export: true))";
    let e = Experiment::parse(src, Path::new("bad.ron"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("pillars+glass") && e.contains("export"), "{e}");
    // A swept count is checked too.
    let src = "Experiment(name: \"bad\", config: Config(scene: Pillars()), sweep: (msaa: [1, 5]))";
    let e = Experiment::parse(src, Path::new("bad.ron"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("msaa = 5"), "{e}");
}
