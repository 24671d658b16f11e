//! `dibench report`: the self-contained HTML page of a compare run.

use crate::error::Result;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// A run directory written by `compare` (holding run.json, summary.csv, results.csv and
    /// the images; the references are read from the scene's reference/ beside it).
    pub run_dir: PathBuf,
}

pub fn run(a: ReportArgs) -> Result<()> {
    println!("{}", crate::report::write_report(&a.run_dir)?.display());
    Ok(())
}
