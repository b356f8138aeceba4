//! MSAA on the command line: `cull --msaa` and `render --msaa`; and `render --hdr`.

use super::*;

/// `cull --repeat N`: N runs back to back, a median per pass and per run.
/// `cull --msaa 4`: every strategy over a 4x multisampled depth buffer, zero false negatives
/// counted per covered sample; a count the device lacks, and `--export` with MSAA, are errors
/// that say what is accepted.
#[test]
fn cull_msaa_counts_every_sample() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("cull");
    for strategy in [
        "tiled-gather",
        "depth-mask",
        "clustered",
        "zbin",
        "tiled-scatter",
    ] {
        let stdout = succeeds(
            &[
                "cull",
                "--scene",
                "pillars",
                "--width",
                "64",
                "--height",
                "36",
                "--lights",
                "64",
                "--strategy",
                strategy,
                "--msaa",
                "4",
                "--out",
                out.to_str().unwrap(),
            ],
            strategy,
        );
        assert!(stdout.contains("MSAA 4"), "{strategy}: {stdout}");
        let line = stdout
            .lines()
            .find(|l| l.contains("covered samples"))
            .expect(&stdout);
        let n: u64 = line.split_whitespace().last().unwrap().parse().unwrap();
        assert!(n > 64 * 36, "{strategy}: {line}");
        assert!(
            stdout.contains("false negatives         0"),
            "{strategy}: {stdout}"
        );
    }
    rejects_cmd(
        "cull",
        &["--msaa", "3"],
        1,
        &["invalid --msaa 3", "supports 1, ", "4"],
    );
    let export = tmp.path().join("export");
    rejects_cmd(
        "cull",
        &["--msaa", "4", "--export", export.to_str().unwrap()],
        1,
        &["--export with --msaa 4"],
    );
}

/// `render --msaa 4`: forward over a strategy, naive forward and the reference, resolved, each
/// within rounding of the reference at the same count (`--compare`), with `prepass.depth_bounds`
/// timed for forward and deferred (naive forward culls nothing), and deferred, which lights an edge's samples apart; bad counts, the stored
/// position and `--export` with MSAA are errors that say what is accepted.
#[test]
fn render_msaa_matches_the_reference_at_its_count() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("render");
    for backend in [
        &["--backend", "forward", "--strategy", "clustered"][..],
        &["--backend", "deferred", "--strategy", "zbin"],
        &["--backend", "visibility", "--strategy", "tiled-gather"],
        &["--backend", "naive-forward"],
        &["--backend", "reference"],
    ] {
        let mut args = vec![
            "render",
            "--scene",
            "pillars",
            "--width",
            "64",
            "--height",
            "36",
            "--lights",
            "64",
            "--msaa",
            "4",
            "--compare",
            "--out",
        ];
        args.push(out.to_str().unwrap());
        args.extend_from_slice(backend);
        let stdout = succeeds(&args, &format!("{backend:?}"));
        assert!(stdout.contains("MSAA 4"), "{backend:?}: {stdout}");
        let psnr = psnr_vs_reference(&stdout);
        // The reference lights an edge's samples apart, as deferred and the visibility buffer
        // do (the visibility buffer's triangle ids see one fragment where llvmpipe can light
        // two); forward lights each fragment once, at its centroid.
        let bound = match backend[1] {
            "forward" | "naive-forward" => 30.0,
            "visibility" => 60.0,
            _ => 80.0,
        };
        assert!(psnr > bound, "{backend:?}: PSNR {psnr}");
        assert_eq!(
            stdout.contains("prepass.depth_bounds"),
            ["forward", "deferred", "visibility"].contains(&backend[1]),
            "{backend:?}: {stdout}"
        );
    }
    rejects(&["--msaa", "3"], 1, &["invalid --msaa 3", "supports 1,"]);
    rejects(
        &["--msaa", "4", "--backend", "deferred-stored-position"],
        1,
        &["--msaa 4", "the stored position takes no MSAA"],
    );
    rejects(
        &["--msaa", "4", "--backend", "forward", "--export", "x"],
        1,
        &["--export with --msaa 4"],
    );
}

/// `render --hdr f16`: deferred into a 16-bit lit image, compared with the 32-bit references:
/// near them (PSNR over 80 dB) but not as near as the 32-bit image (the rounding shows); with the
/// reference backend it is an error that says what is accepted.
#[test]
fn render_hdr_f16_shows_its_rounding() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("render");
    let psnr = |hdr: &str| {
        let args = [
            "render",
            "--scene",
            "pillars",
            "--width",
            "64",
            "--height",
            "36",
            "--lights",
            "64",
            "--backend",
            "deferred",
            "--strategy",
            "tiled-gather",
            "--hdr",
            hdr,
            "--compare",
            "--out",
            out.to_str().unwrap(),
        ];
        psnr_vs_reference(&succeeds(&args, hdr))
    };
    let (full, half) = (psnr("f32"), psnr("f16"));
    assert!(
        half > 80.0 && half < full,
        "PSNR f16 {half} against f32 {full}"
    );
    rejects(
        &["--hdr", "f16", "--backend", "reference"],
        1,
        &["--hdr f16 with --backend reference", "--hdr f32"],
    );
}
