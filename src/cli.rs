//! The `dibench` command line.

use crate::error::{Error, Result};
use crate::harness::{compare, crosscheck, reference};
use crate::prepare::PreparedScene;
use crate::scene::Scene;
use crate::strategy;
use crate::tracer::backends;
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

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
    /// List the strategies, and which apply to a scene.
    Strategies {
        /// Scene file or name under scenes/.
        scene: Option<String>,
    },
    /// Trace fixed ray sets through every compiled-in backend and compare each with obvhs.
    #[command(after_help = CROSSCHECK_HELP)]
    Crosscheck(CrosscheckArgs),
}

const CROSSCHECK_HELP: &str = "\
Ray sets: primary (camera rays in 4x4 tiles), shadow_area (surface points to light samples,
finite tmax), incoherent (uniform hemisphere directions from surface points); each traced for
closest hit and occlusion, single rays and 16-packets. Fails (non-zero exit) when, against
obvhs, per set: hit/miss mismatches > 1e-4 of the rays, primitive mismatches > 1e-4 (ties,
where our exact tests hit both primitives at the same t within 1e-4, are excepted), occlusion
mismatches > 1e-4, max t difference > 1e-3 relative to max(t, largest |origin coordinate|), or the image relative RMSE after 4 passes
of the same strategy and seed > 1e-2. Timing (seconds, mrays_per_s) is single-threaded, best of
5 interleaved rounds. Without --features embree only obvhs is compiled in and it trivially
agrees with itself.";

/// Which tracer backend renders: `obvhs` (default), or `embree` with --features embree.
#[derive(Args, Debug)]
pub struct BackendArg {
    /// Tracer backend (obvhs; embree when built with --features embree).
    #[arg(long, default_value = backends::DEFAULT)]
    pub backend: String,
}

#[derive(Args, Debug)]
pub struct CrosscheckArgs {
    /// Scene file, or the name of a scene in scenes/ (e.g. cornell).
    #[arg(default_value = "cornell")]
    pub scene: String,
    /// Output root; the table goes to <out>/<scene>/crosscheck.csv.
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// Seed of the ray sets and of the renders.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads for the renders (ray tracing and timing are single-threaded).
    #[arg(long)]
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
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
}

#[derive(Args, Debug)]
pub struct CompareArgs {
    #[command(flatten)]
    pub common: Common,
    #[command(flatten)]
    pub backend: BackendArg,
    /// Wall-clock budget per strategy, in seconds.
    #[arg(long, default_value_t = 2.0, allow_negative_numbers = true)]
    pub time: f64,
    /// Samples per pixel of the reference rendered when no matching one is stored.
    #[arg(long, default_value_t = 8192)]
    pub reference_spp: u64,
    /// Comma-separated subset of strategies to run (default: every applicable one).
    #[arg(long, value_delimiter = ',')]
    pub strategies: Option<Vec<String>>,
}

#[derive(Args, Debug)]
pub struct ReferenceArgs {
    #[command(flatten)]
    pub common: Common,
    #[command(flatten)]
    pub backend: BackendArg,
    /// Samples per pixel.
    #[arg(long, default_value_t = 8192)]
    pub spp: u64,
}

fn load(scene: &str) -> Result<PreparedScene> {
    load_with(scene, backends::DEFAULT)
}

fn load_with(scene: &str, backend: &str) -> Result<PreparedScene> {
    backends::check(backend)?;
    let path = Scene::resolve(scene)?;
    let scene = Scene::load(&path)?;
    let mut err = None;
    let prepared =
        PreparedScene::with_tracer(scene, |g| match backends::build(backend, g.clone()) {
            Ok(t) => t,
            Err(e) => {
                err = Some(e);
                backends::build(backends::DEFAULT, g).expect("the default backend always builds")
            }
        });
    match err {
        Some(e) => Err(e),
        None => Ok(prepared),
    }
}

fn pool(threads: Option<usize>) -> Result<(rayon::ThreadPool, usize)> {
    let n = threads.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    if n == 0 {
        return Err(Error::Usage("--threads must be at least 1".into()));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(|e| Error::Usage(format!("cannot start {n} threads: {e}")))?;
    Ok((pool, n))
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Compare(a) => run_compare(a),
        Command::Reference(a) => run_reference(a),
        Command::Strategies { scene } => run_strategies(scene),
        Command::Crosscheck(a) => run_crosscheck(a),
    }
}

