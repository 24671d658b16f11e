//! The rigor harness through the CLI: repeated runs with summary.csv, variance images, run
//! metadata, reference noise floor and checkpoints, plots, and errors for bad arguments.

mod common;
use common::{TINY_WITH_AO as SCENE, dibench, stored_file};

use std::path::{Path, PathBuf};
use std::process::Command;

/// A CSV text's rows split into fields, and a column's index by its header name.
fn columns(text: &str) -> (impl Fn(&str) -> usize + '_, Vec<Vec<&str>>) {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let rows = lines.map(|l| l.split(',').collect()).collect();
    let col = move |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no column `{name}`"))
    };
    (col, rows)
}

fn run_dirs(scene_dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(scene_dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| !p.ends_with("reference"))
        .collect()
}

#[test]
fn compare_runs_writes_summary_variance_metadata_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), SCENE).unwrap();
    let (code, stdout, stderr) = dibench(
        &[
            "compare",
            "tiny.toml",
            "--runs",
            "3",
            "--time",
            "0.05",
            "--reference-spp",
            "256",
            "--strategies",
            "light,cosine,ao-cosine",
            "--threads",
            "1",
            "--out",
            "out",
        ],
        dir.path(),
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("noise floor"), "{stdout}");
    let runs = run_dirs(&dir.path().join("out/tiny"));
    assert_eq!(runs.len(), 1);
    let run = &runs[0];

    let results = std::fs::read_to_string(run.join("results.csv")).unwrap();
    for k in 0..3 {
        let seed = 1 + k;
        assert!(
            results.lines().any(
                |l| l.contains(&format!(",light,direct,packet,1,{k},{seed},7,"))
                    || l.contains(&format!(",{k},{seed},7,"))
            ),
            "no final row for run {k}:\n{results}"
        );
    }

    let summary = std::fs::read_to_string(run.join("summary.csv")).unwrap();
    let mut lines = summary.lines();
    assert_eq!(
        lines.next().unwrap(),
        "scene,integrand,strategy,runs,budget_s,time_s_mean,overshoot_max,spp_mean,rmse_mean,\
         rmse_ci95,rmse_debiased,mse_debiased_mean,mse_debiased_ci95,relmse_mean,relmse_ci95,\
         relmse_debiased_mean,relmse_debiased_ci95,efficiency,predicted_rmse,\
         reference_noise_floor,slope_time_mean,slope_time_ci95,slope_spp_mean,welch_p_vs_best,\
         holm_p_vs_best,vs_best,sampler,budget_spp,flip_mean,flip_ci95"
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 3, "{summary}");
    for r in &rows {
        assert_eq!(r[3], "3", "runs: {summary}");
        let ci: f64 = r[9].parse().expect("an RMSE CI with 3 runs");
        assert!(ci.is_finite() && ci >= 0.0);
        let floor: f64 = r[19].parse().expect("a reference noise floor");
        assert!(floor > 0.0 && floor.is_finite());
        // Debiased MSE + floor² is the mean of the runs' MSE, at least the squared mean RMSE
        // (Jensen); debiased relMSE is relMSE less the reference's positive relMSE floor.
        let (rmse, mse_d): (f64, f64) = (r[8].parse().unwrap(), r[11].parse().unwrap());
        assert!(
            mse_d + floor * floor >= rmse * rmse * (1.0 - 1e-12),
            "{summary}"
        );
        let (rel, rel_d): (f64, f64) = (r[13].parse().unwrap(), r[15].parse().unwrap());
        assert!(rel_d < rel, "{summary}");
        let slope: f64 = r[20].parse().expect("a convergence slope");
        assert!(slope.is_finite() && slope < 0.0, "slope {slope}: {summary}");
        if !r[23].is_empty() {
            let (raw, holm): (f64, f64) = (r[23].parse().unwrap(), r[24].parse().unwrap());
            assert!(holm >= raw && holm <= 1.0, "{summary}");
        }
    }
    // One best per integrand: light vs cosine for direct, ao-cosine alone for AO.
    let best: Vec<_> = rows
        .iter()
        .filter(|r| r[25] == "best")
        .map(|r| r[2])
        .collect();
    assert_eq!(best.len(), 2, "{summary}");
    assert!(best.contains(&"ao-cosine"));

    for s in ["light", "cosine", "ao-cosine"] {
        for suffix in ["", ".variance"] {
            assert!(
                run.join(format!("{s}{suffix}.exr")).is_file(),
                "{s}{suffix}.exr"
            );
        }
    }
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("run.json")).unwrap()).unwrap();
    for key in [
        "commit",
        "cpu_model",
        "isa",
        "threads",
        "backend",
        "seeds",
        "budget_s",
        "rustc",
    ] {
        assert!(meta.get(key).is_some(), "run.json lacks {key}: {meta}");
    }
    assert_eq!(meta["seeds"], serde_json::json!([1, 2, 3]));

    let (code, stdout, stderr) = dibench(&["plot", run.to_str().unwrap()], dir.path());
    assert_eq!(code, 0, "{stderr}");
    for f in [
        "rmse_vs_time.png",
        "rmse_vs_time.svg",
        "rmse_vs_spp.png",
        "rmse_vs_spp.svg",
        "strip.png",
        "variance.png",
    ] {
        let p = run.join("plots").join(f);
        assert!(std::fs::metadata(&p).unwrap().len() > 1000, "{f} empty");
        assert!(stdout.contains(f));
    }
    let png = std::fs::read(run.join("plots/strip.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
}

/// The reference's noise floor predicts the RMSE between two independent references:
/// E[RMSE²(a, b)] = floor_a² + floor_b². Checked with the spread of the per-pixel terms as
/// the tolerance (z ≤ 4.4 over 16·12·3 pixel-channels).
#[test]
fn reference_noise_floor_predicts_the_difference_of_two_references() {
    use dibench::output::read_exr;
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), SCENE).unwrap();
    let mut images = Vec::new();
    let mut floors = Vec::new();
    for seed in ["1", "2"] {
        let out = format!("out{seed}");
        let (code, _, stderr) = dibench(
            &[
                "reference",
                "tiny.toml",
                "--spp",
                "200",
                "--seed",
                seed,
                "--threads",
                "1",
                "--out",
                &out,
            ],
            dir.path(),
        );
        assert_eq!(code, 0, "{stderr}");
        let refdir = dir.path().join(&out).join("tiny/reference");
        let meta: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(refdir.join("direct.json")).unwrap())
                .unwrap();
        assert_eq!(
            meta["spp"], 200,
            "the final save replaces the 64 and 128 spp checkpoints"
        );
        floors.push(meta["noise_floor_rmse"].as_f64().unwrap());
        images.push(read_exr(&stored_file(&refdir.join("direct.json"), "image")).unwrap());
        assert!(stored_file(&refdir.join("direct.json"), "variance").is_file());
    }
    let d2: Vec<f64> = images[0]
        .pixels
        .iter()
        .zip(&images[1].pixels)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).powi(2)))
        .collect();
    let n = d2.len() as f64;
    let mean = d2.iter().sum::<f64>() / n;
    let sd = (d2.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let expected = floors[0].powi(2) + floors[1].powi(2);
    let z = (mean - expected) / (sd / n.sqrt());
    assert!(
        z.abs() < 4.4,
        "MSE {mean:.4e} vs predicted {expected:.4e}, z = {z:.2}"
    );
}

