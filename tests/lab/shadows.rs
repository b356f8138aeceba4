//! Shadows in experiments (`shadows: Exact`): cells with and without shadows, end to end: the
//! BVH built for the cell, `shadows=exact` in its params, no false negative, the frame within
//! tolerance of its shadowed reference, and darker than the unshadowed cell's; the shadow
//! columns (the shadowed infinite-range reference's error, rays, their cost).

use std::path::Path;

use manylights_lab::Experiment;
use manylights_lab::runner::run_parsed;

use super::{common, opts};

#[test]
fn shadowed_cells_match_their_shadowed_reference() {
    let ctx = common::gpu();
    let src = r#"Experiment(
        name: "shadows",
        config: Config(
            scene: Pillars(),
            lights: (count: 128, radius: Fixed(4.0), intensity: 2.0),
            resolution: (64, 36),
            frames: 1,
            warmup: 0,
            shadowed_reference: true,
        ),
        sweep: (
            variants: [
                (label: "off", backend: Deferred, strategy: ZBin(tile_size: 16)),
                (label: "exact", backend: Deferred, strategy: ZBin(tile_size: 16), shadows: Exact),
                (label: "exact-forward", backend: Forward, strategy: Clustered(tile_size: 16, slices: 16), shadows: Exact),
                (label: "exact-visibility", backend: Visibility, strategy: TiledGather(tile_size: 8), shadows: Exact),
            ],
        ),
    )"#;
    let e = Experiment::parse(src, Path::new("shadows.ron")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let s = run_parsed(&ctx, &e, src, Path::new("."), tmp.path(), &opts()).unwrap();
    assert_eq!(s.rows.len(), 4);
    for r in &s.rows {
        let what = &r.cell;
        assert_eq!(r.false_negatives, Some(0), "{what}");
        assert_eq!(
            r.params.contains("shadows=exact"),
            r.cell.contains("exact"),
            "{what}: {}",
            r.params
        );
        // Against its own (shadowed, for shadowed cells) reference: the backends' tolerance.
        assert!(
            r.psnr_db.is_some_and(|p| p > 60.0) && r.flip_mean.is_some_and(|f| f < 1e-3),
            "{what}: PSNR {:?}, FLIP {:?}",
            r.psnr_db,
            r.flip_mean
        );
    }
    // The unshadowed infinite-range reference is brighter than the shadowed frames: their
    // energy against it is lower than the unshadowed frame's.
    let energy = |label: &str| {
        s.rows
            .iter()
            .find(|r| r.cell.contains(&format!("variant={label}")))
            .and_then(|r| r.energy_error_infinite)
            .unwrap_or_else(|| panic!("{label}: no energy against infinite range"))
    };
    assert!(
        energy("exact") < energy("off") - 1e-3,
        "shadows must take light away: exact {} off {}",
        energy("exact"),
        energy("off")
    );
    shadow_columns(&s.rows);
}

/// Light leaking through walls, measured: in the atrium (whose bays' walls stand between the
/// lights and much of the floor) at long ranges, the unshadowed frame is brighter than the
/// shadowed infinite-range reference, and further from it than the shadowed frame.
#[test]
fn unshadowed_frames_leak_light_through_walls() {
    let ctx = common::gpu();
    let src = r#"Experiment(
        name: "leaks",
        config: Config(
            scene: Atrium(bays: 2),
            lights: (generator: Uniform, count: 200, seed: 3, radius: Fixed(30.0), intensity: 2.0),
            resolution: (48, 32),
            frames: 1,
            warmup: 0,
            backend: Deferred,
            strategy: ZBin(tile_size: 16),
            shadowed_reference: true,
        ),
        sweep: (
            variants: [(label: "off"), (label: "exact", shadows: Exact)],
        ),
    )"#;
    let e = Experiment::parse(src, Path::new("leaks.ron")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let s = run_parsed(&ctx, &e, src, Path::new("."), tmp.path(), &opts()).unwrap();
    manylights_lab::report::write_report(tmp.path()).unwrap();
    let md = std::fs::read_to_string(tmp.path().join("report.md")).unwrap();
    assert!(
        md.contains("| FLIP shadowed | energy shadowed | rays/px | shadow ms | Grays/s |"),
        "the report's table has the shadow columns"
    );
    let [off, exact] = [0, 1].map(|i| &s.rows[i].shadow);
    let leak = off.energy_error_shadowed.unwrap();
    assert!(
        leak > exact.energy_error_shadowed.unwrap() + 0.05 && leak > 0.05,
        "light must leak through walls without shadows: off {off:?}, exact {exact:?}"
    );
    assert!(
        off.flip_mean_shadowed > exact.flip_mean_shadowed,
        "off {off:?}, exact {exact:?}"
    );
}

