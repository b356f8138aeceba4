//! The reports' comparisons of forward and deferred shading on the grounds on which the
//! Forward+ paper argues between them: MSAA and glass (`msaa_summary`), and material variety
//! (`materials_summary`).

use std::collections::BTreeMap;

use crate::report::fmt_opt;
use crate::results::Row;

/// MSAA and glass, where cells ran at several sample counts or with transparent surfaces: for
/// each (glass, strategy, sample count), forward against deferred (the frame, what it is spent
/// on, the memory of the multisampled targets, the error against the reference at that count),
/// and what going from one sample to several cost each; the visibility buffer beside them where
/// it ran.
pub(crate) fn msaa_summary(rows: &[Row]) -> Vec<String> {
    let mut out = Vec::new();
    if !rows.iter().any(|r| r.msaa > 1 || r.transparent) {
        return out;
    }
    let find = |backend: &str, strategy: &str, n: u32, glass: bool| {
        rows.iter().find(|r| {
            r.backend == backend && r.strategy == strategy && r.msaa == n && r.transparent == glass
        })
    };
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    let mut strategies: Vec<&str> = rows.iter().map(|r| r.strategy.as_str()).collect();
    strategies.sort_unstable();
    strategies.dedup();
    let mut counts: Vec<u32> = rows.iter().map(|r| r.msaa).collect();
    counts.sort_unstable();
    counts.dedup();
    for glass in [false, true] {
        for s in &strategies {
            for &n in &counts {
                let (Some(f), Some(d)) =
                    (find("forward", s, n, glass), find("deferred", s, n, glass))
                else {
                    continue;
                };
                // The frame in steady state where both have it (geometry, then culling and
                // shading, each back to back after the clock has risen); otherwise the frames
                // timed one at a time.
                let steady = f.gpu_ms_frame_steady.is_some() && d.gpu_ms_frame_steady.is_some();
                let time = |r: &Row| {
                    if steady {
                        (
                            r.gpu_ms_frame_steady,
                            r.gpu_ms_geometry_steady,
                            r.gpu_ms_cull_shade,
                        )
                    } else {
                        let cull_shade = r.gpu_ms_shade.map(|t| t + r.gpu_ms_cull.unwrap_or(0.0));
                        (r.gpu_ms_total, r.gpu_ms_prepass, cull_shade)
                    }
                };
                let ((Some(ft), fg, fs), (Some(dt), dg, ds)) = (time(f), time(d)) else {
                    continue;
                };
                let scale = |b: &str, t: f64| {
                    (n > 1)
                        .then(|| find(b, s, 1, glass).and_then(|r| time(r).0))
                        .flatten()
                        .map_or(String::new(), |t1| {
                            format!(", {:.1}x its time at one sample", t / t1)
                        })
                };
                out.push(format!(
                    "{} {}, {s}: {} is faster, {:.2} ms a frame for forward (geometry and bounds {} ms, culling and shading {} ms{}) against {:.2} ms for deferred (G-buffer and bounds {} ms, culling and lighting{} {} ms{}){}. Multisampled targets: forward {:.0} MiB, deferred {:.0} MiB (its G-buffer {:.0} MiB); lists {:.0} and {:.0} KiB. Against the reference: forward PSNR {} dB, deferred mean FLIP {}{}.",
                    if n > 1 { format!("MSAA {n}") } else { "One sample".to_owned() },
                    if glass { "with glass" } else { "without glass" },
                    if ft <= dt { "forward" } else { "deferred" },
                    ft,
                    fmt_opt(fg, 2),
                    fmt_opt(fs, 2),
                    scale("forward", ft),
                    dt,
                    fmt_opt(dg, 2),
                    if glass { " and its forward pass over the glass" } else { "" },
                    fmt_opt(ds, 2),
                    scale("deferred", dt),
                    if steady {
                        " in steady state (`gpu_ms_frame_steady`)"
                    } else {
                        ""
                    },
                    mib(f.msaa_target_bytes),
                    mib(d.msaa_target_bytes.max(d.gbuffer_bytes)),
                    mib(d.gbuffer_bytes),
                    f.list_bytes as f64 / 1024.0,
                    d.list_bytes as f64 / 1024.0,
                    fmt_opt(f.psnr_db, 1),
                    fmt_opt(d.flip_mean, 4),
                    if n > 1 {
                        " (deferred lights an edge's samples apart, the reference each fragment once)"
                    } else {
                        ""
                    },
                ));
                if let Some(v) = find("visibility", s, n, glass)
                    && let (Some(vt), vg, vs) = time(v)
                {
                    out.push(format!(
                        "The visibility buffer there: {vt:.2} ms a frame ({:.2}x deferred's; visibility buffer and bounds {} ms, culling and lighting {} ms), its targets {:.0} MiB (the buffer {:.0} MiB), mean FLIP {} against the reference.",
                        vt / dt,
                        fmt_opt(vg, 2),
                        fmt_opt(vs, 2),
                        mib(v.msaa_target_bytes.max(v.gbuffer_bytes)),
                        mib(v.gbuffer_bytes),
                        fmt_opt(v.flip_mean, 4),
                    ));
                }
            }
        }
    }
    if rows
        .iter()
        .any(|r| r.transparent && r.backend == "deferred")
    {
        out.push("Deferred cannot shade transparent surfaces: it shades them with a forward pass over the same lists after its lighting (`shade.forward_transparent`), as engines do.".into());
    }
    out
}

