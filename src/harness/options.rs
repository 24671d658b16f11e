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
    }
}