#[test]
fn bad_harness_arguments_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), SCENE).unwrap();
    let cases: [(&[&str], &str); 4] = [
        (
            &["compare", "tiny.toml", "--runs", "0", "--out", "o"],
            "--runs",
        ),
        (
            &["reference", "tiny.toml", "--time", "0", "--out", "o"],
            "--time",
        ),
        (
            &["reference", "tiny.toml", "--spp", "0", "--out", "o"],
            "--spp",
        ),
        (&["plot", "no_such_dir"], "results.csv"),
    ];
    for (args, needle) in cases {
        let (code, _, stderr) = dibench(args, dir.path());
        assert_ne!(code, 0, "{args:?} succeeded");
        assert!(
            stderr.contains(needle),
            "{args:?}: `{stderr}` lacks `{needle}`"
        );
    }
    assert!(
        !dir.path().join("o").exists(),
        "a failed run left output behind"
    );
}

/// Ctrl-C during `compare`: the command stops between passes, exits 130, keeps the strategy
/// runs that finished (results.csv, their EXRs, a summary) and records the interruption in
/// run.json; the unfinished strategy leaves nothing, and no temp file is left behind.
#[test]
fn ctrl_c_keeps_finished_strategies_and_exits_130() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), SCENE).unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_dibench"))
        .args([
            "compare",
            "tiny.toml",
            "--time",
            "1.5",
            "--reference-spp",
            "64",
            "--strategies",
            "light,cosine",
            "--threads",
            "1",
            "--out",
            "out",
        ])
        .current_dir(dir.path())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for the first strategy's rows, then interrupt the second one (1.5 s long).
    let scene_dir = dir.path().join("out/tiny");
    let start = std::time::Instant::now();
    let run = loop {
        assert!(start.elapsed().as_secs() < 60, "no results.csv after 60 s");
        if scene_dir.exists()
            && let Some(r) = run_dirs(&scene_dir)
                .into_iter()
                .find(|r| r.join("results.csv").exists())
        {
            break r;
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    };
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");

    let meta = std::fs::read_to_string(run.join("run.json")).unwrap();
    let meta: serde_json::Value = serde_json::from_str(&meta).unwrap();
    assert_eq!(meta["interrupted"], true);
    let completed = meta["completed"].as_array().unwrap();
    assert_eq!(completed.len(), 1, "{meta}");
    let done = completed[0][0].as_str().unwrap();
    let other = if done == "light" { "cosine" } else { "light" };
    let results = std::fs::read_to_string(run.join("results.csv")).unwrap();
    assert!(results.lines().count() > 1);
    assert!(
        results
            .lines()
            .skip(1)
            .all(|l| l.contains(&format!(",{done},"))),
        "{results}"
    );
    assert!(run.join(format!("{done}.exr")).exists());
    assert!(run.join(format!("{done}.variance.exr")).exists());
    assert!(!run.join(format!("{other}.exr")).exists());
    let summary = std::fs::read_to_string(run.join("summary.csv")).unwrap();
    assert_eq!(summary.lines().count(), 2, "{summary}");
    for e in walk(dir.path()) {
        let name = e.file_name().unwrap().to_string_lossy().into_owned();
        assert!(!name.contains(".tmp"), "temp file left: {}", e.display());
    }
}

