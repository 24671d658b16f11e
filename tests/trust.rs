//! Trust by default: references sized by the comparison they serve, debiased errors, and
//! convergence slopes (`harness::pilot`, `harness::summary`).

mod common;
use common::{TINY as SCENE, dibench, run_dirs};

use dibench::film::{Film, Image};
use dibench::harness::reference;
use dibench::metrics::{relmse, relmse_floor, rmse};
use dibench::prepare::PreparedScene;
use dibench::render::Renderer;
use dibench::scene::Scene;
use dibench::strategy::Integrand;

fn scene() -> PreparedScene {
    let dir = tempfile::tempdir().unwrap();
    PreparedScene::new(Scene::parse(SCENE, &dir.path().join("tiny.toml")).unwrap())
}

fn image(scene: &PreparedScene, strategy: &str, spp: u64, seed: u64) -> Image {
    let s = dibench::strategy::by_name(strategy).unwrap();
    let mut r = Renderer::new(scene, s.as_ref(), seed).unwrap();
    let mut film = Film::new(scene.scene.width, scene.scene.height);
    for _ in 0..spp {
        r.add_pass(&mut film);
    }
    film.mean()
}

/// Mean and standard error of `xs`.
fn mean_se(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    let v = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (v / n).sqrt())
}

/// Against many small, noisy references (each paired with its own image), the debiased MSE
/// and relMSE match the errors against one large reference within their standard errors;
/// the raw ones do not (the negative control: the floor is what debiasing removes).
#[test]
fn debiased_errors_against_small_references_match_a_large_one() {
    let sc = scene();
    let big = reference::render(&sc, Integrand::DIRECT, 16384, 7, 1).unwrap();
    let big_floor2 = big.meta.noise_floor_rmse.unwrap().powi(2);
    let big_rel = relmse_floor(&big.variance, &big.image);
    let (mut d_mse, mut raw_mse, mut d_rel, mut raw_rel) = (vec![], vec![], vec![], vec![]);
    for k in 0..48u64 {
        let img = image(&sc, "light", 16, 1000 + k);
        let small = reference::render(&sc, Integrand::DIRECT, 64, 2000 + k, 1).unwrap();
        let floor2 = small.meta.noise_floor_rmse.unwrap().powi(2);
        let truth_mse = rmse(&img, &big.image).powi(2) - big_floor2;
        let measured = rmse(&img, &small.image).powi(2);
        d_mse.push(measured - floor2 - truth_mse);
        raw_mse.push(measured - truth_mse);
        let truth_rel = relmse(&img, &big.image) - big_rel;
        let measured = relmse(&img, &small.image);
        d_rel.push(measured - relmse_floor(&small.variance, &small.image) - truth_rel);
        raw_rel.push(measured - truth_rel);
    }
    for (name, debiased, raw) in [("MSE", &d_mse, &raw_mse), ("relMSE", &d_rel, &raw_rel)] {
        let (m, se) = mean_se(debiased);
        eprintln!(
            "{name}: debiased − truth {m:.3e} ± {se:.3e}, raw − truth {:.3e}",
            mean_se(raw).0
        );
        assert!(m.abs() <= 4.0 * se, "debiased {name}: {m:.3e} ± {se:.3e}");
        let (m, se) = mean_se(raw);
        assert!(
            m > 4.0 * se,
            "raw {name} should be biased: {m:.3e} ± {se:.3e}"
        );
    }
}

fn field<'a>(header: &'a str, row: &'a str, name: &str) -> &'a str {
    let k = header.split(',').position(|h| h == name).unwrap();
    row.split(',').nth(k).unwrap()
}

