//! Shadows in experiments (`shadows: Exact`): cells with and without shadows, end to end: the
//! BVH built for the cell, `shadows=exact` in its params, no false negative, the frame within
//! tolerance of its shadowed reference, and darker than the unshadowed cell's.

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
}