fn walk(p: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(p).unwrap().flatten() {
        let path = e.path();
        if path.is_dir() {
            out.extend(walk(&path));
        }
        out.push(path);
    }
    out
}

/// `reference --shard i/n` on three "machines" plus `dibench merge` gives the reference a
/// single process renders (same streams per pass; sums merged by Chan's formula, so equal up
/// to roundoff), and a missing shard is an error naming it.
#[test]
fn sharded_reference_merges_to_the_single_process_one() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), SCENE).unwrap();
    let (code, _, stderr) = dibench(
        &["reference", "tiny.toml", "--spp", "30", "--out", "single"],
        dir.path(),
    );
    assert_eq!(code, 0, "{stderr}");
    for i in 0..3 {
        let shard = format!("{i}/3");
        let (code, stdout, stderr) = dibench(
            &[
                "reference",
                "tiny.toml",
                "--spp",
                "30",
                "--shard",
                &shard,
                "--threads",
                "1",
                "--out",
                "sharded",
            ],
            dir.path(),
        );
        assert_eq!(code, 0, "{stderr}");
        assert!(stdout.contains("10 of 30 spp"), "{stdout}");
        if i == 1 {
            // Two of three shards: merging is refused, naming the missing one.
            let (code, _, stderr) =
                dibench(&["merge", "tiny.toml", "--out", "sharded"], dir.path());
            assert_eq!(code, 1);
            assert!(stderr.contains("shards 2 of 3 missing"), "{stderr}");
        }
    }
    let (code, _, stderr) = dibench(&["merge", "tiny.toml", "--out", "sharded"], dir.path());
    assert_eq!(code, 0, "{stderr}");
    for name in ["direct", "ao"] {
        let read = |root: &str, role: &str| {
            let manifest = dir
                .path()
                .join(root)
                .join("tiny/reference")
                .join(format!("{name}.json"));
            dibench::output::read_exr(&stored_file(&manifest, role)).unwrap()
        };
        for file in ["image", "variance"] {
            let (a, b) = (read("single", file), read("sharded", file));
            assert_eq!(a.pixels.len(), b.pixels.len());
            let mut worst = 0.0f64;
            for (p, q) in a.pixels.iter().zip(&b.pixels) {
                for c in 0..3 {
                    let scale = p[c].abs().max(q[c].abs()).max(1e-30);
                    worst = worst.max((p[c] - q[c]).abs() / scale);
                }
            }
            // f32 storage: sums in a different order may round to the neighbouring float.
            assert!(worst < 1e-5, "{file}: relative difference {worst}");
        }
        let meta = std::fs::read_to_string(
            dir.path()
                .join(format!("sharded/tiny/reference/{name}.json")),
        )
        .unwrap();
        assert!(
            meta.contains("\"spp\": 30") || meta.contains("\"spp\":30"),
            "{meta}"
        );
        // The three "machines" are one here: the merged reference names it once.
        let cpu = serde_json::from_str::<serde_json::Value>(&meta).unwrap()["cpu"]
            .as_str()
            .unwrap_or_default()
            .to_string();
        assert!(!cpu.is_empty() && !cpu.contains(" | "), "{meta}");
    }
    let (code, _, stderr) = dibench(
        &[
            "reference",
            "tiny.toml",
            "--spp",
            "30",
            "--shard",
            "3/3",
            "--out",
            "x",
        ],
        dir.path(),
    );
    assert_eq!(code, 1);
    assert!(stderr.contains("--shard must be i/n"), "{stderr}");
}

