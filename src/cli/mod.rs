//! The `dibench` command line.

use crate::error::{Error, Result};
use crate::harness::{compare, crosscheck, rays, reference};
use crate::prepare::PreparedScene;
use crate::scene::Scene;
use crate::simd::Isa;
use crate::strategy::{self, Strategy};
use crate::tracer::backends;
use clap::{Args, Parser, Subcommand};
use std::path::{Path, PathBuf};

#[derive(Parser, Debug)]
#[command(
    name = "dibench",
    version,
    about = "Which direct-illumination sampling strategy wins on this scene, at equal time?"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render every applicable strategy for the same wall-clock budget; write EXRs and results.csv.
    Compare(CompareArgs),
    /// Render a high-sample reference image (EXR + JSON metadata) for later comparisons.
    Reference(ReferenceArgs),
    /// χ²-test one registered sampler: histogram vs integrated pdf, p-value, optional PNG.
    Warp(WarpArgs),
    /// Ray throughput of each backend (and ISA) on fixed ray sets; writes <out>/<scene>/rays.csv.
    Rays(RaysArgs),
    /// List the strategies, and which apply to a scene.
    Strategies {
        /// Scene file or name under scenes/.
        scene: Option<String>,
    },
    /// Trace fixed ray sets through every compiled-in backend and compare each with obvhs.
    #[command(after_help = CROSSCHECK_HELP)]
    Crosscheck(CrosscheckArgs),
    /// Every applicable strategy on every stiff case: non-finite or negative samples and
    /// closed-form mismatches fail (non-zero exit); writes <out>/stress/stress.csv.
    Stress(StressArgs),
    /// Figures of a compare run: RMSE against time with CI bands, variance heatmaps, image
    /// strip; PNG (and SVG for the chart) in RUN_DIR/plots/.
    Plot {
        /// A run directory written by `compare` (holding results.csv).
        run_dir: PathBuf,
    },
    /// Merge the shards written by `reference --shard i/n` into the scene's reference files.
    Merge {
        /// Scene file or name under scenes/ (names the results directory).
        scene: String,
        /// Output root holding <scene>/reference/shards/.
        #[arg(long, default_value = "results")]
        out: PathBuf,
    },
}

#[derive(Args, Debug)]
pub struct StressArgs {
    /// Samples per (case, strategy).
    #[arg(long, default_value_t = 200_000, allow_negative_numbers = true)]
    pub samples: u64,
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Only these cases (comma-separated; see --list).
    #[arg(long, value_delimiter = ',')]
    pub cases: Option<Vec<String>>,
    /// List the cases and exit.
    #[arg(long)]
    pub list: bool,
    /// Also write each case as a scene (<dir>/<case>/scene.toml) to render with `compare`.
    #[arg(long)]
    pub export: Option<PathBuf>,
    /// Output root; the table goes to <out>/stress/stress.csv.
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// Worker threads (default: all cores); the result does not depend on it.
    #[arg(long, value_parser = parse_threads, allow_negative_numbers = true)]
    pub threads: Option<usize>,
}

const CROSSCHECK_HELP: &str = "\
Ray sets: primary (camera rays in 4x4 tiles), shadow_area (surface points to light samples,
finite tmax), incoherent (uniform hemisphere directions from surface points); each traced for
closest hit and occlusion, single rays and 16-packets. Fails (non-zero exit) when, against
obvhs, per set: hit/miss mismatches > 1e-4 of the rays, primitive mismatches > 1e-4 (ties,
where our exact tests hit both primitives at the same t within 1e-4, are excepted), occlusion
mismatches > 1e-4, max t difference > 1e-3 relative to max(t, largest |origin coordinate|), or the image relative RMSE after 4 passes
of the same strategy and seed > 1e-2. Timing (seconds, mrays_per_s) is single-threaded, best of
5 interleaved rounds. Without --features embree the packet backend is checked against obvhs.";

#[derive(Args, Debug)]
pub struct CrosscheckArgs {
    /// Scene file, or the name of a scene in scenes/ (e.g. cornell).
    #[arg(default_value = "cornell")]
    pub scene: String,
    /// Output root; the table goes to <out>/<scene>/crosscheck.csv.
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// Seed of the ray sets and of the renders.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Worker threads for the renders (ray tracing and timing are single-threaded).
    #[arg(long, value_parser = parse_threads, allow_negative_numbers = true)]
    pub threads: Option<usize>,
}

