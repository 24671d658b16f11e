//! Shared by the CLI tests: run the `dibench` binary and check it never panics.

use std::path::Path;
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
