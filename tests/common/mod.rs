//! Shared by the CLI tests: run the `dibench` binary and check it never panics.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs `dibench args` in `cwd`; returns (exit code, stdout, stderr). A panic is a test failure:
/// user errors must be reported, not crash.
pub fn dibench(args: &[&str], cwd: &Path) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_dibench"))
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        !stderr.contains("panicked"),
        "dibench {args:?} panicked: {stderr}"
    );
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr,
    )
}

/// The file with `role` (`image`, `variance`, `film`) of the stored unit whose manifest is
/// `manifest` (`<out>/<scene>/reference/<integrand>.json`; see `output::store`).
#[allow(dead_code)]
pub fn stored_file(manifest: &Path, role: &str) -> PathBuf {
    let text = std::fs::read(manifest).unwrap_or_else(|e| panic!("{}: {e}", manifest.display()));
    let v: serde_json::Value = serde_json::from_slice(&text).unwrap();
    let name = v["files"][role]["name"]
        .as_str()
        .unwrap_or_else(|| panic!("{} names no {role} file", manifest.display()));
    manifest.with_file_name(name)
}
