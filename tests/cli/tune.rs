//! `tune`.

use super::*;

/// `tune` tries every candidate on this device, ranks the conservative ones by culling and
/// shading together, and writes the best as an experiment file that `run` reproduces; a budget
/// that leaves no candidate is an error that says so.
#[test]
fn tune_ranks_candidates_and_writes_the_best_as_an_experiment() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("tune");
    let small = [
        "--scene", "atrium", "--lights", "48", "--width", "48", "--height", "32", "--frames", "1",
        "--warmup", "0",
    ];
    let mut args = vec!["tune", "--out", out.to_str().unwrap(), "--budget-s", "600"];
    args.extend_from_slice(&small);
    let o = manylights(&args);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    // Every candidate finished (a generous budget) and none of them drops a light here.
    let ranked: Vec<&str> = stdout
        .lines()
        .filter(|l| l.trim_start().starts_with(|c: char| c.is_ascii_digit()))
        .collect();
    assert_eq!(
        ranked.len(),
        manylights_lab::tune::candidates().len(),
        "{stdout}"
    );
    assert!(!stdout.contains("untried"), "{stdout}");
    // Ranked by the culling-and-shading time, fastest first.
    let times: Vec<f64> = ranked
        .iter()
        .map(|l| {
            let at = l.find(" ms").unwrap();
            l[..at].split_whitespace().last().unwrap().parse().unwrap()
        })
        .collect();
    assert!(times.windows(2).all(|w| w[0] <= w[1]), "{stdout}");
    assert!(stdout.contains("best: deferred + "), "{stdout}");
    let best = out.join("best.ron");
    let (e, _) = manylights_lab::Experiment::load(&best).unwrap();
    assert_eq!(e.cells().len(), 1);
    let again = tmp.path().join("again");
    let o = manylights(&[
        "run",
        best.to_str().unwrap(),
        "--out",
        again.to_str().unwrap(),
        "--no-report",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.join("report.html").is_file() && out.join("results.csv").is_file());
    // No time for any candidate.
    let none = tmp.path().join("none");
    let mut args = vec!["tune", "--out", none.to_str().unwrap(), "--budget-s", "0"];
    args.extend_from_slice(&small);
    let o = manylights(&args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("no candidate was eligible within the budget of 0 s")
            && stderr.contains("raise --budget-s"),
        "{stderr}"
    );
}
