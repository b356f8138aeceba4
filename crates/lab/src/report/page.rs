//! The report's two pages from what it says ([`Page`]): the results table, `report.md` and
//! `report.html`.

use std::fmt::Write as _;

use super::{fmt_opt, utc};
use crate::results::Row;

/// What the report's two pages say.
pub(super) struct Page<'a> {
    pub(super) name: &'a str,
    pub(super) description: &'a str,
    pub(super) adapter: &'a str,
    pub(super) driver: &'a str,
    pub(super) commit: &'a str,
    pub(super) date: u64,
    pub(super) cells: String,
    pub(super) exp_src: &'a str,
    pub(super) findings: &'a [String],
    pub(super) head: &'a [&'static str],
    pub(super) table: &'a [Vec<String>],
    pub(super) figs: &'a [(&'a str, String)],
    /// The gallery: a cell each, and whether it has a FLIP map against infinite range.
    pub(super) images: &'a [(&'a Row, bool)],
}

/// The results table's header and rows (the moving lights' columns where cells moved them, the
/// shadow columns where cells cast shadows or were scored against the shadowed light).
pub(super) fn results_table(rows: &[Row]) -> (Vec<&'static str>, Vec<Vec<String>>) {
    // Moving lights' update columns, in reports of runs that have them.
    let moving = rows
        .iter()
        .any(|r| r.gpu_ms_light_update.is_some() || r.cpu_ms_upload.is_some());
    let shadowed = rows
        .iter()
        .any(|r| r.shadow.flip_mean_shadowed.is_some() || r.shadow.rays_per_pixel.is_some());
    let mut head = vec![
        "cell",
        "lights",
        "res",
        "backend",
        "strategy",
        "GPU ms",
        "p10",
        "p90",
        "frame steady",
        "cull ms",
        "steady",
        "span",
        "cull+shade",
        "shade ms",
        "geometry ms",
        "FN",
        "FP ratio",
        "max/tile",
        "dropped",
        "list KiB",
        "PSNR dB",
        "FLIP",
        "FLIP inf",
        "energy inf",
    ];
    if moving {
        head.extend(["light update ms", "upload host ms"]);
    }
    if shadowed {
        head.extend([
            "shadows",
            "FLIP shadowed",
            "energy shadowed",
            "rays/px",
            "shadow ms",
            "Grays/s",
        ]);
    }
    let table: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let mut row = vec![
                r.cell.clone(),
                r.lights.to_string(),
                format!("{}x{}", r.width, r.height),
                r.backend.clone(),
                format!("{} ({})", r.strategy, r.params),
                fmt_opt(r.gpu_ms_total, 3),
                fmt_opt(r.gpu_ms_total_p10, 3),
                fmt_opt(r.gpu_ms_total_p90, 3),
                fmt_opt(r.gpu_ms_frame_steady, 3),
                fmt_opt(r.gpu_ms_cull, 3),
                fmt_opt(r.gpu_ms_cull_steady, 3),
                fmt_opt(r.gpu_ms_cull_span, 3),
                fmt_opt(r.gpu_ms_cull_shade, 3),
                fmt_opt(r.gpu_ms_shade, 3),
                fmt_opt(r.gpu_ms_prepass, 3),
                r.false_negatives.map_or("-".into(), |v| v.to_string()),
                fmt_opt(r.false_positive_ratio, 2),
                r.max_lights_per_tile.map_or("-".into(), |v| v.to_string()),
                r.dropped_lights.to_string(),
                format!("{:.1}", r.list_bytes as f64 / 1024.0),
                // Identical images (no error at all) have an infinite PSNR.
                if r.psnr_db.is_none() && r.max_abs_error == Some(0.0) {
                    "inf".into()
                } else {
                    fmt_opt(r.psnr_db, 1)
                },
                fmt_opt(r.flip_mean, 5),
                fmt_opt(r.flip_mean_infinite, 4),
                fmt_opt(r.energy_error_infinite, 4),
            ];
            if moving {
                row.extend([
                    fmt_opt(r.gpu_ms_light_update, 3),
                    fmt_opt(r.cpu_ms_upload, 3),
                ]);
            }
            if shadowed {
                let sh = &r.shadow;
                row.extend([
                    sh.shadows.clone(),
                    fmt_opt(sh.flip_mean_shadowed, 4),
                    fmt_opt(sh.energy_error_shadowed, 4),
                    fmt_opt(sh.rays_per_pixel, 2),
                    fmt_opt(sh.gpu_ms_shadow, 3),
                    fmt_opt(sh.grays_per_s, 2),
                ]);
            }
            row
        })
        .collect();
    (head, table)
}

