//! Faults from outside, through the CLI: `kill -9` at random moments, concurrent runs on one
//! `--out`, Ctrl-C once and twice in every phase, a full disk, closed stdout and stderr. After
//! each: no panic, no hang, no half-written file, no lost row, and output that says truthfully
//! how complete it is. Every checker used here is first shown to catch what it is for (the
//! negative controls), so a passing test means something.

mod common;
use common::{
    Outcome, TINY, check_run_dir, check_store, dibench_bounded, dibench_bounded_with, run_dirs,
    signal, temps_under,
};

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const PATIENT: Duration = Duration::from_secs(60);

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_dibench"))
}

/// SplitMix64: a fixed stream of kill moments, so a failure can be rerun.
struct Mix(u64);
impl Mix {
    fn below(&mut self, n: u64) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (z ^ (z >> 31)) % n
    }
}

/// A scene large enough that a reference takes a while and writes images of some size.
fn scene_of_side(side: u32) -> String {
    TINY.replace("width = 16", &format!("width = {side}"))
        .replace("height = 16", &format!("height = {side}"))
}

fn sh(script: &str) -> Command {
    let mut c = Command::new("sh");
    c.arg("-c").arg(script);
    c
}

/// The bounded runner catches a hang (a process that ignores Ctrl-C)...
#[test]
#[should_panic(expected = "did not end")]
fn the_runner_catches_a_hang() {
    common::bounded(
        sh("trap '' INT; sleep 30"),
        "hang",
        Duration::from_millis(50),
        Duration::from_millis(500),
    );
}

/// ... a panic ...
#[test]
#[should_panic(expected = "panicked")]
fn the_runner_catches_a_panic() {
    common::bounded(
        sh("echo \"thread 'main' panicked at x\" >&2; exit 101"),
        "panic",
        PATIENT,
        PATIENT,
    );
}

/// ... and a crash.
#[test]
#[should_panic(expected = "crashed")]
fn the_runner_catches_a_crash() {
    common::bounded(sh("kill -SEGV $$"), "crash", PATIENT, PATIENT);
}

/// The checkers catch what they are for: a reference whose image is not the one its manifest
/// names (the mixed set a kill between two renames used to leave), a completed strategy
/// without its rows, a run that says complete without all of them.
#[test]
fn the_checkers_catch_mixed_sets_and_lost_rows() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), TINY).unwrap();
    let o = dibench_bounded(
        &[
            "compare",
            "tiny.toml",
            "--time",
            "0.01",
            "--reference-spp",
            "64",
            "--strategies",
            "light,cosine",
            "--threads",
            "1",
            "--out",
            "out",
        ],
        dir.path(),
        PATIENT,
    );
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    let refs = dir.path().join("out/tiny/reference");
    check_store(&refs, true).unwrap();
    let run = run_dirs(&dir.path().join("out/tiny")).remove(0);
    check_run_dir(&run, true).unwrap();

    // A mixed set: the image replaced by another valid EXR (the variance) behind the manifest.
    let manifest = refs.join("direct.json");
    let image = common::stored_file(&manifest, "image");
    let saved = std::fs::read(&image).unwrap();
    std::fs::copy(common::stored_file(&manifest, "variance"), &image).unwrap();
    assert!(
        check_store(&refs, true).is_err(),
        "a mixed set passed the store check"
    );
    std::fs::write(&image, &saved).unwrap();
    // An orphan no manifest names is leftover that a settled store must not have.
    std::fs::write(refs.join("direct.0123456789abcdef.exr"), b"x").unwrap();
    assert!(
        check_store(&refs, true).is_err(),
        "an orphan passed the settled store check"
    );
    assert!(check_store(&refs, false).is_ok());

    // A lost row: the final row of a completed strategy removed.
    let csv = std::fs::read_to_string(run.join("results.csv")).unwrap();
    let without: Vec<&str> = csv
        .lines()
        .filter(|l| !l.contains(",light,") || !l.contains(",7,"))
        .collect();
    std::fs::write(run.join("results.csv"), without.join("\n") + "\n").unwrap();
    assert!(
        check_run_dir(&run, true).is_err(),
        "a lost row passed the run check"
    );
    std::fs::write(run.join("results.csv"), &csv).unwrap();
    // A run claiming completeness without its summary.
    std::fs::remove_file(run.join("summary.csv")).unwrap();
    assert!(
        check_run_dir(&run, true).is_err(),
        "a complete run without summary passed"
    );
    // Nor one still running whose completed strategies are not summarised.
    let meta = std::fs::read_to_string(run.join("run.json")).unwrap();
    let mut running: serde_json::Value = serde_json::from_str(&meta).unwrap();
    running["status"] = "running".into();
    std::fs::write(run.join("run.json"), running.to_string()).unwrap();
    assert!(
        check_run_dir(&run, false).is_err(),
        "a running run without summary passed"
    );
}

