//! The bounds of the harness's options, each with its message, in one place. The command line
//! checks them as it parses (`cli`'s value parsers call the `*_value` functions, or clap's own
//! ranges); the library entry points (`compare::run`, `reference::render_progressive`,
//! `shard::render`) call the `check_*` functions, so a caller that bypasses the command line
//! gets the same bound as an error naming the flag, not a second copy of the logic.

use crate::error::{Error, Result};
use std::time::Duration;

/// Longest accepted time budget: about 31 years, far below what `Duration` holds.
pub const MAX_SECONDS: f64 = 1e9;
/// Shortest accepted time budget: below a millisecond the clock's resolution is the budget.
pub const MIN_SECONDS: f64 = 1e-3;

/// A time budget in seconds, from [`MIN_SECONDS`] to [`MAX_SECONDS`] (NaN is refused).
pub fn seconds_value(t: f64) -> std::result::Result<f64, String> {
    if (MIN_SECONDS..=MAX_SECONDS).contains(&t) {
        Ok(t)
    } else {
        Err(format!(
            "expected a number of seconds from {MIN_SECONDS} to {MAX_SECONDS:e}"
        ))
    }
}

/// [`seconds_value`] for the value `t` of `flag`, as the budget it gives.
pub fn check_seconds(flag: &str, t: f64) -> Result<Duration> {
    seconds_value(t)
        .map(Duration::from_secs_f64)
        .map_err(|e| Error::Usage(format!("{flag} {t}: {e}")))
}

/// A count that must be at least 1 (`--spp`, `--runs`; the command line's parsers refuse 0
/// with clap's range check).
pub fn check_at_least_one(flag: &str, n: u64) -> Result<()> {
    if n == 0 {
        return Err(Error::Usage(format!("{flag} must be at least 1")));
    }
    Ok(())
}

/// What every strategy of a comparison gets: the same wall-clock time (`--time`, the
/// default), or the same number of samples per pixel (`--spp`: what a stratified generator
/// needs, and the axis on which QMC convergence rates are defined).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// Seconds of render time per strategy run.
    Time(f64),
    /// Passes (samples per pixel) per strategy run.
    Spp(u64),
}

impl Budget {
    /// The bound of the flag that set it (`--time` or `--spp`).
    pub fn check(&self) -> Result<()> {
        match *self {
            Budget::Time(t) => check_seconds("--time", t).map(|_| ()),
            Budget::Spp(n) => check_at_least_one("--spp", n),
        }
    }

    /// The fixed sample count, if this is one.
    pub fn spp(&self) -> Option<u64> {
        match *self {
            Budget::Spp(n) => Some(n),
            Budget::Time(_) => None,
        }
    }

    /// The time budget, if this is one.
    pub fn seconds(&self) -> Option<f64> {
        match *self {
            Budget::Time(t) => Some(t),
            Budget::Spp(_) => None,
        }
    }

    /// The samples per pixel a strategy costing `seconds_per_pass` gets: T / t at equal time,
    /// N at equal spp. The variance of its mean is then σ² / that (independent samples).
    pub fn passes(&self, seconds_per_pass: f64) -> f64 {
        match *self {
            Budget::Time(t) => t / seconds_per_pass,
            Budget::Spp(n) => n as f64,
        }
    }
}

impl std::fmt::Display for Budget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Budget::Time(t) => write!(f, "{t} s"),
            Budget::Spp(n) => write!(f, "{n} spp"),
        }
    }
}

/// The seeds `seed`, `seed + 1`, … of `runs` runs must all be below 2^64.
pub fn check_seeds(seed: u64, runs: u32) -> Result<()> {
    if seed.checked_add((runs as u64).saturating_sub(1)).is_none() {
        return Err(Error::Usage(format!(
            "--seed {seed} with --runs {runs}: the seeds {seed}…{seed}+{} pass 2^64 − 1",
            runs - 1
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Equal time gives T / t passes; equal spp gives N whatever the cost.
    #[test]
    fn passes_per_budget() {
        assert_eq!(Budget::Time(2.0).passes(0.01), 200.0);
        assert_eq!(Budget::Spp(64).passes(0.01), 64.0);
        assert_eq!(Budget::Spp(64).passes(1.0), 64.0);
    }

    #[test]
    fn bounds() {
        assert!(seconds_value(MIN_SECONDS).is_ok() && seconds_value(MAX_SECONDS).is_ok());
        for t in [0.0, -1.0, 0.0009, 1e10, f64::NAN, f64::INFINITY] {
            assert!(seconds_value(t).is_err(), "{t}");
        }
        let e = check_seconds("--time", 0.0).unwrap_err().to_string();
        assert!(
            e.starts_with("--time 0: expected a number of seconds"),
            "{e}"
        );
        assert!(check_at_least_one("--spp", 0).is_err() && check_at_least_one("--spp", 1).is_ok());
        assert!(check_seeds(u64::MAX, 1).is_ok() && check_seeds(u64::MAX - 1, 2).is_ok());
        let e = check_seeds(u64::MAX, 2).unwrap_err().to_string();
        assert!(e.contains("--seed") && e.contains("--runs 2"), "{e}");
        let e = Budget::Spp(0).check().unwrap_err().to_string();
        assert!(e.contains("--spp"), "{e}");
        let e = Budget::Time(0.0).check().unwrap_err().to_string();
        assert!(e.contains("--time"), "{e}");
        assert!(Budget::Spp(1).check().is_ok() && Budget::Time(1.0).check().is_ok());
    }
}
