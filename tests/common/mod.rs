//! Shared by the CLI tests: run the `dibench` binary and check it never panics, never hangs,
//! and leaves consistent output (checkers for the reference store and for run directories).
#![allow(dead_code)]

use sha2::{Digest, Sha256};
use std::ffi::OsStr;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

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

/// How a bounded run ended.
#[derive(Debug)]
pub struct Outcome {
    pub code: Option<i32>,
    pub signal: Option<i32>,
    pub stdout: String,
    pub stderr: String,
    /// It was still running after its patience and got a SIGINT.
    pub interrupted: bool,
}

impl Outcome {
    /// An ordinary end: success, or a reported error (exit 1, clap's 2, 3 for a failed check,
    /// 4 for an unusable backend: `cli::exit_status`), or 130 after Ctrl-C.
    pub fn ended_cleanly(&self) -> bool {
        matches!(self.code, Some(0..=4 | 130))
    }
}

/// Runs dibench; if it still runs after `patience`, sends SIGINT as Ctrl-C does, and fails the
/// test if it has not ended 20 s later (a hang: the bound catches hangs, it measures nothing).
/// A panic, an abort or a crash is a test failure.
pub fn dibench_bounded<S: AsRef<OsStr>>(args: &[S], cwd: &Path, patience: Duration) -> Outcome {
    dibench_bounded_with(args, cwd, patience, |_| {})
}

/// As [`dibench_bounded`], with `setup` applied to the command (limits, stdin, ...).
pub fn dibench_bounded_with<S: AsRef<OsStr>>(
    args: &[S],
    cwd: &Path,
    patience: Duration,
    setup: impl FnOnce(&mut Command),
) -> Outcome {
    let shown: Vec<String> = args
        .iter()
        .map(|a| a.as_ref().to_string_lossy().into_owned())
        .collect();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_dibench"));
    cmd.args(args).current_dir(cwd);
    setup(&mut cmd);
    bounded(
        cmd,
        &format!("dibench {shown:?}"),
        patience,
        Duration::from_secs(20),
    )
}

/// Runs `cmd`; if it still runs after `patience`, sends SIGINT, and fails the test (after
/// killing it) if it has not ended `grace` later. Fails on a panic, an abort or a crash.
pub fn bounded(mut cmd: Command, shown: &str, patience: Duration, grace: Duration) -> Outcome {
    cmd.stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn().unwrap();
    let reader = |mut r: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut v = Vec::new();
            let _ = r.read_to_end(&mut v);
            String::from_utf8_lossy(&v).into_owned()
        })
    };
    let out = child.stdout.take().map(|s| reader(Box::new(s)));
    let err = child.stderr.take().map(|s| reader(Box::new(s)));
    let start = Instant::now();
    let mut interrupted = false;
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        let waited = start.elapsed();
        if !interrupted && waited > patience {
            signal(child.id(), libc::SIGINT);
            interrupted = true;
        }
        if waited > patience + grace {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{shown} did not end {grace:?} after Ctrl-C");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let stdout = out.map(|h| h.join().unwrap()).unwrap_or_default();
    let stderr = err.map(|h| h.join().unwrap()).unwrap_or_default();
    use std::os::unix::process::ExitStatusExt;
    let outcome = Outcome {
        code: status.code(),
        signal: status.signal(),
        stdout,
        stderr,
        interrupted,
    };
    assert!(
        !outcome.stderr.contains("panicked") && outcome.code != Some(101),
        "{shown} panicked: {}",
        outcome.stderr
    );
    assert!(
        !matches!(
            outcome.signal,
            Some(libc::SIGABRT | libc::SIGSEGV | libc::SIGBUS | libc::SIGILL)
        ),
        "{shown} crashed ({outcome:?})"
    );
    outcome
}

/// Sends `sig` to process `pid`.
pub fn signal(pid: u32, sig: i32) {
    // SAFETY: kill(2) on a child of this process.
    unsafe {
        libc::kill(pid as libc::pid_t, sig);
    }
}