/// Without `--reference-spp`, `compare` pilots the strategies and renders a reference whose
/// floor meets `--reference-floor` against the smallest RMSE measured, so it ends without a
/// warning; independent-sample strategies converge at slope −½ in spp.
#[test]
fn the_default_compare_sizes_its_reference_and_ends_without_warning() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), SCENE).unwrap();
    let args = [
        "compare",
        "tiny.toml",
        "--time",
        "0.1",
        "--runs",
        "3",
        "--reference-floor",
        "0.3",
        "--strategies",
        "light,cosine,mis-power",
        "--threads",
        "1",
        "--out",
        "out",
    ];
    let (code, stdout, stderr) = dibench(&args, dir.path());
    assert_eq!(code, 0, "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
    assert!(stderr.contains("pilot: 3 strategies"), "{stderr}");
    let scene_dir = dir.path().join("out/tiny");
    let runs = run_dirs(&scene_dir);
    assert_eq!(runs.len(), 1, "{runs:?}");
    let run = &runs[0];
    let summary = std::fs::read_to_string(run.join("summary.csv")).unwrap();
    let mut lines = summary.lines();
    let header = lines.next().unwrap();
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 3, "{summary}");
    let min_rmse = rows
        .iter()
        .map(|r| field(header, r, "rmse_mean").parse::<f64>().unwrap())
        .fold(f64::INFINITY, f64::min);
    let floor: f64 = field(header, rows[0], "reference_noise_floor")
        .parse()
        .unwrap();
    assert!(
        floor <= 0.3 * min_rmse,
        "floor {floor}, smallest RMSE {min_rmse}"
    );
    for r in &rows {
        let slope: f64 = field(header, r, "slope_spp_mean").parse().unwrap();
        assert!((-0.65..=-0.35).contains(&slope), "{r}: slope {slope}");
    }
    // The table comes last, ranked: the best first, the last row a verdict against it.
    let last = stdout.lines().last().unwrap();
    assert!(last.ends_with("worse") || last.ends_with("tie"), "{stdout}");
    // A second run's pilot differs by its noise, and still reuses the stored reference.
    let (code, _, stderr) = dibench(&args, dir.path());
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("reusing"), "{stderr}");
}

/// `compare --plan` prints one plan per integrand and renders and writes nothing. The plan's
/// time is the model's T/(f·MARGIN)² (the reference strategy is the one of smallest predicted
/// RMSE); a cap shorter than it is named with the floor it would leave.
#[test]
fn compare_plan_prints_the_reference_plan_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), SCENE).unwrap();
    let plan = |cap: &str| {
        let args = [
            "compare",
            "tiny.toml",
            "--plan",
            "--time",
            "0.1",
            "--strategies",
            "light,cosine",
            "--threads",
            "1",
            "--reference-cap",
            cap,
            "--out",
            "out",
        ];
        let (code, stdout, stderr) = dibench(&args, dir.path());
        assert_eq!(code, 0, "{stderr}");
        stdout
    };
    let stdout = plan("1800");
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 2, "{stdout}");
    let (header, row) = (lines[0], lines[1]);
    assert_eq!(field(header, row, "integrand"), "direct");
    let strategy = field(header, row, "reference_strategy");
    assert_eq!(strategy, field(header, row, "smallest_by"), "{row}");
    let share: f64 = field(header, row, "target_share").parse().unwrap();
    assert!(
        (share - 0.1 * dibench::harness::pilot::MARGIN).abs() < 1e-3,
        "{row}"
    );
    let secs: f64 = field(header, row, "predicted_s").parse().unwrap();
    let spp: f64 = field(header, row, "predicted_spp").parse().unwrap();
    let model = 0.1 / (0.1f64 * dibench::harness::pilot::MARGIN).powi(2);
    // spp = ⌈T / ((f·MARGIN)² t)⌉ passes of t = secs / spp seconds: the model's time plus at
    // most one pass, printed to 0.05 s.
    let (round, pass) = (0.05, secs / spp);
    assert!(
        secs >= model - round && secs <= model + pass + round,
        "{secs} s vs the model's {model} s (+ one pass of {pass} s): {row}"
    );
    assert_eq!(field(header, row, "outcome"), "reaches the floor");
    assert!(!dir.path().join("out").exists(), "--plan wrote output");
    let capped = plan("1");
    assert!(
        capped.contains("the cap (1 s) ends it at a floor of about"),
        "{capped}"
    );
}
