//! Equal-time comparison: every applicable strategy renders for the same wall-clock budget
//! (or, with `--spp`, the same number of samples per pixel); the error against the reference
//! is recorded at log-spaced checkpoints, so one run gives the error-against-time curve
//! (RMSE ∝ 1/√t for an unbiased estimator with independent samples). With `runs` > 1 every
//! strategy is run that many times with independent seeds, so that the error of each is
//! known with a confidence interval (Celarek et al. 2019); see `summary`.

pub use super::options::Budget;
use super::summary::{FinalRun, SummaryRow, summarize};
use super::{COMMIT, RUSTC, VERSION, cpu_model, progress_bar};
use crate::error::{Error, Result};
use crate::film::{Film, Image};
use crate::metrics::{relmse, rmse};
use crate::output::run_dir::{RunDir, Status};
use crate::output::store::Store;
use crate::output::{Provenance, write_csv, write_exr_with};
use crate::prepare::PreparedScene;
use crate::render::{Renderer, group_size};
use crate::sampling::{SampleGenerator, Setup};
use crate::strategy::{Integrand, Skipped, Strategy};
use serde::Deserialize;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Checkpoints at T/2^(K-1), ..., T/2, T (or N/2^(K-1), ..., N passes, rounded up).
pub const CHECKPOINTS: u32 = 8;

#[derive(Clone, Debug)]
pub struct CompareOptions {
    /// Equal time (`--time`) or equal samples per pixel (`--spp`).
    pub budget: Budget,
    /// Seed of run 0; run k uses `seed + k`.
    pub seed: u64,
    pub threads: usize,
    /// Independent repetitions of every strategy.
    pub runs: u32,
    /// The ISA path the tracer runs (`avx2`, `portable`, ... or `scalar`), for the metadata.
    pub isa: String,
    /// The sample generators every strategy runs with (`--sampler`, names in
    /// `sampling::GENERATORS`); empty means the default (independent) alone.
    pub samplers: Vec<String>,
}

impl CompareOptions {
    /// The bounds `compare::run` needs (`harness::options`; the command line checks the same
    /// ones as it parses).
    pub fn check(&self) -> Result<()> {
        self.budget.check()?;
        super::options::check_at_least_one("--runs", self.runs as u64)?;
        super::options::check_seeds(self.seed, self.runs)?;
        self.generators().map(|_| ())
    }

    /// The generators of `samplers` ([`resolve_samplers`]).
    pub fn generators(&self) -> Result<Vec<&'static dyn SampleGenerator>> {
        resolve_samplers(&self.samplers, self.budget)
    }
}

/// The generators named (the default one when `names` is empty), each checked against the
/// budget: an equal-time one does not know the sample count, which stratification needs. A
/// usage error names `--sampler` and lists the generators.
pub fn resolve_samplers(
    names: &[String],
    budget: Budget,
) -> Result<Vec<&'static dyn SampleGenerator>> {
    if names.is_empty() {
        return Ok(vec![crate::sampling::GENERATORS[0]]);
    }
    let mut out: Vec<&'static dyn SampleGenerator> = Vec::new();
    for name in names {
        let g = crate::sampling::generator(name.trim()).ok_or_else(|| {
            Error::Usage(format!(
                "--sampler: unknown sample generator `{name}` (known: {})",
                crate::sampling::generator_names()
            ))
        })?;
        // Under a time budget the sample count per pixel is not known up front.
        let probe = Setup::image(crate::sampling::Layout::default(), budget.spp(), 1, 1);
        if let Err(why) = g.check(&probe) {
            return Err(Error::Usage(match budget {
                Budget::Time(_) => format!(
                    "--sampler {}: {why}; `compare` runs at equal time (--time) unless given \
                     --spp N, so give --spp or leave `{}` out of --sampler",
                    g.name(),
                    g.name()
                ),
                Budget::Spp(n) => format!("--sampler {} with --spp {n}: {why}", g.name()),
            }));
        }
        if !out.iter().any(|o| o.name() == g.name()) {
            out.push(g);
        }
    }
    Ok(out)
}

