//! `dibench stress`: every applicable strategy on every stiff case.

use super::{parse_threads, pool};
use crate::error::{Error, Result};
use crate::stress::{self, Status};
use clap::Args;
use std::path::PathBuf;

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

pub fn run(a: StressArgs) -> Result<()> {
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
    let report = stress::Report {
        cases: cases.iter().map(|c| c.name.clone()).collect(),
        samples: a.samples,
        seed: a.seed,
        threads,
        rows,
        csv: path,
    };
    print!("{report}");
    let failed = report.count(Status::Fail);
    if failed > 0 {
        return Err(Error::Check(format!(
            "stress: {failed} checks failed (see above)"
        )));
    }
    Ok(())
}