/// The shadow columns of the cells above: every cell scored against the shadowed light (the
/// unshadowed one too: `shadowed_reference`), the reference rendered once and then taken from
/// the run's cache; the shadowed cells' rays counted, the same rays in every
/// backend over conservative lists, and their cost timed.
fn shadow_columns(rows: &[manylights_lab::results::Row]) {
    let row = |label: &str| {
        rows.iter()
            .find(|r| r.cell.ends_with(&format!("variant={label}")))
            .unwrap_or_else(|| panic!("no cell {label}"))
    };
    for r in rows {
        let (what, sh) = (&r.cell, &r.shadow);
        assert_eq!(
            sh.shadows,
            if what.contains("exact") {
                "exact"
            } else {
                "off"
            },
            "{what}"
        );
        assert!(sh.flip_mean_shadowed.is_some(), "{what}: {sh:?}");
        assert_eq!(
            sh.reference_shadowed_cached,
            Some(r.index > 0),
            "{what}: the shadowed reference is rendered once a view"
        );
        match sh.shadows.as_str() {
            "exact" => {
                let rays = sh.rays_per_pixel.expect("rays counted");
                assert!(rays > 1.0, "{what}: {rays} rays a pixel");
                assert!(sh.gpu_ms_shadow.is_some(), "{what}: {sh:?}");
            }
            _ => assert!(sh.rays_per_pixel.is_none() && sh.gpu_ms_shadow.is_none()),
        }
    }
    let exact = &row("exact").shadow;
    let rays = exact.rays_per_pixel.unwrap();
    for label in ["exact-forward", "exact-visibility"] {
        let other = row(label).shadow.rays_per_pixel.unwrap();
        assert!(
            (other - rays).abs() <= 2e-3 * rays,
            "{label}: {other} rays a pixel, deferred {rays}"
        );
    }
}

/// Shadows with every light model and material model: the hierarchy's lights (each level's
/// aggregate shadowed from its position) and stochastic ranges, over five material models,
/// forward, deferred and the visibility buffer: no false negative, and each cell within the
/// backends' tolerance of its own shadowed reference (the same lights, ranges and draws).
#[test]
fn shadows_work_with_every_light_and_material_model() {
    let ctx = common::gpu();
    let src = r#"Experiment(
        name: "shadows-models",
        config: Config(
            scene: Atrium(bays: 2),
            lights: (generator: Uniform, count: 300, seed: 4, intensity: 2.0, spot_fraction: 0.2),
            materials: [BlinnPhong, Ggx, Sheen, ClearCoat, Wrap],
            resolution: (64, 40),
            frames: 1,
            warmup: 0,
            shadows: Exact,
        ),
        sweep: (
            radius: [Hierarchy(alpha: 1.0, spacing: 0.25), Stochastic(error: 0.5, seeds: 1)],
            variants: [
                (label: "forward-gather", backend: Forward, strategy: TiledGather(tile_size: 8)),
                (label: "deferred-zbin", backend: Deferred, strategy: ZBin(tile_size: 8)),
                (label: "visibility-clusters", backend: Visibility, strategy: Clustered(tile_size: 16, slices: 16)),
            ],
        ),
    )"#;
    let e = Experiment::parse(src, Path::new("shadows-models.ron")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let s = run_parsed(&ctx, &e, src, Path::new("."), tmp.path(), &opts()).unwrap();
    assert_eq!(s.rows.len(), 6);
    for r in &s.rows {
        let cell = &r.cell;
        assert!(r.params.contains("shadows=exact"), "{cell}: {}", r.params);
        assert_eq!(r.false_negatives, Some(0), "{cell}");
        let flip = r.flip_mean.expect("its shadowed reference");
        let tolerance = if r.backend == "forward" { 1e-6 } else { 1e-3 };
        assert!(
            flip <= tolerance,
            "{cell}: mean FLIP {flip} against its reference"
        );
    }
}

