//! The shipped experiment files: every one parses, and a tiny variant of each the issues name
//! runs end to end.

use super::*;

/// The experiment files the issue names.
pub(crate) const SHIPPED: [&str; 33] = [
    "quickstart",
    "harada2012",
    "cis5650-scaling",
    "cis5650-field",
    "tile-size",
    "cluster-grid",
    "depth-mask",
    "cutoff-accuracy",
    "scaling-1m",
    "dynamic-lights",
    "msaa-transparency",
    "infinite-range",
    "infinite-range-1m",
    "material-variety",
    "zbin-1m",
    "cluster-cells-1m",
    "stochastic-materials",
    "infinite-range-halls",
    "referee-bevy",
    "hierarchy-goals",
    "hierarchy-sampled",
    "hierarchy-sampled-1m",
    "visibility-frame",
    "hierarchy-front",
    "hierarchy-front-1m",
    "hierarchy-growth",
    "hierarchy-ramps",
    "hierarchy-ramps-hall",
    "real-scenes",
    "real-scenes-goals",
    "real-scenes-gallery",
    "real-scenes-infinite",
    "real-scenes-dynamic",
];

#[test]
fn every_shipped_experiment_parses() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments");
    let mut found: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| {
            e.ok()?
                .path()
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
        })
        .collect();
    found.sort();
    // Every file in experiments/ parses, under its own name, into cells of distinct names
    // (those SHIPPED also run tiny, below).
    for name in found
        .iter()
        .filter(|n| dir.join(format!("{n}.ron")).is_file())
    {
        let (e, _, _) = shipped(name);
        assert_eq!(
            &e.name, name,
            "experiments/{name}.ron names itself {}",
            e.name
        );
        let cells = e.cells();
        let mut names: Vec<&str> = cells.iter().map(|c| c.name.as_str()).collect();
        names.sort_unstable();
        names.dedup();
        assert!(
            !cells.is_empty() && names.len() == cells.len(),
            "{name}: {} cells, {} names",
            cells.len(),
            names.len()
        );
    }
    for name in SHIPPED {
        assert!(
            found.contains(&name.to_string()),
            "experiments/{name}.ron is missing"
        );
        let (e, _, _) = shipped(name);
        assert_eq!(e.name, name);
        let cells = e.cells();
        assert!(!cells.is_empty(), "{name}: no cells");
        let mut names: Vec<&str> = cells.iter().map(|c| c.name.as_str()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), cells.len(), "{name}: two cells share a name");
    }
    assert_eq!(shipped("harada2012").0.config.lights.count, 3072);
    assert_eq!(shipped("harada2012").0.config.resolution, (1280, 720));
    assert_eq!(
        shipped("scaling-1m")
            .0
            .sweep
            .light_count
            .as_ref()
            .unwrap()
            .last(),
        Some(&1_048_576)
    );
}

