//! Embeds the commit the binary is built from (`MANYLIGHTS_COMMIT`), for the `commit` column of
//! results; "unknown" outside a git checkout, with "-dirty" when the tree has changes.
fn main() {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
    };
    let commit = git(&["rev-parse", "--short=12", "HEAD"]).map_or_else(
        || "unknown".into(),
        |o| String::from_utf8_lossy(&o.stdout).trim().to_string(),
    );
    let dirty = git(&["status", "--porcelain", "--untracked-files=no"])
        .is_some_and(|o| !o.stdout.is_empty());
    println!(
        "cargo:rustc-env=MANYLIGHTS_COMMIT={commit}{}",
        if dirty { "-dirty" } else { "" }
    );
    // HEAD moves on commit (the index and the reflog change); sources decide "-dirty".
    for path in [
        ".git/HEAD",
        ".git/index",
        ".git/logs/HEAD",
        "src",
        "crates",
        "shaders",
        "experiments",
    ] {
        println!("cargo:rerun-if-changed={path}");
    }
}
