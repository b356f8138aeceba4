//! Against the committed fixture (tests/fixtures/bevy): Bevy's CPU clusterer, read back from the
//! render world's GPU buffers by this adapter, gives the CPU adapter's lists cluster for
//! cluster (the readback and the light mapping are right); Bevy's GPU clusterer gives the lists
//! committed in `gpu/`, byte for byte; bad options are errors. Needs a Vulkan adapter
//! (lavapipe in CI).

use std::path::{Path, PathBuf};
use std::process::Command;

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/bevy")
}

fn read_u32(path: &Path) -> Vec<u32> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    npyz::NpyFile::new(&bytes[..]).unwrap().into_vec().unwrap()
}

/// Each cluster's lights, in ascending order.
fn lists(dir: &Path) -> Vec<Vec<u32>> {
    let (o, i) = (
        read_u32(&dir.join("offsets.npy")),
        read_u32(&dir.join("indices.npy")),
    );
    o.windows(2)
        .map(|w| {
            let mut l = i[w[0] as usize..w[1] as usize].to_vec();
            l.sort_unstable();
            l
        })
        .collect()
}

fn grid(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("grid.json")).unwrap()).unwrap()
}

fn adapter(out: &Path, extra: &[&str]) -> std::process::Output {
    let o = Command::new(env!("CARGO_BIN_EXE_manylights-bevy-gpu-referee"))
        .arg(fixture().join("export"))
        .arg(out)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        o.status.success() || !extra.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

#[test]
fn bevys_cpu_lists_read_back_from_the_gpu_are_the_cpu_adapters() {
    let tmp = std::env::temp_dir().join(format!("bevy-gpu-referee-cpu-{}", std::process::id()));
    for (name, extra) in [("default", &[][..]), ("xyz", &["--xyz", "7,5,12"][..])] {
        let out = tmp.join(name);
        let o = adapter(&out, &[&["--clustering", "cpu"], extra].concat());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let (ours, theirs) = (grid(&out), grid(&fixture().join(name)));
        for k in ["dims", "slicing", "width", "height", "screen", "order"] {
            assert_eq!(ours[k], theirs[k], "{name}: {k}");
        }
        assert_eq!(lists(&out), lists(&fixture().join(name)), "{name}");
    }
    let _ = std::fs::remove_dir_all(&tmp);
}

#[test]
fn bevys_gpu_lists_are_the_committed_ones() {
    let tmp = std::env::temp_dir().join(format!("bevy-gpu-referee-gpu-{}", std::process::id()));
    let o = adapter(&tmp, &[]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("settled at frame"), "{stdout}");
    for f in ["grid.json", "offsets.npy", "indices.npy"] {
        assert_eq!(
            std::fs::read(tmp.join(f)).unwrap(),
            std::fs::read(fixture().join("gpu").join(f)).unwrap(),
            "{f} differs from the committed fixture"
        );
    }
    let _ = std::fs::remove_dir_all(&tmp);
}

#[test]
fn bad_options_name_the_option() {
    let tmp = std::env::temp_dir().join(format!("bevy-gpu-referee-bad-{}", std::process::id()));
    for (extra, says) in [
        (
            &["--clustering", "both"][..],
            "--clustering both: expected gpu or cpu",
        ),
        (&["--xyz", "7,0,12"], "--xyz 7,0,12"),
        (
            &["--frames", "1"],
            "--frames 1: expected a frame count >= 2",
        ),
    ] {
        let o = adapter(&tmp, extra);
        assert!(!o.status.success(), "{extra:?}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains(says), "{extra:?}: {e}");
    }
}