/// Stochastic shadows in a run: `shadows=stochastic;shadow_rays=K` in the params, K rays a lit
/// pixel counted, the noise over the seeds measured against the shadowed light and falling with
/// K, as the error does, and with four frames accumulated a seed; the shadowed figure draws
/// each K as a family of its own; bad values are errors naming the field.
#[test]
fn stochastic_shadow_cells_measure_their_noise() {
    let ctx = common::gpu();
    let src = r#"Experiment(
        name: "stochastic-shadows",
        config: Config(
            scene: Atrium(bays: 2),
            lights: (generator: Uniform, count: 200, seed: 3, radius: Fixed(30.0), intensity: 2.0),
            resolution: (48, 32),
            frames: 1,
            warmup: 0,
            backend: Deferred,
            strategy: ZBin(tile_size: 16),
        ),
        sweep: (
            variants: [
                (label: "exact", shadows: Exact),
                (label: "rays-1", shadows: Stochastic(rays: 1, seeds: 3)),
                (label: "rays-8", shadows: Stochastic(rays: 8, seeds: 3)),
                (label: "rays-1-x4", shadows: Stochastic(rays: 1, accumulate: 4, seeds: 3)),
            ],
        ),
    )"#;
    let e = Experiment::parse(src, Path::new("stochastic-shadows.ron")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let s = run_parsed(&ctx, &e, src, Path::new("."), tmp.path(), &opts()).unwrap();
    let [exact, one, eight, accumulated] = [0, 1, 2, 3].map(|i| &s.rows[i]);
    assert_eq!(accumulated.accumulate, Some(4), "{}", accumulated.params);
    assert!(
        accumulated.params.contains("shadow_accumulate=4"),
        "{}",
        accumulated.params
    );
    assert!(
        accumulated.noise_infinite < one.noise_infinite,
        "four frames a seed: noise {:?}, one frame {:?}",
        accumulated.noise_infinite,
        one.noise_infinite
    );
    assert_eq!(exact.shadow.shadows, "exact");
    for (r, k) in [(one, 1.0), (eight, 8.0)] {
        let what = &r.cell;
        assert_eq!(r.shadow.shadows, "stochastic", "{what}");
        assert!(
            r.params
                .contains(&format!("shadows=stochastic;shadow_rays={k}"))
                && r.params.contains("shadow_seeds=3"),
            "{what}: {}",
            r.params
        );
        let rays = r.shadow.rays_per_pixel.unwrap();
        assert!(rays <= k && rays >= 0.9 * k, "{what}: {rays} rays a pixel");
        assert_eq!(r.seeds, Some(3), "{what}");
        assert!(
            r.noise_infinite.is_some_and(|n| n > 0.0),
            "{what}: {:?}",
            r.noise_infinite
        );
        assert!(r.shadow.gpu_ms_shadow.is_some(), "{what}");
    }
    assert!(
        exact.shadow.rays_per_pixel.unwrap() > 8.0,
        "{:?}",
        exact.shadow
    );
    assert!(
        eight.noise_infinite < one.noise_infinite,
        "noise: 8 rays {:?}, 1 ray {:?}",
        eight.noise_infinite,
        one.noise_infinite
    );
    assert!(
        eight.shadow.flip_mean_shadowed < one.shadow.flip_mean_shadowed,
        "8 rays {:?}, 1 ray {:?}",
        eight.shadow,
        one.shadow
    );
    manylights_lab::report::write_report(tmp.path()).unwrap();
    let svg = std::fs::read_to_string(tmp.path().join("figures/frame_shadowed.svg")).unwrap();
    assert!(svg.contains("1 ray: ") && svg.contains("8 rays: ") && svg.contains("shadowed: "));

    for (value, want) in [
        (
            "Stochastic(rays: 17)",
            "shadows.rays = 17: stochastic shadows cast 1 to 16",
        ),
        (
            "Stochastic(rays: 2, accumulate: 1)",
            "shadows.accumulate = 1",
        ),
        ("Stochastic(rays: 2, seeds: 0)", "shadows.seeds = 0"),
    ] {
        let bad = src.replace("Stochastic(rays: 1, seeds: 3)", value);
        let err = Experiment::parse(&bad, Path::new("bad.ron"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("bad.ron") && err.contains(want),
            "{value}: {err}"
        );
    }
}

/// Culling by visibility in an experiment (`occlusion: true`): the city at 200 lights of 60 m,
/// tiled gather and clusters, each with and without it: `occlusion=true` in the params, pairs
/// dropped (`occluded_pairs`), no false negative against the shadowed exact set, fewer lights a
/// pixel and the same image as the cell without it; with z-binning a parse error naming the
/// field.
#[test]
fn occlusion_cells_drop_hidden_pairs_and_keep_the_image() {
    let ctx = common::gpu();
    let src = r#"Experiment(
        name: "occlusion",
        config: Config(
            scene: City(),
            lights: (count: 200, radius: Fixed(60.0), intensity: 2.0),
            resolution: (96, 64),
            frames: 1,
            warmup: 0,
            backend: Deferred,
            shadows: Exact,
            exact_stride: 1,
        ),
        sweep: (
            strategy: [TiledGather(tile_size: 8), Clustered(tile_size: 16, slices: 16)],
            variants: [
                (label: "lists"),
                (label: "occlusion", occlusion: Some(true)),
            ],
        ),
    )"#;
    let e = Experiment::parse(src, Path::new("occlusion.ron")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let s = run_parsed(&ctx, &e, src, Path::new("."), tmp.path(), &opts()).unwrap();
    assert_eq!(s.rows.len(), 4);
    for pair in s.rows.chunks(2) {
        let (off, on) = (&pair[0], &pair[1]);
        assert!(
            on.params.contains("occlusion=true") && !off.params.contains("occlusion"),
            "{}",
            on.params
        );
        assert_eq!(off.shadow.occluded_pairs, None);
        let dropped = on.shadow.occluded_pairs.expect("occluded_pairs");
        assert!(dropped > 0, "{}: nothing dropped", on.cell);
        assert_eq!(on.false_negatives, Some(0), "{}", on.cell);
        assert!(
            on.lights_per_pixel_mean < off.lights_per_pixel_mean,
            "{} evaluates no fewer",
            on.cell
        );
        let (f_on, f_off) = (on.flip_mean.unwrap(), off.flip_mean.unwrap());
        assert!(
            (f_on - f_off).abs() < 1e-3,
            "{}: the image changed with occlusion: FLIP {f_on} against {f_off}",
            on.cell
        );
    }
    let bad = src.replace(
        "TiledGather(tile_size: 8), Clustered(tile_size: 16, slices: 16)",
        "ZBin(tile_size: 16)",
    );
    let err = Experiment::parse(&bad, Path::new("occlusion.ron"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("occlusion") && err.contains("ZBin"), "{err}");
}

/// The shadowed infinite-range reference estimated (`shadowed_reference_rays`): the same
/// unshadowed cell scored against the exact reference and against the estimate with 64 rays a
/// pixel agrees within its standard error (`shadowed_reference_se`, reported only for the
/// estimate, positive and small); the estimate's halves are cached in the run folder, so the
/// second cell of the view uses them; bad values are errors naming the field.
#[test]
fn the_shadowed_reference_estimate_scores_as_the_exact_one() {
    let ctx = common::gpu();
    let src = |rays: &str| {
        format!(
            r#"Experiment(
        name: "estimate",
        config: Config(
            scene: Atrium(),
            lights: (count: 96, radius: Fixed(3.0), intensity: 2.0),
            resolution: (48, 27),
            frames: 1,
            warmup: 0,
            shadowed_reference: true,
            {rays}
            backend: Deferred,
            strategy: ZBin(tile_size: 16),
        ),
        sweep: (strategy: [ZBin(tile_size: 16), TiledGather(tile_size: 16)]),
    )"#
        )
    };
    let run = |rays: &str, dir: &Path| {
        let text = src(rays);
        let e = Experiment::parse(&text, Path::new("estimate.ron")).unwrap();
        let s = run_parsed(&ctx, &e, &text, Path::new("."), dir, &opts()).unwrap();
        assert_eq!(s.rows.len(), 2);
        s.rows
    };
    let tmp = tempfile::tempdir().unwrap();
    let exact = run("", &tmp.path().join("exact"));
    let estimates = run(
        "shadowed_reference_rays: Some(64),",
        &tmp.path().join("estimate"),
    );
    let (exact, estimated) = (&exact[0], &estimates[0]);
    assert_eq!(exact.shadow.shadowed_reference_se, None);
    let se = estimated
        .shadow
        .shadowed_reference_se
        .expect("shadowed_reference_se");
    let (a, b) = (
        exact.shadow.flip_mean_shadowed.unwrap(),
        estimated.shadow.flip_mean_shadowed.unwrap(),
    );
    println!("exact {a}, estimated {b}, se {se}");
    assert!(se > 0.0 && se < 0.05, "standard error {se}");
    assert!(
        (a - b).abs() <= 4.0 * se + 1e-3,
        "exact {a}, estimated {b}, se {se}"
    );
    assert_eq!(exact.flip_mean_infinite, estimated.flip_mean_infinite);
    // The second cell, of the same view, takes the estimate's halves from the cache.
    assert_eq!(estimated.shadow.reference_shadowed_cached, Some(false));
    assert_eq!(estimates[1].shadow.reference_shadowed_cached, Some(true));
    assert_eq!(estimates[1].shadow.shadowed_reference_se, Some(se));
    for (value, want) in [
        (
            "shadowed_reference_rays: Some(0),",
            "shadowed_reference_rays = Some(0)",
        ),
        (
            "shadowed_reference_rays: Some(8), msaa: 4,",
            "shadowed_reference_rays = Some(8) with msaa = 4",
        ),
    ] {
        let err = Experiment::parse(&src(value), Path::new("bad.ron"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("bad.ron") && err.contains(want),
            "{value}: {err}"
        );
    }
}
