//! Bad input gets a clear error naming the file and the field, a non-zero exit, and no panic.

mod common;
use common::{dibench, stored_file};

use dibench::scene::Scene;
use std::path::Path;

const GOOD: &str = r#"
[camera]
eye = [0.0, 1.0, 3.0]
look_at = [0.0, 0.0, 0.0]
fov_y_deg = 40.0
[image]
width = 8
height = 8
[[material]]
name = "m"
albedo = [0.5, 0.5, 0.5]
[[quad]]
corner = [-1.0, 1.0, -1.0]
edge_u = [2.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 2.0]
material = "m"
emission = [1.0, 1.0, 1.0]
"#;

fn load_err(text: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad_scene.toml");
    std::fs::write(&path, text).unwrap();
    Scene::load(&path)
        .expect_err("bad scene accepted")
        .to_string()
}

fn assert_mentions(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(
            msg.contains(p),
            "error message `{msg}` does not mention `{p}`"
        );
    }
}

#[test]
fn good_scene_loads() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.toml");
    std::fs::write(&path, GOOD).unwrap();
    Scene::load(&path).unwrap();
}

#[test]
fn malformed_toml_names_file_and_line() {
    let msg = load_err(&GOOD.replace("width = 8", "width = = 8"));
    assert_mentions(&msg, &["bad_scene.toml", "line 7"]);
}

#[test]
fn unknown_key_is_an_error() {
    let msg = load_err(&GOOD.replace(
        "albedo = [0.5, 0.5, 0.5]",
        "albedo = [0.5, 0.5, 0.5]\nroughness = 0.3",
    ));
    assert_mentions(&msg, &["bad_scene.toml", "roughness"]);
}

#[test]
fn missing_obj_names_the_field_and_the_file() {
    let msg = load_err(&format!(
        "{GOOD}[[mesh]]\nfile = \"nowhere/missing.obj\"\nmaterial = \"m\"\n"
    ));
    assert_mentions(&msg, &["bad_scene.toml", "mesh[0].file", "missing.obj"]);
}

#[test]
fn obj_with_nan_vertex_or_bad_index() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    for (obj, expect) in [
        ("v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n", "vertex 2"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", "bad.obj"),
    ] {
        std::fs::write(dir.path().join("bad.obj"), obj).unwrap();
        std::fs::write(
            &scene,
            format!("{GOOD}[[mesh]]\nfile = \"bad.obj\"\nmaterial = \"m\"\n"),
        )
        .unwrap();
        let msg = Scene::load(&scene)
            .expect_err("bad OBJ accepted")
            .to_string();
        assert_mentions(&msg, &["bad.obj", expect]);
    }
}

#[test]
fn invalid_values_name_their_field() {
    let cases = [
        (
            GOOD.replace("emission = [1.0, 1.0, 1.0]", "emission = [1.0, -1.0, 1.0]"),
            "quad[0].emission",
        ),
        (
            GOOD.replace("emission = [1.0, 1.0, 1.0]", "emission = [1.0, nan, 1.0]"),
            "quad[0].emission",
        ),
        (GOOD.replace("width = 8", "width = 0"), "image"),
        (
            GOOD.replace("material = \"m\"", "material = \"steel\""),
            "quad[0].material",
        ),
        (
            GOOD.replace("fov_y_deg = 40.0", "fov_y_deg = 180.0"),
            "camera.fov_y_deg",
        ),
        (
            GOOD.replace("edge_v = [0.0, 0.0, 2.0]", "edge_v = [4.0, 0.0, 0.0]"),
            "quad[0]",
        ),
        (GOOD.replace("emission = [1.0, 1.0, 1.0]", ""), "light"),
    ];
    for (text, field) in cases {
        let msg = load_err(&text);
        assert_mentions(&msg, &["bad_scene.toml", field]);
    }
}