#[derive(Args, Debug)]
pub struct Common {
    /// Scene file, or the name of a scene in scenes/ (e.g. cornell).
    #[arg(default_value = "cornell")]
    pub scene: String,
    /// Output root; results go to <out>/<scene>/...
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// Seed of the random streams: same scene, seed and threads give the same image.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = parse_threads, allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// Tracer backend: packet (default), obvhs, or embree when built with --features embree.
    #[arg(long, default_value = backends::DEFAULT)]
    pub backend: String,
    /// ISA of the packet backend: avx512, avx2 or portable (default: best available, or
    /// the DIBENCH_ISA environment variable).
    #[arg(long)]
    pub isa: Option<String>,
}

#[derive(Args, Debug)]
pub struct CompareArgs {
    #[command(flatten)]
    pub common: Common,
    /// Wall-clock budget per strategy, in seconds.
    #[arg(long, default_value_t = 2.0, value_parser = parse_seconds, allow_hyphen_values = true)]
    pub time: f64,
    /// Samples per pixel of the reference rendered when no matching one is stored.
    #[arg(long, default_value_t = 8192, value_parser = clap::value_parser!(u64).range(1..), allow_negative_numbers = true)]
    pub reference_spp: u64,
    /// Comma-separated subset of strategies to run (default: every applicable one).
    #[arg(long, value_delimiter = ',')]
    pub strategies: Option<Vec<String>>,
    /// Independent runs per strategy (seeds seed, seed+1, ...); summary.csv gives 95 %
    /// confidence intervals over them.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..), allow_negative_numbers = true)]
    pub runs: u32,
}

#[derive(Args, Debug)]
pub struct WarpArgs {
    /// Registered sampler name (see --list).
    pub name: Option<String>,
    /// List every registered sampler with its parameters.
    #[arg(long)]
    pub list: bool,
    /// Override a parameter, e.g. --param n=1000 (repeatable).
    #[arg(long = "param", value_parser = parse_param)]
    pub params: Vec<(String, f64)>,
    /// Number of samples.
    #[arg(long, default_value_t = 1_000_000, value_parser = clap::value_parser!(u64).range(1..), allow_negative_numbers = true)]
    pub samples: u64,
    /// Significance level of the test.
    #[arg(long, default_value_t = 0.01, value_parser = parse_alpha, allow_hyphen_values = true)]
    pub alpha: f64,
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Write the observed histogram beside the expected counts as a PNG.
    #[arg(long)]
    pub png: Option<PathBuf>,
}

fn parse_param(s: &str) -> std::result::Result<(String, f64), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected KEY=VALUE, got `{s}`"))?;
    let v: f64 = v
        .parse()
        .map_err(|_| format!("parameter `{k}`: `{v}` is not a number"))?;
    // The samplers compute in f32: a larger value would become infinite there.
    if v.abs() > f32::MAX as f64 {
        return Err(format!(
            "parameter `{k}`: {v:e} is beyond the f32 range (±{:e}) the samplers compute in",
            f32::MAX
        ));
    }
    Ok((k.to_string(), v))
}

/// Longest accepted time budget: about 31 years, far below what `Duration` holds.
const MAX_SECONDS: f64 = 1e9;
/// Shortest accepted time budget: below a millisecond the clock's resolution is the budget.
const MIN_SECONDS: f64 = 1e-3;

fn parse_seconds(s: &str) -> std::result::Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(t) if (MIN_SECONDS..=MAX_SECONDS).contains(&t) => Ok(t),
        _ => Err(format!(
            "expected a number of seconds from {MIN_SECONDS} to {MAX_SECONDS:e}"
        )),
    }
}

fn parse_alpha(s: &str) -> std::result::Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(a) if a > 0.0 && a < 1.0 => Ok(a),
        _ => Err("expected a significance level strictly between 0 and 1".into()),
    }
}

fn parse_rounds(s: &str) -> std::result::Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!("expected a whole number from 1 to {}", usize::MAX)),
    }
}

/// The most worker threads accepted: 1024, or the number of cores where there are more.
/// Beyond the cores threads only add contention, and creating tens of thousands takes minutes.
pub fn max_threads() -> usize {
    std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .max(1024)
}

fn parse_threads(s: &str) -> std::result::Result<usize, String> {
    let max = max_threads();
    match s.trim().parse::<usize>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        _ => Err(format!(
            "expected a whole number of threads from 1 to {max} (1024, or the cores if more)"
        )),
    }
}

