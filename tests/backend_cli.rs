//! `--backend` and `crosscheck` through the CLI: unknown or not-compiled-in backends are clear
//! errors listing the available ones; crosscheck writes its CSV.

use std::process::Command;

fn dibench(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_dibench"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        !stderr.contains("panicked"),
        "dibench {args:?} panicked: {stderr}"
    );
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    (out.status.code().unwrap_or(-1), stdout, stderr)
}

#[test]
fn unknown_backend_is_an_error_listing_the_available_ones() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    for cmd in ["compare", "reference"] {
        let (code, _, stderr) = dibench(&[cmd, "cornell", "--backend", "magic", "--out", out]);
        assert_ne!(code, 0);
        assert!(
            stderr.contains("unknown backend `magic`") && stderr.contains("obvhs"),
            "{stderr}"
        );
    }
    if !cfg!(feature = "embree") {
        let (code, _, stderr) =
            dibench(&["compare", "cornell", "--backend", "embree", "--out", out]);
        assert_ne!(code, 0);
        assert!(stderr.contains("--features embree"), "{stderr}");
    }
    assert!(
        std::fs::read_dir(dir.path()).unwrap().next().is_none(),
        "output left behind"
    );
}

#[test]
fn crosscheck_writes_csv_and_passes_on_cornell() {
    let dir = tempfile::tempdir().unwrap();
    let (code, stdout, stderr) = dibench(&[
        "crosscheck",
        "cornell",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let csv = std::fs::read_to_string(dir.path().join("cornell/crosscheck.csv")).unwrap();
    assert!(csv.starts_with("scene,set,backend,mode,rays,"), "{csv}");
    for set in ["primary", "shadow_area", "incoherent"] {
        assert!(
            csv.contains(&format!("cornell,{set},obvhs,packet16")),
            "{csv}"
        );
    }
    if cfg!(feature = "embree") {
        assert!(csv.contains("cornell,render,embree"), "{csv}");
    }
}
