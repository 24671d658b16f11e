//! `dibench crosscheck`: every compiled-in backend against obvhs on fixed ray sets.

use super::{check_image_memory, load, parse_threads, pool};
use crate::error::Result;
use crate::harness::crosscheck;
use crate::tracer::backends;
use clap::Args;
use std::path::PathBuf;

/// The thresholds and timing, after `dibench crosscheck --help`.
pub(crate) const HELP: &str = "\
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

pub fn run(a: CrosscheckArgs) -> Result<()> {
    let (pool, _) = pool(a.threads)?;
    let mut scene = load(&a.scene)?;
    crate::output::check_output_dir(&a.out.join(&scene.scene.name), "--out")?;
    // A render per backend and pass beside the ray sets.
    check_image_memory(&scene, 8)?;
    if backends::AVAILABLE.len() < 2 {
        eprintln!("crosscheck: only one backend is compiled in");
    }
    let report = pool.install(|| crosscheck::run(&mut scene, &a.out, a.seed))?;
    print!("{report}");
    crosscheck::into_result(&report)
}