/// Every file under `p` (directories included), depth first.
pub fn walk(p: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(p) else {
        return out;
    };
    for e in entries.flatten() {
        let path = e.path();
        if path.is_dir() && !path.is_symlink() {
            out.extend(walk(&path));
        }
        out.push(path);
    }
    out
}

/// Temporary files (`.<name>.<pid>.<random>.tmp`) under `p`.
pub fn temps_under(p: &Path) -> Vec<PathBuf> {
    walk(p)
        .into_iter()
        .filter(|f| {
            let n = f.file_name().unwrap().to_string_lossy();
            n.starts_with('.') && n.ends_with(".tmp")
        })
        .collect()
}

/// The file with `role` (`image`, `variance`, `film`) of the stored unit whose manifest is
/// `manifest` (`<out>/<scene>/reference/<integrand>.json`; see `output::store`).
pub fn stored_file(manifest: &Path, role: &str) -> PathBuf {
    let text = std::fs::read(manifest).unwrap_or_else(|e| panic!("{}: {e}", manifest.display()));
    let v: serde_json::Value = serde_json::from_slice(&text).unwrap();
    let name = v["files"][role]["name"]
        .as_str()
        .unwrap_or_else(|| panic!("{} names no {role} file", manifest.display()));
    manifest.with_file_name(name)
}

fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Checks a store directory (`reference/` or `reference/shards/`): every manifest names files
/// that exist with its size and SHA-256, every EXR it names decodes. With `settled` (after a
/// writer has held the units), nothing else is there: no file no manifest names, no temporary
/// file. Returns the manifests' contents by file name.
pub fn check_store(dir: &Path, settled: bool) -> Result<Vec<(String, serde_json::Value)>, String> {
    let mut manifests = Vec::new();
    let mut named = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(manifests);
    };
    let mut names: Vec<String> = entries
        .flatten()
        .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
        .map(|e| e.file_name().into_string().unwrap())
        .collect();
    names.sort();
    for n in names.iter().filter(|n| n.ends_with(".json")) {
        let text = std::fs::read(dir.join(n)).map_err(|e| format!("{n}: {e}"))?;
        let v: serde_json::Value =
            serde_json::from_slice(&text).map_err(|e| format!("{n}: not JSON: {e}"))?;
        let files = v["files"]
            .as_object()
            .ok_or_else(|| format!("{n}: no `files`"))?;
        for (role, f) in files {
            let name = f["name"]
                .as_str()
                .ok_or_else(|| format!("{n}: {role}: no name"))?;
            let bytes = std::fs::read(dir.join(name)).map_err(|e| format!("{n}: {name}: {e}"))?;
            if Some(bytes.len() as u64) != f["bytes"].as_u64() {
                return Err(format!(
                    "{n}: {name}: {} bytes, manifest says {}",
                    bytes.len(),
                    f["bytes"]
                ));
            }
            if Some(sha256_hex(&bytes).as_str()) != f["sha256"].as_str() {
                return Err(format!("{n}: {name}: SHA-256 differs from the manifest's"));
            }
            if name.ends_with(".exr") {
                let img = dibench::output::read_exr(&dir.join(name)).map_err(|e| e.to_string())?;
                let dims = (v["width"].as_u64(), v["height"].as_u64());
                if dims != (Some(img.width as u64), Some(img.height as u64)) {
                    return Err(format!(
                        "{n}: {name}: {}×{}, manifest says {dims:?}",
                        img.width, img.height
                    ));
                }
            }
            named.push(name.to_string());
        }
        manifests.push((n.clone(), v));
    }
    if settled {
        for n in &names {
            let lock = n.starts_with('.') && n.ends_with(".lock");
            if !lock && !n.ends_with(".json") && !named.contains(n) {
                return Err(format!(
                    "{}: a file no manifest names",
                    dir.join(n).display()
                ));
            }
        }
    }
    Ok(manifests)
}