/// `kill -9` of `reference` and `compare` at 24 random moments (fixed seed), then: every stored
/// reference is whole (its manifest's files, sizes and hashes), every run directory says how
/// complete it is and has the rows it claims, and a rerun succeeds, reuses a reference only if
/// one was committed, and leaves no leftover of the killed processes.
#[test]
fn sigkill_at_random_moments_leaves_consistent_output() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.toml"), scene_of_side(48)).unwrap();
    let mut rng = Mix(12);
    let start = Instant::now();
    for k in 0..24 {
        let args: Vec<&str> = if k % 2 == 0 {
            vec![
                "reference",
                "s.toml",
                "--spp",
                "1024",
                "--threads",
                "1",
                "--out",
                "out",
            ]
        } else {
            vec![
                "compare",
                "s.toml",
                "--time",
                "0.02",
                "--reference-spp",
                "256",
                "--strategies",
                "light,cosine",
                "--threads",
                "1",
                "--out",
                "out",
            ]
        };
        let mut child = bin()
            .args(&args)
            .current_dir(dir.path())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(rng.below(400)));
        signal(child.id(), libc::SIGKILL);
        let _ = child.wait();
        // Whatever the moment, what is committed is whole.
        check_store(&dir.path().join("out/s/reference"), false)
            .unwrap_or_else(|e| panic!("after kill {k}: {e}"));
        for run in run_dirs(&dir.path().join("out/s")) {
            if run.join("run.json").exists() {
                check_run_dir(&run, false).unwrap_or_else(|e| panic!("after kill {k}: {e}"));
            }
        }
    }
    assert!(
        start.elapsed() < Duration::from_secs(120),
        "the kills took too long to be useful"
    );
    let committed = check_store(&dir.path().join("out/s/reference"), false).unwrap();
    let o = dibench_bounded(
        &[
            "compare",
            "s.toml",
            "--time",
            "0.02",
            "--reference-spp",
            "64",
            "--strategies",
            "light",
            "--threads",
            "1",
            "--out",
            "out",
        ],
        dir.path(),
        PATIENT,
    );
    assert_eq!(o.code, Some(0), "the rerun failed: {}", o.stderr);
    let reused = o.stderr.contains("reusing");
    assert_eq!(
        reused,
        committed
            .iter()
            .any(|(n, v)| n == "direct.json" && v["spp"].as_u64() >= Some(64)),
        "reuse must follow exactly what was committed: {}",
        o.stderr
    );
    // The rerun held the reference unit and looked at the scene directory: no leftovers.
    check_store(&dir.path().join("out/s/reference"), true).unwrap();
    let left = temps_under(&dir.path().join("out"));
    assert!(left.is_empty(), "{left:?}");
    for run in run_dirs(&dir.path().join("out/s")) {
        check_run_dir(&run, true).unwrap();
    }
}

/// Four `compare` runs of the same scene and seed on one `--out` at once (they start in the
/// same second): four run directories, each complete with every row, and one stored reference,
/// rendered once (the others wait for it and reuse it).
#[test]
fn concurrent_compares_share_one_reference_and_keep_every_row() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), TINY).unwrap();
    let handles: Vec<_> = (0..4)
        .map(|_| {
            let cwd = dir.path().to_path_buf();
            std::thread::spawn(move || {
                dibench_bounded(
                    &[
                        "compare",
                        "tiny.toml",
                        "--time",
                        "0.02",
                        "--reference-spp",
                        "512",
                        "--strategies",
                        "light,cosine",
                        "--runs",
                        "2",
                        "--threads",
                        "1",
                        "--out",
                        "out",
                    ],
                    &cwd,
                    PATIENT,
                )
            })
        })
        .collect();
    let outcomes: Vec<Outcome> = handles.into_iter().map(|h| h.join().unwrap()).collect();
    for o in &outcomes {
        assert_eq!(o.code, Some(0), "{}", o.stderr);
    }
    let rendered = outcomes
        .iter()
        .filter(|o| o.stderr.contains("rendering 512 spp"))
        .count();
    assert_eq!(rendered, 1, "the reference was rendered {rendered} times");
    let runs = run_dirs(&dir.path().join("out/tiny"));
    assert_eq!(runs.len(), 4, "{runs:?}");
    for run in &runs {
        let meta = check_run_dir(run, true).unwrap();
        assert_eq!(meta["status"], "complete");
        assert_eq!(meta["completed"].as_array().unwrap().len(), 4);
    }
    let manifests = check_store(&dir.path().join("out/tiny/reference"), true).unwrap();
    assert_eq!(manifests.len(), 1, "{manifests:?}");
}

