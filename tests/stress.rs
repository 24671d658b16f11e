//! The stiff-case suite (`dibench stress`): it passes with zero non-finite or negative samples,
//! and it can fail — a closed form off by 3 %, or a case whose lights a strategy must reach but
//! cannot, is reported as a failure.

use dibench::stress::{self, Status, cases};
use std::process::Command;
use std::sync::Arc;

#[test]
fn the_stiff_suite_passes_with_only_finite_samples() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_dibench"))
        .args(["stress", "--samples", "60000", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "dibench stress failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains(" 0 fail; 0 non-finite or negative samples"),
        "{stdout}"
    );
    let csv = std::fs::read_to_string(dir.path().join("stress/stress.csv")).unwrap();
    assert!(
        csv.lines().count() > 100,
        "expected a row per (case, strategy)"
    );
}

#[test]
fn a_wrong_closed_form_fails() {
    let mut picked: Vec<_> = cases::all()
        .into_iter()
        .filter(|c| c.name == "mesh-degenerate" || c.name == "sphere-sin-1e-4")
        .collect();
    assert_eq!(picked.len(), 2);
    for c in &mut picked {
        let right = c.expected.clone().unwrap();
        c.expected = Some(Arc::new(move |p| 1.03 * right(p)));
    }
    let rows = stress::run(&picked, 60_000, 1).unwrap();
    for name in ["light", "light-mesh-sa", "mis-power"] {
        let failed = rows
            .iter()
            .filter(|r| r.strategy == name)
            .all(|r| r.status == Status::Fail);
        assert!(
            failed,
            "{name} did not notice a 3% error in the closed form"
        );
    }
}

#[test]
fn a_required_strategy_that_never_reaches_the_light_fails() {
    let mut case = cases::all()
        .into_iter()
        .find(|c| c.name == "sphere-sin-1e-4")
        .unwrap();
    // Cosine sampling never finds a sphere of sinθmax = 1e-4 in 60k samples.
    case.must_resolve = &["cosine"];
    let rows = stress::run(&[case], 60_000, 1).unwrap();
    let cosine = rows.iter().find(|r| r.strategy == "cosine").unwrap();
    assert_eq!(cosine.status, Status::Fail, "{}", cosine.detail);
}

#[test]
fn unknown_case_and_zero_samples_are_user_errors() {
    for args in [
        &["stress", "--cases", "no-such-case"][..],
        &["stress", "--samples", "0"][..],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_dibench"))
            .args(args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(
            stderr.contains("no-such-case") || stderr.contains("--samples"),
            "{stderr}"
        );
    }
}
