//! `dibench compare`: every applicable strategy at equal time (or, with `--spp`, at equal
//! sample count).

use super::{Common, check_image_memory, image_memory, load_with, parse_seconds, pool};
use crate::error::{Error, Result};
use crate::harness::{compare, options, pilot, reference};
use crate::strategy::{self, Strategy};
use clap::Args;
use std::time::Duration;

#[derive(Args, Debug)]
pub struct CompareArgs {
    #[command(flatten)]
    pub common: Common,
    /// Wall-clock budget per strategy, in seconds.
    #[arg(long, default_value_t = 2.0, value_parser = parse_seconds, allow_hyphen_values = true)]
    pub time: f64,
    /// Samples per pixel per strategy instead of a time budget: every strategy renders exactly
    /// this many passes (what `--sampler stratified` needs; a power of two keeps a Sobol
    /// prefix a (0,2)-net).
    #[arg(long, conflicts_with = "time", value_parser = clap::value_parser!(u64).range(1..), allow_negative_numbers = true)]
    pub spp: Option<u64>,
    /// Samples per pixel of the reference, fixed; by default a pilot of every strategy sizes
    /// the reference by its noise floor instead (`--reference-floor`).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..), allow_negative_numbers = true)]
    pub reference_spp: Option<u64>,
    /// The reference's noise floor as a share of the smallest RMSE the pilot predicts for the
    /// compared strategies; also the share above which the result warns.
    #[arg(long, default_value_t = 0.1, value_parser = parse_fraction, allow_hyphen_values = true)]
    pub reference_floor: f64,
    /// Longest a reference renders to reach its floor, in seconds; past it the reference
    /// stops and says what floor it reached.
    #[arg(long, default_value_t = 1800.0, value_parser = parse_seconds, allow_hyphen_values = true)]
    pub reference_cap: f64,
    /// Comma-separated subset of strategies to run (default: every applicable one).
    #[arg(long, value_delimiter = ',')]
    pub strategies: Option<Vec<String>>,
    /// Independent runs per strategy (seeds seed, seed+1, ...); summary.csv gives 95 %
    /// confidence intervals over them.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..), allow_negative_numbers = true)]
    pub runs: u32,
    /// Comma-separated sample generators; every strategy runs with each
    /// (independent, stratified, sobol, zsobol; stratified needs the sample count up front,
    /// so it needs `--spp`). References stay independent.
    #[arg(long, value_delimiter = ',', default_value = "independent")]
    pub sampler: Vec<String>,
    /// Run the pilots only and print each reference's plan (its strategy, target floor,
    /// predicted samples and time, and whether `--reference-cap` would end it first); render
    /// nothing and write nothing.
    #[arg(long, conflicts_with = "reference_spp")]
    pub plan: bool,
}

impl CompareArgs {
    /// `--spp N` if given, else `--time`.
    pub fn budget(&self) -> compare::Budget {
        match self.spp {
            Some(n) => compare::Budget::Spp(n),
            None => compare::Budget::Time(self.time),
        }
    }
}