/// What summary.csv, run.json and the console say once when a non-independent generator ran.
pub const QMC_NOTE: &str = "predicted_rmse is left empty and no <strategy>.<sampler>.variance.exr \
    is written for a non-independent sampler: its samples within a pixel are correlated, so the \
    per-pixel variance across passes is not the variance of the mean; errors, intervals, tests \
    and slopes are across runs (independent seeds), which stay valid (docs/samplers.md)";

/// The file stem of a (strategy, sampler) run's images: the strategy's name for the
/// independent generator (as before the sampler axis), `<strategy>.<sampler>` otherwise.
pub fn image_stem(strategy: &str, sampler: &str) -> String {
    if sampler == crate::sampling::GENERATORS[0].name() {
        strategy.to_string()
    } else {
        format!("{strategy}.{sampler}")
    }
}

fn default_sampler() -> String {
    crate::sampling::GENERATORS[0].name().to_string()
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ResultRow {
    pub scene: String,
    pub strategy: String,
    pub integrand: String,
    pub backend: String,
    pub threads: usize,
    pub run: u32,
    pub seed: u64,
    pub checkpoint: u32,
    pub time_s: f64,
    pub spp: u64,
    pub rmse: f64,
    pub relmse: f64,
    /// The sample generator (`--sampler`), appended last so earlier columns keep their
    /// positions; a results.csv written before the column existed reads as `independent`.
    #[serde(default = "default_sampler")]
    pub sampler: String,
    /// Mean HDR-FLIP against the reference (`crate::flip`, Andersson et al. 2020/2021) of the
    /// final (equal-budget) image; empty at the earlier checkpoints, where it is not computed
    /// (the summary and the report use the final image's only).
    #[serde(default)]
    pub flip: Option<f64>,
}

#[derive(Serialize)]
struct RunMeta<'a> {
    scene: &'a str,
    scene_hash: &'a str,
    width: u32,
    height: u32,
    backend: &'a str,
    isa: &'a str,
    threads: usize,
    cpu_model: String,
    runs: u32,
    seeds: Vec<u64>,
    /// One of the two: seconds (`--time`) or samples per pixel (`--spp`) per strategy run.
    #[serde(skip_serializing_if = "Option::is_none")]
    budget_s: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    budget_spp: Option<u64>,
    strategies: Vec<String>,
    samplers: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    sampler_note: Option<&'static str>,
    skipped: &'a [Skipped],
    reference_spp: &'a [(String, u64)],
    reference_noise_floor: &'a [(String, Option<f64>)],
    dibench_version: &'a str,
    rustc: &'a str,
    commit: &'a str,
    /// The (strategy, run) pairs whose rows are in results.csv and images written; `run_dir`
    /// adds `status` (`running`, `complete`, `interrupted`, `failed`, `unfinished`), whether the
    /// run was interrupted, and the error that ended it.
    completed: Vec<(String, u32)>,
    /// The same pairs' samplers, in the same order.
    completed_samplers: Vec<String>,
}

/// What one strategy's run leaves: the mean and variance images, the rows, and the final
/// per-sample variance for predicting the error.
pub struct StrategyRun {
    pub image: Image,
    pub variance: Image,
    /// The final image's per-pixel HDR-FLIP against the reference.
    pub flip: crate::flip::FlipMap,
    pub rows: Vec<ResultRow>,
    /// None for a generator whose samples are not independent (the across-pass variance is
    /// then not the per-sample variance the prediction needs).
    pub mean_sample_variance: Option<f64>,
    /// An interrupt arrived before the budget was spent: the run is incomplete and must be
    /// discarded (its error is not comparable with the others').
    pub interrupted: bool,
}