/// Material variety, where cells ran with several `materials` values: for each setting (scene,
/// lights, resolution) and strategy, forward against deferred (and the visibility buffer
/// where it ran) in steady state at each list of models (in the order of their counts), where deferred's advantage turns if it does; what
/// mixing costs each backend (a mixed frame's shading pass against the mean of its models'
/// passes alone); and each model's shading time per light evaluated from the cells that shade
/// it alone.
pub(crate) fn materials_summary(rows: &[Row]) -> Vec<String> {
    let mut out = Vec::new();
    let mut kinds: Vec<&str> = rows.iter().map(|r| r.materials.as_str()).collect();
    kinds.sort_unstable();
    kinds.dedup();
    if kinds.len() < 2 {
        return out;
    }
    let mut groups: BTreeMap<(String, u64, u32, u32, &str), Vec<&Row>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.msaa == 1 && !r.transparent) {
        groups
            .entry((
                r.scene.clone(),
                r.lights,
                r.width,
                r.height,
                r.strategy.as_str(),
            ))
            .or_default()
            .push(r);
    }
    for ((scene, lights, w, h, strategy), rs) in &groups {
        let mut lists: Vec<&str> = rs.iter().map(|r| r.materials.as_str()).collect();
        lists.sort_by_key(|m| (m.matches('+').count(), *m));
        lists.dedup();
        let row = |backend: &str, m: &str| {
            rs.iter()
                .find(|r| r.backend == backend && r.materials == m)
                .copied()
        };
        let frame = |backend: &str, m: &str| row(backend, m).and_then(|r| r.gpu_ms_frame_steady);
        let mut parts = Vec::new();
        let mut turns = None;
        for m in &lists {
            let (Some(f), Some(d)) = (frame("forward", m), frame("deferred", m)) else {
                continue;
            };
            let visibility = frame("visibility", m).map_or(String::new(), |v| {
                format!(", visibility {v:.3} ms ({:.2}x deferred's)", v / d)
            });
            parts.push(format!(
                "{m} {f:.3} against {d:.3} ms ({:.2}x){visibility}",
                f / d
            ));
            let n = m.matches('+').count() + 1;
            if n > 1 && f <= d && turns.is_none() {
                turns = Some(n);
            }
        }
        if parts.is_empty() {
            continue;
        }
        let verdict = match turns {
            Some(n) => format!("forward overtakes deferred from {n} models a frame"),
            None => "deferred's advantage does not turn at these counts".to_owned(),
        };
        out.push(format!(
            "Material variety, {scene} ({lights} lights, {w} x {h}), {strategy}: the frame in steady state, forward against deferred (forward / deferred): {}; {verdict}. Forward shades in a raster pass, deferred in a compute pass: on a GPU with little raster hardware (H100, H200) the ratio measures that hardware as much as the backends, and what mixing costs each (below) is the comparison that carries over.",
            parts.join("; ")
        ));
        // The shading pass alone: what the models cost.
        let shade = |backend: &str, m: &str| row(backend, m).and_then(shade_ms);
        let mut mixing = Vec::new();
        for m in lists.iter().filter(|m| m.contains('+')) {
            for backend in ["forward", "deferred", "visibility"] {
                let alone: Option<Vec<f64>> = m.split('+').map(|one| shade(backend, one)).collect();
                if let (Some(mixed), Some(alone)) = (shade(backend, m), alone) {
                    let mean = alone.iter().sum::<f64>() / alone.len() as f64;
                    mixing.push(format!("{backend} {m} {:.2}x", mixed / mean));
                }
            }
        }
        if !mixing.is_empty() {
            out.push(format!(
                "What mixing models costs, {scene}, {strategy}: the shading pass of the mixed frame against the mean of its models' passes alone (1.00x: nothing; deferred's lighting branches a pixel at a time, forward draws a model at a time): {}.",
                mixing.join("; ")
            ));
        }
        let mut costs = Vec::new();
        for m in lists.iter().filter(|m| !m.contains('+')) {
            let ps = |backend: &str| {
                row(backend, m)
                    .and_then(|r| r.ns_per_light_eval)
                    .map_or("-".to_owned(), |ns| format!("{:.1}", ns * 1e3))
            };
            costs.push(format!(
                "{m} {}, {} and {}",
                ps("forward"),
                ps("deferred"),
                ps("visibility")
            ));
        }
        if !costs.is_empty() {
            out.push(format!(
                "Shading time per light evaluated (ps, forward, deferred and the visibility buffer; `ns_per_light_eval` times 1,000, - where not run), {scene}, {strategy}, each model alone: {}.",
                costs.join("; ")
            ));
        }
    }
    out
}

/// A cell's shading passes in steady state (forward's or deferred's), ms.
fn shade_ms(r: &Row) -> Option<f64> {
    let ms: f64 = r
        .passes_steady
        .iter()
        .filter(|(label, _)| *label == "shade.forward" || *label == "shade.deferred")
        .map(|(_, ms)| ms)
        .sum();
    (ms > 0.0).then_some(ms)
}
