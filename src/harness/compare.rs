//! Equal-time comparison: every applicable strategy renders for the same wall-clock budget;
//! the error against the reference is recorded at log-spaced checkpoints, so one run gives the
//! error-against-time curve (RMSE ∝ 1/√t for an unbiased estimator).

use super::{COMMIT, VERSION, progress_bar};
use crate::error::{Error, Result};
use crate::film::{Film, Image};
use crate::metrics::{relmse, rmse};
use crate::output::{write_csv, write_exr, write_json};
use crate::prepare::PreparedScene;
use crate::render::Renderer;
use crate::strategy::{Integrand, Skipped, Strategy};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Checkpoints at T/2^(K-1), ..., T/2, T.
pub const CHECKPOINTS: u32 = 8;

#[derive(Clone, Debug)]
pub struct CompareOptions {
    pub time_s: f64,
    pub seed: u64,
    pub threads: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct ResultRow {
    pub scene: String,
    pub strategy: String,
    pub integrand: String,
    pub backend: String,
    pub threads: usize,
    pub seed: u64,
    pub checkpoint: u32,
    pub time_s: f64,
    pub spp: u64,
    pub rmse: f64,
    pub relmse: f64,
}

#[derive(Serialize)]
struct RunMeta<'a> {
    scene: &'a str,
    scene_hash: &'a str,
    width: u32,
    height: u32,
    backend: &'a str,
    threads: usize,
    seed: u64,
    budget_s: f64,
    strategies: Vec<&'a str>,
    skipped: &'a [Skipped],
    reference_spp: &'a [(String, u64)],
    dibench_version: &'a str,
    commit: &'a str,
}

/// One strategy's equal-time run: passes until the budget is spent, rows at checkpoints.
/// Time spent measuring the error is excluded from the clock.
pub fn run_strategy(
    scene: &PreparedScene,
    strategy: &dyn Strategy,
    reference: &Image,
    opts: &CompareOptions,
    mut on_progress: impl FnMut(Duration),
) -> (Image, Vec<ResultRow>) {
    let renderer = Renderer::new(scene, strategy, opts.seed);
    let mut film = Film::new(scene.scene.width, scene.scene.height);
    let budget = Duration::from_secs_f64(opts.time_s);
    let checkpoint_at = |k: u32| budget.div_f64(2f64.powi((CHECKPOINTS - 1 - k) as i32));
    let mut rows = Vec::new();
    let mut next = 0u32;
    let mut elapsed = Duration::ZERO;
    while elapsed < budget {
        let start = Instant::now();
        renderer.add_pass(&mut film);
        elapsed += start.elapsed();
        on_progress(elapsed);
        if elapsed >= checkpoint_at(next) || elapsed >= budget {
            let image = film.mean();
            rows.push(ResultRow {
                scene: scene.scene.name.clone(),
                strategy: strategy.name().to_string(),
                integrand: strategy.integrand().name().to_string(),
                backend: scene.tracer.name().to_string(),
                threads: opts.threads,
                seed: opts.seed,
                checkpoint: next,
                time_s: elapsed.as_secs_f64(),
                spp: film.spp,
                rmse: rmse(&image, reference),
                relmse: relmse(&image, reference),
            });
            // One pass may cover several checkpoints; the next row is for the next one ahead.
            while next < CHECKPOINTS && elapsed >= checkpoint_at(next) {
                next += 1;
            }
        }
    }
    (film.mean(), rows)
}

pub struct CompareReport {
    pub run_dir: PathBuf,
    pub rows: Vec<ResultRow>,
    pub skipped: Vec<Skipped>,
}

/// A reference image (and its spp) per integrand the compared strategies need.
pub struct References {
    pub images: Vec<(Integrand, Image, u64)>,
}

impl References {
    fn get(&self, i: Integrand) -> Option<&Image> {
        self.images
            .iter()
            .find(|(k, _, _)| *k == i)
            .map(|(_, img, _)| img)
    }
}

/// Runs `strategies` at equal time and writes `<out>/<scene>/<run-id>/`: one EXR per strategy,
/// `results.csv` (rewritten after each strategy, so an interrupted run keeps what finished)
/// and `run.json`.
pub fn run(
    scene: &PreparedScene,
    strategies: &[Box<dyn Strategy>],
    skipped: Vec<Skipped>,
    references: &References,
    out: &Path,
    opts: &CompareOptions,
) -> Result<CompareReport> {
    if !(opts.time_s.is_finite() && opts.time_s > 0.0) {
        return Err(Error::Usage(format!(
            "--time must be a positive number of seconds, got {}",
            opts.time_s
        )));
    }
    if strategies.is_empty() {
        return Err(Error::Usage(format!(
            "scene `{}`: no strategy applies",
            scene.scene.name
        )));
    }
    let stamp = humantime::format_rfc3339_seconds(std::time::SystemTime::now())
        .to_string()
        .replace(':', "-");
    let run_dir = out
        .join(&scene.scene.name)
        .join(format!("{stamp}-seed{}", opts.seed));
    let meta = RunMeta {
        scene: &scene.scene.name,
        scene_hash: &scene.scene.content_hash,
        width: scene.scene.width,
        height: scene.scene.height,
        backend: scene.tracer.name(),
        threads: opts.threads,
        seed: opts.seed,
        budget_s: opts.time_s,
        strategies: strategies.iter().map(|s| s.name()).collect(),
        skipped: &skipped,
        reference_spp: &references
            .images
            .iter()
            .map(|(i, _, spp)| (i.name().to_string(), *spp))
            .collect::<Vec<_>>(),
        dibench_version: VERSION,
        commit: COMMIT,
    };
    write_json(&run_dir.join("run.json"), &meta)?;
    let mut rows = Vec::new();
    let budget_ms = (opts.time_s * 1000.0).ceil() as u64;
    for s in strategies {
        let bar = progress_bar(
            budget_ms,
            format!("{:<10}", s.name()),
            "{prefix} [{bar:30}] {msg}",
        );
        let reference = references.get(s.integrand()).ok_or_else(|| {
            Error::Usage(format!(
                "no {} reference for strategy `{}`",
                s.integrand().name(),
                s.name()
            ))
        })?;
        let (image, mut r) = run_strategy(scene, s.as_ref(), reference, opts, |t| {
            bar.set_position(t.as_millis() as u64);
        });
        bar.finish_and_clear();
        write_exr(&run_dir.join(format!("{}.exr", s.name())), &image)?;
        rows.append(&mut r);
        write_csv(&run_dir.join("results.csv"), &rows)?;
    }
    Ok(CompareReport {
        run_dir,
        rows,
        skipped,
    })
}