/// Waits until `path` exists (the child reached a phase), for at most a minute.
fn wait_for(path: &Path) {
    let start = Instant::now();
    while !path.exists() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "{} never appeared",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The first matching path under `root`, once one exists.
fn wait_for_under(root: &Path, name: &str) -> std::path::PathBuf {
    let start = Instant::now();
    loop {
        if let Some(p) = common::walk(root).into_iter().find(|p| p.ends_with(name)) {
            return p;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no {name} under {}",
            root.display()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Waits (at most a minute) until the store `dir` holds a manifest written since `since`
/// that records at least 64 spp.
fn wait_for_checkpoint(dir: &Path, since: std::time::SystemTime) {
    let start = Instant::now();
    loop {
        let fresh = check_store(dir, false)
            .unwrap_or_default()
            .iter()
            .any(|(name, v)| {
                v["spp"].as_u64().is_some_and(|s| s >= 64)
                    && std::fs::metadata(dir.join(name))
                        .and_then(|m| m.modified())
                        .is_ok_and(|t| t >= since)
            });
        if fresh {
            return;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no checkpoint in {}",
            dir.display()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Sends `count` SIGINTs 20 ms apart and waits for the end (at most 20 s: a bound on hangs).
fn interrupt(mut child: std::process::Child, count: usize) -> std::process::Output {
    for _ in 0..count {
        signal(child.id(), libc::SIGINT);
        std::thread::sleep(Duration::from_millis(20));
    }
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(20) {
            // What each thread was doing (state and kernel wait channel), then what it said.
            let threads = thread_states(child.id());
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!(
                "no end 20 s after Ctrl-C; threads: {threads}; stderr: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    child.wait_with_output().unwrap()
}

/// `name:state:wchan` of each thread of process `pid` (Linux /proc), for a hang's report.
fn thread_states(pid: u32) -> String {
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return "unknown".into();
    };
    let mut states: Vec<String> = tasks
        .flatten()
        .map(|t| {
            let read = |f: &str| std::fs::read_to_string(t.path().join(f)).unwrap_or_default();
            let stat = read("stat");
            // The state follows the parenthesised name, which may contain spaces.
            let state = stat
                .rsplit_once(") ")
                .map_or("?", |(_, r)| &r[..1])
                .to_string();
            format!("{}:{state}:{}", read("comm").trim(), read("wchan").trim())
        })
        .collect();
    states.sort();
    states.dedup();
    states.join(" ")
}

fn spawn(args: &[&str], cwd: &Path) -> std::process::Child {
    spawn_with(args, cwd, false)
}

/// [`spawn`], with SIGHUP inherited ignored when `sighup_ignored` (as under `nohup`).
fn spawn_with(args: &[&str], cwd: &Path, sighup_ignored: bool) -> std::process::Child {
    use std::os::unix::process::CommandExt;
    let mut cmd = bin();
    // As from a terminal: a test run started in the background by a shell without job
    // control inherits SIGINT ignored, and a Ctrl-C that lands before dibench installs its
    // handler would then be lost (`ctrl_c_is_answered_in_every_phase` hung on it).
    let hangup = if sighup_ignored {
        libc::SIG_IGN
    } else {
        libc::SIG_DFL
    };
    // SAFETY: `signal` is async-signal-safe, as `pre_exec` requires.
    unsafe {
        cmd.pre_exec(move || {
            libc::signal(libc::SIGINT, libc::SIG_DFL);
            libc::signal(libc::SIGHUP, hangup);
            Ok(())
        });
    }
    cmd.args(args)
        .current_dir(cwd)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Ctrl-C twice while the second strategy renders: exit 130, run.json says interrupted with
/// the one completed strategy, whose rows and images are there, and no temporary file is left.
/// Ctrl-C twice during the reference render: exit 130, no run directory, no stored reference.
#[test]
fn double_ctrl_c_leaves_a_truthful_run_and_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), TINY).unwrap();
    let child = spawn(
        &[
            "compare",
            "tiny.toml",
            "--time",
            "30",
            "--reference-spp",
            "64",
            "--strategies",
            "light,cosine",
            "--threads",
            "1",
            "--out",
            "out",
        ],
        dir.path(),
    );
    // Twice while the first strategy renders (its 30 s): nothing finished, nothing is kept.
    let scene_dir = dir.path().join("out/tiny");
    let started = Instant::now();
    while !run_dirs(&scene_dir).iter().any(|r| {
        std::fs::read_to_string(r.join("run.json")).is_ok_and(|t| t.contains("\"strategies\""))
    }) {
        assert!(started.elapsed() < Duration::from_secs(60));
        std::thread::sleep(Duration::from_millis(5));
    }
    let out = interrupt(child, 2);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let runs = run_dirs(&scene_dir);
    assert!(runs.is_empty(), "{runs:?}");

    // One strategy finished, the second interrupted twice.
    let child = spawn(
        &[
            "compare",
            "tiny.toml",
            "--time",
            "0.3",
            "--reference-spp",
            "64",
            "--strategies",
            "light,cosine",
            "--runs",
            "20",
            "--threads",
            "1",
            "--out",
            "out",
        ],
        dir.path(),
    );
    wait_for(&wait_for_under(&scene_dir, "results.csv"));
    let out = interrupt(child, 2);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    let run = run_dirs(&scene_dir).remove(0);
    let meta = check_run_dir(&run, true).unwrap();
    assert_eq!(meta["status"], "interrupted", "{meta}");
    assert_eq!(meta["interrupted"], true);
    assert!(!meta["completed"].as_array().unwrap().is_empty());
    assert!(
        temps_under(dir.path()).is_empty(),
        "{:?}",
        temps_under(dir.path())
    );

    // During the reference render of a compare: nothing kept, nothing stored.
    let other = tempfile::tempdir().unwrap();
    std::fs::write(other.path().join("tiny.toml"), TINY).unwrap();
    let mut child = bin()
        .args([
            "compare",
            "tiny.toml",
            "--reference-spp",
            "100000000",
            "--threads",
            "1",
            "--out",
            "out",
        ])
        .current_dir(other.path())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = child.stderr.take().unwrap();
    let mut seen = Vec::new();
    let mut byte = [0u8; 1];
    while !String::from_utf8_lossy(&seen).contains("rendering") {
        use std::io::Read;
        assert_eq!(
            err.read(&mut byte).unwrap(),
            1,
            "{}",
            String::from_utf8_lossy(&seen)
        );
        seen.push(byte[0]);
    }
    std::thread::sleep(Duration::from_millis(50));
    let out = interrupt(child, 2);
    assert_eq!(out.status.code(), Some(130));
    assert!(run_dirs(&other.path().join("out/tiny")).is_empty());
    assert!(
        check_store(&other.path().join("out/tiny/reference"), false)
            .unwrap()
            .is_empty()
    );
    let temps = temps_under(other.path());
    assert!(temps.is_empty(), "{temps:?}");
}

/// Ctrl-C in the phases that used to ignore it: creating 1024 worker threads, loading a large
/// mesh, rendering a reference (`reference`, which keeps its last checkpoint): each process
/// ends with 130 (or by the signal itself, when it lands before the handler is installed),
/// leaving no temporary file; a stored checkpoint is whole.
#[test]
fn ctrl_c_is_answered_in_every_phase() {
    let dir = tempfile::tempdir().unwrap();
    // A 200×200-quad grid: some 1.4 MB of OBJ, a noticeable load.
    let mut obj = String::new();
    let n = 200;
    for y in 0..=n {
        for x in 0..=n {
            obj.push_str(&format!(
                "v {} 0 {}\n",
                x as f32 / n as f32,
                y as f32 / n as f32
            ));
        }
    }
    for y in 0..n {
        for x in 0..n {
            let i = y * (n + 1) + x + 1;
            obj.push_str(&format!("f {} {} {} {}\n", i, i + 1, i + n + 2, i + n + 1));
        }
    }
    std::fs::write(dir.path().join("grid.obj"), obj).unwrap();
    std::fs::write(
        dir.path().join("mesh.toml"),
        format!("{TINY}[[mesh]]\nfile = \"grid.obj\"\nmaterial = \"m\"\n"),
    )
    .unwrap();
    std::fs::write(dir.path().join("tiny.toml"), TINY).unwrap();
    // The reference case is interrupted once a checkpoint of its own is stored (a fixed delay
    // reaches none on a loaded machine); the others after a delay that lands in each phase.
    const CHECKPOINT: u64 = u64::MAX;
    for (args, after_ms) in [
        (
            &["compare", "tiny.toml", "--threads", "1024", "--out", "out"][..],
            1u64,
        ),
        (
            &["compare", "tiny.toml", "--threads", "1024", "--out", "out"][..],
            30,
        ),
        (
            &["compare", "mesh.toml", "--threads", "1", "--out", "out"][..],
            20,
        ),
        (
            &["compare", "mesh.toml", "--threads", "1", "--out", "out"][..],
            80,
        ),
        (
            &[
                "reference",
                "tiny.toml",
                "--spp",
                "100000000",
                "--threads",
                "1",
                "--out",
                "out",
            ][..],
            CHECKPOINT,
        ),
    ] {
        let spawned = std::time::SystemTime::now();
        let child = spawn(args, dir.path());
        if after_ms == CHECKPOINT {
            wait_for_checkpoint(&dir.path().join("out/tiny/reference"), spawned);
        } else {
            std::thread::sleep(Duration::from_millis(after_ms));
        }
        let out = interrupt(child, 1);
        use std::os::unix::process::ExitStatusExt;
        let (code, sig) = (out.status.code(), out.status.signal());
        assert!(
            code == Some(130) || sig == Some(libc::SIGINT) || code == Some(0),
            "{args:?} after {after_ms} ms: {:?}: {}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            temps_under(dir.path()).is_empty(),
            "{args:?}: {:?}",
            temps_under(dir.path())
        );
        check_store(&dir.path().join("out/tiny/reference"), false).unwrap();
    }
    let kept = check_store(&dir.path().join("out/tiny/reference"), true).unwrap();
    assert!(
        kept.iter()
            .any(|(_, v)| v["spp"].as_u64().is_some_and(|s| s >= 64)),
        "the interrupted reference kept no checkpoint: {kept:?}"
    );
}

/// A full disk (here a file-size limit, which fails writes as ENOSPC would) at every stage of a
/// compare: the command fails naming a file, leaves no temporary file, and its run directory is
/// either absent (nothing was recorded) or says `failed` / stays `running`, never `complete`
/// without its files. The sweep is shown to reach every outcome.
#[test]
fn a_full_disk_at_any_stage_is_reported_and_recorded() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), TINY).unwrap();
    let args = [
        "compare",
        "tiny.toml",
        "--time",
        "0.005",
        "--reference-spp",
        "64",
        "--strategies",
        "light,cosine",
        "--runs",
        "3",
        "--threads",
        "1",
        "--out",
        "out",
    ];
    // The reference first, without a limit; then each limit on a fresh run.
    assert_eq!(dibench_bounded(&args, dir.path(), PATIENT).code, Some(0));
    for r in run_dirs(&dir.path().join("out/tiny")) {
        std::fs::remove_dir_all(r).unwrap();
    }
    let (mut no_dir, mut failed_with_results, mut complete) = (0, 0, 0);
    for limit in [64, 256, 512]
        .into_iter()
        .chain((1..=12).map(|k| k * 1024))
        .chain([1 << 20])
    {
        let o = dibench_bounded_with(&args, dir.path(), PATIENT, |cmd| {
            use std::os::unix::process::CommandExt;
            // SAFETY: setrlimit in the child before exec touches only that process.
            unsafe {
                cmd.pre_exec(move || {
                    let l = libc::rlimit {
                        rlim_cur: limit,
                        rlim_max: limit,
                    };
                    libc::setrlimit(libc::RLIMIT_FSIZE, &l);
                    Ok(())
                });
            }
        });
        assert!(o.ended_cleanly(), "limit {limit}: {o:?}");
        assert!(
            temps_under(dir.path()).is_empty(),
            "limit {limit}: {:?}",
            temps_under(dir.path())
        );
        let runs = run_dirs(&dir.path().join("out/tiny"));
        if o.code == Some(0) {
            let meta = check_run_dir(&runs[0], true).unwrap();
            assert_eq!(meta["status"], "complete");
            complete += 1;
        } else {
            assert!(
                o.stderr.contains("File too large") || o.stderr.contains("os error"),
                "limit {limit}: {}",
                o.stderr
            );
            match runs.first() {
                None => no_dir += 1,
                Some(run) => {
                    let meta = check_run_dir(run, false).unwrap();
                    assert!(
                        meta["status"] == "failed" || meta["status"] == "running",
                        "limit {limit}: {meta}"
                    );
                    failed_with_results += 1;
                }
            }
        }
        for r in runs {
            std::fs::remove_dir_all(r).unwrap();
        }
    }
    assert!(
        no_dir > 0 && failed_with_results > 0 && complete > 0,
        "the sweep missed an outcome: {no_dir} without a directory, {failed_with_results} failed \
         with results, {complete} complete"
    );
}

/// A closed stdout (`dibench warp --list | head -1`) ends the program quietly (SIGPIPE, as
/// for any filter), and after compare's files are written; a closed stderr does not break a
/// run or end up in its files.
#[test]
fn closed_stdout_and_stderr_end_quietly() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), TINY).unwrap();
    for args in [
        &["warp", "--list"][..],
        &[
            "compare",
            "tiny.toml",
            "--time",
            "0.01",
            "--reference-spp",
            "16",
            "--strategies",
            "light",
            "--out",
            "out",
        ][..],
    ] {
        // A reader that has gone: the pipe's read end is closed before dibench writes.
        let mut child = bin()
            .args(args)
            .current_dir(dir.path())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        use std::os::unix::process::ExitStatusExt;
        assert!(
            out.status.signal() == Some(libc::SIGPIPE) || out.status.success(),
            "{args:?}: {:?} {stderr}",
            out.status
        );
        assert!(
            !stderr.contains("panicked") && !stderr.contains("Broken pipe"),
            "{stderr}"
        );
    }
    let run = run_dirs(&dir.path().join("out/tiny")).remove(0);
    assert_eq!(check_run_dir(&run, true).unwrap()["status"], "complete");
    // stderr closed outright (`2>&-`): the run succeeds and its files are intact.
    let status = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "exec {} compare tiny.toml --time 0.01 --reference-spp 16 --strategies light --out closed 2>&-",
            env!("CARGO_BIN_EXE_dibench")
        ))
        .current_dir(dir.path())
        .stdout(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success(), "{status:?}");
    let run = run_dirs(&dir.path().join("closed/tiny")).remove(0);
    check_run_dir(&run, true).unwrap();
    check_store(&dir.path().join("closed/tiny/reference"), true).unwrap();
    assert!(std::fs::read_to_string(dir.path().join("tiny.toml")).unwrap() == TINY);
}

