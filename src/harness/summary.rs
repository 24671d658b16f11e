//! `summary.csv`: per strategy, the final error over repeated equal-time runs as a mean with a
//! 95 % confidence interval, the efficiency, and whether it differs significantly from the
//! best strategy (Celarek et al. 2019, "Quantifying the Error of Light Transport Algorithms").

use super::compare::ResultRow;
use super::options::Budget;
use crate::stats::{fit_line, holm_adjust, mean_ci, welch_t_test};
use serde::{Deserialize, Serialize};

/// Confidence level of the intervals and the significance level α = 1 − level of the tests.
pub const LEVEL: f64 = 0.95;

/// The final row of one run of one strategy, with what predicts its error.
#[derive(Clone, Debug)]
pub struct FinalRun {
    pub row: ResultRow,
    /// σ² of the 1-spp estimator, mean over pixels and channels; None for a generator whose
    /// samples are not independent (no prediction is made for it).
    pub mean_sample_variance: Option<f64>,
    pub reference_noise_floor: Option<f64>,
    /// What the reference's noise adds to relMSE in expectation (`metrics::relmse_floor`).
    pub reference_relmse_floor: f64,
    /// Slopes of log RMSE against log time and against log spp over this run's checkpoints.
    pub slope_time: Option<f64>,
    pub slope_spp: Option<f64>,
}

impl FinalRun {
    /// The run's final row with the slopes of its checkpoint rows `rows`.
    pub fn new(
        rows: &[ResultRow],
        mean_sample_variance: Option<f64>,
        reference_noise_floor: Option<f64>,
        reference_relmse_floor: f64,
    ) -> Option<FinalRun> {
        let row = rows.last()?.clone();
        let (slope_time, slope_spp) = convergence_slopes(rows);
        Some(FinalRun {
            row,
            mean_sample_variance,
            reference_noise_floor,
            reference_relmse_floor,
            slope_time,
            slope_spp,
        })
    }

    /// MSE against the truth, debiased: measured MSE − floor² (an unbiased estimate, so it may
    /// be negative when the error is below what the reference resolves).
    pub fn mse_debiased(&self) -> f64 {
        let floor2 = self.reference_noise_floor.map_or(0.0, |f| f * f);
        self.row.rmse * self.row.rmse - floor2
    }

    pub fn relmse_debiased(&self) -> f64 {
        self.row.relmse - self.reference_relmse_floor
    }
}

