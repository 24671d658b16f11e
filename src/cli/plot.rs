//! `dibench plot`: the figures of a compare run.

use crate::error::Result;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct PlotArgs {
    /// A run directory written by `compare` (holding results.csv).
    pub run_dir: PathBuf,
}

pub fn run(a: PlotArgs) -> Result<()> {
    for p in crate::plot::plot_run(&a.run_dir)? {
        println!("{}", p.display());
    }
    Ok(())
}