/// One strategy's run with seed `seed`: passes until the budget is spent, rows at
/// checkpoints. Time spent measuring the error is excluded from the clock.
///
/// Budget bound: a pass is the unit of work (a partial pass would leave some pixels with one
/// sample fewer and bias the mean). Passes are rendered in groups of up to 16
/// ([`Renderer::add_passes`]), each group the same film as its passes one by one. At equal
/// time the loop predicts each pass's duration as the mean pass time so far and starts only
/// as many passes as are predicted to end within the budget: the final time lies within about
/// one pass of the budget, on either side, and the measured deviation is reported (`time_s` of
/// the last row, `overshoot` in summary.csv). At equal spp it renders exactly N passes;
/// checkpoint k is at ⌈N / 2^(K−1−k)⌉ passes, and no group runs past a checkpoint.
pub fn run_strategy(
    scene: &PreparedScene,
    strategy: &dyn Strategy,
    generator: &dyn SampleGenerator,
    reference: &Image,
    opts: &CompareOptions,
    run: u32,
    mut on_progress: impl FnMut(Duration, u64),
) -> Result<StrategyRun> {
    let seed = opts.seed.wrapping_add(run as u64);
    let mut renderer = Renderer::with_sampler(scene, strategy, seed, generator, opts.budget.spp())?;
    let name = strategy.name();
    let sampler = generator.name().to_string();
    let mut film = Film::new(scene.scene.width, scene.scene.height);
    let _polling = crate::interrupt::polling();
    let scale = |k: u32| 2f64.powi((CHECKPOINTS - 1 - k) as i32);
    // Whether checkpoint k has been reached after `spp` passes taking `elapsed`.
    let reached = |k: u32, spp: u64, elapsed: Duration| match opts.budget {
        // `--time` is validated where the options are built; saturating for other callers.
        Budget::Time(t) => {
            elapsed >= Duration::try_from_secs_f64(t / scale(k)).unwrap_or(Duration::MAX)
        }
        Budget::Spp(n) => spp as f64 >= (n as f64 / scale(k)).ceil(),
    };
    let mut rows = Vec::new();
    let mut next = 0u32;
    let mut elapsed = Duration::ZERO;
    let mut interrupted = false;
    let row = |film: &Film, checkpoint: u32, elapsed: Duration| {
        let image = film.mean();
        ResultRow {
            scene: scene.scene.name.clone(),
            strategy: name.clone(),
            sampler: sampler.clone(),
            integrand: strategy.integrand().name().to_string(),
            backend: scene.tracer.name().to_string(),
            threads: opts.threads,
            run,
            seed,
            checkpoint,
            time_s: elapsed.as_secs_f64(),
            spp: film.spp,
            rmse: rmse(&image, reference),
            relmse: relmse(&image, reference),
            flip: None,
        }
    };
    loop {
        if crate::interrupt::requested() {
            interrupted = true;
            break;
        }
        let done = match opts.budget {
            Budget::Time(t) => {
                film.spp > 0 && (elapsed + elapsed.div_f64(film.spp as f64)).as_secs_f64() > t
            }
            Budget::Spp(n) => film.spp >= n,
        };
        if done {
            break;
        }
        // Passes go in groups (one pixel's samples share a packet): as many as are
        // predicted to end within the budget, and none past the next checkpoint.
        let per_pass = (film.spp > 0).then(|| elapsed.as_secs_f64() / film.spp as f64);
        let left = match (opts.budget, per_pass) {
            (Budget::Time(_), None) => 1,
            (Budget::Time(t), Some(p)) => {
                let e = elapsed.as_secs_f64();
                let fits = ((t - e) / p).floor();
                let to_checkpoint = if next < CHECKPOINTS - 1 {
                    ((t / scale(next) - e) / p).ceil()
                } else {
                    f64::INFINITY
                };
                fits.min(to_checkpoint).max(1.0) as u64
            }
            (Budget::Spp(n), _) => {
                let target = if next < CHECKPOINTS - 1 {
                    (n as f64 / scale(next)).ceil() as u64
                } else {
                    n
                };
                target.saturating_sub(film.spp)
            }
        };
        let start = Instant::now();
        renderer.add_passes(&mut film, group_size(left, per_pass));
        elapsed += start.elapsed();
        on_progress(elapsed, film.spp);
        if next < CHECKPOINTS - 1 && reached(next, film.spp, elapsed) {
            rows.push(row(&film, next, elapsed));
            // One pass may cover several checkpoints; the next row is for the next one ahead.
            while next < CHECKPOINTS - 1 && reached(next, film.spp, elapsed) {
                next += 1;
            }
        }
    }
    // The last row is always the final image at the (bounded) budget, with its FLIP.
    let image = film.mean();
    let flip = crate::flip::hdr_flip_image(reference, &image)?;
    rows.push(ResultRow {
        flip: Some(flip.mean()),
        ..row(&film, CHECKPOINTS - 1, elapsed)
    });
    Ok(StrategyRun {
        flip,
        image,
        variance: film.variance_of_mean(),
        rows,
        mean_sample_variance: generator
            .independent_samples()
            .then(|| film.mean_sample_variance()),
        interrupted,
    })
}