/// A tiny variant of every shipped experiment (48 x 27 at most, one frame, at most 256 lights)
/// runs end to end: every cell has a row, no false negatives anywhere, and a report. The
/// infinite-range experiments (180, 13 and 40 cells, each stochastic one rendered for several
/// seeds) run one cell in 17, 4 and 5 (a shard: every variant, and most kinds of radius rule,
/// among them),
/// material variety one in 11, stochastic materials one in 7, the real scenes one in 45 (a
/// cell of each scene and placement) and their goals one in 15 (a cell of each scene), so that
/// the suite stays within its time.
#[test]
fn a_tiny_variant_of_each_shipped_experiment_runs() {
    let ctx = common::gpu();
    let tmp = tempfile::tempdir().unwrap();
    for name in SHIPPED {
        let (e, src, path) = shipped(name);
        let tiny = e.tiny();
        let out = tmp.path().join(name);
        let shard = match name {
            "infinite-range" => Some((0, 17)),
            // 15 cells: every other one has cut-offs, stochastic in one frame with either draw,
            // accumulated and interleaved, and the hierarchy.
            "infinite-range-1m" => Some((0, 2)),
            // 56 cells: one in 11 from the fourth has both settings, every variant, and 5 of
            // the 7 model lists (the five mixed among them).
            "material-variety" => Some((3, 11)),
            // 72 cells: one in 7 from the second has every setting, both bounds, one frame
            // and sixteen accumulated, and every model list.
            "stochastic-materials" => Some((1, 7)),
            // 40 cells: one in 5 has both settings, cut-offs and stochastic ones with either
            // draw.
            "infinite-range-halls" => Some((0, 5)),
            // 450 cells, 45 a setting: the first of each, every scene with both placements.
            "real-scenes" => Some((0, 45)),
            // 75 cells, 15 a scene: the first of each.
            "real-scenes-goals" => Some((0, 15)),
            // 10 cells: the surface lighting of Sponza and the fixtures of the bathroom.
            "real-scenes-gallery" => Some((0, 7)),
            // 24 cells: one in 5 has both scenes and every family.
            "real-scenes-infinite" => Some((0, 5)),
            // 24 cells: one in 5 has both scenes, both placements and every variant.
            "real-scenes-dynamic" => Some((0, 5)),
            _ => None,
        };
        let options = RunOptions { shard, ..opts() };
        let s = run_parsed(&ctx, &tiny, &src, path.parent().unwrap(), &out, &options)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let (i, n) = shard.unwrap_or((0, 1));
        let cells = tiny.cells().len();
        assert_eq!(s.rows.len(), (cells - i).div_ceil(n), "{name}: rows");
        for r in &s.rows {
            // Naive forward has no lists to count false negatives of; its image is checked
            // against the reference (tests/lab/msaa.rs, hierarchy.rs, stochastic.rs).
            let naive = r.backend == "naive_forward";
            assert_eq!(
                r.false_negatives,
                (!naive).then_some(0),
                "{name} {}: false negatives",
                r.cell
            );
            assert_eq!(r.dropped_lights, 0);
            assert!(!r.materials.is_empty(), "{name} {}: no materials", r.cell);
            assert!(
                r.ns_per_light_eval.is_some_and(|ns| ns > 0.0)
                    || r.lights_per_pixel_mean == Some(0.0),
                "{name} {}: no shading time per light evaluated",
                r.cell
            );
            assert!(
                r.gpu_ms_total.is_some_and(|t| t > 0.0),
                "{name} {}: no GPU time",
                r.cell
            );
            // The frame in steady state for every cell: its geometry back to back, and with
            // culling and shading.
            let geometry = r.gpu_ms_geometry_steady.unwrap_or(0.0);
            let frame = r.gpu_ms_frame_steady.unwrap_or(0.0);
            assert!(geometry > 0.0, "{name} {}: no steady geometry time", r.cell);
            match r.gpu_ms_cull_shade {
                Some(cs) => assert!(
                    (frame - geometry - cs).abs() < 1e-9,
                    "{name} {}: frame {frame} is not geometry {geometry} + culling and shading {cs}",
                    r.cell
                ),
                None => assert_eq!(frame, geometry, "{name} {}", r.cell),
            }
            // Its passes: the single frame's, each timed (back to back, culling may skip the
            // pass that sized its lists, and the clusters' held pairs take
            // `cull.clustered.scatter` in place of the fill passes), its geometry and shading
            // passes all.
            assert!(
                r.passes_steady.iter().all(|(l, &ms)| ms > 0.0
                    && (r.passes.contains_key(l) || l == "cull.clustered.scatter"))
                    && r.passes.keys().all(|l| l.starts_with("cull.")
                        || l.starts_with("scan.")
                        || l.starts_with("sort.")
                        || l.starts_with("lights.")
                        || r.passes_steady.contains_key(l)),
                "{name} {}: steady passes {:?} against the frame's {:?}",
                r.cell,
                r.passes_steady,
                r.passes
            );
            // The cell's parameters as columns: its name is made of them, and its light
            // range's value is a column of its own.
            // (A value may hold commas, a camera pose's: each `name=value` is in the name,
            // and together with the commas between them they are all of it.)
            let parameters: Vec<String> = r
                .sweep
                .parameters
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect();
            if r.cell != "base" {
                let len: usize = parameters.iter().map(String::len).sum();
                assert!(
                    parameters.iter().all(|p| r.cell.contains(p.as_str()))
                        && len + parameters.len() - 1 == r.cell.len(),
                    "{name} {}: parameters {:?}",
                    r.cell,
                    r.sweep.parameters
                );
            }
            assert_eq!(
                r.sweep.setting,
                r.sweep
                    .parameters
                    .get("setting")
                    .cloned()
                    .unwrap_or_default(),
                "{name} {}",
                r.cell
            );
            assert!(
                r.sweep.radius_value.is_some(),
                "{name} {}: no radius_value",
                r.cell
            );
            // Each pass's category, from the plans that recorded it: the per-category columns
            // are the sums of the single frame's passes of each.
            for l in r.passes.keys().chain(r.passes_steady.keys()) {
                assert!(
                    r.pass_categories.contains_key(l),
                    "{name} {}: no category for {l} in {:?}",
                    r.cell,
                    r.pass_categories
                );
            }
            let of = |c: &str| -> f64 {
                r.passes
                    .iter()
                    .filter(|(l, _)| r.pass_categories[*l] == c)
                    .map(|(_, ms)| ms)
                    .sum()
            };
            for (c, column) in [
                ("prepass", r.gpu_ms_prepass),
                ("cull", r.gpu_ms_cull),
                ("shade", r.gpu_ms_shade),
            ] {
                let column = column.unwrap_or(0.0);
                // Medians of sums against sums of medians: equal over one timed frame, near
                // over several.
                assert!(
                    column == 0.0 || of(c) > 0.0,
                    "{name} {}: {c} {column} ms without a pass of it in {:?}",
                    r.cell,
                    r.pass_categories
                );
            }
            // Steady-state culling, and culling with shading, for every culling cell; neither
            // for naive forward.
            if r.backend == "naive_forward" {
                assert_eq!(r.gpu_ms_cull_steady, None, "{name} {}", r.cell);
                assert_eq!(r.gpu_ms_cull_span, None, "{name} {}", r.cell);
                assert_eq!(r.gpu_ms_cull_shade, None, "{name} {}", r.cell);
            } else {
                assert!(
                    r.gpu_ms_cull_shade.is_some_and(|t| t > 0.0)
                        && r.gpu_ms_cull_shade_span.is_none_or(|t| t > 0.0),
                    "{name} {}: no steady-state culling and shading time",
                    r.cell
                );
                assert!(
                    r.gpu_ms_cull_steady.is_some_and(|t| t > 0.0),
                    "{name} {}: no steady-state culling time",
                    r.cell
                );
                assert!(
                    r.gpu_ms_cull_span.is_none_or(|t| t > 0.0),
                    "{name} {}: span",
                    r.cell
                );
            }
            // The lights a pixel needs come with the false-positive ratio (both from the
            // exact oracle), and a conservative list holds at least as many.
            assert_eq!(
                r.lights_needed_per_pixel_mean.is_some(),
                r.false_negatives.is_some() || (naive && r.exact_stride > 0),
                "{name} {}: lights needed",
                r.cell
            );
            if let (Some(needed), Some(ratio)) =
                (r.lights_needed_per_pixel_mean, r.false_positive_ratio)
            {
                assert!(needed > 0.0 && ratio >= 1.0, "{name} {}", r.cell);
            }
            // The lights shading walks, counted on the GPU: at most the lists' lengths where a
            // pixel shades one fragment (no MSAA, no glass; forward lights each triangle's
            // fragment that passes the depth test, so a tie between two shades both: the
            // hall's coplanar faces add 0.1%).
            let walked = r.lights_walked_per_pixel_mean;
            assert!(walked.is_some_and(|n| n > 0.0), "{name} {}: lights walked", r.cell);
            if r.msaa == 1 && !r.transparent {
                let listed = r.lights_per_pixel_mean.unwrap();
                let ties = if r.backend.contains("forward") { 1.01 } else { 1.0 + 1e-9 };
                assert!(
                    walked.unwrap() <= listed * ties,
                    "{name} {}: {walked:?} lights walked, {listed} listed",
                    r.cell
                );
            }
            assert_eq!(r.experiment, name);
        }
        let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
        assert!(csv.starts_with("experiment,cell,scene,lights,width,height,strategy,backend,params,gpu_ms_total,gpu_ms_cull,gpu_ms_shade,gpu_ms_prepass,cpu_ms_encode,false_negatives,false_positive_ratio,lights_per_pixel_mean,max_lights_per_tile,dropped_lights,list_bytes,gbuffer_bytes,psnr_db,flip_mean,max_abs_error,adapter,driver,commit"));
        assert_eq!(csv.lines().count(), s.rows.len() + 1);
        let json: Vec<Row> =
            serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap())
                .unwrap();
        assert_eq!(json.len(), s.rows.len());
        manylights_lab::report::write_report(&out).unwrap();
        assert!(out.join("report.md").is_file() && out.join("report.html").is_file());
        if name.starts_with("infinite-range") {
            // Speed against the error against infinite range: culling + shading, and the frame.
            for f in ["frame_infinite.svg", "frame_steady_infinite.svg"] {
                assert!(out.join("figures").join(f).is_file(), "{name}: {f}");
            }
        }
    }
}