/// Checks a compare run directory: run.json parses and states a status; every (strategy, run)
/// it calls completed has its final row in results.csv (which parses) and, for run 0, its two
/// images; a `complete` run has every (strategy, run) and summary.csv. With `settled` (after
/// a later compare looked at the scene directory), no run still says `running` and no temporary
/// file is left. Returns run.json.
pub fn check_run_dir(dir: &Path, settled: bool) -> Result<serde_json::Value, String> {
    let shown = dir.display();
    let meta: serde_json::Value = serde_json::from_slice(
        &std::fs::read(dir.join("run.json")).map_err(|e| format!("{shown}/run.json: {e}"))?,
    )
    .map_err(|e| format!("{shown}/run.json: {e}"))?;
    let status = meta["status"].as_str().unwrap_or("");
    if !["running", "complete", "interrupted", "failed", "unfinished"].contains(&status) {
        return Err(format!("{shown}: status `{status}`"));
    }
    if meta["interrupted"].as_bool() != Some(status == "interrupted") {
        return Err(format!(
            "{shown}: `interrupted` disagrees with status `{status}`"
        ));
    }
    // A run.json written before the run's metadata was known has no `completed`: nothing is.
    let completed: Vec<(String, u64)> = meta["completed"]
        .as_array()
        .map_or(&[][..], |a| a.as_slice())
        .iter()
        .map(|p| {
            (
                p[0].as_str().unwrap_or("").to_string(),
                p[1].as_u64().unwrap_or(u64::MAX),
            )
        })
        .collect();
    // Their samplers, pair by pair (absent before the sampler axis: independent).
    let samplers: Vec<String> = (0..completed.len())
        .map(|k| {
            meta["completed_samplers"][k]
                .as_str()
                .unwrap_or("independent")
                .to_string()
        })
        .collect();
    let mut finals = Vec::new();
    if dir.join("results.csv").exists() {
        let mut reader = csv::Reader::from_path(dir.join("results.csv"))
            .map_err(|e| format!("{shown}/results.csv: {e}"))?;
        for r in reader.records() {
            let r = r.map_err(|e| format!("{shown}/results.csv: {e}"))?;
            // 14 columns, `flip` last (13 before it existed).
            if r.len() != 14 && r.len() != 13 {
                return Err(format!("{shown}/results.csv: a row of {} fields", r.len()));
            }
            if &r[7] == "7" {
                finals.push((
                    r[1].to_string(),
                    r[5].parse::<u64>().unwrap_or(u64::MAX),
                    r[12].to_string(),
                ));
            }
        }
    }
    for ((s, run), g) in completed.iter().zip(&samplers) {
        if !finals.contains(&(s.clone(), *run, g.clone())) {
            return Err(format!(
                "{shown}: `{s}` ({g}) run {run} is completed but has no final row"
            ));
        }
        if *run == 0 {
            let stem = dibench::harness::compare::image_stem(s, g);
            // A non-independent sampler writes no variance image (docs/samplers.md).
            let suffixes: &[&str] = if g == "independent" {
                &["", ".variance", ".flip"]
            } else {
                &["", ".flip"]
            };
            for suffix in suffixes {
                let exr = dir.join(format!("{stem}{suffix}.exr"));
                dibench::output::read_exr(&exr).map_err(|e| e.to_string())?;
            }
        }
    }
    // summary.csv is rewritten with results.csv: whatever the status, it names every
    // (strategy, sampler) that run.json calls completed.
    if !completed.is_empty() {
        let mut reader = csv::Reader::from_path(dir.join("summary.csv"))
            .map_err(|e| format!("{shown}/summary.csv: {e}"))?;
        let header = reader
            .headers()
            .map_err(|e| format!("{shown}/summary.csv: {e}"))?
            .clone();
        let column = |name: &str| header.iter().position(|h| h == name);
        let (Some(strategy), sampler) = (column("strategy"), column("sampler")) else {
            return Err(format!("{shown}/summary.csv: no strategy column"));
        };
        let mut summarised = Vec::new();
        for r in reader.records() {
            let r = r.map_err(|e| format!("{shown}/summary.csv: {e}"))?;
            let g = sampler.map_or("independent", |k| &r[k]);
            summarised.push((r[strategy].to_string(), g.to_string()));
        }
        for ((s, run), g) in completed.iter().zip(&samplers) {
            if !summarised.contains(&(s.clone(), g.clone())) {
                return Err(format!(
                    "{shown}/summary.csv: `{s}` ({g}) run {run} is completed but not summarised"
                ));
            }
        }
    }
    if status == "complete" {
        let samplers = meta["samplers"].as_array().map_or(1, |a| a.len()) as u64;
        let strategies = meta["strategies"].as_array().map_or(0, |a| a.len()) as u64 * samplers;
        let runs = meta["runs"].as_u64().unwrap_or(0);
        if completed.len() as u64 != strategies * runs {
            return Err(format!(
                "{shown}: complete with {} of {} strategy runs",
                completed.len(),
                strategies * runs
            ));
        }
        let summary = std::fs::read_to_string(dir.join("summary.csv"))
            .map_err(|e| format!("{shown}/summary.csv: {e}"))?;
        if summary.lines().count() as u64 != strategies + 1 {
            return Err(format!(
                "{shown}/summary.csv: {} lines",
                summary.lines().count()
            ));
        }
    }
    if settled {
        if status == "running" {
            return Err(format!("{shown}: still says running"));
        }
        if let Some(t) = temps_under(dir).first() {
            return Err(format!("{}: temporary file left", t.display()));
        }
    }
    Ok(meta)
}

