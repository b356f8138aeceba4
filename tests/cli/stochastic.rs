//! Stochastic light culling from the command line: `--stochastic E` with `--bound`,
//! `--accumulate K` and `--interleave N` on `render` (with `--compare` and `--export`), `cull`
//! and `tune`, and their bad values.

use super::*;

/// Bad values name the option and what it accepts; the options that need --stochastic say so.
#[test]
fn bad_stochastic_options_name_the_option() {
    rejects(
        &["--stochastic", "1", "--accumulate", "0"],
        1,
        &["invalid --accumulate 0", "from 1 (one frame)"],
    );
    rejects(
        &["--stochastic", "1", "--accumulate", "5000"],
        1,
        &["invalid --accumulate 5000", "4096"],
    );
    rejects(
        &["--stochastic", "1", "--interleave", "9"],
        1,
        &["invalid --interleave 9", "1 (none) to 8"],
    );
    for bad in ["0", "-1", "nan", "inf"] {
        rejects(
            &["--stochastic", bad],
            2,
            &["--stochastic", "a finite number above 0"],
        );
    }
    rejects(&["--accumulate", "4"], 2, &["--stochastic"]);
    rejects(&["--interleave", "2"], 2, &["--stochastic"]);
    rejects(&["--bound", "albedo"], 2, &["--stochastic"]);
    rejects(
        &["--stochastic", "1", "--bound", "peak"],
        2,
        &["light", "albedo"],
    );
    rejects(&["--draw", "independent"], 2, &["--stochastic"]);
    rejects(
        &["--stochastic", "1", "--draw", "sobol"],
        2,
        &["stratified", "independent"],
    );
    rejects(
        &["--stochastic", "1", "--threshold", "0.1"],
        2,
        &["--threshold", "cannot be used with"],
    );
    // Stochastic ranges and the hierarchy choose their own ranges: a radius beside them is
    // an error, not dropped.
    for other in [["--stochastic", "0.1"], ["--hierarchy", "1"]] {
        rejects(
            &["--radius", "5", other[0], other[1]],
            2,
            &["--radius", "cannot be used with"],
        );
    }
    rejects_cmd(
        "cull",
        &["--stochastic", "1", "--interleave", "0"],
        1,
        &["--interleave 0"],
    );
}

/// `render --stochastic` on glTF's GGX, the roughness floor included: the lists stay short,
/// the image matches the brute-force reference over the same draws, and its error against
/// infinite range falls as frames accumulate (one frame's RMSE against sixteen's).
#[test]
fn render_stochastic_accumulates_frames_and_compares_against_infinite_range() {
    let tmp = tempfile::tempdir().unwrap();
    let run = |frames: &str, extra: &[&str]| {
        let out = tmp.path().join(format!("r{frames}"));
        let mut args = vec![
            "render",
            "--scene",
            "atrium",
            "--materials",
            "ggx",
            "--lights",
            "600",
            "--intensity",
            "1",
            "--backend",
            "deferred",
            "--width",
            "48",
            "--height",
            "32",
            "--stochastic",
            "0.5",
            "--accumulate",
            frames,
            "--compare",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        succeeds(&args, frames)
    };
    let one = run("1", &[]);
    let sixteen = run("16", &[]);
    assert!(
        sixteen.contains(
            "stochastic light culling: error 0.5 (light bound, stratified draws), 16 frames drawn and averaged"
        ) && sixteen.contains("errors of the mean of 16 frames"),
        "{sixteen}"
    );
    for out in [&one, &sixteen] {
        // The lists of the light bound do not grow with GGX's peak: far from all 600 lights.
        let per_pixel = number_after(out, "lights per pixel", "lights per pixel");
        assert!(per_pixel < 300.0, "{per_pixel} lights a pixel:\n{out}");
        // Culling loses nothing: the backend equals the reference over the same draws.
        let psnr = number_after(out, "vs reference (same draws)", "PSNR");
        assert!(psnr > 60.0, "{out}");
    }
    let rmse = |out: &str| number_after(out, "vs infinite-range reference", "RMSE");
    let (r1, r16) = (rmse(&one), rmse(&sixteen));
    // The noise falls as 1 / sqrt(K): a quarter at 16 frames, with room for the seeds.
    assert!(r16 < 0.5 * r1, "RMSE one frame {r1}, sixteen {r16}");
    // Interleaved over 2 x 2 classes and under the albedo bound, exported.
    let export = tmp.path().join("export");
    let il = run(
        "2",
        &[
            "--interleave",
            "2",
            "--bound",
            "albedo",
            "--export",
            export.to_str().unwrap(),
        ],
    );
    assert!(
        il.contains("(albedo bound), 2 frames drawn and averaged, 2 x 2 interleaved classes"),
        "{il}"
    );
    assert!(export.join("manifest.json").is_file(), "{il}");
    // Independent draws, named in the output.
    let independent = run("1", &["--draw", "independent"]);
    assert!(
        independent.contains("(light bound, independent draws), 1 frame drawn"),
        "{independent}"
    );
}

/// `cull --stochastic --accumulate K` culls and checks every frame's draws: no false negative
/// in any.
#[test]
fn cull_stochastic_checks_every_frame() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("c");
    let stdout = succeeds(
        &[
            "cull",
            "--scene",
            "pillars",
            "--lights",
            "300",
            "--width",
            "40",
            "--height",
            "24",
            "--strategy",
            "clustered",
            "--stochastic",
            "1",
            "--accumulate",
            "3",
            "--interleave",
            "2",
            "--out",
            out.to_str().unwrap(),
        ],
        "cull",
    );
    assert!(stdout.contains("3 frames drawn"), "{stdout}");
    for f in 0..2 {
        assert!(
            stdout.contains(&format!("frame {f} ")) && !stdout.contains("false negatives 1"),
            "{stdout}"
        );
    }
    assert_eq!(
        number_after(&stdout, "false negatives   ", "false negatives"),
        0.0,
        "{stdout}"
    );
}

/// `tune --stochastic E` ranks the candidates with stochastic ranges; with --max-error, E
/// joins --errors and each candidate takes --accumulate.
#[test]
fn tune_takes_stochastic_ranges() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("t");
    let stdout = succeeds(
        &[
            "tune",
            "--scene",
            "atrium",
            "--lights",
            "48",
            "--width",
            "40",
            "--height",
            "24",
            "--frames",
            "1",
            "--warmup",
            "0",
            "--max-error",
            "0.9",
            "--thresholds",
            "1",
            "--errors",
            "0.5",
            "--alphas",
            "1",
            "--stochastic",
            "2",
            "--accumulate",
            "2",
            "--out",
            out.to_str().unwrap(),
        ],
        "tune",
    );
    assert!(stdout.contains("stochastic=2/acc2"), "{stdout}");
    assert!(stdout.contains("stochastic=0.5/acc2"), "{stdout}");
}