/// Least-squares slopes of ln RMSE against ln time and ln spp over checkpoint rows (at least
/// three with positive values): −½ for an unbiased estimator with independent samples.
pub fn convergence_slopes(rows: &[ResultRow]) -> (Option<f64>, Option<f64>) {
    let ok: Vec<&ResultRow> = rows
        .iter()
        .filter(|r| r.rmse > 0.0 && r.time_s > 0.0 && r.spp > 0)
        .collect();
    if ok.len() < 3 {
        return (None, None);
    }
    let y: Vec<f64> = ok.iter().map(|r| r.rmse.ln()).collect();
    let t: Vec<f64> = ok.iter().map(|r| r.time_s.ln()).collect();
    let n: Vec<f64> = ok.iter().map(|r| (r.spp as f64).ln()).collect();
    (
        fit_line(&t, &y).map(|f| f.slope),
        fit_line(&n, &y).map(|f| f.slope),
    )
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SummaryRow {
    pub scene: String,
    pub integrand: String,
    pub strategy: String,
    pub runs: usize,
    /// The time budget per run (`--time`); empty at equal spp (`budget_spp`).
    pub budget_s: Option<f64>,
    pub time_s_mean: f64,
    /// max over runs of time_s / budget − 1 (negative: stopped before the budget); empty at
    /// equal spp, where every run renders exactly the budget.
    pub overshoot_max: Option<f64>,
    pub spp_mean: f64,
    pub rmse_mean: f64,
    /// Half-width of the 95 % Student-t interval of the mean over runs (empty below 2 runs).
    pub rmse_ci95: Option<f64>,
    /// √ of the debiased MSE (MSE − floor², mean over runs); empty when that mean is not
    /// positive (the error is below what the reference resolves).
    pub rmse_debiased: Option<f64>,
    /// The debiased MSE, mean over runs, and its interval.
    pub mse_debiased_mean: f64,
    pub mse_debiased_ci95: Option<f64>,
    pub relmse_mean: f64,
    pub relmse_ci95: Option<f64>,
    /// relMSE − the reference's relMSE floor (`metrics::relmse_floor`), mean over runs: the
    /// ranking metric.
    pub relmse_debiased_mean: f64,
    pub relmse_debiased_ci95: Option<f64>,
    /// Veach's efficiency 1 / (relMSE · t), with the mean relMSE and mean time (the raw relMSE:
    /// the debiased one may be zero or negative); empty when the relMSE is 0 (an exact image).
    pub efficiency: Option<f64>,
    /// √(σ² · (t/spp) / T + floor²): the RMSE expected from the per-sample variance σ², the
    /// measured cost per sample t/spp and the budget T, plus the reference's noise floor
    /// (at equal spp N: √(σ²/N + floor²)).
    /// Empty for a non-independent sampler: that formula assumes independent samples, and
    /// the across-pass variance of correlated samples is not σ².
    pub predicted_rmse: Option<f64>,
    pub reference_noise_floor: Option<f64>,
    /// Slope of ln RMSE against ln time over each run's checkpoints, mean over runs, with its
    /// interval; and against ln spp. −½ for independent samples.
    pub slope_time_mean: Option<f64>,
    pub slope_time_ci95: Option<f64>,
    pub slope_spp_mean: Option<f64>,
    /// Two-sided p-value of Welch's t-test of this (strategy, sampler)'s per-run debiased
    /// relMSE against the best one's (same integrand); empty for the best one and below 2 runs.
    pub welch_p_vs_best: Option<f64>,
    /// That p-value adjusted by Holm–Bonferroni over the family of every pairwise comparison
    /// among the (strategy, sampler) pairs of this integrand (so the choice of the best is
    /// covered too).
    pub holm_p_vs_best: Option<f64>,
    /// `best`; `worse` (Holm-adjusted p < 0.05) or `tie`; `one run: no test` below 2 runs.
    pub vs_best: String,
    /// The sample generator; (strategy, sampler) is a run's identity. Appended last so the
    /// earlier columns keep their positions.
    pub sampler: String,
    /// The sample budget per run (`--spp`); empty at equal time (`budget_s`).
    pub budget_spp: Option<u64>,
    /// Mean HDR-FLIP of the final image against the reference (`crate::flip`), mean over runs,
    /// with its 95 % interval; empty for runs recorded without it.
    pub flip_mean: Option<f64>,
    pub flip_ci95: Option<f64>,
}

/// A summary key: (integrand, strategy, sampler).
type Key<'a> = (&'a str, &'a str, &'a str);

fn key_of(f: &FinalRun) -> Key<'_> {
    (
        f.row.integrand.as_str(),
        f.row.strategy.as_str(),
        f.row.sampler.as_str(),
    )
}