#[derive(Args, Debug)]
pub struct ReferenceArgs {
    #[command(flatten)]
    pub common: Common,
    /// Samples per pixel (default 8192).
    #[arg(long, conflicts_with = "time", value_parser = clap::value_parser!(u64).range(1..), allow_negative_numbers = true)]
    pub spp: Option<u64>,
    /// Render whole passes for this many seconds instead of a fixed spp.
    #[arg(long, value_parser = parse_seconds, allow_hyphen_values = true)]
    pub time: Option<f64>,
    /// Render only shard i of n (passes i, i+n, ... of --spp) into <out>/<scene>/reference/
    /// shards/, for a cluster job array; `dibench merge` then writes the reference.
    #[arg(long, conflicts_with = "time", allow_hyphen_values = true)]
    pub shard: Option<String>,
}

/// Which command-line arguments are not UTF-8, each with the option it is the value of
/// (clap's own error does not say).
pub fn invalid_utf8_args() -> String {
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    let shown = |a: &std::ffi::OsStr| {
        #[cfg(unix)]
        {
            use std::os::unix::ffi::OsStrExt;
            a.as_bytes().escape_ascii().to_string()
        }
        #[cfg(not(unix))]
        {
            a.to_string_lossy().into_owned()
        }
    };
    let bad: Vec<String> = (1..args.len())
        .filter(|&i| args[i].to_str().is_none())
        .map(|i| {
            let of = args[i - 1]
                .to_str()
                .filter(|p| p.starts_with('-'))
                .map(|p| format!(" (the value of {p})"))
                .unwrap_or_default();
            format!("argument {i} `{}`{of}", shown(&args[i]))
        })
        .collect();
    format!(
        "{} is not valid UTF-8: scene names and paths given as SCENE, and every name or number, \
         must be UTF-8 text",
        bad.join(", ")
    )
}

fn load(scene: &str) -> Result<PreparedScene> {
    let path = Scene::resolve(scene)?;
    Ok(PreparedScene::new(Scene::load(&path)?))
}

/// `--isa`, else `DIBENCH_ISA`, else the best the CPU has.
fn isa(arg: &Option<String>) -> Result<Isa> {
    match arg {
        Some(s) => Isa::parse(s).map_err(|e| Error::Usage(format!("--isa {s}: {e}"))),
        None => Isa::detect(),
    }
}

/// Loads a scene traced by the backend (and ISA) `c` names.
fn load_with(c: &Common) -> Result<PreparedScene> {
    backends::check(&c.backend)?;
    // A misspelt --isa is an error with any backend; a valid one that the backend has no use
    // for is said, not silently dropped.
    let chosen = isa(&c.isa)?;
    if c.isa.is_some() && c.backend != "packet" {
        crate::interrupt::note(&format!(
            "warning: --isa is ignored: the {} backend has no ISA paths",
            c.backend
        ));
    }
    let isa = (c.backend == "packet").then_some(chosen);
    let scene = Scene::load(&Scene::resolve(&c.scene)?)?;
    let mut err = None;
    let prepared = PreparedScene::with_tracer(scene, |g| {
        match backends::build_isa(&c.backend, g.clone(), isa) {
            Ok(t) => t,
            Err(e) => {
                err = Some(e);
                backends::build("obvhs", g).expect("the obvhs backend always builds")
            }
        }
    });
    match err {
        Some(e) => Err(e),
        None => Ok(prepared),
    }
}

/// The worker pool; `--threads` is already bounded by its parser (`parse_threads`).
fn pool(threads: Option<usize>) -> Result<(rayon::ThreadPool, usize)> {
    let n = threads.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(|e| Error::Usage(format!("cannot start {n} threads: {e}")))?;
    Ok((pool, n))
}

/// The `dibench` program with the built-in strategies and `extra` ones (a researcher's own,
/// defined outside the crate: see `examples/custom_strategy.rs`): parses the command line,
/// runs it, reports an error on stderr and maps it to the exit status.
pub fn main_with(extra: Vec<Box<dyn Strategy>>) -> std::process::ExitCode {
    use std::process::ExitCode;
    // First: quiet SIGPIPE, reopened standard descriptors, the Ctrl-C handler (`interrupt`).
    crate::interrupt::install();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if e.kind() == clap::error::ErrorKind::InvalidUtf8 => {
            // clap does not say which argument; name it.
            crate::interrupt::note(&format!("error: {}", invalid_utf8_args()));
            return ExitCode::from(2);
        }
        Err(e) => e.exit(),
    };
    let mut strategies = strategy::registry();
    strategies.extend(extra);
    match run_with(cli, strategies) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            crate::interrupt::note(&format!("error: {e}"));
            match e {
                // 128 + SIGINT, as a shell reports a command stopped by Ctrl-C.
                Error::Interrupted(_) => ExitCode::from(130),
                _ => ExitCode::FAILURE,
            }
        }
    }
}

