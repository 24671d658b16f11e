//! A reference good enough for the comparison it serves, chosen before comparing.
//!
//! Every measured RMSE² is, in expectation, the strategy's MSE against the truth plus the
//! reference's floor² (`reference::ReferenceMeta::noise_floor_rmse`). The ranking resolves the
//! strategies only while the floor is small beside their errors, so the reference must be
//! sized by the errors it will be compared with. A short pilot of each strategy measures its
//! per-sample variance σ² (mean over pixels and channels) and its time per pass t; at the
//! budget T it predicts RMSE ≈ √(σ² t / T) (at a fixed N passes, √(σ²/N)), the model `summary::predicted_rmse` checks after
//! the fact. The reference then renders, with the strategy of the smallest σ² t (Veach's
//! efficiency), until its floor √(σ²_ref / N) is at most `fraction` of the smallest predicted
//! RMSE, or until a time cap.

use super::options::Budget;
use crate::error::Result;
use crate::film::Film;
use crate::math::mix64;
use crate::prepare::PreparedScene;
use crate::render::{Renderer, group_size};
use crate::strategy::{Integrand, Strategy};
use std::time::{Duration, Instant};

/// The pilot's floor target is this share of `fraction × smallest predicted RMSE`: a margin
/// for the pilot's own error (its σ² and pass time come from a few passes, and the compared
/// runs may get a little more or less of the machine).
pub const MARGIN: f64 = 0.75;

/// Passes of a pilot at least (the first one, which pays for page faults and cold caches, is
/// not timed), so σ² is an average of several samples per pixel.
pub const MIN_PASSES: u64 = 6;

/// What a pilot measured of one strategy.
#[derive(Clone, Debug)]
pub struct Pilot {
    pub strategy: String,
    pub integrand: Integrand,
    /// σ² of the 1-spp estimator, mean over pixels and channels.
    pub sample_variance: f64,
    /// Wall-clock seconds per pass (every pixel one sample), after the first.
    pub seconds_per_pass: f64,
}

impl Pilot {
    /// The RMSE predicted for `budget`: √(σ² / passes), with T / t passes at equal time.
    pub fn predicted_rmse(&self, budget: Budget) -> f64 {
        (self.sample_variance / budget.passes(self.seconds_per_pass)).sqrt()
    }

    /// σ² t: the work to reach a given MSE (smaller is better: Veach's efficiency inverted).
    pub fn cost(&self) -> f64 {
        self.sample_variance * self.seconds_per_pass
    }
}

/// Runs `strategy` for at least `MIN_PASSES` passes and at least `time` (with random streams
/// of their own, independent of the compared runs and the reference).
pub fn pilot(
    scene: &PreparedScene,
    strategy: &dyn Strategy,
    seed: u64,
    time: Duration,
) -> Result<Pilot> {
    let mut renderer = Renderer::new(scene, strategy, mix64(seed) ^ 0x5049_4c4f_5450_4153)?;
    let mut film = Film::new(scene.scene.width, scene.scene.height);
    renderer.add_pass(&mut film);
    let start = Instant::now();
    // In groups, as compare renders (Renderer::add_passes), so the time per pass is what a
    // compared run pays.
    while film.spp < MIN_PASSES || start.elapsed() < time {
        if crate::interrupt::requested() {
            break;
        }
        let elapsed = start.elapsed().as_secs_f64();
        let timed = film.spp - 1;
        let per_pass = (timed > 0).then(|| elapsed / timed as f64);
        let left = match per_pass {
            _ if film.spp < MIN_PASSES => MIN_PASSES - film.spp,
            Some(p) => ((time.as_secs_f64() - elapsed) / p).ceil().max(1.0) as u64,
            None => 1,
        };
        renderer.add_passes(&mut film, group_size(left, per_pass));
    }
    let timed = (film.spp - 1).max(1) as f64;
    Ok(Pilot {
        strategy: strategy.name(),
        integrand: strategy.integrand(),
        sample_variance: film.mean_sample_variance(),
        seconds_per_pass: start.elapsed().as_secs_f64() / timed,
    })
}

/// The plan for one integrand's reference.
#[derive(Clone, Debug)]
pub struct Plan {
    pub integrand: Integrand,
    /// The strategy that renders it: the smallest σ² t among the pilots.
    pub strategy: String,
    /// The smallest predicted RMSE at the budget, and which strategy predicted it.
    pub smallest_rmse: f64,
    pub smallest_by: String,
    /// The floor to reach: `fraction · MARGIN · smallest_rmse`.
    pub target_floor: f64,
    /// The floor a stored reference may have to be reused: `fraction · smallest_rmse` (the
    /// margin is for rendering; without this slack every pilot's noise would re-render it).
    pub accept_floor: f64,
    /// Passes the target needs by the pilot's σ², and their predicted time.
    pub predicted_spp: u64,
    pub predicted_s: f64,
}