/// A reference interrupted early never replaces a stored one of the same scene with more
/// samples: its checkpoints are skipped while they have fewer (a rerun after a kill used to
/// lose the better reference).
#[test]
fn an_interrupted_reference_keeps_the_better_stored_one() {
    let dir = tempfile::tempdir().unwrap();
    let scene = SCENE
        .replace("width = 16", "width = 32")
        .replace("height = 12", "height = 32")
        .replace("[ambient_occlusion]\ndistance = 0.5\n", "");
    std::fs::write(dir.path().join("tiny.toml"), scene).unwrap();
    let args = ["reference", "tiny.toml", "--threads", "1", "--out", "out"];
    let start = std::time::Instant::now();
    let (code, _, stderr) = dibench(&[&args[..], &["--spp", "1024"]].concat(), dir.path());
    assert_eq!(code, 0, "{stderr}");
    // A third of that time: past the first checkpoints, well short of 1024 spp, on any machine.
    let a_third = start.elapsed() / 3;
    let mut child = Command::new(env!("CARGO_BIN_EXE_dibench"))
        .args([&args[..], &["--spp", "100000000", "--seed", "2"]].concat())
        .current_dir(dir.path())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(a_third);
    common::signal(child.id(), libc::SIGINT);
    let status = child.wait().unwrap();
    let mut stderr = String::new();
    use std::io::Read;
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    assert_eq!(status.code(), Some(130), "{stderr}");
    let meta: serde_json::Value = serde_json::from_slice(
        &std::fs::read(dir.path().join("out/tiny/reference/direct.json")).unwrap(),
    )
    .unwrap();
    let stopped: u64 = stderr
        .split("stopped at ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{stderr}"));
    assert!(
        stopped >= 64,
        "stopped before the first checkpoint: {stderr}"
    );
    if stopped < 1024 {
        assert_eq!(
            (meta["seed"].as_u64(), meta["spp"].as_u64()),
            (Some(1), Some(1024)),
            "{stderr}"
        );
        assert!(stderr.contains("no checkpoint of it stored"), "{stderr}");
    }
}

/// The exit status tells the kind of error (`cli::exit_status`): 1 for a usage error found
/// after parsing, 2 for a command line the parser refuses, 3 for a check that ran and failed,
/// 4 for a backend that cannot be used here.
#[test]
fn exit_statuses_tell_the_kind_of_error() {
    let dir = tempfile::tempdir().unwrap();
    let (code, stdout, stderr) = dibench(
        &["warp", "phong-lecture", "--samples", "100000"],
        dir.path(),
    );
    assert_eq!(code, 3, "{stderr}");
    assert!(
        stdout.contains("χ² =") && stderr.contains("FAILED"),
        "{stdout}{stderr}"
    );
    let (code, _, stderr) = dibench(&["warp", "no-such-sampler"], dir.path());
    assert_eq!(code, 1, "{stderr}");
    let (code, _, stderr) = dibench(&["warp", "phong-lecture", "--alpha", "2"], dir.path());
    assert_eq!(code, 2, "{stderr}");
    if !cfg!(feature = "embree") {
        let (code, _, stderr) = dibench(
            &[
                "reference",
                "cornell",
                "--backend",
                "embree",
                "--out",
                "out",
            ],
            dir.path(),
        );
        assert_eq!(code, 4, "{stderr}");
        assert!(stderr.contains("--features embree"), "{stderr}");
    }
    let (code, _, stderr) = dibench(
        &["reference", "cornell", "--backend", "magic", "--out", "out"],
        dir.path(),
    );
    assert_eq!(code, 1, "{stderr}");
    assert!(!dir.path().join("out").exists());
}