pub struct CompareReport {
    pub run_dir: PathBuf,
    pub rows: Vec<ResultRow>,
    pub summary: Vec<SummaryRow>,
    pub skipped: Vec<Skipped>,
    /// What the run was, for the printed summary.
    pub scene: String,
    pub backend: String,
    pub threads: usize,
    pub seed: u64,
    pub budget: Budget,
    pub references: Vec<ReferenceUsed>,
    /// Whether a non-independent generator ran (then [`QMC_NOTE`] is printed).
    pub qmc: bool,
    /// `report.html`, when it could be written.
    pub report_html: Option<PathBuf>,
}

/// A reference a compare run measured against.
#[derive(Clone, Debug)]
pub struct ReferenceUsed {
    pub integrand: String,
    pub spp: u64,
    pub noise_floor: Option<f64>,
}

/// The summary `dibench compare` prints: the run's setting, a row per (strategy, integrand),
/// the largest deviation from the budget and the references' noise floors.
impl std::fmt::Display for CompareReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let spp: Vec<String> = self
            .references
            .iter()
            .map(|r| format!("{} {} spp", r.integrand, r.spp))
            .collect();
        writeln!(
            f,
            "scene {} · backend {} · {} threads · seed {} · {} per strategy · reference {}",
            self.scene,
            self.backend,
            self.threads,
            self.seed,
            self.budget,
            spp.join(", ")
        )?;
        let overshoot = self
            .summary
            .iter()
            .filter_map(|r| r.overshoot_max)
            .reduce(f64::max);
        if let Some(overshoot) = overshoot {
            writeln!(
                f,
                "largest deviation from the budget: {:+.2} % (a run stops at the last whole pass predicted to fit)",
                100.0 * overshoot
            )?;
        }
        for r in &self.references {
            if let Some(floor) = r.noise_floor {
                writeln!(
                    f,
                    "reference ({}) noise floor: {floor:.3e} RMSE; the debiased columns subtract it",
                    r.integrand
                )?;
            }
        }
        if self.qmc {
            writeln!(f, "note: {QMC_NOTE}")?;
        }
        writeln!(f, "results: {}", self.run_dir.display())?;
        if let Some(html) = &self.report_html {
            writeln!(f, "report: {}", html.display())?;
        }
        // The table last, ranked by the debiased relMSE (see `summary`).
        let ci = |x: Option<f64>| x.map_or("-".to_string(), |h| format!("{h:.2e}"));
        let opt = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.2}"));
        let opt_e = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.3e}"));
        writeln!(
            f,
            "{:<22} {:<11} {:>9} {:>4} {:>8} {:>10} {:>9} {:>10} {:>10} {:>9} {:>6} {:>10} {:>10} vs_best (Holm)",
            "strategy",
            "sampler",
            "integrand",
            "runs",
            "spp",
            "rmse",
            "±95%",
            "rmse_deb",
            "relmse_deb",
            "±95%",
            "slope",
            "pred_rmse",
            "efficiency",
        )?;
        for r in &self.summary {
            writeln!(
                f,
                "{:<22} {:<11} {:>9} {:>4} {:>8.0} {:>10.3e} {:>9} {:>10} {:>10.3e} {:>9} {:>6} {:>10} {:>10} {}",
                r.strategy,
                r.sampler,
                r.integrand,
                r.runs,
                r.spp_mean,
                r.rmse_mean,
                ci(r.rmse_ci95),
                opt_e(r.rmse_debiased),
                r.relmse_debiased_mean,
                ci(r.relmse_debiased_ci95),
                opt(r.slope_time_mean),
                opt_e(r.predicted_rmse),
                opt_e(r.efficiency),
                r.vs_best
            )?;
        }
        Ok(())
    }
}