/// Runs a parsed command with the built-in strategies.
pub fn run(cli: Cli) -> Result<()> {
    run_with(cli, strategy::registry())
}

/// Runs a parsed command with `strategies` as the catalogue `compare` and `strategies` use.
pub fn run_with(cli: Cli, strategies: Vec<Box<dyn Strategy>>) -> Result<()> {
    let mut names = std::collections::BTreeSet::new();
    for s in &strategies {
        if !names.insert(s.name()) {
            return Err(Error::Usage(format!(
                "two strategies are named `{}`: names key results and random streams, so they must be unique",
                s.name()
            )));
        }
    }
    match cli.command {
        Command::Compare(a) => run_compare(a, strategies),
        Command::Reference(a) => run_reference(a),
        Command::Rays(a) => run_rays(a),
        Command::Strategies { scene } => run_strategies(scene, &strategies),
        Command::Warp(a) => run_warp(a),
        Command::Crosscheck(a) => run_crosscheck(a),
        Command::Stress(a) => run_stress(a),
        Command::Merge { scene, out } => {
            let scene = Scene::load(&Scene::resolve(&scene)?)?;
            for p in crate::harness::shard::merge(&out, &scene)? {
                println!("reference: {}", p.display());
            }
            Ok(())
        }
        Command::Plot { run_dir } => {
            for p in crate::plot::plot_run(&run_dir)? {
                println!("{}", p.display());
            }
            Ok(())
        }
    }
}

