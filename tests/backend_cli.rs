//! `--backend` and `crosscheck` through the CLI: unknown or not-compiled-in backends are clear
//! errors listing the available ones; crosscheck writes its CSV.

mod common;

fn dibench(args: &[&str]) -> (i32, String, String) {
    common::dibench(args, std::path::Path::new(env!("CARGO_MANIFEST_DIR")))
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