/// A reference image per integrand the compared strategies need.
pub struct Reference {
    pub integrand: Integrand,
    pub image: Image,
    pub spp: u64,
    /// RMSE the reference's own noise adds to every measured RMSE (see `reference`); None
    /// for references stored before it was tracked.
    pub noise_floor: Option<f64>,
    /// What the reference's noise adds to a measured relMSE in expectation: the mean over
    /// pixels and channels of Var(r) / (r² + ε), the relMSE's own weighting (see
    /// `metrics::relmse_floor`).
    pub relmse_floor: f64,
}

pub struct References {
    pub images: Vec<Reference>,
}

/// What a reference must be to serve: a fixed sample count (`--reference-spp`), or a noise
/// floor planned from pilots (`pilot::plan`), rendered with the plan's strategy within a cap.
pub enum Need<'a> {
    Spp(u64),
    Floor {
        plan: &'a super::pilot::Plan,
        strategy: &'a dyn Strategy,
        cap_s: f64,
    },
}

impl Reference {
    /// The stored reference of `integrand` that meets `need` for this exact scene content,
    /// else a fresh one rendered (with `seed`) and stored. Says which on stderr. The unit stays
    /// locked while it renders, so a concurrent run waits and then reuses it.
    pub fn load_or_render(
        store: &Store,
        scene: &PreparedScene,
        integrand: Integrand,
        need: Need,
        seed: u64,
        threads: usize,
    ) -> Result<Reference> {
        use super::reference::{self, Budget};
        let dir = store.dir();
        let unit = store.lock(integrand.name())?;
        let min_spp = match need {
            Need::Spp(n) => n,
            Need::Floor { .. } => 1,
        };
        let stored =
            reference::load_matching(&unit, scene, min_spp)?.filter(|(_, meta)| match &need {
                Need::Spp(_) => true,
                Need::Floor { plan, .. } => meta
                    .noise_floor_rmse
                    .is_some_and(|f| f <= plan.accept_floor),
            });
        let (image, meta, variance) = match stored {
            Some(r) => {
                eprintln!(
                    "reference ({}): reusing {} spp from {}",
                    integrand.name(),
                    r.1.spp,
                    dir.display()
                );
                let variance = reference::load_variance(&unit, r.0.width, r.0.height)?;
                (r.0, r.1, variance)
            }
            None => {
                let r = match need {
                    Need::Spp(spp) => {
                        eprintln!(
                            "reference ({}): rendering {spp} spp (no matching one stored)",
                            integrand.name()
                        );
                        reference::render(scene, integrand, spp, seed, threads)?
                    }
                    Need::Floor {
                        plan,
                        strategy,
                        cap_s,
                    } => {
                        eprintln!(
                            "reference ({}): rendering with `{}` to a noise floor of {:.2e} \
                             ({:.0} % of the smallest predicted RMSE, {:.2e} by `{}`): about \
                             {} spp, {:.0} s",
                            integrand.name(),
                            plan.strategy,
                            plan.target_floor,
                            100.0 * plan.target_floor / plan.smallest_rmse,
                            plan.smallest_rmse,
                            plan.smallest_by,
                            plan.predicted_spp,
                            plan.predicted_s
                        );
                        let budget = Budget::Floor {
                            target: plan.target_floor,
                            cap: cap_s,
                            expected_spp: plan.predicted_spp,
                        };
                        let r =
                            reference::render_with(scene, strategy, budget, seed, threads, None)?;
                        let floor = r.meta.noise_floor_rmse.unwrap_or(0.0);
                        if floor > plan.target_floor {
                            eprintln!(
                                "reference ({}): stopped at the cap of {cap_s} s \
                                 (--reference-cap) with a noise floor of {floor:.2e}, above \
                                 the target {:.2e}",
                                integrand.name(),
                                plan.target_floor
                            );
                        }
                        r
                    }
                };
                reference::save(&unit, &r.image, &r.variance, &r.meta)?;
                eprintln!(
                    "reference ({}): {} spp in {:.1} s with `{}`",
                    integrand.name(),
                    r.meta.spp,
                    r.meta.wall_time_s,
                    r.meta.strategy
                );
                (r.image, r.meta, r.variance)
            }
        };
        Ok(Reference {
            integrand,
            relmse_floor: crate::metrics::relmse_floor(&variance, &image),
            image,
            spp: meta.spp,
            noise_floor: meta.noise_floor_rmse,
        })
    }
}

