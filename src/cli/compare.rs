//! `dibench compare`: every applicable strategy at equal time.

use super::{Common, check_image_memory, image_memory, load_with, parse_seconds, pool};
use crate::error::{Error, Result};
use crate::harness::{compare, options, reference};
use crate::strategy::{self, Strategy};
use clap::Args;

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

pub fn run(a: CompareArgs, strategies: Vec<Box<dyn Strategy>>) -> Result<()> {
    // --time and --runs are bounded by their parsers; their seeds together, here, before
    // anything is loaded.
    options::check_seeds(a.common.seed, a.runs)?;
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
    let run_dir = compare::create_run_dir(&a.common.out, &scene.scene.name, a.common.seed)?;
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
            isa: isa.to_string(),
        };
        let report = compare::run(&scene, &run, skipped, &references, &run_dir, &opts)?;
        print!("{report}");
        for w in crate::harness::summary::noise_floor_warnings(&report.summary) {
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