/// One summary row per (integrand, strategy, sampler), sorted per integrand by the ranking
/// metric (the debiased relMSE), integrands in order of first appearance.
pub fn summarize(finals: &[FinalRun], budget: Budget) -> Vec<SummaryRow> {
    let mut keys: Vec<Key> = Vec::new();
    for f in finals {
        let k = key_of(f);
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let group = |k: &Key| -> Vec<&FinalRun> { finals.iter().filter(|f| key_of(f) == *k).collect() };
    let debiased = |k: &Key| -> Vec<f64> { group(k).iter().map(|f| f.relmse_debiased()).collect() };
    let mut rows: Vec<SummaryRow> = keys
        .iter()
        .map(|k| {
            let g = group(k);
            let pick = |f: &dyn Fn(&FinalRun) -> f64| g.iter().map(|r| f(r)).collect::<Vec<f64>>();
            let time = mean_ci(&pick(&|f| f.row.time_s), LEVEL);
            let rmse = mean_ci(&pick(&|f| f.row.rmse), LEVEL);
            let mse_d = mean_ci(&pick(&|f| f.mse_debiased()), LEVEL);
            let relmse = mean_ci(&pick(&|f| f.row.relmse), LEVEL);
            let relmse_d = mean_ci(&pick(&|f| f.relmse_debiased()), LEVEL);
            let slopes_t: Vec<f64> = g.iter().filter_map(|f| f.slope_time).collect();
            let slopes_n: Vec<f64> = g.iter().filter_map(|f| f.slope_spp).collect();
            let slope_t = (!slopes_t.is_empty()).then(|| mean_ci(&slopes_t, LEVEL));
            let flips: Option<Vec<f64>> = g.iter().map(|f| f.row.flip).collect();
            let flip = flips.map(|v| mean_ci(&v, LEVEL));
            let floor = g[0].reference_noise_floor;
            // Only when every run has an independent-sample variance.
            let predicted: Option<Vec<f64>> = g
                .iter()
                .map(|f| {
                    let cost = f.row.time_s / f.row.spp as f64;
                    let floor2 = f.reference_noise_floor.map_or(0.0, |x| x * x);
                    f.mean_sample_variance
                        .map(|v| (v / budget.passes(cost) + floor2).sqrt())
                })
                .collect();
            SummaryRow {
                scene: g[0].row.scene.clone(),
                integrand: k.0.to_string(),
                strategy: k.1.to_string(),
                sampler: k.2.to_string(),
                runs: g.len(),
                budget_s: budget.seconds(),
                budget_spp: budget.spp(),
                flip_mean: flip.as_ref().map(|m| m.mean),
                flip_ci95: flip.and_then(|m| m.half_width),
                time_s_mean: time.mean,
                overshoot_max: budget
                    .seconds()
                    .and_then(|t| g.iter().map(|f| f.row.time_s / t - 1.0).reduce(f64::max)),
                spp_mean: mean_ci(&pick(&|f| f.row.spp as f64), LEVEL).mean,
                rmse_mean: rmse.mean,
                rmse_ci95: rmse.half_width,
                rmse_debiased: (mse_d.mean > 0.0).then(|| mse_d.mean.sqrt()),
                mse_debiased_mean: mse_d.mean,
                mse_debiased_ci95: mse_d.half_width,
                relmse_mean: relmse.mean,
                relmse_ci95: relmse.half_width,
                relmse_debiased_mean: relmse_d.mean,
                relmse_debiased_ci95: relmse_d.half_width,
                efficiency: (relmse.mean > 0.0).then(|| 1.0 / (relmse.mean * time.mean)),
                predicted_rmse: predicted.map(|p| p.iter().sum::<f64>() / p.len() as f64),
                reference_noise_floor: floor,
                slope_time_mean: slope_t.as_ref().map(|m| m.mean),
                slope_time_ci95: slope_t.and_then(|m| m.half_width),
                slope_spp_mean: (!slopes_n.is_empty())
                    .then(|| slopes_n.iter().sum::<f64>() / slopes_n.len() as f64),
                welch_p_vs_best: None,
                holm_p_vs_best: None,
                vs_best: String::new(),
            }
        })
        .collect();
    let mut integrands: Vec<&str> = Vec::new();
    for k in &keys {
        if !integrands.contains(&k.0) {
            integrands.push(k.0);
        }
    }
    for &integrand in &integrands {
        let mine: Vec<Key> = keys.iter().copied().filter(|k| k.0 == integrand).collect();
        // Best = lowest mean debiased relMSE.
        let Some(best) = rows
            .iter()
            .filter(|r| r.integrand == integrand)
            .min_by(|a, b| a.relmse_debiased_mean.total_cmp(&b.relmse_debiased_mean))
            .map(|r| (r.strategy.clone(), r.sampler.clone()))
        else {
            continue;
        };
        // The family: every pair of this integrand's (strategy, sampler) runs (Welch on
        // per-run debiased relMSE), Holm-adjusted together; each row reports its pair with
        // the best.
        let mut pairs = Vec::new();
        let mut raw = Vec::new();
        for i in 0..mine.len() {
            for j in i + 1..mine.len() {
                if let Some(w) = welch_t_test(&debiased(&mine[i]), &debiased(&mine[j])) {
                    pairs.push(((mine[i].1, mine[i].2), (mine[j].1, mine[j].2)));
                    raw.push(w.p_value);
                }
            }
        }
        let adjusted = holm_adjust(&raw);
        for r in rows.iter_mut().filter(|r| r.integrand == integrand) {
            let me = (r.strategy.as_str(), r.sampler.as_str());
            let b = (best.0.as_str(), best.1.as_str());
            if me == b {
                r.vs_best = "best".into();
                continue;
            }
            let pair = pairs
                .iter()
                .position(|&(x, y)| (x == me && y == b) || (y == me && x == b));
            match pair {
                Some(k) => {
                    r.welch_p_vs_best = Some(raw[k]);
                    r.holm_p_vs_best = Some(adjusted[k]);
                    r.vs_best = if adjusted[k] < 1.0 - LEVEL {
                        "worse"
                    } else {
                        "tie"
                    }
                    .into();
                }
                None => r.vs_best = "one run: no test".into(),
            }
        }
    }
    // Sorted by the ranking metric within each integrand (stable: ties keep their order).
    rows.sort_by(|a, b| {
        let ia = integrands.iter().position(|&i| i == a.integrand);
        let ib = integrands.iter().position(|&i| i == b.integrand);
        ia.cmp(&ib)
            .then(a.relmse_debiased_mean.total_cmp(&b.relmse_debiased_mean))
    });
    rows
}

/// The RMSE a row's strategy is expected to reach: its predicted RMSE (from its own
/// per-sample variance, with the floor) where the model holds, else the measured mean. The
/// prediction averages the variance over every pixel and sample of the run, so it is far less
/// noisy than one run's realized RMSE; and the smallest realized RMSE of many strategies is
/// biased low (the minimum of noisy values), so a bar set by it warns at random.
fn expected_rmse(r: &SummaryRow) -> f64 {
    r.predicted_rmse.unwrap_or(r.rmse_mean)
}

/// Warnings for integrands whose reference noise floor exceeds `fraction` of the smallest
/// expected RMSE compared ([`expected_rmse`]): then the reference, not the strategies, limits
/// what the ranking can resolve.
pub fn noise_floor_warnings(rows: &[SummaryRow], fraction: f64) -> Vec<String> {
    let mut out = Vec::new();
    let mut seen: Vec<&str> = Vec::new();
    for r in rows {
        if seen.contains(&r.integrand.as_str()) {
            continue;
        }
        seen.push(&r.integrand);
        let Some(smallest) = rows
            .iter()
            .filter(|x| x.integrand == r.integrand)
            .min_by(|a, b| expected_rmse(a).total_cmp(&expected_rmse(b)))
        else {
            continue;
        };
        let min_rmse = expected_rmse(smallest);
        match r.reference_noise_floor {
            Some(floor) if floor > fraction * min_rmse => out.push(format!(
                "warning: {} reference noise floor {floor:.3e} is {:.0} % of the smallest RMSE \
                 expected ({min_rmse:.3e}, `{}` with `{}`); render a reference with more samples",
                r.integrand,
                100.0 * floor / min_rmse,
                smallest.strategy,
                smallest.sampler
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
                sampler: "independent".into(),
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
                flip: Some(0.1),
            },
            mean_sample_variance: Some(0.01),
            reference_noise_floor: Some(0.001),
            reference_relmse_floor: 0.0,
            slope_time: None,
            slope_spp: None,
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
        let rows = summarize(&finals, Budget::Time(1.0));
        let get = |s: &str| rows.iter().find(|r| r.strategy == s).unwrap();
        assert_eq!(get("a").vs_best, "best");
        assert_eq!(get("b").vs_best, "worse");
        assert_eq!(get("c").vs_best, "tie");
        assert!(get("b").welch_p_vs_best.unwrap() < 1e-6);
        assert_eq!(get("a").runs, 5);
        assert!((get("a").relmse_mean - 1.0).abs() < 1e-12);
        // predicted √(σ²·c/T + floor²) with σ² = 0.01, c = 0.01 s, T = 1 s.
        assert!((get("a").predicted_rmse.unwrap() - (1e-4f64 + 1e-6).sqrt()).abs() < 1e-12);
        assert!((get("a").efficiency.unwrap() - 1.0).abs() < 1e-12);
        assert!(noise_floor_warnings(&rows, 0.1).is_empty());
    }

    /// At equal spp N the prediction is √(σ²/N + floor²) whatever the time per sample, the
    /// budget is N (no seconds, no overshoot); at equal time it uses the cost (the control).
    #[test]
    fn an_spp_budget_predicts_from_the_sample_count() {
        let mut slow = fr("a", 0, 1.0);
        slow.row.time_s = 5.0; // 50 ms per sample: irrelevant at equal spp
        let rows = summarize(&[slow.clone()], Budget::Spp(100));
        let r = &rows[0];
        assert!((r.predicted_rmse.unwrap() - (0.01f64 / 100.0 + 1e-6).sqrt()).abs() < 1e-15);
        assert_eq!(
            (r.budget_s, r.budget_spp, r.overshoot_max),
            (None, Some(100), None)
        );
        let rows = summarize(&[slow], Budget::Time(1.0));
        let r = &rows[0];
        // T / c = 1 s / 50 ms = 20 passes.
        assert!((r.predicted_rmse.unwrap() - (0.01f64 / 20.0 + 1e-6).sqrt()).abs() < 1e-15);
        assert_eq!((r.budget_s, r.budget_spp), (Some(1.0), None));
        assert!((r.overshoot_max.unwrap() - 4.0).abs() < 1e-12);
    }

    /// The bar is the smallest *expected* RMSE: a strategy whose one run came out lucky (a
    /// realized RMSE far below its prediction) does not trigger the warning, while a floor
    /// above the share of the smallest prediction does (the negative control); a row without
    /// a prediction (a QMC sampler) counts by its measured RMSE.
    #[test]
    fn the_floor_warning_is_against_the_smallest_expected_rmse() {
        let finals: Vec<FinalRun> = (0..3).map(|k| fr("a", k, 1.0)).collect();
        let base = summarize(&finals, Budget::Time(1.0)).remove(0);
        let row = |strategy: &str, predicted: Option<f64>, measured: f64, floor: f64| SummaryRow {
            strategy: strategy.into(),
            predicted_rmse: predicted,
            rmse_mean: measured,
            reference_noise_floor: Some(floor),
            ..base.clone()
        };
        // `lucky` measured 0.06 against a prediction of 0.1: a floor of 0.009 is 9 % of the
        // expected 0.1 (no warning) though 15 % of the realized 0.06.
        let rows = [
            row("lucky", Some(0.1), 0.06, 0.009),
            row("b", Some(0.2), 0.2, 0.009),
        ];
        assert!(noise_floor_warnings(&rows, 0.1).is_empty());
        let rows = [
            row("lucky", Some(0.08), 0.06, 0.009),
            row("b", Some(0.2), 0.2, 0.009),
        ];
        let w = noise_floor_warnings(&rows, 0.1);
        assert!(
            w.len() == 1 && w[0].contains("11 %") && w[0].contains("`lucky`"),
            "{w:?}"
        );
        let rows = [
            row("qmc", None, 0.05, 0.009),
            row("b", Some(0.2), 0.2, 0.009),
        ];
        let w = noise_floor_warnings(&rows, 0.1);
        assert!(
            w.len() == 1 && w[0].contains("18 %") && w[0].contains("`qmc`"),
            "{w:?}"
        );
    }

    /// A standard normal from a hashed key (Box–Muller).
    fn normal(key: u64) -> f64 {
        let u = |k: u64| ((crate::math::mix64(k) >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
        (-2.0 * u(key).ln()).sqrt() * (std::f64::consts::TAU * u(key ^ 0x9e37_79b9)).cos()
    }

    /// Under a true null (eight strategies with the same error distribution, five runs each)
    /// the family-wise error rate of `worse` verdicts stays at most α = 5 % with Holm over all
    /// pairs; the uncorrected p-value against the (selected) best exceeds it several-fold —
    /// the negative control that shows the simulation can see a missing correction.
    #[test]
    fn holm_keeps_the_family_wise_error_rate_under_a_true_null() {
        let (families, m, runs) = (1000u64, 8usize, 5u32);
        let (mut holm_errors, mut raw_errors) = (0u32, 0u32);
        for f in 0..families {
            let mut finals = Vec::new();
            for s in 0..m {
                for k in 0..runs {
                    let key = (f << 16) | ((s as u64) << 8) | k as u64;
                    let name = format!("s{s}");
                    finals.push(fr(&name, k, 1.0 + 0.1 * normal(key)));
                }
            }
            let rows = summarize(&finals, Budget::Time(1.0));
            holm_errors += rows.iter().any(|r| r.vs_best == "worse") as u32;
            raw_errors += rows
                .iter()
                .any(|r| r.welch_p_vs_best.is_some_and(|p| p < 1.0 - LEVEL))
                as u32;
        }
        let (holm, raw) = (
            holm_errors as f64 / families as f64,
            raw_errors as f64 / families as f64,
        );
        eprintln!("family-wise error rate: Holm {holm}, uncorrected {raw}");
        // 3σ of a binomial rate 0.05 over 1000 families: 0.021.
        assert!(holm <= 0.05 + 0.021, "Holm FWER {holm}");
        assert!(
            raw > 0.15,
            "uncorrected FWER {raw}: the simulation cannot see the correction"
        );
    }

    /// A run whose RMSE falls as c·t^(-1/2) and c·n^(-1/2) has slopes −½ exactly; one with a
    /// floor (a biased or correlated estimator) is flatter.
    #[test]
    fn convergence_slopes_of_a_clean_and_a_flattening_run() {
        let rows = |floor: f64| -> Vec<ResultRow> {
            (0..8)
                .map(|k| {
                    let spp = 4u64 << k;
                    let mut r = fr("a", 0, 1.0).row;
                    r.spp = spp;
                    r.time_s = 0.01 * spp as f64;
                    r.rmse = (1.0 / spp as f64 + floor * floor).sqrt();
                    r
                })
                .collect()
        };
        let (t, n) = convergence_slopes(&rows(0.0));
        assert!((t.unwrap() + 0.5).abs() < 1e-12 && (n.unwrap() + 0.5).abs() < 1e-12);
        let (t, _) = convergence_slopes(&rows(0.05));
        assert!(t.unwrap() > -0.45, "{t:?}");
        assert_eq!(convergence_slopes(&rows(0.0)[..2]), (None, None));
    }

    /// Debiased MSE subtracts floor²; debiased relMSE the reference's relMSE floor; the ranking
    /// and the verdicts use the debiased relMSE.
    #[test]
    fn debiased_errors_subtract_the_floors() {
        let mut a = fr("a", 0, 0.04);
        a.reference_relmse_floor = 0.01;
        assert!((a.mse_debiased() - (0.04 - 1e-6)).abs() < 1e-15);
        assert!((a.relmse_debiased() - 0.03).abs() < 1e-15);
        let rows = summarize(&[a.clone()], Budget::Time(1.0));
        assert!((rows[0].relmse_debiased_mean - 0.03).abs() < 1e-15);
        assert_eq!(rows[0].vs_best, "best");
        let b = fr("b", 0, 0.02);
        let rows = summarize(&[a, b], Budget::Time(1.0));
        assert_eq!(rows[0].strategy, "b", "sorted by the ranking metric");
        assert_eq!(rows[1].vs_best, "one run: no test");
    }

    /// The sampler is part of a row's identity: the same strategy with two samplers gives two
    /// rows in one Holm family, and a non-independent sampler's row has no prediction.
    #[test]
    fn samplers_are_separate_rows_and_qmc_predicts_nothing() {
        let mut finals = Vec::new();
        for k in 0..4u32 {
            let e = k as f64 * 0.01;
            finals.push(fr("a", k, 1.0 + e));
            let mut q = fr("a", k, 0.1 + e);
            q.row.sampler = "sobol".into();
            q.mean_sample_variance = None;
            finals.push(q);
        }
        let rows = summarize(&finals, Budget::Time(1.0));
        assert_eq!(rows.len(), 2);
        assert_eq!(
            (rows[0].sampler.as_str(), rows[0].vs_best.as_str()),
            ("sobol", "best")
        );
        assert_eq!(rows[0].predicted_rmse, None);
        assert_eq!(rows[1].vs_best, "worse");
        assert!(rows[1].predicted_rmse.is_some() && rows[1].holm_p_vs_best.is_some());
    }
}