pub fn run(a: CompareArgs, strategies: Vec<Box<dyn Strategy>>) -> Result<()> {
    // --time and --runs are bounded by their parsers; their seeds together, here, before
    // anything is loaded.
    options::check_seeds(a.common.seed, a.runs)?;
    let samplers = compare::resolve_samplers(&a.sampler, a.budget())?.len() as u64;
    let (pool, threads) = pool(a.common.threads)?;
    let (scene, isa) = load_with(&a.common)?;
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
    // then per (strategy, sampler, run) its rows and summary input, about 3 kB.
    let integrands = strategy::integrands(&scene).len() as u64;
    // … and HDR-FLIP's working images at the end of each run.
    let images = integrands + 3 + crate::flip::WORKING_IMAGES;
    check_image_memory(&scene, images)?;
    crate::bounded::check_memory(
        || {
            format!(
                "--runs {} (strategies: {}, samplers: {samplers})",
                a.runs,
                run.len()
            )
        },
        image_memory(&scene, images).saturating_add(crate::bounded::bytes(
            (a.runs as u64 * run.len() as u64).saturating_mul(samplers),
            3000,
        )),
    )?;
    if a.plan {
        let plans = pool.install(|| pilot_plans(&scene, &run, &a))?;
        print_plans(&scene.scene.name, &plans, &a);
        return Ok(());
    }
    // The output location is checked, and the run's directory taken, before any rendering.
    crate::output::check_output_dir(&a.common.out, "--out")?;
    let run_dir = compare::create_run_dir(&a.common.out, &scene.scene.name, a.common.seed)?;
    let store = reference::store(&a.common.out, &scene.scene.name)?;
    if !skipped.is_empty() {
        // One line; the reasons are in run.json and `dibench strategies SCENE`.
        let names: Vec<&str> = skipped.iter().map(|k| k.name.as_str()).collect();
        eprintln!(
            "skipping {} strategies that do not apply to this scene ({}); why: `dibench strategies {}`",
            names.len(),
            abbreviate(&names, 4),
            scene.scene.name
        );
    }
    let result = pool.install(|| -> Result<()> {
        // Without a fixed --reference-spp, pilots size each reference (`harness::pilot`).
        let plans = match a.reference_spp {
            Some(_) => Vec::new(),
            None => pilot_plans(&scene, &run, &a)?,
        };
        let mut images = Vec::new();
        for integrand in strategy::integrands(&scene) {
            if !run.iter().any(|s| s.integrand() == integrand) {
                continue;
            }
            let need = match a.reference_spp {
                Some(spp) => compare::Need::Spp(spp),
                None => {
                    let plan = plans.iter().find(|p| p.integrand == integrand);
                    let strategy = plan
                        .and_then(|p| run.iter().find(|s| s.name() == p.strategy))
                        .map(|s| s.as_ref());
                    let (Some(plan), Some(strategy)) = (plan, strategy) else {
                        return Err(Error::Usage(format!(
                            "no pilot sized the {} reference",
                            integrand.name()
                        )));
                    };
                    compare::Need::Floor {
                        plan,
                        strategy,
                        cap_s: a.reference_cap,
                    }
                }
            };
            images.push(compare::Reference::load_or_render(
                &store,
                &scene,
                integrand,
                need,
                a.common.seed,
                threads,
            )?);
        }
        let references = compare::References { images };
        let opts = compare::CompareOptions {
            budget: a.budget(),
            seed: a.common.seed,
            threads,
            runs: a.runs,
            isa: isa.to_string(),
            samplers: a.sampler.clone(),
        };
        let report = compare::run(&scene, &run, skipped, &references, &run_dir, &opts)?;
        // The warnings, then the report, whose ranked table comes last.
        for w in crate::harness::summary::noise_floor_warnings(&report.summary, a.reference_floor) {
            eprintln!("{w}");
        }
        print!("{report}");
        Ok(())
    });
    if let Err(e) = &result {
        run_dir.abandon(e);
    }
    result
}

/// A pilot of every strategy in `run`, 5 % of the budget each (0.25 s to 2 s), and the
/// reference plan they give each integrand (`harness::pilot`).
fn pilot_plans(
    scene: &crate::prepare::PreparedScene,
    run: &[Box<dyn Strategy>],
    a: &CompareArgs,
) -> Result<Vec<pilot::Plan>> {
    let each = Duration::from_secs_f64((0.05 * a.time).clamp(0.25, 2.0));
    eprintln!(
        "pilot: {} strategies, {:.2} s each, to size the reference",
        run.len(),
        each.as_secs_f64()
    );
    let pilots = run
        .iter()
        .map(|s| pilot::pilot(scene, s.as_ref(), a.common.seed, each))
        .collect::<Result<Vec<_>>>()?;
    if crate::interrupt::requested() {
        return Err(Error::Interrupted(
            "compare stopped during the pilot".into(),
        ));
    }
    Ok(pilot::plan(&pilots, a.budget(), a.reference_floor))
}

/// `compare --plan`: one line per integrand. The floor falls as 1/√N and N grows with time,
/// so a reference the cap stops reaches the target floor × √(predicted time / cap).
fn print_plans(scene: &str, plans: &[pilot::Plan], a: &CompareArgs) {
    println!(
        "scene,integrand,reference_strategy,smallest_predicted_rmse,smallest_by,target_floor,\
         target_share,predicted_spp,predicted_s,outcome"
    );
    for p in plans {
        let outcome = if p.predicted_s <= a.reference_cap {
            "reaches the floor".to_string()
        } else {
            let floor = p.target_floor * (p.predicted_s / a.reference_cap).sqrt();
            format!(
                "the cap ({:.0} s) ends it at a floor of about {floor:.2e} ({:.0} % of the \
                 smallest RMSE)",
                a.reference_cap,
                100.0 * floor / p.smallest_rmse
            )
        };
        println!(
            "{scene},{},{},{:.3e},{},{:.3e},{:.3},{},{:.1},{outcome}",
            p.integrand.name(),
            p.strategy,
            p.smallest_rmse,
            p.smallest_by,
            p.target_floor,
            p.target_floor / p.smallest_rmse,
            p.predicted_spp,
            p.predicted_s,
        );
    }
}

fn parse_fraction(s: &str) -> std::result::Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(a) if a > 0.0 && a <= 1.0 => Ok(a),
        _ => Err("expected a share greater than 0 and at most 1".into()),
    }
}

/// The first `n` of `names`, then how many more.
fn abbreviate(names: &[&str], n: usize) -> String {
    match names.len() {
        k if k <= n => names.join(", "),
        k => format!("{}, … {} more", names[..n].join(", "), k - n),
    }
}