/// `report.md`.
pub(super) fn markdown(p: &Page<'_>) -> String {
    // Markdown.
    let mut md = String::new();
    let _ = writeln!(md, "# {}\n\n{}\n", p.name, p.description);
    let _ = writeln!(
        md,
        "## Setup\n\n- adapter: {}\n- driver: {}\n- commit: {}\n- finished: {}\n- cells: {}\n",
        p.adapter,
        p.driver,
        p.commit,
        utc(p.date),
        p.cells
    );
    let _ = writeln!(
        md,
        "GPU times are medians over each cell's measured frames (timestamp queries), with p10 and p90 in the results. Accuracy is against the brute-force reference with the same falloff (PSNR, FLIP: the implementation check) and against the infinite-range reference, the light as it is (FLIP inf at the reference's exposure, energy inf: the signed mean relative error over lit pixels), and where cells have them against the shadowed infinite-range reference, the light as it arrives (FLIP shadowed, energy shadowed; with shadows also the rays a covered pixel, what they cost, shadow ms, and the rays a second, Grays/s); list metrics against the exact per-pixel oracle.\n"
    );
    let _ = writeln!(md, "```ron\n{}\n```\n", p.exp_src.trim_end());
    let _ = writeln!(md, "## Findings\n");
    for f in p.findings.iter() {
        let _ = writeln!(md, "- {f}");
    }
    let _ = writeln!(
        md,
        "\n## Results\n\n| {} |\n|{}|",
        p.head.join(" | "),
        p.head.iter().map(|_| "---").collect::<Vec<_>>().join("|")
    );
    for row in p.table.iter() {
        let _ = writeln!(
            md,
            "| {} |",
            row.iter()
                .map(|c| c.replace('|', "\\|"))
                .collect::<Vec<_>>()
                .join(" | ")
        );
    }
    let _ = writeln!(md, "\n## Figures\n");
    for (f, caption) in p.figs.iter() {
        let _ = writeln!(md, "![{caption}](figures/{f})\n\n{caption}\n");
    }
    if !p.images.is_empty() {
        let _ = writeln!(md, "## {}\n", gallery_title(p.images));
        for (r, flip) in p.images.iter() {
            let flip = if *flip {
                format!(" ![FLIP against infinite range](images/{}_flip.png)", r.id)
            } else {
                String::new()
            };
            let _ = writeln!(
                md,
                "`{}`\n\n![render](images/{}_render.png) ![lights per pixel](images/{}_heat.png){flip}\n",
                r.cell, r.id, r.id
            );
        }
    }
    md
}

/// The gallery's heading: what its images are.
fn gallery_title(images: &[(&Row, bool)]) -> &'static str {
    if images.iter().any(|(_, flip)| *flip) {
        "Renders, lights-per-pixel heatmaps and FLIP maps against infinite range"
    } else {
        "Renders and lights-per-pixel heatmaps"
    }
}

/// `report.html`.
pub(super) fn html(p: &Page<'_>) -> String {
    // HTML.
    let esc = |s: &str| {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let mut html = String::new();
    let _ = write!(
        html,
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{0}</title>\n<style>body{{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em}}.table{{overflow-x:auto;max-width:100%;border:1px solid #ddd}}table{{border-collapse:collapse;font-size:12px}}td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right;white-space:nowrap}}th{{position:sticky;top:0;background:#f6f6f6;white-space:normal}}td:nth-child(5){{white-space:normal;min-width:16em;text-align:left}}td:first-child,th:first-child{{text-align:left;position:sticky;left:0;background:#fff;z-index:1}}pre{{background:#f6f6f6;padding:1em;overflow:auto;white-space:pre-wrap}}img{{max-width:100%}}</style></head><body>\n<h1>{0}</h1>\n<p>{1}</p>\n",
        esc(p.name),
        esc(p.description)
    );
    let _ = writeln!(
        html,
        "<h2>Setup</h2><ul><li>adapter: {}</li><li>driver: {}</li><li>commit: {}</li><li>finished: {}</li><li>cells: {}</li></ul>",
        esc(p.adapter),
        esc(p.driver),
        esc(p.commit),
        utc(p.date),
        esc(&p.cells)
    );
    let _ = write!(
        html,
        "<pre>{}</pre>\n<h2>Findings</h2><ul>",
        esc(p.exp_src.trim_end())
    );
    for f in p.findings.iter() {
        let _ = write!(html, "<li>{}</li>", esc(f).replace('`', ""));
    }
    let _ = write!(
        html,
        "</ul>\n<h2>Results</h2><div class=\"table\"><table><tr>{}</tr>\n",
        p.head
            .iter()
            .map(|h| format!("<th>{h}</th>"))
            .collect::<String>()
    );
    for row in p.table.iter() {
        let _ = writeln!(
            html,
            "<tr>{}</tr>",
            row.iter()
                .map(|c| format!("<td>{}</td>", esc(c)))
                .collect::<String>()
        );
    }
    let _ = write!(html, "</table></div>\n<h2>Figures</h2>\n");
    for (f, caption) in p.figs.iter() {
        let _ = writeln!(
            html,
            "<figure><img src=\"figures/{f}\" alt=\"{}\"><figcaption>{}</figcaption></figure>",
            esc(caption),
            esc(caption)
        );
    }
    if !p.images.is_empty() {
        let _ = writeln!(html, "<h2>{}</h2>", gallery_title(p.images));
        for (r, flip) in p.images.iter() {
            let flip = if *flip {
                format!(
                    " <img src=\"images/{}_flip.png\" alt=\"FLIP against infinite range\">",
                    r.id
                )
            } else {
                String::new()
            };
            let _ = writeln!(
                html,
                "<p>{}</p><img src=\"images/{}_render.png\" alt=\"render\"> <img src=\"images/{}_heat.png\" alt=\"lights per pixel\">{flip}",
                esc(&r.cell),
                r.id,
                r.id
            );
        }
    }
    // Marks the page once every figure has loaded (checked by the headless-browser test).
    let _ = write!(
        html,
        "<script>window.addEventListener('load',function(){{var i=Array.from(document.images);document.body.setAttribute('data-figures',i.every(function(x){{return x.complete&&x.naturalWidth>0}})?'loaded':'missing');document.body.setAttribute('data-figure-count',String(i.length));}});</script>\n</body></html>\n"
    );
    html
}