/// `warp`'s verdict re-tests a failed χ² once, independently with 4× the samples: a correct
/// sampler that fails at one seed by chance (`env-octa-cdf`, seed 48: p = 3.9e-3 < 0.01; the
/// seed was found anew when the random streams' seeding changed, since seed 1 now passes)
/// passes, and a wrong one (`phong-lecture`) still fails, naming both p-values.
#[test]
fn warp_retests_before_it_says_failed() {
    let dir = tempfile::tempdir().unwrap();
    let (code, stdout, stderr) = dibench(&["warp", "env-octa-cdf", "--seed", "48"], dir.path());
    assert_eq!(code, 0, "{stdout}{stderr}");
    assert!(stdout.contains("re-testing"), "{stdout}");
    assert!(
        stdout.contains("passed at alpha = 0.01 on the re-test"),
        "{stdout}"
    );
    let (code, _, stderr) = dibench(
        &["warp", "phong-lecture", "--samples", "100000"],
        dir.path(),
    );
    assert_eq!(code, 3, "{stderr}");
    assert!(stderr.contains("at 100000 samples and p ="), "{stderr}");
}

/// `--sampler independent,sobol`: every strategy runs with both; results.csv and summary.csv
/// carry the sampler column for both, the Sobol rows leave predicted_rmse empty (and write no
/// variance image), the independent ones keep it; the console and run.json say why once; the
/// plot labels both. Bad samplers are usage errors naming the flag; stratified is refused at
/// equal time, saying it needs --spp.
#[test]
fn compare_with_two_samplers() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), SCENE).unwrap();
    let args = |sampler: &str| -> Vec<String> {
        [
            "compare",
            "tiny.toml",
            "--runs",
            "2",
            "--time",
            "0.05",
            "--reference-spp",
            "64",
            "--strategies",
            "light,cosine",
            "--threads",
            "1",
            "--sampler",
            sampler,
            "--out",
            "out",
        ]
        .map(String::from)
        .to_vec()
    };
    let run = |sampler: &str| {
        let a = args(sampler);
        let a: Vec<&str> = a.iter().map(|s| s.as_str()).collect();
        dibench(&a, dir.path())
    };
    let (code, stdout, stderr) = run("independent,sobol");
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(
        stdout.matches("predicted_rmse is left empty").count(),
        1,
        "{stdout}"
    );
    let runs = run_dirs(&dir.path().join("out/tiny"));
    let run_dir = &runs[0];
    let results = std::fs::read_to_string(run_dir.join("results.csv")).unwrap();
    assert!(
        results
            .lines()
            .next()
            .unwrap()
            .ends_with(",relmse,sampler,flip")
    );
    for s in ["light", "cosine"] {
        for g in ["independent", "sobol"] {
            assert!(
                results
                    .lines()
                    .any(|l| l.contains(&format!(",{s},")) && l.split(",").nth(12) == Some(g)),
                "no {s} × {g} rows:\n{results}"
            );
        }
        assert!(run_dir.join(format!("{s}.exr")).is_file());
        assert!(run_dir.join(format!("{s}.variance.exr")).is_file());
        assert!(run_dir.join(format!("{s}.sobol.exr")).is_file());
        assert!(!run_dir.join(format!("{s}.sobol.variance.exr")).exists());
    }
    let summary = std::fs::read_to_string(run_dir.join("summary.csv")).unwrap();
    let (col, rows) = columns(&summary);
    assert_eq!(rows.len(), 4, "{summary}");
    for r in &rows {
        let predicted = r[col("predicted_rmse")];
        match r[col("sampler")] {
            "independent" => assert!(predicted.parse::<f64>().unwrap() > 0.0, "{summary}"),
            "sobol" => assert_eq!(predicted, "", "a QMC row predicted: {summary}"),
            other => panic!("sampler {other}"),
        }
        assert!(!r[col("slope_time_mean")].is_empty(), "{summary}");
    }
    // One Holm family over the four (strategy, sampler) pairs: one best.
    assert_eq!(
        rows.iter().filter(|r| r[col("vs_best")] == "best").count(),
        1
    );
    let meta = std::fs::read_to_string(run_dir.join("run.json")).unwrap();
    assert!(
        meta.contains("\"samplers\"") && meta.contains("sampler_note"),
        "{meta}"
    );
    let (code, _, stderr) = dibench(&["plot", run_dir.to_str().unwrap()], dir.path());
    assert_eq!(code, 0, "{stderr}");
    let svg = std::fs::read_to_string(run_dir.join("plots/rmse_vs_time.svg")).unwrap();
    assert!(svg.contains("light [sobol]") && svg.contains("light [independent]"));

    for bad in ["bogus", "independent,bogus", ""] {
        let (code, _, stderr) = run(bad);
        assert_ne!(code, 0, "--sampler {bad:?} accepted");
        assert!(stderr.contains("--sampler"), "{bad:?}: {stderr}");
        if !bad.is_empty() {
            assert!(
                stderr.contains("zsobol"),
                "the generators are not listed: {stderr}"
            );
        }
    }
    let (code, _, stderr) = run("stratified");
    assert_ne!(code, 0);
    assert!(
        stderr.contains("--sampler stratified") && stderr.contains("--spp"),
        "{stderr}"
    );
}