impl References {
    pub fn get(&self, i: Integrand) -> Option<&Reference> {
        self.images.iter().find(|r| r.integrand == i)
    }
}

/// Creates the run directory `<out>/<scene>/<time>-seed<N>` (exclusively: `-2`, `-3`, … when
/// the name is taken) before anything is rendered, so a bad `--out` is reported at once.
pub fn create_run_dir(out: &Path, scene: &str, seed: u64) -> Result<RunDir> {
    let stamp = humantime::format_rfc3339_seconds(std::time::SystemTime::now())
        .to_string()
        .replace(':', "-");
    RunDir::create(&out.join(scene), &format!("{stamp}-seed{seed}"))
}

/// Runs `strategies` at equal time, `opts.runs` times each, and writes into `run_dir`: per
/// strategy the run-0 image and its per-pixel variance of the mean (`<strategy>.exr`,
/// `<strategy>.variance.exr`), `results.csv` and `summary.csv` (both rewritten after each
/// strategy, so an interrupted or killed run keeps what finished) and `run.json` (which says how
/// complete the run is).
pub fn run(
    scene: &PreparedScene,
    strategies: &[Box<dyn Strategy>],
    skipped: Vec<Skipped>,
    references: &References,
    run_dir: &RunDir,
    opts: &CompareOptions,
) -> Result<CompareReport> {
    opts.check()?;
    let generators = opts.generators()?;
    let qmc = generators.iter().any(|g| !g.independent_samples());
    if strategies.is_empty() {
        return Err(Error::Usage(format!(
            "scene `{}`: no strategy applies",
            scene.scene.name
        )));
    }
    let mut meta = RunMeta {
        scene: &scene.scene.name,
        scene_hash: &scene.scene.content_hash,
        width: scene.scene.width,
        height: scene.scene.height,
        backend: scene.tracer.name(),
        isa: &opts.isa,
        threads: opts.threads,
        cpu_model: cpu_model(),
        runs: opts.runs,
        seeds: (0..opts.runs as u64)
            .map(|k| opts.seed.wrapping_add(k))
            .collect(),
        budget_s: opts.budget.seconds(),
        budget_spp: opts.budget.spp(),
        strategies: strategies.iter().map(|s| s.name()).collect(),
        samplers: generators.iter().map(|g| g.name().to_string()).collect(),
        sampler_note: qmc.then_some(QMC_NOTE),
        skipped: &skipped,
        reference_spp: &references
            .images
            .iter()
            .map(|r| (r.integrand.name().to_string(), r.spp))
            .collect::<Vec<_>>(),
        reference_noise_floor: &references
            .images
            .iter()
            .map(|r| (r.integrand.name().to_string(), r.noise_floor))
            .collect::<Vec<_>>(),
        dibench_version: VERSION,
        rustc: RUSTC,
        commit: COMMIT,
        completed: Vec::new(),
        completed_samplers: Vec::new(),
    };
    let dir = run_dir.path();
    run_dir.record(&meta, Status::Running)?;
    let mut rows = Vec::new();
    let mut finals = Vec::new();
    // The progress bar counts milliseconds at equal time, passes at equal spp.
    let bar_len = match opts.budget {
        Budget::Time(t) => (t * 1000.0).ceil() as u64,
        Budget::Spp(n) => n,
    };
    // Strategies (and, within each, samplers) interleaved within each run, so slow drifts in
    // machine load spread over all.
    let pairs: Vec<(&Box<dyn Strategy>, &dyn SampleGenerator)> = strategies
        .iter()
        .flat_map(|s| generators.iter().map(move |g| (s, *g)))
        .collect();
    // Ctrl-C anywhere in the loop (between strategies, or while one's images are written) is
    // a request: the loop stops before the next strategy with what finished in place.
    let _polling = crate::interrupt::polling();
    let interrupted = |meta: &RunMeta, stem: &str, run: u32| {
        Error::Interrupted(format!(
            "compare kept {} finished strategy run(s) in {}; `{stem}` (run {run}) was discarded",
            meta.completed.len(),
            dir.display(),
        ))
    };
    for run in 0..opts.runs {
        for &(s, g) in &pairs {
            let stem = image_stem(&s.name(), g.name());
            if crate::interrupt::requested() {
                return Err(interrupted(&meta, &stem, run));
            }
            let bar = progress_bar(
                bar_len,
                format!("run {run} {:<10}", stem),
                "{prefix} [{bar:30}] {msg}",
            );
            let reference = references.get(s.integrand()).ok_or_else(|| {
                Error::Usage(format!(
                    "no {} reference for strategy `{}`",
                    s.integrand().name(),
                    s.name()
                ))
            })?;
            let r = run_strategy(
                scene,
                s.as_ref(),
                g,
                &reference.image,
                opts,
                run,
                |t, spp| {
                    bar.set_position(match opts.budget {
                        Budget::Time(_) => t.as_millis() as u64,
                        Budget::Spp(_) => spp,
                    });
                },
            )?;
            bar.finish_and_clear();
            if r.interrupted {
                // What finished is already written (results.csv, summary.csv, images); the
                // unfinished strategy leaves no file behind.
                return Err(interrupted(&meta, &stem, run));
            }
            if run == 0 {
                let last = r.rows.last();
                let provenance = Provenance {
                    scene: scene.scene.name.clone(),
                    scene_hash: scene.scene.content_hash.clone(),
                    strategy: s.name(),
                    integrand: s.integrand().name().to_string(),
                    sampler: g.name().to_string(),
                    content: "radiance".into(),
                    spp: last.map_or(0, |l| l.spp),
                    render_time_s: last.map_or(0.0, |l| l.time_s),
                    seed: opts.seed.wrapping_add(run as u64),
                    backend: scene.tracer.name().to_string(),
                    threads: opts.threads,
                    version: VERSION.to_string(),
                    commit: COMMIT.to_string(),
                    cpu: Some(meta.cpu_model.clone()),
                };
                write_exr_with(&dir.join(format!("{stem}.exr")), &r.image, &provenance)?;
                if g.independent_samples() {
                    write_exr_with(
                        &dir.join(format!("{stem}.variance.exr")),
                        &r.variance,
                        &provenance.variance(),
                    )?;
                }
                write_exr_with(
                    &dir.join(format!("{stem}.flip.exr")),
                    &r.flip.to_image(),
                    &Provenance {
                        content: crate::flip::CONTENT.into(),
                        ..provenance
                    },
                )?;
            }
            let Some(last) = FinalRun::new(
                &r.rows,
                r.mean_sample_variance,
                reference.noise_floor,
                reference.relmse_floor,
            ) else {
                return Err(Error::Usage(format!("`{stem}` (run {run}) left no rows")));
            };
            finals.push(last);
            rows.extend(r.rows);
            write_csv(&dir.join("results.csv"), &rows)?;
            // Rewritten with results.csv, so a run killed at any instant keeps a summary of
            // what finished.
            write_csv(&dir.join("summary.csv"), &summarize(&finals, opts.budget))?;
            run_dir.keep();
            meta.completed.push((s.name().to_string(), run));
            meta.completed_samplers.push(g.name().to_string());
            run_dir.record(&meta, Status::Running)?;
        }
    }
    let summary = summarize(&finals, opts.budget);
    write_csv(&dir.join("summary.csv"), &summary)?;
    run_dir.record(&meta, Status::Complete)?;
    // The page over everything the run wrote. A run whose images are too large to embed is
    // still a complete run: it says why there is no page (`dibench report` says the same).
    let report_html = match crate::report::write_report(dir) {
        Ok(path) => Some(path),
        Err(e) => {
            crate::interrupt::note(&format!("report.html not written: {e}"));
            None
        }
    };
    Ok(CompareReport {
        run_dir: dir.to_path_buf(),
        rows,
        summary,
        skipped,
        scene: scene.scene.name.clone(),
        backend: scene.tracer.name().to_string(),
        threads: opts.threads,
        seed: opts.seed,
        budget: opts.budget,
        references: references
            .images
            .iter()
            .map(|r| ReferenceUsed {
                integrand: r.integrand.name().to_string(),
                spp: r.spp,
                noise_floor: r.noise_floor,
            })
            .collect(),
        qmc,
        report_html,
    })
}
