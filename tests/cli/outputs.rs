//! What a run leaves: its files' modes, and exports that NumPy reads.

use super::*;

/// Every file under `dir`, recursively.
fn files_under(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(files_under(&p));
        } else {
            out.push(p);
        }
    }
    out
}

/// Output files (images, results, reports, figures) get the mode any new file gets, 0666 less
/// the umask, not a temporary file's private 0600; and a run that succeeds prints no error
/// line, even without `XDG_RUNTIME_DIR` (with which Mesa's device-select layer made libwayland
/// print two).
#[cfg(unix)]
#[test]
fn outputs_follow_the_umask_and_a_clean_run_prints_no_error() {
    use std::os::unix::fs::PermissionsExt;
    let tmp = tempfile::tempdir().unwrap();
    let exp = tmp.path().join("modes.ron");
    std::fs::write(
        &exp,
        "Experiment(name: \"modes\", config: Config(scene: Pillars(), lights: (count: 8), \
         resolution: (32, 16), frames: 1, warmup: 0))",
    )
    .unwrap();
    for (umask, mode) in [("022", 0o644), ("027", 0o640)] {
        let dir = tmp.path().join(umask);
        let render = dir.join("render");
        let run = dir.join("run");
        for args in [
            vec![
                "render", "--width", "32", "--height", "16", "--lights", "4", "--out",
            ],
            vec!["run", exp.to_str().unwrap(), "--out"],
        ] {
            let out = if args[0] == "render" { &render } else { &run };
            let o = Command::new("sh")
                .arg("-c")
                .arg(format!("umask {umask}; exec \"$0\" \"$@\""))
                .arg(env!("CARGO_BIN_EXE_manylights"))
                .args(&args)
                .arg(out)
                .env_remove("XDG_RUNTIME_DIR")
                .env_remove("NODEVICE_SELECT")
                .output()
                .expect("run manylights through sh");
            let stderr = String::from_utf8_lossy(&o.stderr);
            assert!(o.status.success(), "{args:?}: {stderr}");
            assert!(
                !stderr.lines().any(|l| l.to_lowercase().contains("error")),
                "{args:?}: an error line in a run that succeeded:\n{stderr}"
            );
        }
        let files = [files_under(&render), files_under(&run)].concat();
        assert!(files.len() > 5, "{files:?}");
        for f in files {
            let m = std::fs::metadata(&f).unwrap().permissions().mode() & 0o777;
            assert_eq!(m, mode, "umask {umask}: {} has mode {m:o}", f.display());
        }
    }
}

/// A Python with NumPy, or None (then the caller skips, except in CI, which installs
/// `python3-numpy` and must run what needs it).
fn python_with_numpy() -> Option<&'static str> {
    let found = ["python3", "/usr/bin/python3"].into_iter().find(|p| {
        Command::new(p)
            .args(["-c", "import numpy"])
            .output()
            .is_ok_and(|o| o.status.success())
    });
    if found.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must have Python with NumPy (`apt-get install python3-numpy`)"
        );
        eprintln!("skipped: no Python with NumPy here (`apt-get install python3-numpy`)");
    }
    found
}

/// The number after `label` in `text`.
fn number_after(text: &str, label: &str) -> u64 {
    let at = text
        .find(label)
        .unwrap_or_else(|| panic!("`{label}` not in:\n{text}"));
    text[at + label.len()..]
        .split_whitespace()
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no number after `{label}` in:\n{text}"))
}

/// `--export` on `cull` and `render` and `export: true` in experiments write the documented
/// arrays, and the ten-odd lines of NumPy in docs/EXPERIMENTS.md recompute from them the false
/// negatives the program counts: none for exact lists, and every light a deliberate capacity
/// drops. `render --export` without lists is a clear error.
#[test]
fn exports_let_numpy_recompute_the_false_negatives() {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/EXPERIMENTS.md"))
            .unwrap();
    let start = doc.find("```python\n").expect("a ```python block") + "```python\n".len();
    let script = &doc[start..start + doc[start..].find("```").unwrap()];
    let tmp = tempfile::tempdir().unwrap();
    let py = tmp.path().join("false_negatives.py");
    std::fs::write(&py, script).unwrap();
    rejects(
        &[
            "--backend",
            "reference",
            "--export",
            tmp.path().join("x").to_str().unwrap(),
        ],
        1,
        &["--export needs lists", "--backend reference"],
    );
    let size = ["--width", "64", "--height", "40", "--lights", "64"];
    let mut dirs = Vec::new();
    for (k, extra) in [
        vec![],
        vec!["--capacity", "2"],
        vec!["--strategy", "clustered"],
    ]
    .into_iter()
    .enumerate()
    {
        let dir = tmp.path().join(format!("cull{k}"));
        let out = tmp.path().join(format!("out{k}"));
        let mut args = vec!["cull", "--out", out.to_str().unwrap()];
        args.extend(size);
        args.extend(&extra);
        args.extend(["--export", dir.to_str().unwrap()]);
        let o = manylights(&args);
        let stdout = String::from_utf8_lossy(&o.stdout);
        let fneg = number_after(&stdout, "false negatives");
        assert_eq!(
            fneg > 0,
            !extra.is_empty() && extra[0] == "--capacity",
            "{args:?}: {stdout}"
        );
        assert!(stdout.contains("exported 22 files"), "{stdout}");
        dirs.push((dir, Some(fneg)));
    }
    let render = tmp.path().join("render");
    let o = manylights(&[
        "render",
        "--backend",
        "deferred",
        "--width",
        "64",
        "--height",
        "40",
        "--lights",
        "64",
        "--out",
        tmp.path().join("r").to_str().unwrap(),
        "--export",
        render.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    dirs.push((render, Some(0)));
    let exp = tmp.path().join("export.ron");
    std::fs::write(
        &exp,
        "Experiment(name: \"export\", config: Config(scene: Pillars(), lights: (count: 16), \
         resolution: (48, 32), frames: 1, warmup: 0, accuracy: false, export: true))",
    )
    .unwrap();
    let run = tmp.path().join("run");
    let o = manylights(&["run", exp.to_str().unwrap(), "--out", run.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cells: Vec<_> = std::fs::read_dir(run.join("cells"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    assert_eq!(cells.len(), 1, "{cells:?}");
    dirs.push((cells[0].clone(), Some(0)));
    for (dir, _) in &dirs {
        let manifest: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("manifest.json")).unwrap())
                .unwrap();
        for (name, a) in manifest["arrays"].as_object().unwrap() {
            assert!(
                dir.join(name).is_file(),
                "{}: {name} missing",
                dir.display()
            );
            assert!(
                a["shape"].is_array() && a["dtype"].is_string(),
                "{name}: {a}"
            );
        }
    }
    let Some(python) = python_with_numpy() else {
        return;
    };
    for (dir, expected) in dirs {
        let o = Command::new(python)
            .arg(&py)
            .arg(&dir)
            .output()
            .expect("run the documented script");
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success(),
            "{}: {stdout}{}",
            dir.display(),
            String::from_utf8_lossy(&o.stderr)
        );
        assert_eq!(
            Some(number_after(&stdout, "false negatives:")),
            expected,
            "{}: NumPy against the program",
            dir.display()
        );
    }
}
