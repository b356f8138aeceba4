//! Each culling pass's declared reads and writes (`Step::pass`) against what its entry point
//! does: naga's use of each global variable by the entry point (and everything it calls),
//! each global standing for the run's buffers it is bound to.

use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

use manylights_cull::record::{Buf, StepInfo};
use naga::valid::GlobalUse;

/// The buffers a storage or texture global of the culling shaders is bound to, by its name;
/// none for the material table, which culling does not read.
fn bound_to(global: &str) -> Option<&'static [Buf]> {
    use Buf::*;
    Some(match global {
        "materials" => return None,
        "lights" => &[Lights],
        "depth_tex" => &[Depth],
        "tile_depth" => &[TileDepth],
        "bin_counts" => &[Counts],
        "bin_offsets" => &[Offsets],
        "bin_cursors" => &[Cursors],
        "bin_ranges" | "out_ranges" | "zbin_ranges" => &[Ranges],
        "light_indices" => &[Indices],
        // Z-binning's sorted lights, then its masks, in one buffer.
        "zbin_lists" | "zbin_masks" => &[Indices, TileMasks],
        // Tiled scatter's mask pass reads the blocks cull.depth_bounds queued there.
        "out_indices" => &[Indices, BlockQueue],
        "occupancy" => &[Occupancy],
        "cull_stats" => &[Stats],
        "light_rects" | "zbin_rects" => &[LightRects],
        // On gather's lines path, the tile lines.
        "tile_masks" => &[TileMasks, TileLines],
        "tile_lines" => &[TileLines],
        "block_queue" => &[BlockQueue],
        // On the clusters' tile path, their masks.
        "wide_lights" => &[WideLights, ClusterMasks],
        // The clusters' and z-binning's buffer of several roles, one bound a pass.
        "cluster_aux" => &[WideArgs, ClusterBoxes, LightRects],
        "zbin_aux" => &[PairKeys, LightRects],
        "zbin_covers" => &[ZBinCovers],
        "occluders" => &[Occluders],
        // Tiled scatter's mask pass reads the lights' rectangles there.
        "pair_keys" => &[PairKeys, LightRects],
        other => panic!("global `{other}` of a culling shader: which buffer is it?"),
    })
}

/// Uses naga sees but a pass never makes (its analysis follows every branch): code behind a
/// constant argument of a function two entry points share (a count and a fill mode), or behind
/// an override constant the pass's pipeline sets otherwise; (entry point, globals, why).
const STATIC_ONLY: &[(&str, &[&str], &str)] = &[
    (
        "depth_bounds",
        &["block_queue", "cull_stats"],
        "store_light_rect queues blocks only for depth_bounds_blocks (LIGHT_ROWS_BLOCKS)",
    ),
    (
        "depth_bounds",
        &["lights", "light_rects"],
        "the light rows' work, run where the host dispatches them (the pass declares it then)",
    ),
    (
        "gather_count",
        &[
            "bin_offsets",
            "out_ranges",
            "out_indices",
            "tile_masks",
            "cull_stats",
        ],
        "gather_chunk(CHUNK_COUNT) counts alone",
    ),
    (
        "gather_fill",
        &["bin_counts", "tile_masks", "cull_stats"],
        "gather_chunk(CHUNK_FILL) writes the lists alone",
    ),
    (
        "scatter_count",
        &["bin_offsets", "pair_keys", "out_indices"],
        "scatter_light writes the pairs only when it writes (write = false here)",
    ),
    (
        "scatter_pairs",
        &["bin_counts", "cull_stats"],
        "scatter_light counts only when it does not write (write = true here)",
    ),
    (
        "gather_count_masks",
        &["bin_counts", "bin_offsets", "out_ranges", "out_indices"],
        "gather_chunk(CHUNK_MASK) sets the tile masks alone",
    ),
    (
        "gather_lines_count",
        &["out_ranges", "out_indices"],
        "lines_tile writes the lists only when it fills (fill = false here)",
    ),
    (
        "clustered_count",
        &["bin_offsets", "bin_cursors", "out_indices"],
        "emit writes the lists only when it fills (fill = false here)",
    ),
    (
        "clustered_count_wide",
        &["bin_offsets", "bin_cursors", "out_indices"],
        "as clustered_count",
    ),
    (
        "clustered_fill",
        &["bin_counts"],
        "emit counts only when it does not fill (fill = true here)",
    ),
    ("clustered_fill_wide", &["bin_counts"], "as clustered_fill"),
    ("clustered_scatter", &["bin_counts"], "as clustered_fill"),
    (
        "clustered_count",
        &["cull_stats"],
        "the held pairs' offsets, taken only with CLUSTER_PAIRS (that pipeline's pass declares them)",
    ),
    (
        "clustered_count_wide",
        &["cull_stats"],
        "as clustered_count",
    ),
    (
        "clustered_count",
        &["cluster_aux"],
        "the stored boxes, read only with CULL_FLAG_CLUSTER_BOXES (the pass declares them then)",
    ),
    ("clustered_fill", &["cluster_aux"], "as clustered_count"),
    (
        "clustered_count_wide",
        &["cluster_aux"],
        "as clustered_count",
    ),
    (
        "clustered_fill_wide",
        &["cluster_aux"],
        "as clustered_count",
    ),
    (
        "gather_count_flat",
        &["bin_offsets", "out_indices"],
        "gather_batch writes the lists only when it fills (fill = false here)",
    ),
    (
        "gather_fill_flat",
        &["bin_counts"],
        "count_done counts only when it does not fill (fill = true here)",
    ),
    (
        "cluster_masks_fill",
        &["bin_offsets"],
        "with CLUSTER_FILL_CURSOR its ranges come from a cursor (that pipeline's pass declares no offsets)",
    ),
    (
        "cluster_tiles_count",
        &["cluster_aux"],
        "the rectangles, read only with CLUSTER_TILE_RECTS (that pipeline's pass declares them)",
    ),
];

