//! Glass on the command line (`--glass`): `cull` culls over the lookup bounds and its exact
//! oracle checks every visible glass fragment; `render` shades it forward, deferred and naive
//! as the reference does; a scene without glass panes says so.

use super::*;

#[test]
fn glass_is_culled_exactly_and_rendered_as_the_reference_does() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("glass");
    let common = [
        "--scene", "pillars", "--glass", "--width", "64", "--height", "36", "--lights", "300",
        "--radius", "2", "--out",
    ];
    let run = |cmd: &str, extra: &[&str]| {
        let mut args = vec![cmd];
        args.extend_from_slice(&common);
        args.push(out.to_str().unwrap());
        args.extend_from_slice(extra);
        succeeds(&args, &format!("{cmd} {extra:?}"))
    };
    for strategy in ["tiled-gather", "depth-mask", "clustered", "zbin"] {
        let stdout = run("cull", &["--strategy", strategy]);
        assert!(
            stdout.contains("false negatives         0"),
            "{strategy}: {stdout}"
        );
        let line = stdout
            .lines()
            .find(|l| l.contains("shaded points"))
            .expect(&stdout);
        let points: u64 = line.split_whitespace().last().unwrap().parse().unwrap();
        assert!(
            points > 64 * 36,
            "{strategy}: {line}: no glass fragment counted"
        );
    }
    for backend in ["forward", "deferred", "naive-forward"] {
        let stdout = run("render", &["--backend", backend, "--compare"]);
        let psnr = psnr_vs_reference(&stdout);
        assert!(psnr > 80.0, "{backend}: PSNR {psnr}");
    }
    rejects(
        &[
            "--scene",
            "pillars",
            "--glass",
            "--backend",
            "forward",
            "--export",
            "x",
        ],
        1,
        &["--export with --glass"],
    );
    rejects(
        &["--scene", "city", "--glass"],
        1,
        &["--glass", "city", "atrium, pillars and cis5650"],
    );
}