/// One plan per integrand among `pilots`, for `budget` per strategy.
pub fn plan(pilots: &[Pilot], budget: Budget, fraction: f64) -> Vec<Plan> {
    let mut integrands: Vec<Integrand> = Vec::new();
    for p in pilots {
        if !integrands.contains(&p.integrand) {
            integrands.push(p.integrand);
        }
    }
    integrands
        .into_iter()
        .filter_map(|integrand| {
            let mine: Vec<&Pilot> = pilots.iter().filter(|p| p.integrand == integrand).collect();
            let smallest = mine.iter().min_by(|a, b| {
                a.predicted_rmse(budget)
                    .total_cmp(&b.predicted_rmse(budget))
            })?;
            let best = mine.iter().min_by(|a, b| a.cost().total_cmp(&b.cost()))?;
            let smallest_rmse = smallest.predicted_rmse(budget);
            let target_floor = fraction * MARGIN * smallest_rmse;
            // σ²/N ≤ target² ⇔ N ≥ σ²/target²; a noise-free integrand needs one pass.
            let spp = if target_floor > 0.0 {
                (best.sample_variance / (target_floor * target_floor)).ceil()
            } else {
                1.0
            };
            let predicted_spp = if spp.is_finite() && spp < u64::MAX as f64 {
                (spp as u64).max(MIN_PASSES)
            } else {
                u64::MAX
            };
            Some(Plan {
                integrand,
                strategy: best.strategy.clone(),
                smallest_rmse,
                smallest_by: smallest.strategy.clone(),
                target_floor,
                accept_floor: fraction * smallest_rmse,
                predicted_spp,
                predicted_s: predicted_spp as f64 * best.seconds_per_pass,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(name: &str, var: f64, t: f64) -> Pilot {
        Pilot {
            strategy: name.into(),
            integrand: Integrand::DIRECT,
            sample_variance: var,
            seconds_per_pass: t,
        }
    }

    /// The reference strategy is the most efficient (smallest σ² t), not the one of smallest
    /// variance per sample; the target follows the smallest predicted RMSE; the spp meets it.
    #[test]
    fn plan_picks_the_most_efficient_strategy_and_meets_the_target() {
        // `cheap`: σ² 4, 1 ms per pass (cost 4e-3); `good`: σ² 1, 10 ms (cost 1e-2).
        let pilots = [p("good", 1.0, 0.01), p("cheap", 4.0, 0.001)];
        let plans = plan(&pilots, Budget::Time(2.0), 0.1);
        assert_eq!(plans.len(), 1);
        let pl = &plans[0];
        assert_eq!(pl.strategy, "cheap");
        assert_eq!(pl.smallest_by, "cheap");
        let smallest = (4.0f64 * 0.001 / 2.0).sqrt();
        assert!((pl.smallest_rmse - smallest).abs() < 1e-15);
        assert!((pl.target_floor - 0.1 * MARGIN * smallest).abs() < 1e-15);
        assert!((pl.accept_floor - 0.1 * smallest).abs() < 1e-15);
        let floor = (4.0 / pl.predicted_spp as f64).sqrt();
        assert!(floor <= pl.target_floor, "{floor} > {}", pl.target_floor);
        // One pass fewer would miss it: the plan is not wasteful.
        assert!((4.0 / (pl.predicted_spp - 1) as f64).sqrt() > pl.target_floor);
        assert!((pl.predicted_s - pl.predicted_spp as f64 * 0.001).abs() < 1e-12);
    }

    /// At equal spp the smallest predicted RMSE is the smallest σ² (time per pass no longer
    /// buys samples), while the reference is still rendered by the most efficient strategy.
    #[test]
    fn at_equal_spp_the_target_follows_the_smallest_variance() {
        let pilots = [p("good", 1.0, 0.01), p("cheap", 4.0, 0.001)];
        let pl = &plan(&pilots, Budget::Spp(100), 0.1)[0];
        assert_eq!(
            (pl.strategy.as_str(), pl.smallest_by.as_str()),
            ("cheap", "good")
        );
        assert!((pl.smallest_rmse - (1.0f64 / 100.0).sqrt()).abs() < 1e-15);
        let floor = (4.0 / pl.predicted_spp as f64).sqrt();
        assert!(
            floor <= pl.target_floor
                && (4.0 / (pl.predicted_spp - 1) as f64).sqrt() > pl.target_floor
        );
    }

    #[test]
    fn a_noise_free_integrand_needs_few_passes() {
        let plans = plan(&[p("a", 0.0, 0.01)], Budget::Time(1.0), 0.1);
        assert_eq!(plans[0].predicted_spp, MIN_PASSES);
    }
}