/// The run directories of a scene's results directory (all but `reference` and hidden ones,
/// which are run directories being built).
pub fn run_dirs(scene_dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(scene_dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            let hidden = p
                .file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with('.'));
            p.is_dir() && !hidden && !p.ends_with("reference")
        })
        .collect();
    v.sort();
    v
}

/// A quick compare of [`TINY`] (saved as `tiny.toml`) into `out`: one strategy, 10 ms.
pub const QUICK_COMPARE: [&str; 12] = [
    "compare",
    "tiny.toml",
    "--time",
    "0.01",
    "--reference-spp",
    "16",
    "--strategies",
    "light",
    "--threads",
    "1",
    "--out",
    "out",
];

/// The tiny scenes' text: a quad light over a floor, `height` pixels tall, then `extra`.
macro_rules! tiny_scene {
    ($height:literal, $extra:literal) => {
        concat!(
            r#"
[camera]
eye = [0.0, 1.0, 3.0]
look_at = [0.0, 0.0, 0.0]
fov_y_deg = 40.0
[image]
width = 16
height = "#,
            $height,
            r#"
[[material]]
name = "m"
albedo = [0.5, 0.5, 0.5]
[[quad]]
corner = [-3.0, 0.0, -3.0]
edge_u = [0.0, 0.0, 6.0]
edge_v = [6.0, 0.0, 0.0]
material = "m"
[[quad]]
corner = [-0.5, 1.5, -0.5]
edge_u = [1.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.0]
material = "m"
emission = [4.0, 4.0, 4.0]
"#,
            $extra
        )
    };
}

/// A quad light over a floor with a sphere: light and direction strategies both apply, and
/// an [ambient_occlusion] section adds the AO integrand.
pub const TINY_WITH_AO: &str = tiny_scene!(
    12,
    r#"[[sphere]]
center = [0.3, 0.3, 0.0]
radius = 0.3
material = "m"
[ambient_occlusion]
distance = 0.5
"#
);

/// A small scene: a quad light over a floor, so light and direction strategies apply.
pub const TINY: &str = tiny_scene!(16, "");
