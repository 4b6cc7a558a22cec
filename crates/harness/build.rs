//! Records what built the harness, for the run manifest: the rustc version, and the git
//! commit of the source tree the binary was built from (with whether that tree had
//! uncommitted changes), so a manifest names the code that ran, wherever it runs.
//!
//! The build script runs again when the commit moves (HEAD, refs, index) or any source
//! file of the workspace changes, so the dirty flag is the one of the last build.
//! `RECONBENCH_BUILD_COMMIT` set at build time overrides the commit (for builds from a
//! tarball without `.git`); without either, the commit is `unknown`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let version = run(Command::new(rustc).arg("--version")).unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=RECONBENCH_RUSTC_VERSION={version}");
    println!("cargo:rerun-if-env-changed=RUSTC");

    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    watch_sources(&root);
    println!("cargo:rerun-if-env-changed=RECONBENCH_BUILD_COMMIT");
    let git = |args: &[&str]| run(Command::new("git").arg("-C").arg(&root).args(args));
    let (commit, dirty) = match std::env::var("RECONBENCH_BUILD_COMMIT") {
        Ok(c) if !c.trim().is_empty() => (c.trim().to_string(), "unknown".to_string()),
        _ => match git(&["rev-parse", "HEAD"]) {
            Some(c) => {
                let dirty = git(&["status", "--porcelain", "--untracked-files=no"])
                    .map_or("unknown".to_string(), |s| (!s.is_empty()).to_string());
                (c, dirty)
            }
            None => ("unknown".into(), "unknown".into()),
        },
    };
    println!("cargo:rustc-env=RECONBENCH_BUILD_COMMIT={commit}");
    println!("cargo:rustc-env=RECONBENCH_BUILD_DIRTY={dirty}");
}

/// Asks cargo to rerun this script when the checked-out commit or a source changes.
fn watch_sources(root: &Path) {
    let git_dir = root.join(".git");
    let mut watch: Vec<PathBuf> = vec![
        git_dir.join("HEAD"),
        git_dir.join("index"),
        git_dir.join("packed-refs"),
        root.join("Cargo.lock"),
    ];
    if let Ok(head) = std::fs::read_to_string(git_dir.join("HEAD"))
        && let Some(r) = head.trim().strip_prefix("ref: ")
    {
        watch.push(git_dir.join(r));
    }
    for dir in ["crates", "tools"] {
        let Ok(entries) = std::fs::read_dir(root.join(dir)) else {
            continue;
        };
        for e in entries.flatten() {
            watch.push(e.path().join("src"));
        }
    }
    for p in watch.into_iter().filter(|p| p.exists()) {
        println!("cargo:rerun-if-changed={}", p.display());
    }
}

/// A command's trimmed stdout when it succeeds.
fn run(cmd: &mut Command) -> Option<String> {
    cmd.output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
}
