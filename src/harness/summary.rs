//! `summary.csv`: per strategy, the final error over repeated equal-time runs as a mean with a
//! 95 % confidence interval, the efficiency, and whether it differs significantly from the
//! best strategy (Celarek et al. 2019, "Quantifying the Error of Light Transport Algorithms").

use super::compare::ResultRow;
use crate::stats::{mean_ci, welch_t_test};
use serde::{Deserialize, Serialize};

/// Confidence level of the intervals and the significance level α = 1 − level of the tests.
pub const LEVEL: f64 = 0.95;

/// The final row of one run of one strategy, with what predicts its error.
#[derive(Clone, Debug)]
pub struct FinalRun {
    pub row: ResultRow,
    /// σ² of the 1-spp estimator, mean over pixels and channels.
    pub mean_sample_variance: f64,
    pub reference_noise_floor: Option<f64>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SummaryRow {
    pub scene: String,
    pub integrand: String,
    pub strategy: String,
    pub runs: usize,
    pub budget_s: f64,
    pub time_s_mean: f64,
    /// max over runs of time_s / budget − 1 (negative: stopped before the budget).
    pub overshoot_max: f64,
    pub spp_mean: f64,
    pub rmse_mean: f64,
    /// Half-width of the 95 % Student-t interval of the mean over runs (empty below 2 runs).
    pub rmse_ci95: Option<f64>,
    pub relmse_mean: f64,
    pub relmse_ci95: Option<f64>,
    /// Veach's efficiency 1 / (relMSE · t), with the mean relMSE and mean time.
    pub efficiency: f64,
    /// √(σ² · (t/spp) / T + floor²): the RMSE expected from the per-sample variance σ², the
    /// measured cost per sample t/spp and the budget T, plus the reference's noise floor.
    pub predicted_rmse: f64,
    pub reference_noise_floor: Option<f64>,
    /// Two-sided p-value of Welch's t-test of this strategy's per-run relMSE against the
    /// best strategy's (same integrand); empty for the best one and below 2 runs.
    pub welch_p_vs_best: Option<f64>,
    /// `best`, `worse` (p < 0.05), `tie` (not significantly different) or `n/a` (one run).
    pub vs_best: String,
}

/// One summary row per (integrand, strategy), in order of first appearance.
pub fn summarize(finals: &[FinalRun], budget_s: f64) -> Vec<SummaryRow> {
    let mut keys: Vec<(&str, &str)> = Vec::new();
    for f in finals {
        let k = (f.row.integrand.as_str(), f.row.strategy.as_str());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let group = |k: &(&str, &str)| -> Vec<&FinalRun> {
        finals
            .iter()
            .filter(|f| (f.row.integrand.as_str(), f.row.strategy.as_str()) == *k)
            .collect()
    };
    let mut rows: Vec<SummaryRow> = keys
        .iter()
        .map(|k| {
            let g = group(k);
            let pick = |f: fn(&FinalRun) -> f64| g.iter().map(|r| f(r)).collect::<Vec<f64>>();
            let time = mean_ci(&pick(|f| f.row.time_s), LEVEL);
            let rmse = mean_ci(&pick(|f| f.row.rmse), LEVEL);
            let relmse = mean_ci(&pick(|f| f.row.relmse), LEVEL);
            let floor = g[0].reference_noise_floor;
            let predicted: Vec<f64> = g
                .iter()
                .map(|f| {
                    let cost = f.row.time_s / f.row.spp as f64;
                    let floor2 = f.reference_noise_floor.map_or(0.0, |x| x * x);
                    (f.mean_sample_variance * cost / budget_s + floor2).sqrt()
                })
                .collect();
            SummaryRow {
                scene: g[0].row.scene.clone(),
                integrand: k.0.to_string(),
                strategy: k.1.to_string(),
                runs: g.len(),
                budget_s,
                time_s_mean: time.mean,
                overshoot_max: g
                    .iter()
                    .map(|f| f.row.time_s / budget_s - 1.0)
                    .fold(f64::NEG_INFINITY, f64::max),
                spp_mean: mean_ci(&pick(|f| f.row.spp as f64), LEVEL).mean,
                rmse_mean: rmse.mean,
                rmse_ci95: rmse.half_width,
                relmse_mean: relmse.mean,
                relmse_ci95: relmse.half_width,
                efficiency: 1.0 / (relmse.mean * time.mean),
                predicted_rmse: predicted.iter().sum::<f64>() / predicted.len() as f64,
                reference_noise_floor: floor,
                welch_p_vs_best: None,
                vs_best: String::new(),
            }
        })
        .collect();
    // Best = lowest mean relMSE per integrand; the others are tested against it.
    for integrand in keys.iter().map(|k| k.0).collect::<Vec<_>>() {
        let Some(best) = rows
            .iter()
            .filter(|r| r.integrand == integrand)
            .min_by(|a, b| a.relmse_mean.total_cmp(&b.relmse_mean))
            .map(|r| r.strategy.clone())
        else {
            continue;
        };
        let best_relmse: Vec<f64> = group(&(integrand, best.as_str()))
            .iter()
            .map(|f| f.row.relmse)
            .collect();
        for r in rows.iter_mut().filter(|r| r.integrand == integrand) {
            if r.strategy == best {
                r.vs_best = "best".into();
                continue;
            }
            let mine: Vec<f64> = group(&(integrand, r.strategy.as_str()))
                .iter()
                .map(|f| f.row.relmse)
                .collect();
            match welch_t_test(&mine, &best_relmse) {
                Some(w) => {
                    r.welch_p_vs_best = Some(w.p_value);
                    r.vs_best = if w.p_value < 1.0 - LEVEL {
                        "worse"
                    } else {
                        "tie"
                    }
                    .into();
                }
                None => r.vs_best = "n/a".into(),
            }
        }
    }
    rows
}

/// Warnings for integrands whose reference noise floor exceeds 10 % of the smallest RMSE
/// compared: then the reference, not the strategies, limits what the ranking can resolve.
pub fn noise_floor_warnings(rows: &[SummaryRow]) -> Vec<String> {
    let mut out = Vec::new();
    let mut seen: Vec<&str> = Vec::new();
    for r in rows {
        if seen.contains(&r.integrand.as_str()) {
            continue;
        }
        seen.push(&r.integrand);
        let min_rmse = rows
            .iter()
            .filter(|x| x.integrand == r.integrand)
            .map(|x| x.rmse_mean)
            .fold(f64::INFINITY, f64::min);
        match r.reference_noise_floor {
            Some(floor) if floor > 0.1 * min_rmse => out.push(format!(
                "warning: {} reference noise floor {floor:.3e} is {:.0} % of the smallest RMSE \
                 compared ({min_rmse:.3e}); render a reference with more samples",
                r.integrand,
                100.0 * floor / min_rmse
            )),
            None => out.push(format!(
                "warning: the stored {} reference does not record its noise floor; \
                 re-render it with `dibench reference`",
                r.integrand
            )),
            _ => {}
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fr(strategy: &str, run: u32, relmse: f64) -> FinalRun {
        FinalRun {
            row: ResultRow {
                scene: "s".into(),
                strategy: strategy.into(),
                integrand: "direct".into(),
                backend: "packet".into(),
                threads: 1,
                run,
                seed: run as u64,
                checkpoint: 7,
                time_s: 1.0,
                spp: 100,
                rmse: relmse.sqrt(),
                relmse,
            },
            mean_sample_variance: 0.01,
            reference_noise_floor: Some(0.001),
        }
    }

    #[test]
    fn best_worse_and_tie() {
        let mut finals = Vec::new();
        for (k, e) in [0.0, 1.0, -1.0, 0.5, -0.5].iter().enumerate() {
            let k = k as u32;
            finals.push(fr("a", k, 1.0 + 0.01 * e));
            finals.push(fr("b", k, 2.0 + 0.01 * e)); // clearly worse
            finals.push(fr("c", k, 1.001 - 0.02 * e)); // within the noise
        }
        let rows = summarize(&finals, 1.0);
        let get = |s: &str| rows.iter().find(|r| r.strategy == s).unwrap();
        assert_eq!(get("a").vs_best, "best");
        assert_eq!(get("b").vs_best, "worse");
        assert_eq!(get("c").vs_best, "tie");
        assert!(get("b").welch_p_vs_best.unwrap() < 1e-6);
        assert_eq!(get("a").runs, 5);
        assert!((get("a").relmse_mean - 1.0).abs() < 1e-12);
        // predicted √(σ²·c/T + floor²) with σ² = 0.01, c = 0.01 s, T = 1 s.
        assert!((get("a").predicted_rmse - (1e-4f64 + 1e-6).sqrt()).abs() < 1e-12);
        assert!((get("a").efficiency - 1.0).abs() < 1e-12);
        assert!(noise_floor_warnings(&rows).is_empty());
    }
}