fn run_stress(a: StressArgs) -> Result<()> {
    use crate::stress::{self, Status};
    let mut cases = stress::cases::all();
    if a.list {
        for c in &cases {
            println!("{:<26} {}", c.name, c.about);
        }
        return Ok(());
    }
    if let Some(names) = &a.cases {
        for n in names {
            if !cases.iter().any(|c| &c.name == n) {
                return Err(Error::Usage(format!(
                    "unknown stress case `{n}` (see `dibench stress --list`)"
                )));
            }
        }
        cases.retain(|c| names.contains(&c.name));
    }
    let path = a.out.join("stress").join("stress.csv");
    crate::output::check_output_dir(&a.out.join("stress"), "--out")?;
    if let Some(dir) = &a.export {
        crate::output::check_output_dir(dir, "--export")?;
        for c in &cases {
            c.write_to(dir)?;
        }
        println!("scenes: {}/<case>/scene.toml", dir.display());
    }
    let (pool, threads) = pool(a.threads)?;
    let rows = pool.install(|| stress::run(&cases, a.samples, a.seed))?;
    crate::output::write_csv(&path, &rows)?;
    println!(
        "{} cases · {} samples per strategy · seed {} · {threads} threads",
        cases.len(),
        a.samples,
        a.seed
    );
    println!(
        "{:<24} {:<20} {:>5} {:>9} {:>12} {:>12} {:>7} {:>10}  status",
        "case", "strategy", "bad", "ess", "mean", "expected", "z", "rel.var"
    );
    let opt = |x: Option<f64>, f: &dyn Fn(f64) -> String| x.map_or("-".to_string(), f);
    for r in &rows {
        println!(
            "{:<24} {:<20} {:>5} {:>9.0} {:>12.5e} {:>12} {:>7} {:>10}  {:?}{}{}",
            r.case,
            r.strategy,
            r.nan + r.inf + r.negative,
            r.effective_samples,
            r.mean,
            opt(r.expected, &|v| format!("{v:.5e}")),
            opt(r.z, &|v| format!("{v:.2}")),
            opt(r.rel_variance, &|v| format!("{v:.3e}")),
            r.status,
            if r.detail.is_empty() { "" } else { ": " },
            r.detail
        );
    }
    println!();
    println!(
        "{:<24} {:>4} {:>4} {:>10} {:>4} {:>9}  lowest relative variance",
        "case", "runs", "pass", "unresolved", "fail", "nonfinite"
    );
    for c in &cases {
        let of: Vec<_> = rows.iter().filter(|r| r.case == c.name).collect();
        let n = |s: Status| of.iter().filter(|r| r.status == s).count();
        let best = of
            .iter()
            .filter(|r| r.status == Status::Pass)
            .filter_map(|r| r.rel_variance.map(|v| (v, &r.strategy)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map_or("-".to_string(), |(v, s)| format!("{s} {v:.2e}"));
        println!(
            "{:<24} {:>4} {:>4} {:>10} {:>4} {:>9}  {best}",
            c.name,
            of.iter().filter(|r| r.samples > 0).count(),
            n(Status::Pass),
            n(Status::Unresolved),
            n(Status::Fail),
            of.iter().map(|r| r.nan + r.inf + r.negative).sum::<u64>(),
        );
    }
    let count = |s: Status| rows.iter().filter(|r| r.status == s).count();
    let bad: u64 = rows.iter().map(|r| r.nan + r.inf + r.negative).sum();
    println!(
        "{} checks: {} pass, {} unresolved, {} fail; {bad} non-finite or negative samples",
        rows.len(),
        count(Status::Pass),
        count(Status::Unresolved),
        count(Status::Fail)
    );
    println!("results: {}", path.display());
    if count(Status::Fail) > 0 {
        return Err(Error::Usage(format!(
            "stress: {} checks failed (see above)",
            count(Status::Fail)
        )));
    }
    Ok(())
}

fn run_reference(a: ReferenceArgs) -> Result<()> {
    use crate::harness::shard;
    let spec = a
        .shard
        .as_deref()
        .map(shard::ShardSpec::parse)
        .transpose()?;
    let (pool, threads) = pool(a.common.threads)?;
    let scene = load_with(&a.common)?;
    scene.scene.require_light_power()?;
    // The film, its mean and variance, and a checkpoint being written.
    check_image_memory(&scene, 3)?;
    let budget = match (a.spp, a.time) {
        (_, Some(t)) => reference::Budget::Time(t),
        (n, None) => reference::Budget::Spp(n.unwrap_or(8192)),
    };
    crate::output::check_output_dir(&a.common.out, "--out")?;
    if let Some(spec) = spec {
        let store = shard::store(&a.common.out, &scene.scene.name)?;
        let total = a.spp.unwrap_or(8192);
        for integrand in strategy::integrands(&scene) {
            let unit = store.lock(&shard::stem(integrand.name(), spec))?;
            let (film, meta) =
                pool.install(|| shard::render(&scene, integrand, total, a.common.seed, spec))?;
            let path = shard::save_shard(&unit, &film, &meta)?;
            println!(
                "shard {}/{}: {} ({} of {total} spp, {:.1} s, {threads} threads)",
                spec.index,
                spec.count,
                path.display(),
                meta.spp,
                meta.wall_time_s
            );
        }
        return Ok(());
    }
    let store = reference::store(&a.common.out, &scene.scene.name)?;
    for integrand in strategy::integrands(&scene) {
        // Locked while it renders: a concurrent `compare` waits for it instead of rendering
        // its own, and checkpoints of two processes never interleave.
        let unit = store.lock(integrand.name())?;
        let r = pool.install(|| {
            reference::render_progressive(
                &scene,
                integrand,
                budget,
                a.common.seed,
                threads,
                Some(&unit),
            )
        })?;
        let path = reference::save(&unit, &r.image, &r.variance, &r.meta)?;
        println!(
            "reference: {} ({} spp, {:.1} s, strategy {}, noise floor {:.3e} RMSE)",
            path.display(),
            r.meta.spp,
            r.meta.wall_time_s,
            r.meta.strategy,
            r.meta.noise_floor_rmse.unwrap_or(0.0)
        );
    }
    Ok(())
}

/// Refuses, before anything is rendered, a scene whose image needs more memory than there is:
/// the film (sum and M2, 48 bytes per pixel), `images` more f64 RGB images (24 bytes each:
/// references, the mean, the variance) and EXR encoding (16 bytes).
fn check_image_memory(scene: &PreparedScene, images: u64) -> Result<()> {
    let s = &scene.scene;
    crate::bounded::check_memory(
        || {
            format!(
                "{}: field `image`: {}×{} pixels",
                s.path.display(),
                s.width,
                s.height
            )
        },
        image_memory(scene, images),
    )
}

fn image_memory(scene: &PreparedScene, images: u64) -> u64 {
    crate::bounded::bytes(scene.scene.pixel_count() as u64, 48 + 24 * images + 16)
}

fn run_compare(a: CompareArgs, strategies: Vec<Box<dyn Strategy>>) -> Result<()> {
    let seed = a.common.seed;
    if seed.checked_add(a.runs as u64 - 1).is_none() {
        return Err(Error::Usage(format!(
            "--seed {seed} with --runs {}: the seeds {seed}…{seed}+{} pass 2^64 − 1",
            a.runs,
            a.runs - 1
        )));
    }
    let (pool, threads) = pool(a.common.threads)?;
    let scene = load_with(&a.common)?;
    scene.scene.require_light_power()?;
    let known: Vec<String> = strategies.iter().map(|s| s.name()).collect();
    let (mut run, mut skipped) = strategy::split_applicable(strategies, &scene);
    if let Some(wanted) = &a.strategies {
        for w in wanted {
            if !known.contains(w) {
                return Err(Error::Usage(format!(
                    "unknown strategy `{w}` (known: {})",
                    known.join(", ")
                )));
            }
            if let Some(skip) = skipped.iter().find(|k| &k.name == w) {
                return Err(Error::Usage(format!(
                    "strategy `{w}` does not apply to scene `{}`: {}",
                    scene.scene.name, skip.reason
                )));
            }
        }
        run.retain(|s| wanted.contains(&s.name()));
        skipped.retain(|k| wanted.contains(&k.name));
    }
    // References (one per integrand), the film's mean, its variance and a checkpoint's mean;
    // then per (strategy, run) its rows and summary input, about 3 kB.
    let integrands = strategy::integrands(&scene).len() as u64;
    check_image_memory(&scene, integrands + 3)?;
    crate::bounded::check_memory(
        || format!("--runs {} (strategies: {})", a.runs, run.len()),
        image_memory(&scene, integrands + 3).saturating_add(crate::bounded::bytes(
            a.runs as u64 * run.len() as u64,
            3000,
        )),
    )?;
    // The output location is checked, and the run's directory taken, before any rendering.
    crate::output::check_output_dir(&a.common.out, "--out")?;
    let run_dir = compare::create_run_dir(&a.common.out, &scene.scene.name, seed)?;
    let store = reference::store(&a.common.out, &scene.scene.name)?;
    for k in &skipped {
        eprintln!("skipping strategy `{}`: {}", k.name, k.reason);
    }
    let result = pool.install(|| -> Result<()> {
        let mut images = Vec::new();
        for integrand in strategy::integrands(&scene) {
            if !run.iter().any(|s| s.integrand() == integrand) {
                continue;
            }
            images.push(compare::Reference::load_or_render(
                &store,
                &scene,
                integrand,
                a.reference_spp,
                a.common.seed,
                threads,
            )?);
        }
        let references = compare::References { images };
        let opts = compare::CompareOptions {
            time_s: a.time,
            seed: a.common.seed,
            threads,
            runs: a.runs,
            isa: isa_path(&a.common)?,
        };
        let report = compare::run(&scene, &run, skipped, &references, &run_dir, &opts)?;
        let spp: Vec<String> = references
            .images
            .iter()
            .map(|r| format!("{} {} spp", r.integrand.name(), r.spp))
            .collect();
        println!(
            "scene {} · backend {} · {} threads · seed {} · {} s per strategy · reference {}",
            scene.scene.name,
            scene.tracer.name(),
            threads,
            a.common.seed,
            a.time,
            spp.join(", ")
        );
        let ci = |x: Option<f64>| x.map_or("-".to_string(), |h| format!("{h:.2e}"));
        println!(
            "{:<20} {:>9} {:>4} {:>8} {:>8} {:>10} {:>9} {:>10} {:>9} {:>10} {:>10} {:>6}",
            "strategy",
            "integrand",
            "runs",
            "spp",
            "time_s",
            "rmse",
            "±95%",
            "relmse",
            "±95%",
            "pred_rmse",
            "efficiency",
            "vs_best"
        );
        for r in &report.summary {
            println!(
                "{:<20} {:>9} {:>4} {:>8.0} {:>8.3} {:>10.3e} {:>9} {:>10.3e} {:>9} {:>10.3e} {:>10.3e} {:>6}",
                r.strategy,
                r.integrand,
                r.runs,
                r.spp_mean,
                r.time_s_mean,
                r.rmse_mean,
                ci(r.rmse_ci95),
                r.relmse_mean,
                ci(r.relmse_ci95),
                r.predicted_rmse,
                r.efficiency,
                r.vs_best
            );
        }
        let overshoot = report
            .summary
            .iter()
            .map(|r| r.overshoot_max)
            .fold(f64::NEG_INFINITY, f64::max);
        println!(
            "largest deviation from the budget: {:+.2} % (a run stops at the last whole pass predicted to fit)",
            100.0 * overshoot
        );
        for floor in &references.images {
            if let Some(f) = floor.noise_floor {
                println!(
                    "reference ({}) noise floor: {f:.3e} RMSE",
                    floor.integrand.name()
                );
            }
        }
        for w in compare_warnings(&report.summary) {
            eprintln!("{w}");
        }
        println!("results: {}", report.run_dir.display());
        Ok(())
    });
    if let Err(e) = &result {
        run_dir.abandon(e);
    }
    result
}

fn compare_warnings(rows: &[crate::harness::summary::SummaryRow]) -> Vec<String> {
    crate::harness::summary::noise_floor_warnings(rows)
}

/// The ISA path the chosen backend runs, for run metadata.
fn isa_path(c: &Common) -> Result<String> {
    Ok(if c.backend == "packet" {
        isa(&c.isa)?.name().to_string()
    } else {
        "scalar".to_string()
    })
}

fn run_strategies(scene: Option<String>, strategies: &[Box<dyn Strategy>]) -> Result<()> {
    let prepared = scene.as_deref().map(load).transpose()?;
    for s in strategies {
        let status = match &prepared {
            None => String::new(),
            Some(p) => match strategy::applies(s.as_ref(), p) {
                Ok(()) => "  [applies]".into(),
                Err(why) => format!("  [skipped: {why}]"),
            },
        };
        println!("{:<20} {}{status}", s.name(), s.describe());
    }
    Ok(())
}

fn run_warp(a: WarpArgs) -> Result<()> {
    use crate::chi2::registry::{by_name, registry};
    if a.list || a.name.is_none() {
        for e in registry() {
            let params: Vec<String> = e.params.iter().map(|(k, v)| format!("{k}={v}")).collect();
            println!(
                "{:<20} {}{}  [{}]",
                e.name,
                e.describe,
                if e.expect_fail {
                    " (expected to fail)"
                } else {
                    ""
                },
                params.join(", ")
            );
        }
        return Ok(());
    }
    let name = a.name.unwrap_or_default();
    let entry = by_name(&name).ok_or_else(|| {
        let known: Vec<_> = registry().iter().map(|e| e.name.clone()).collect();
        Error::Usage(format!(
            "unknown sampler `{name}` (known: {})",
            known.join(", ")
        ))
    })?;
    let params = entry.params(&a.params).map_err(Error::Usage)?;
    if let Some(png) = &a.png {
        let dir = png.parent().filter(|d| !d.as_os_str().is_empty());
        crate::output::check_output_dir(dir.unwrap_or(Path::new(".")), "--png")?;
    }
    let case =
        (entry.build)(&params).map_err(|e| Error::Usage(format!("sampler `{name}`: {e}")))?;
    let r = crate::chi2::run(&case, a.samples, 40, 80, a.seed);
    if let Some(png) = &a.png {
        crate::chi2::image::write_png(png, &r.histogram)?;
        println!(
            "histogram (left) and expected counts (right): {}",
            png.display()
        );
    }
    println!(
        "{}: χ² = {:.1}, dof = {}, p = {:.4e} ({} samples)",
        r.label, r.chi2, r.dof, r.p_value, r.samples
    );
    if let Some(f) = &r.hard_failure {
        return Err(Error::Usage(format!("{}: FAILED: {f}", r.label)));
    }
    if r.p_value < a.alpha {
        return Err(Error::Usage(format!(
            "{}: FAILED: p = {:.3e} < alpha = {}",
            r.label, r.p_value, a.alpha
        )));
    }
    println!("{}: passed at alpha = {}", r.label, a.alpha);
    Ok(())
}

#[derive(Args, Debug)]
pub struct RaysArgs {
    /// Scene file, or the name of a scene in scenes/.
    #[arg(default_value = "bunny")]
    pub scene: String,
    /// Output root; the table goes to <out>/<scene>/rays.csv.
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// Comma-separated backends (obvhs, packet); packet runs at every available ISA.
    #[arg(long, value_delimiter = ',', default_value = "obvhs,packet")]
    pub backend: Vec<String>,
    /// Only this ISA for the packet backend (default: every ISA the CPU has).
    #[arg(long)]
    pub isa: Option<String>,
    /// Tracing threads (default 1: single-thread throughput).
    #[arg(long, default_value_t = 1, value_parser = parse_threads, allow_negative_numbers = true)]
    pub threads: usize,
    /// Image side of the ray sets, in pixels.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=crate::scene::MAX_IMAGE_SIDE as i64), allow_negative_numbers = true)]
    pub size: u32,
    /// Timing rounds (best round is reported; order alternates between rounds).
    #[arg(long, default_value_t = 5, value_parser = parse_rounds, allow_negative_numbers = true)]
    pub rounds: usize,
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
}

fn run_rays(a: RaysArgs) -> Result<()> {
    for b in &a.backend {
        if !rays::BACKENDS.contains(&b.as_str()) {
            return Err(rays::unknown_backend(b));
        }
    }
    let isas = match (&a.isa, std::env::var("DIBENCH_ISA")) {
        (Some(s), _) => vec![Isa::parse(s)?],
        (None, Ok(s)) if !s.is_empty() => vec![Isa::detect()?],
        _ => Isa::available(),
    };
    let (pool, threads) = pool(Some(a.threads))?;
    let scene = load(&a.scene)?;
    let name = scene.scene.name.clone();
    let path = a.out.join(&name).join("rays.csv");
    crate::output::check_output_dir(&a.out.join(&name), "--out")?;
    // Four sets of size² rays, with their packets and masks: about 256 bytes per ray.
    crate::bounded::check_memory(
        || format!("--size {}", a.size),
        crate::bounded::bytes(a.size as u64 * a.size as u64, 256),
    )?;
    let sets = rays::generate(&scene, a.size, a.seed);
    let subjects = rays::subjects(&scene, &a.backend, &isas)?;
    let rows = pool.install(|| rays::measure(&name, &sets, &subjects, a.rounds, threads));
    crate::output::write_csv(&path, &rows)?;
    println!(
        "scene {name} · {} threads · {}x{} rays per class · best of {} rounds",
        threads, a.size, a.size, a.rounds
    );
    println!(
        "{:<8} {:<9} {:<15} {:>8} {:>9} {:>10} {:>8} {:>8} {:>8}",
        "backend", "isa", "ray_class", "rays", "Mrays/s", "x obvhs", "lanes", "nodes/r", "tests/r"
    );
    let opt = |x: Option<f64>, p: usize| x.map_or("-".to_string(), |v| format!("{v:.p$}"));
    for r in &rows {
        println!(
            "{:<8} {:<9} {:<15} {:>8} {:>9.2} {:>10} {:>8} {:>8} {:>8}",
            r.backend,
            r.isa,
            r.ray_class,
            r.rays,
            r.mrays_per_s,
            opt(r.ratio_to_obvhs, 2),
            opt(r.active_lane_fraction, 2),
            opt(r.nodes_per_ray, 1),
            opt(r.tests_per_ray, 1)
        );
    }
    // Our best packet path against Embree's best kernel, per class (the bar to steer by).
    for class in rows
        .iter()
        .map(|r| r.ray_class.clone())
        .collect::<std::collections::BTreeSet<_>>()
    {
        let best = |b: &str| {
            rows.iter()
                .filter(|r| r.ray_class == class && r.backend == b)
                .map(|r| r.mrays_per_s)
                .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))))
        };
        if let (Some(ours), Some(embree)) = (best("packet"), best("embree")) {
            println!("packet/embree {class:<15} {:.2}", ours / embree);
        }
    }
    println!("results: {}", path.display());
    Ok(())
}