/// `nohup dibench reference …`: started with SIGHUP ignored, a run survives its terminal's
/// hang-up (the Ctrl-C handler must not take SIGHUP over), and still answers Ctrl-C. Its
/// negative control is the same run started with SIGHUP at its default: the hang-up ends it.
#[test]
fn a_nohup_run_survives_a_hang_up() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tiny.toml"), TINY).unwrap();
    for nohup in [true, false] {
        let spawned = std::time::SystemTime::now();
        let out = format!("out-{nohup}");
        let args = [
            "reference",
            "tiny.toml",
            "--spp",
            "100000000",
            "--threads",
            "1",
            "--out",
            &out,
        ];
        let mut child = spawn_with(&args, dir.path(), nohup);
        wait_for_checkpoint(&dir.path().join(&out).join("tiny/reference"), spawned);
        signal(child.id(), libc::SIGHUP);
        std::thread::sleep(Duration::from_millis(1500));
        let alive = child.try_wait().unwrap().is_none();
        if !nohup {
            if alive {
                let _ = child.kill();
            }
            assert!(
                !alive,
                "a hang-up did not end a run that does not ignore it"
            );
            continue;
        }
        assert!(alive, "a nohup run ended on a hang-up");
        let done = interrupt(child, 1);
        assert_eq!(
            done.status.code(),
            Some(130),
            "{}",
            String::from_utf8_lossy(&done.stderr)
        );
    }
}