#[test]
fn cli_reports_user_errors_with_nonzero_exit() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("broken.toml"), "[camera\n").unwrap();
    std::fs::write(dir.path().join("ok.toml"), GOOD).unwrap();
    let out = dir.path().join("out");
    let out = out.to_str().unwrap();
    let cases: [(&[&str], &str); 6] = [
        (&["compare", "broken.toml", "--out", out], "broken.toml"),
        (&["compare", "no_such_scene", "--out", out], "no_such_scene"),
        (
            &["compare", "ok.toml", "--time", "0", "--out", out],
            "--time",
        ),
        (
            &["compare", "ok.toml", "--time", "-1", "--out", out],
            "--time",
        ),
        (
            &["compare", "ok.toml", "--strategies", "magic", "--out", out],
            "unknown strategy `magic`",
        ),
        (
            &["reference", "ok.toml", "--spp", "0", "--out", out],
            "--spp",
        ),
    ];
    for (args, expect) in cases {
        let (code, _, stderr) = dibench(args, dir.path());
        assert_ne!(code, 0, "dibench {args:?} succeeded");
        assert!(
            stderr.contains(expect),
            "dibench {args:?}: stderr `{stderr}` does not mention `{expect}`"
        );
    }
    assert!(
        !dir.path().join("out").join("ok").exists()
            || std::fs::read_dir(dir.path().join("out/ok"))
                .unwrap()
                .next()
                .is_none(),
        "a failed run left output behind"
    );
}