/// `compare --spp 16`: every strategy × sampler renders exactly 16 passes, checkpoints at
/// ⌈16 / 2^(7−k)⌉ passes (1, 2, 4, 8, 16: the first four coincide), the stratified generator is
/// accepted, summary.csv has the sample budget and no time budget or overshoot, and the
/// console says "16 spp per strategy". `--spp` with `--time` is a usage error naming both.
#[test]
fn compare_at_equal_spp() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), SCENE).unwrap();
    let (code, stdout, stderr) = dibench(
        &[
            "compare",
            "tiny.toml",
            "--spp",
            "16",
            "--runs",
            "2",
            "--reference-spp",
            "64",
            "--strategies",
            "light,cosine",
            "--threads",
            "1",
            "--sampler",
            "independent,stratified,zsobol",
            "--out",
            "out",
        ],
        dir.path(),
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("16 spp per strategy"), "{stdout}");
    assert!(!stdout.contains("deviation from the budget"), "{stdout}");
    let run_dir = &run_dirs(&dir.path().join("out/tiny"))[0];
    let results = std::fs::read_to_string(run_dir.join("results.csv")).unwrap();
    let (col, rows) = columns(&results);
    // 2 strategies × 3 samplers × 2 runs, five checkpoint rows each.
    assert_eq!(rows.len(), 2 * 3 * 2 * 5, "{results}");
    for r in &rows {
        let expected = match r[col("checkpoint")] {
            "0" => "1",
            "4" => "2",
            "5" => "4",
            "6" => "8",
            "7" => "16",
            other => panic!("checkpoint {other}: {results}"),
        };
        assert_eq!(r[col("spp")], expected, "{results}");
    }
    for g in ["independent", "stratified", "zsobol"] {
        assert!(
            rows.iter().any(|r| r[col("sampler")] == g),
            "no {g}: {results}"
        );
    }
    let summary = std::fs::read_to_string(run_dir.join("summary.csv")).unwrap();
    let (col, rows) = columns(&summary);
    assert_eq!(rows.len(), 6, "{summary}");
    for r in &rows {
        assert_eq!(r[col("budget_spp")], "16", "{summary}");
        assert_eq!(r[col("budget_s")], "", "{summary}");
        assert_eq!(r[col("overshoot_max")], "", "{summary}");
        assert_eq!(r[col("spp_mean")], "16.0", "{summary}");
        let predicted = r[col("predicted_rmse")];
        if r[col("sampler")] == "independent" {
            assert!(predicted.parse::<f64>().unwrap() > 0.0, "{summary}");
        } else {
            assert_eq!(predicted, "", "a non-independent row predicted: {summary}");
        }
    }
    // Every image says how it was made (strategy, sampler, spp, seed, …) in its EXR header.
    let p = dibench::output::read_provenance(&run_dir.join("light.stratified.exr"))
        .unwrap()
        .expect("no provenance in light.stratified.exr");
    assert_eq!(
        (
            p.strategy.as_str(),
            p.sampler.as_str(),
            p.integrand.as_str()
        ),
        ("light", "stratified", "direct")
    );
    assert_eq!(
        (p.spp, p.seed, p.threads, p.content.as_str()),
        (16, 1, 1, "radiance")
    );
    assert!(p.render_time_s > 0.0 && !p.scene_hash.is_empty() && p.backend == "packet");
    let v = dibench::output::read_provenance(&run_dir.join("cosine.variance.exr"))
        .unwrap()
        .unwrap();
    assert_eq!(
        (v.strategy.as_str(), v.content.as_str()),
        ("cosine", "variance of the mean")
    );
    let reference = std::fs::read_dir(dir.path().join("out/tiny/reference"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| {
            let n = p.file_name().unwrap().to_string_lossy().to_string();
            n.ends_with(".exr") && !n.ends_with(".variance.exr")
        })
        .unwrap();
    let r = dibench::output::read_provenance(&reference)
        .unwrap()
        .unwrap();
    // The machine, as the run's metadata names it (`cpu_model`), in the images and the
    // reference alike.
    let run_json = std::fs::read_to_string(run_dir.join("run.json")).unwrap();
    let cpu_model = serde_json::from_str::<serde_json::Value>(&run_json).unwrap()["cpu_model"]
        .as_str()
        .unwrap()
        .to_string();
    // The run describes this machine, as the library does (same process environment).
    assert_eq!(cpu_model, dibench::harness::cpu_model());
    assert_eq!(p.cpu.as_deref(), Some(cpu_model.as_str()));
    assert_eq!(v.cpu.as_deref(), Some(cpu_model.as_str()));
    assert_eq!(r.cpu.as_deref(), Some(cpu_model.as_str()));
    assert_eq!(
        (r.spp, r.sampler.as_str(), r.scene_hash),
        (64, "independent", p.scene_hash)
    );
    // FLIP: the final row of each run has it, the earlier ones not; run 0's value is the
    // HDR-FLIP of the EXRs on disk (recomputed here), whose map is <stem>.flip.exr.
    let results = std::fs::read_to_string(run_dir.join("results.csv")).unwrap();
    let (col, rows) = columns(&results);
    for r in &rows {
        assert_eq!(
            r[col("flip")].is_empty(),
            r[col("checkpoint")] != "7",
            "{results}"
        );
    }
    let final_flip: f64 = rows
        .iter()
        .find(|r| {
            r[col("strategy")] == "light"
                && r[col("sampler")] == "stratified"
                && r[col("run")] == "0"
                && r[col("checkpoint")] == "7"
        })
        .unwrap()[col("flip")]
    .parse()
    .unwrap();
    let image = dibench::output::read_exr(&run_dir.join("light.stratified.exr")).unwrap();
    let reference_image = dibench::output::read_exr(&reference).unwrap();
    let flip = dibench::flip::hdr_flip_image(&reference_image, &image).unwrap();
    assert_eq!(flip.mean(), final_flip);
    assert!(final_flip > 0.0 && final_flip < 1.0, "{final_flip}");
    let map = dibench::output::read_exr(&run_dir.join("light.stratified.flip.exr")).unwrap();
    assert_eq!(map, flip.to_image());
    let fp = dibench::output::read_provenance(&run_dir.join("light.stratified.flip.exr"))
        .unwrap()
        .unwrap();
    assert_eq!(fp.content, dibench::flip::CONTENT);
    let summary = std::fs::read_to_string(run_dir.join("summary.csv")).unwrap();
    let (col, rows) = columns(&summary);
    assert!(
        rows.iter().all(|r| r[col("flip_mean")]
            .parse::<f64>()
            .is_ok_and(|m| m > 0.0 && m < 1.0)),
        "flip_mean: {summary}"
    );
    // The spp chart: x in samples per pixel, one curve per pair with its slope.
    let (code, _, stderr) = dibench(&["plot", run_dir.to_str().unwrap()], dir.path());
    assert_eq!(code, 0, "{stderr}");
    let svg = std::fs::read_to_string(run_dir.join("plots/rmse_vs_spp.svg")).unwrap();
    assert!(
        svg.contains("samples per pixel") && svg.contains("light [stratified], slope"),
        "spp chart"
    );
    let meta = std::fs::read_to_string(run_dir.join("run.json")).unwrap();
    assert!(
        meta.contains("\"budget_spp\": 16") && !meta.contains("budget_s\""),
        "{meta}"
    );

    let (code, _, stderr) = dibench(
        &[
            "compare",
            "tiny.toml",
            "--spp",
            "16",
            "--time",
            "1",
            "--out",
            "out",
        ],
        dir.path(),
    );
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("--spp") && stderr.contains("--time"),
        "{stderr}"
    );
}
