//! The adapter reproduces the lists committed in tests/fixtures/bevy from the committed export,
//! byte for byte, for Bevy's default grid and a fixed XYZ grid; bad input is an error.

use std::path::Path;
use std::process::Command;

fn fixture() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/bevy")
}

#[test]
fn the_committed_lists_are_what_the_adapter_makes() {
    let tmp = std::env::temp_dir().join(format!("bevy-referee-{}", std::process::id()));
    for (name, extra) in [("default", &[][..]), ("xyz", &["--xyz", "7,5,12"][..])] {
        let out = tmp.join(name);
        let o = Command::new(env!("CARGO_BIN_EXE_manylights-bevy-referee"))
            .arg(fixture().join("export"))
            .arg(&out)
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        for f in ["grid.json", "offsets.npy", "indices.npy"] {
            assert_eq!(
                std::fs::read(out.join(f)).unwrap(),
                std::fs::read(fixture().join(name).join(f)).unwrap(),
                "{name}/{f} differs from the committed fixture"
            );
        }
    }
    let o = Command::new(env!("CARGO_BIN_EXE_manylights-bevy-referee"))
        .arg(fixture().join("export"))
        .arg(tmp.join("bad"))
        .args(["--xyz", "7,0,12"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--xyz 7,0,12"));
    let _ = std::fs::remove_dir_all(&tmp);
}