#[test]
fn cli_compare_writes_exrs_and_csv() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("ok.toml"), GOOD).unwrap();
    let (code, _, stderr) = dibench(
        &[
            "compare",
            "ok.toml",
            "--time",
            "0.2",
            "--reference-spp",
            "64",
            "--out",
            "out",
        ],
        dir.path(),
    );
    assert_eq!(code, 0, "{stderr}");
    let runs: Vec<_> = std::fs::read_dir(dir.path().join("out/ok"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| !p.ends_with("reference"))
        .collect();
    assert_eq!(runs.len(), 1);
    let csv = std::fs::read_to_string(runs[0].join("results.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert_eq!(
        header,
        "scene,strategy,integrand,backend,threads,run,seed,checkpoint,time_s,spp,rmse,relmse,sampler,flip"
    );
    for s in ["light", "cosine", "mis-power"] {
        assert!(
            runs[0].join(format!("{s}.exr")).is_file(),
            "{s}.exr missing"
        );
        assert!(
            csv.lines().any(|l| l.starts_with(&format!("ok,{s},"))),
            "no rows for {s}"
        );
    }
    let stored = stored_file(&dir.path().join("out/ok/reference/direct.json"), "image");
    assert!(stored.is_file());

    // A truncated stored reference is an error naming it, not a panic or a silent re-render.
    let bytes = std::fs::read(&stored).unwrap();
    std::fs::write(&stored, &bytes[..bytes.len() / 3]).unwrap();
    let (code, _, stderr) = dibench(
        &[
            "compare",
            "ok.toml",
            "--time",
            "0.1",
            "--reference-spp",
            "64",
            "--out",
            "out",
        ],
        dir.path(),
    );
    assert_ne!(code, 0, "a truncated reference was accepted");
    let name = stored.file_name().unwrap().to_string_lossy();
    assert!(stderr.contains(&*name), "{stderr}");
    let leftovers: Vec<_> = walk(&dir.path().join("out"))
        .into_iter()
        .filter(|p| p.to_string_lossy().contains(".tmp-"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

fn walk(p: &Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(p).unwrap().flatten() {
        let path = e.path();
        if path.is_dir() {
            out.extend(walk(&path));
        } else {
            out.push(path);
        }
    }
    out
}

/// Every class of bad scene input, through the command line: exit status 1, an error naming the
/// file and the field (or line), no panic, and nothing written.
#[test]
fn every_bad_input_class_exits_nonzero_naming_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("nan.obj"),
        "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("inf.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("index.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
    )
    .unwrap();
    std::fs::create_dir(dir.path().join("folder.obj")).unwrap();
    let mesh = |f: &str| format!("{GOOD}[[mesh]]\nfile = \"{f}\"\nmaterial = \"m\"\n");
    let classes: Vec<(&str, String, &[&str])> = vec![
        (
            "malformed TOML",
            GOOD.replace("width = 8", "width = = 8"),
            &["line 7"],
        ),
        (
            "unknown key",
            GOOD.replace(
                "albedo = [0.5, 0.5, 0.5]",
                "albedo = [0.5, 0.5, 0.5]\ncolour = 1",
            ),
            &["colour"],
        ),
        (
            "missing file",
            mesh("gone.obj"),
            &["mesh[0].file", "gone.obj"],
        ),
        ("unreadable file", mesh("folder.obj"), &["folder.obj"]),
        (
            "unknown top-level key",
            format!("{GOOD}[[pointlight]]\nposition = [0.0, 2.0, 0.0]\n"),
            &["pointlight", "point_light", "linear_spot_light"],
        ),
        (
            "light type given as a value",
            format!("point_light = 3\n{GOOD}"),
            &["point_light", "array of tables"],
        ),
        (
            "unknown light field",
            format!(
                "{GOOD}[[spot_light]]\nposition = [0.0, 2.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\ncone_angle_deg = 30.0\nintensity = [1.0, 1.0, 1.0]\ncolour = 1\n"
            ),
            &["spot_light[0].colour", "falloff_start_deg"],
        ),
        (
            "light field out of range",
            format!(
                "{GOOD}[[linear_spot_light]]\nposition = [0.0, 2.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\ncone_angle_deg = 200.0\nintensity = [1.0, 1.0, 1.0]\n"
            ),
            &["linear_spot_light[0].cone_angle_deg", "[0, 180]"],
        ),
        (
            "light field missing",
            format!("{GOOD}[[directional_light]]\nirradiance = [1.0, 1.0, 1.0]\n"),
            &["directional_light[0].direction", "missing"],
        ),
        (
            "NaN vertex",
            mesh("nan.obj"),
            &["mesh[0].file", "nan.obj", "vertex 2"],
        ),
        (
            "Inf vertex",
            mesh("inf.obj"),
            &["mesh[0].file", "inf.obj", "vertex 3"],
        ),
        (
            "index out of range",
            mesh("index.obj"),
            &["mesh[0].file", "index.obj", "index"],
        ),
        (
            "negative radiance",
            GOOD.replace("emission = [1.0, 1.0, 1.0]", "emission = [1.0, -2.0, 1.0]"),
            &["quad[0].emission"],
        ),
        (
            "non-finite radiance",
            GOOD.replace("emission = [1.0, 1.0, 1.0]", "emission = [inf, 1.0, 1.0]"),
            &["quad[0].emission"],
        ),
        (
            "zero-size image",
            GOOD.replace("height = 8", "height = 0"),
            &["image"],
        ),
        (
            "unknown material name",
            GOOD.replace("material = \"m\"", "material = \"chrome\""),
            &["quad[0].material", "chrome"],
        ),
    ];
    for (class, text, fields) in classes {
        std::fs::write(dir.path().join("bad.toml"), text).unwrap();
        let (code, _, stderr) = dibench(&["compare", "bad.toml", "--out", "out"], dir.path());
        assert_eq!(code, 1, "{class}: exit status {code}, stderr {stderr}");
        assert!(stderr.contains("bad.toml"), "{class}: {stderr}");
        for f in fields {
            assert!(
                stderr.contains(f),
                "{class}: `{stderr}` does not mention `{f}`"
            );
        }
        assert!(!stderr.contains("backtrace"), "{class}: {stderr}");
    }
    assert!(
        !dir.path().join("out").exists(),
        "a rejected scene left output behind"
    );
}
