//! The report's gallery: renders, lights-per-pixel heatmaps and FLIP maps.

use std::path::Path;

use manylights_lab::Experiment;
use manylights_lab::runner::run_parsed;

use super::{common, opts};

/// A tiny experiment over the atrium and the pillars (each a setting) and two strategies,
/// `accuracy` as given.
fn gallery_src(accuracy: bool) -> String {
    format!(
        r#"Experiment(
        name: "gallery",
        config: Config(
            scene: Atrium(),
            lights: (generator: Uniform, count: 64, seed: 3, radius: Fixed(3.0)),
            resolution: (40, 24),
            frames: 1,
            warmup: 0,
            accuracy: {accuracy},
        ),
        sweep: (
            settings: [(label: "atrium"), (label: "pillars", scene: Pillars())],
            strategy: [TiledGather(tile_size: 8), ZBin(tile_size: 8)],
        ),
    )"#
    )
}

/// The gallery shows a cell a setting (the first of each with a render): its render, its
/// lights-per-pixel heatmap and, where the infinite-range reference was rendered, its FLIP map
/// against it, at the image's size; without references there is no FLIP map.
#[test]
fn the_gallery_shows_each_setting_with_its_flip_map() {
    let ctx = common::gpu();
    let tmp = tempfile::tempdir().unwrap();
    for accuracy in [true, false] {
        let src = gallery_src(accuracy);
        let e = Experiment::parse(&src, Path::new("gallery.ron")).unwrap();
        let out = tmp.path().join(format!("accuracy-{accuracy}"));
        let s = run_parsed(&ctx, &e, &src, tmp.path(), &out, &opts()).unwrap();
        assert_eq!(s.rows.len(), 4);
        manylights_lab::report::write_report(&out).unwrap();
        let md = std::fs::read_to_string(out.join("report.md")).unwrap();
        let heading = if accuracy {
            "## Renders, lights-per-pixel heatmaps and FLIP maps against infinite range"
        } else {
            "## Renders and lights-per-pixel heatmaps"
        };
        let gallery = &md[md
            .find(heading)
            .unwrap_or_else(|| panic!("{heading}: {md}"))..];
        for r in &s.rows {
            let flip = out.join("images").join(format!("{}_flip.png", r.id));
            assert_eq!(flip.exists(), accuracy, "{}", r.cell);
            let first = r.strategy == "tiled_gather";
            assert_eq!(
                gallery.contains(&format!("`{}`", r.cell)),
                first,
                "{}",
                r.cell
            );
            assert_eq!(
                gallery.contains(&format!("images/{}_flip.png", r.id)),
                first && accuracy,
                "{}",
                r.cell
            );
            if flip.exists() {
                let img = image::open(&flip).unwrap();
                assert_eq!((img.width(), img.height()), (40, 24));
            }
        }
    }
}
