//! The generated lights' options.

use super::*;

/// `--irradiance E`, the exposure rule: the lights' intensity scales with E (a render at 4 is
/// four times as bright as at 1, the radii fixed), and it takes a finite value above 0 and not
/// together with `--intensity`.
#[test]
fn irradiance_sets_the_lights_intensity_by_the_exposure_rule() {
    let tmp = tempfile::tempdir().unwrap();
    let mean = |e: &str| -> f64 {
        let out = tmp.path().join(format!("irradiance-{e}"));
        succeeds(
            &[
                "render",
                "--scene",
                "sponza",
                "--generator",
                "fixtures",
                "--lights",
                "64",
                "--radius",
                "4",
                "--irradiance",
                e,
                "--backend",
                "deferred",
                "--width",
                "64",
                "--height",
                "36",
                "--out",
                out.to_str().unwrap(),
            ],
            e,
        );
        let img = image::open(out.join("deferred.exr")).unwrap().into_rgb32f();
        img.pixels()
            .map(|p| f64::from(p[0] + p[1] + p[2]))
            .sum::<f64>()
    };
    let ratio = mean("4") / mean("1");
    assert!((ratio - 4.0).abs() < 1e-3, "4 against 1: {ratio}");
    for (args, want) in [
        (&["--irradiance", "0"][..], "--irradiance"),
        (
            &["--irradiance", "1", "--intensity", "2"][..],
            "cannot be used with",
        ),
    ] {
        let mut all = vec!["render", "--scene", "sponza", "--lights", "8"];
        all.extend_from_slice(args);
        let o = manylights(&all);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(want), "{args:?}: {err}");
    }
}