/// Each global's name and use by `entry` of shader `shader` (validated once a shader).
fn uses(shader: &str, entry: &str) -> Vec<(String, GlobalUse)> {
    type Analysed = (naga::Module, naga::valid::ModuleInfo);
    static CACHE: OnceLock<Mutex<HashMap<String, &'static Analysed>>> = OnceLock::new();
    let mut cache = CACHE.get_or_init(Default::default).lock().unwrap();
    let (module, info) = *cache.entry(shader.to_owned()).or_insert_with(|| {
        let def = manylights_cull::shaders::SHADERS
            .iter()
            .find(|d| d.name == shader)
            .unwrap_or_else(|| panic!("no shader {shader}"));
        let src = def.compose();
        let module = naga::front::wgsl::parse_str(&src).unwrap();
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .unwrap();
        Box::leak(Box::new((module, info)))
    });
    let i = module
        .entry_points
        .iter()
        .position(|e| e.name == entry)
        .unwrap_or_else(|| panic!("{shader} has no entry point {entry}"));
    let f = info.get_entry_point(i);
    module
        .global_variables
        .iter()
        // The run's buffers and textures (workgroup and private memory are the pass's own).
        .filter(|(_, g)| {
            matches!(
                g.space,
                naga::AddressSpace::Storage { .. } | naga::AddressSpace::Handle
            )
        })
        .map(|(h, g)| (g.name.clone().unwrap_or_default(), f[h]))
        .filter(|(_, u)| u.intersects(GlobalUse::READ | GlobalUse::WRITE))
        .collect()
}

/// Every pass of `passes`: a buffer its entry point writes is declared written; one it reads is
/// declared read or written (a pass "writes" a buffer it updates atomically, which naga counts
/// as a read too); and every buffer declared is one it reads (declared read) or writes
/// (declared written).
pub(crate) fn check_global_use(what: &str, passes: &[StepInfo]) {
    let mut wrong = Vec::new();
    for s in passes {
        let Some((shader, entry)) = s.kernel else {
            continue;
        };
        let used = uses(shader, entry);
        let declared = |bufs: &[Buf], among: &[Buf]| bufs.iter().any(|b| among.contains(b));
        for (global, u) in &used {
            let Some(bufs) = bound_to(global) else {
                continue;
            };
            if STATIC_ONLY
                .iter()
                .any(|&(e, g, _)| e == entry && g.contains(&global.as_str()))
            {
                continue;
            }
            if u.contains(GlobalUse::WRITE) {
                if !(declared(bufs, &s.writes)) {
                    wrong.push(format!("{what}: {} ({shader} {entry}) writes `{global}` but declares none of {:?} written",
                    s.name,
                    bufs));
                }
            } else {
                if !(declared(bufs, &s.reads) || declared(bufs, &s.writes)) {
                    wrong.push(format!(
                        "{what}: {} ({shader} {entry}) reads `{global}` but declares none of {:?}",
                        s.name, bufs
                    ));
                }
            }
        }
        let by = |b: &Buf, flag: GlobalUse| {
            used.iter()
                .any(|(g, u)| u.contains(flag) && bound_to(g).is_some_and(|bufs| bufs.contains(b)))
        };
        for b in &s.reads {
            if !(by(b, GlobalUse::READ) || s.indirect == Some(*b)) {
                wrong.push(format!("{what}: {} ({shader} {entry}) declares it reads {} but reads no global bound to it",
                s.name,
                b.name()));
            }
        }
        for b in &s.writes {
            if !(by(b, GlobalUse::WRITE)) {
                wrong.push(format!("{what}: {} ({shader} {entry}) declares it writes {} but writes no global bound to it",
                s.name,
                b.name()));
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// Each use [`STATIC_ONLY`] lets through is one naga does see (so none outlives its code), of
/// an entry point of some culling shader.
#[test]
fn static_only_uses_are_uses_naga_sees() {
    for &(entry, globals, why) in STATIC_ONLY {
        let shaders: Vec<&str> = manylights_cull::shaders::SHADERS
            .iter()
            .filter(|d| {
                naga::front::wgsl::parse_str(&d.compose())
                    .is_ok_and(|m| m.entry_points.iter().any(|e| e.name == entry))
            })
            .map(|d| d.name)
            .collect();
        assert!(!shaders.is_empty(), "{entry}: no culling shader has it");
        for shader in shaders {
            let used = uses(shader, entry);
            for g in globals {
                assert!(
                    used.iter().any(|(name, _)| name == g),
                    "{shader} {entry} does not use `{g}` ({why}): drop it from STATIC_ONLY"
                );
            }
        }
    }
}