fn run_reference(a: ReferenceArgs) -> Result<()> {
    let (pool, threads) = pool(a.common.threads)?;
    let scene = load_with(&a.common.scene, &a.backend.backend)?;
    let (image, meta) =
        pool.install(|| reference::render(&scene, a.spp, a.common.seed, threads))?;
    let path = reference::save(&a.common.out, &image, &meta)?;
    println!(
        "reference: {} ({} spp, {:.1} s, strategy {})",
        path.display(),
        meta.spp,
        meta.wall_time_s,
        meta.strategy
    );
    Ok(())
}

fn run_compare(a: CompareArgs) -> Result<()> {
    let (pool, threads) = pool(a.common.threads)?;
    if !(a.time.is_finite() && a.time > 0.0) {
        return Err(Error::Usage(format!(
            "--time must be a positive number of seconds, got {}",
            a.time
        )));
    }
    if a.reference_spp == 0 {
        return Err(Error::Usage("--reference-spp must be at least 1".into()));
    }
    let scene = load_with(&a.common.scene, &a.backend.backend)?;
    let (mut run, mut skipped) = strategy::applicable(&scene);
    if let Some(wanted) = &a.strategies {
        for w in wanted {
            if strategy::by_name(w).is_none() {
                let known: Vec<_> = strategy::registry().iter().map(|s| s.name()).collect();
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
        run.retain(|s| wanted.iter().any(|w| w == s.name()));
        skipped.retain(|k| wanted.contains(&k.name));
    }
    for k in &skipped {
        eprintln!("skipping strategy `{}`: {}", k.name, k.reason);
    }
    pool.install(|| -> Result<()> {
        let (reference, ref_meta) =
            match reference::load_matching(&a.common.out, &scene, a.reference_spp)? {
                Some(r) => {
                    eprintln!(
                        "reference: reusing {} spp from {}",
                        r.1.spp,
                        reference::reference_dir(&a.common.out, &scene.scene.name).display()
                    );
                    r
                }
                None => {
                    eprintln!(
                        "reference: rendering {} spp (no matching one stored)",
                        a.reference_spp
                    );
                    let (img, meta) =
                        reference::render(&scene, a.reference_spp, a.common.seed, threads)?;
                    reference::save(&a.common.out, &img, &meta)?;
                    eprintln!("reference: {:.1} s", meta.wall_time_s);
                    (img, meta)
                }
            };
        let opts = compare::CompareOptions {
            time_s: a.time,
            seed: a.common.seed,
            threads,
        };
        let report = compare::run(
            &scene,
            &run,
            skipped,
            &reference,
            ref_meta.spp,
            &a.common.out,
            &opts,
        )?;
        println!(
            "scene {} · backend {} · {} threads · seed {} · {} s per strategy · reference {} spp",
            scene.scene.name,
            scene.tracer.name(),
            threads,
            a.common.seed,
            a.time,
            ref_meta.spp
        );
        println!(
            "{:<12} {:>8} {:>9} {:>12} {:>12}",
            "strategy", "spp", "time_s", "rmse", "relmse"
        );
        for s in &run {
            if let Some(last) = report.rows.iter().rev().find(|r| r.strategy == s.name()) {
                println!(
                    "{:<12} {:>8} {:>9.3} {:>12.5e} {:>12.5e}",
                    last.strategy, last.spp, last.time_s, last.rmse, last.relmse
                );
            }
        }
        println!("results: {}", report.run_dir.display());
        Ok(())
    })
}

fn run_strategies(scene: Option<String>) -> Result<()> {
    let prepared = scene.as_deref().map(load).transpose()?;
    for s in strategy::registry() {
        let status = match &prepared {
            None => String::new(),
            Some(p) => match s.applies(p) {
                Ok(()) => "  [applies]".into(),
                Err(why) => format!("  [skipped: {why}]"),
            },
        };
        println!("{:<12} {}{status}", s.name(), s.describe());
    }
    Ok(())
}

fn run_crosscheck(a: CrosscheckArgs) -> Result<()> {
    let (pool, _) = pool(a.threads)?;
    let mut scene = load(&a.scene)?;
    if backends::AVAILABLE.len() < 2 {
        eprintln!(
            "crosscheck: only `obvhs` is compiled in (build with --features embree for a second backend)"
        );
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
