//! `dibench rays` and `--backend`/`--isa` reject bad names with a clear error, no panic.

use std::process::Command;

fn run(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_dibench"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn unknown_backend_lists_known_ones() {
    for args in [
        &["rays", "cornell", "--backend", "obvhs,embreex"][..],
        &["reference", "cornell", "--backend", "embreex", "--spp", "1"][..],
    ] {
        let (ok, err) = run(args);
        assert!(!ok);
        assert!(err.contains("unknown backend `embreex`"), "{err}");
        assert!(err.contains("obvhs, packet"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

#[test]
fn bad_isa_is_a_clear_error() {
    let (ok, err) = run(&["rays", "cornell", "--isa", "sse9"]);
    assert!(!ok && err.contains("unknown ISA `sse9`"), "{err}");
    // An ISA this CPU lacks (if any) names the available ones.
    if let Some(missing) = ["avx512", "avx2"]
        .into_iter()
        .find(|i| dibench::simd::Isa::parse(i).is_err())
    {
        let (ok, err) = run(&["rays", "cornell", "--isa", missing]);
        assert!(!ok && err.contains("not supported by this CPU"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

#[test]
fn rays_writes_csv() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let (ok, err) = run(&[
        "rays", "cornell", "--out", out, "--size", "16", "--rounds", "1",
    ]);
    assert!(ok, "{err}");
    let csv = std::fs::read_to_string(dir.path().join("cornell/rays.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    for col in [
        "backend",
        "isa",
        "ray_class",
        "packets",
        "rays",
        "seconds",
        "mrays_per_s",
        "active_lane_fraction",
        "nodes_per_ray",
        "build_s",
    ] {
        assert!(header.split(',').any(|c| c == col), "{header}");
    }
    for class in ["primary", "shadow_area", "shadow_distant", "incoherent"] {
        assert!(csv.contains(&format!("obvhs,scalar,{class}")), "{csv}");
        assert!(csv.contains(&format!("packet,portable,{class}")), "{csv}");
    }
    // Every subject's build time, the same on each of its rows.
    let build = header.split(',').position(|c| c == "build_s").unwrap();
    let mut seen: Vec<(String, String, String)> = vec![];
    for line in csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let s: f64 = f[build].parse().unwrap();
        assert!(s > 0.0 && s.is_finite(), "{line}");
        let key = (f[1].to_string(), f[2].to_string(), f[build].to_string());
        if !seen.contains(&key) {
            assert!(
                !seen.iter().any(|k| (&k.0, &k.1) == (&key.0, &key.1)),
                "two build times for {key:?}: {csv}"
            );
            seen.push(key);
        }
    }
}

/// `--class` times only the named ray classes, and an unknown one is an error naming the
/// flag and the known classes.
#[test]
fn class_picks_the_ray_classes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let (ok, err) = run(&[
        "rays",
        "cornell",
        "--out",
        out,
        "--size",
        "16",
        "--rounds",
        "1",
        "--class",
        "shadow_distant,primary",
    ]);
    assert!(ok, "{err}");
    let csv = std::fs::read_to_string(dir.path().join("cornell/rays.csv")).unwrap();
    let classes: std::collections::BTreeSet<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(3).unwrap())
        .collect();
    assert_eq!(
        classes.into_iter().collect::<Vec<_>>(),
        ["primary", "shadow_distant"],
        "{csv}"
    );
    let (ok, err) = run(&["rays", "cornell", "--out", out, "--class", "shadow"]);
    assert!(!ok, "an unknown class was accepted");
    assert!(
        err.contains("--class") && err.contains("unknown ray class `shadow`"),
        "{err}"
    );
    assert!(err.contains("shadow_area"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

/// `--packets pixel` packs one pixel's samples per packet and says so in every row (`tile`
/// by default); an unknown packing is an error naming the flag and the known ones.
#[test]
fn packets_choose_the_packing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    for (args, want) in [(&[][..], "tile"), (&["--packets", "pixel"][..], "pixel")] {
        let mut all = vec![
            "rays", "cornell", "--out", out, "--size", "16", "--rounds", "1",
        ];
        all.extend_from_slice(args);
        let (ok, err) = run(&all);
        assert!(ok, "{err}");
        let csv = std::fs::read_to_string(dir.path().join("cornell/rays.csv")).unwrap();
        let col = csv
            .lines()
            .next()
            .unwrap()
            .split(',')
            .position(|c| c == "packets")
            .unwrap();
        let rows: Vec<&str> = csv.lines().skip(1).collect();
        assert!(!rows.is_empty());
        for row in rows {
            assert_eq!(row.split(',').nth(col), Some(want), "{csv}");
        }
    }
    let (ok, err) = run(&["rays", "cornell", "--out", out, "--packets", "rows"]);
    assert!(!ok, "an unknown packing was accepted");
    assert!(err.contains("--packets") && err.contains("pixel"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}
