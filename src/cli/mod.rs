//! The `dibench` command line: the parser ([`Cli`], [`Command`]), the option groups and
//! parsers the commands share, and [`main_with`]. Each command's arguments and the function
//! that runs it live in a submodule of its name.

use crate::error::{Error, Result};
use crate::prepare::PreparedScene;
use crate::scene::Scene;
use crate::simd::Isa;
use crate::strategy::{self, Strategy};
use crate::tracer::backends;
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

pub mod compare;
pub mod crosscheck;
pub mod merge;
pub mod plot;
pub mod rays;
pub mod reference;
pub mod report;
pub mod strategies;
pub mod stress;
pub mod warp;

pub use compare::CompareArgs;
pub use crosscheck::CrosscheckArgs;
pub use merge::MergeArgs;
pub use plot::PlotArgs;
pub use rays::RaysArgs;
pub use reference::ReferenceArgs;
pub use report::ReportArgs;
pub use strategies::StrategiesArgs;
pub use stress::StressArgs;
pub use warp::WarpArgs;

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
    Strategies(StrategiesArgs),
    /// Trace fixed ray sets through every compiled-in backend and compare each with obvhs.
    #[command(after_help = crosscheck::HELP)]
    Crosscheck(CrosscheckArgs),
    /// Every applicable strategy on every stiff case: non-finite or negative samples and
    /// closed-form mismatches fail (non-zero exit); writes <out>/stress/stress.csv.
    Stress(StressArgs),
    /// Figures of a compare run: RMSE against time with CI bands, variance heatmaps, image
    /// strip; PNG (and SVG for the chart) in RUN_DIR/plots/.
    Plot(PlotArgs),
    /// A self-contained HTML page of a compare run (RUN_DIR/report.html, no network needed):
    /// sortable summary, convergence plot, flip-book viewer with exposure, zoom and pixel
    /// readout, error maps, region statistics.
    Report(ReportArgs),
    /// Merge the shards written by `reference --shard i/n` into the scene's reference files.
    Merge(MergeArgs),
}

/// The options of the commands that render a scene (`compare`, `reference`).
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

/// `--time`: a number of seconds within `harness::options`' bounds.
pub(crate) fn parse_seconds(s: &str) -> std::result::Result<f64, String> {
    crate::harness::options::seconds_value(s.trim().parse().unwrap_or(f64::NAN))
}

/// The most worker threads accepted: 1024, or the number of cores where there are more.
/// Beyond the cores threads only add contention, and creating tens of thousands takes minutes.
pub fn max_threads() -> usize {
    std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .max(1024)
}

/// `--threads`: from 1 to [`max_threads`].
pub(crate) fn parse_threads(s: &str) -> std::result::Result<usize, String> {
    let max = max_threads();
    match s.trim().parse::<usize>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        _ => Err(format!(
            "expected a whole number of threads from 1 to {max} (1024, or the cores if more)"
        )),
    }
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
        Some(s) => Isa::parse(s).map_err(|e| e.prefixed(&format!("--isa {s}"))),
        None => Isa::detect(),
    }
}

/// Loads a scene traced by the backend (and ISA) `c` names; returns it with the ISA path the
/// backend runs (`avx2`, `portable`, ..., or `scalar` for a backend without ISA paths), for
/// run metadata.
fn load_with(c: &Common) -> Result<(PreparedScene, &'static str)> {
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
        None => Ok((prepared, isa.map_or("scalar", Isa::name))),
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

/// The exit status of an error.
///
/// | status | meaning |
/// |---|---|
/// | 0 | success |
/// | 1 | an error: bad input (scene, files, stored results), output that cannot be written, not enough memory, or a usage error found after parsing ([`Error::Usage`]) |
/// | 2 | the command line was refused by the parser (unknown flag, bad value, not UTF-8) |
/// | 3 | a check ran and failed ([`Error::Check`]: `crosscheck`, `stress`, `warp`) |
/// | 4 | a tracer backend cannot be built or used here ([`Error::Backend`]) |
/// | 130 | interrupted by Ctrl-C or SIGTERM ([`Error::Interrupted`]), after writing what was complete |
pub fn exit_status(e: &Error) -> u8 {
    match e {
        Error::Check(_) => 3,
        Error::Backend(_) => 4,
        // 128 + SIGINT, as a shell reports a command stopped by Ctrl-C.
        Error::Interrupted(_) => 130,
        _ => 1,
    }
}

/// The `dibench` program with the built-in strategies and `extra` ones (a researcher's own,
/// defined outside the crate: see `examples/custom_strategy.rs`): parses the command line,
/// runs it, reports an error on stderr and maps it to the exit status: 0 on success, 2 when
/// the parser refuses the command line, else [`exit_status`] of the error (1 for most, 3 for
/// a failed check, 4 for an unusable backend, 130 when interrupted).
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
            ExitCode::from(exit_status(&e))
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
        Command::Compare(a) => compare::run(a, strategies),
        Command::Reference(a) => reference::run(a),
        Command::Rays(a) => rays::run(a),
        Command::Strategies(a) => strategies::run(a, &strategies),
        Command::Warp(a) => warp::run(a),
        Command::Crosscheck(a) => crosscheck::run(a),
        Command::Stress(a) => stress::run(a),
        Command::Merge(a) => merge::run(a),
        Command::Plot(a) => plot::run(a),
        Command::Report(a) => report::run(a),
    }
}
