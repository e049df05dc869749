//! Records the commit the `nlrt` binary is built from (for `nlrt bench --json`): `git
//! rev-parse HEAD` and whether tracked files differ from it, or `unknown` where the source is
//! not a git checkout or git is missing.

use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    let commit = git(&["rev-parse", "HEAD"]).filter(|c| !c.is_empty());
    let dirty = commit.is_some()
        && git(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
    println!(
        "cargo:rustc-env=NLRT_COMMIT={}",
        commit.as_deref().unwrap_or("unknown")
    );
    println!("cargo:rustc-env=NLRT_DIRTY={dirty}");
    // Rerun when the answer can change: a commit moves the branch HEAD names (or HEAD
    // itself), staging rewrites the index, and an edit of any tracked source changes the
    // dirty flag (cargo scans these directories for changed files).
    let mut watched = vec![
        "../../.git/HEAD".to_string(),
        "../../.git/index".to_string(),
        "../../crates".to_string(),
        "../../tests".to_string(),
        "../../Cargo.toml".to_string(),
    ];
    if let Some(branch) = std::fs::read_to_string("../../.git/HEAD")
        .ok()
        .and_then(|h| h.strip_prefix("ref: ").map(|r| r.trim().to_string()))
    {
        watched.push(format!("../../.git/{branch}"));
    }
    for path in watched {
        println!("cargo:rerun-if-changed={path}");
    }
}