fn run_crosscheck(a: CrosscheckArgs) -> Result<()> {
    let (pool, _) = pool(a.threads)?;
    let mut scene = load(&a.scene)?;
    crate::output::check_output_dir(&a.out.join(&scene.scene.name), "--out")?;
    // A render per backend and pass beside the ray sets.
    check_image_memory(&scene, 8)?;
    if backends::AVAILABLE.len() < 2 {
        eprintln!("crosscheck: only one backend is compiled in");
    }
    let report = pool.install(|| crosscheck::run(&mut scene, &a.out, a.seed))?;
    println!(
        "{:<12} {:<8} {:<9} {:>7} {:>6} {:>6} {:>5} {:>9} {:>6} {:>9} {:>8}",
        "set",
        "backend",
        "mode",
        "rays",
        "hitMM",
        "primMM",
        "ties",
        "t_rel",
        "occMM",
        "seconds",
        "Mrays/s"
    );
    for r in &report.rows {
        if let Some(d) = r.image_rel_rmse {
            println!(
                "{:<12} {:<8} {:<9} image relative RMSE vs obvhs {d:.3e} {}",
                r.set,
                r.backend,
                r.mode,
                if r.pass { "ok" } else { "FAIL" }
            );
            continue;
        }
        println!(
            "{:<12} {:<8} {:<9} {:>7} {:>6} {:>6} {:>5} {:>9.2e} {:>6} {:>9.4} {:>8.2}{}",
            r.set,
            r.backend,
            r.mode,
            r.rays,
            r.hit_mismatch,
            r.prim_mismatch,
            r.ties,
            r.t_rel_max,
            r.occlusion_mismatch,
            r.seconds,
            r.mrays_per_s,
            if r.pass { "" } else { "  FAIL" }
        );
    }
    println!("results: {}", report.csv.display());
    crosscheck::into_result(&report)
}
