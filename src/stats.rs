//! Statistics in f64: running moments and the tests the harness and test suite decide with.

/// Welford's online mean and variance (numerically stable single pass).
#[derive(Clone, Copy, Debug, Default)]
pub struct Welford {
    pub n: u64,
    pub mean: f64,
    m2: f64,
}

impl Welford {
    pub fn add(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    /// Unbiased sample variance.
    pub fn variance(&self) -> f64 {
        if self.n < 2 {
            0.0
        } else {
            self.m2 / (self.n - 1) as f64
        }
    }

    /// Standard error of the mean.
    pub fn std_error(&self) -> f64 {
        (self.variance() / self.n as f64).sqrt()
    }

    /// z-score of the mean against an expected value.
    pub fn z_score(&self, expected: f64) -> f64 {
        (self.mean - expected) / self.std_error()
    }

    /// Sum of squared deviations from the mean.
    pub fn m2(&self) -> f64 {
        self.m2
    }

    /// The moments of the union of two samples (Chan, Golub & LeVeque 1979): exact up to
    /// roundoff, so shards of a computation can be merged in any order.
    pub fn merge(&self, other: &Welford) -> Welford {
        let n = self.n + other.n;
        if n == 0 {
            return Welford::default();
        }
        let (na, nb) = (self.n as f64, other.n as f64);
        let d = other.mean - self.mean;
        Welford {
            n,
            mean: self.mean + d * nb / n as f64,
            m2: self.m2 + other.m2 + d * d * na * nb / n as f64,
        }
    }
}

/// Pearson's correlation of two equally long samples (two passes: means, then centred sums).
pub fn correlation(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(
        a.len(),
        b.len(),
        "correlation of samples of different lengths"
    );
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

/// Two-sided critical t for significance α with `dof` degrees of freedom.
pub fn t_critical(alpha: f64, dof: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    match StudentsT::new(0.0, 1.0, dof) {
        Ok(t) => t.inverse_cdf(1.0 - 0.5 * alpha),
        Err(_) => f64::INFINITY,
    }
}

/// Mean of repeated measurements with a two-sided Student-t confidence interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeanCi {
    pub n: usize,
    pub mean: f64,
    /// Sample standard deviation (n - 1 in the denominator).
    pub std: f64,
    /// Half-width of the confidence interval; None below two samples.
    pub half_width: Option<f64>,
}

/// t-based confidence interval of the mean at `level` (e.g. 0.95): x̄ ± t(1-α/2, n-1)·s/√n.
pub fn mean_ci(xs: &[f64], level: f64) -> MeanCi {
    let mut w = Welford::default();
    xs.iter().for_each(|&x| w.add(x));
    let std = w.variance().sqrt();
    let half_width =
        (w.n >= 2).then(|| t_critical(1.0 - level, (w.n - 1) as f64) * std / (w.n as f64).sqrt());
    MeanCi {
        n: xs.len(),
        mean: w.mean,
        std,
        half_width,
    }
}

/// Welch's unequal-variance t-test of equal means (Welch 1947): the t statistic, the
/// Welch–Satterthwaite degrees of freedom and the two-sided p-value. None when either sample
/// has fewer than two values or both have zero variance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WelchTest {
    pub t: f64,
    pub dof: f64,
    pub p_value: f64,
}

pub fn welch_t_test(a: &[f64], b: &[f64]) -> Option<WelchTest> {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    if a.len() < 2 || b.len() < 2 {
        return None;
    }
    let (mut wa, mut wb) = (Welford::default(), Welford::default());
    a.iter().for_each(|&x| wa.add(x));
    b.iter().for_each(|&x| wb.add(x));
    let (va, vb) = (wa.variance() / wa.n as f64, wb.variance() / wb.n as f64);
    let se2 = va + vb;
    if se2 <= 0.0 {
        return None;
    }
    let t = (wa.mean - wb.mean) / se2.sqrt();
    let dof = se2 * se2 / (va * va / (wa.n - 1) as f64 + vb * vb / (wb.n - 1) as f64);
    let dist = StudentsT::new(0.0, 1.0, dof).ok()?;
    let p_value = 2.0 * dist.sf(t.abs());
    Some(WelchTest { t, dof, p_value })
}

/// Holm's step-down adjusted p-values (Holm 1979), in the order given: with the p-values sorted
/// ascending, adj₍ᵢ₎ = max over j ≤ i of min(1, (m − j + 1)·p₍ⱼ₎). Rejecting every hypothesis
/// with adjusted p ≤ α keeps the family-wise error rate at most α under any dependence.
pub fn holm_adjust(p: &[f64]) -> Vec<f64> {
    let m = p.len();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| p[a].total_cmp(&p[b]));
    let mut out = vec![0.0; m];
    let mut running = 0.0f64;
    for (rank, &i) in order.iter().enumerate() {
        running = running.max(((m - rank) as f64 * p[i]).min(1.0));
        out[i] = running;
    }
    out
}

/// A least-squares line y ≈ intercept + slope·x.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineFit {
    pub slope: f64,
    pub intercept: f64,
    pub n: usize,
}

/// Ordinary least squares through (x, y); None below two distinct x.
pub fn fit_line(x: &[f64], y: &[f64]) -> Option<LineFit> {
    let n = x.len().min(y.len());
    if n < 2 {
        return None;
    }
    let mx = x[..n].iter().sum::<f64>() / n as f64;
    let my = y[..n].iter().sum::<f64>() / n as f64;
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for (xi, yi) in x.iter().zip(y) {
        sxx += (xi - mx) * (xi - mx);
        sxy += (xi - mx) * (yi - my);
    }
    if sxx <= 0.0 {
        return None;
    }
    let slope = sxy / sxx;
    Some(LineFit {
        slope,
        intercept: my - slope * mx,
        n,
    })
}

/// Two-sided critical z for significance α: Φ⁻¹(1 - α/2).
pub fn z_critical(alpha: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::standard().inverse_cdf(1.0 - 0.5 * alpha)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welford_matches_two_pass() {
        let xs = [1.0, 2.0, 4.0, 8.0, 16.0, 1e9 + 1.0, 1e9 + 3.0];
        let mut w = Welford::default();
        xs.iter().for_each(|&x| w.add(x));
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (xs.len() - 1) as f64;
        assert!((w.mean - mean).abs() < 1e-6 && ((w.variance() - var) / var).abs() < 1e-12);
    }

    #[test]
    fn chan_merge_equals_one_pass() {
        let xs: Vec<f64> = (0..1000)
            .map(|i| ((i * 7919) % 1013) as f64 * 0.37 + 1e6)
            .collect();
        let mut all = Welford::default();
        xs.iter().for_each(|&x| all.add(x));
        let mut parts = [Welford::default(); 3];
        for (i, &x) in xs.iter().enumerate() {
            parts[i % 3 * (i % 5) / 4].add(x);
        }
        let merged = parts[0].merge(&parts[1]).merge(&parts[2]);
        assert_eq!(merged.n, all.n);
        assert!((merged.mean - all.mean).abs() <= 1e-12 * all.mean.abs());
        assert!(((merged.variance() - all.variance()) / all.variance()).abs() < 1e-10);
        let empty = Welford::default();
        assert_eq!(empty.merge(&all).mean, all.mean);
    }

    #[test]
    fn t_critical_matches_the_t_table() {
        // Student-t table, two-sided 95 %: dof 4 → 2.776, dof 9 → 2.262, dof 30 → 2.042.
        assert!((t_critical(0.05, 4.0) - 2.776445).abs() < 1e-5);
        assert!((t_critical(0.05, 9.0) - 2.262157).abs() < 1e-5);
        assert!((t_critical(0.05, 30.0) - 2.042272).abs() < 1e-5);
    }

    /// Coverage of the 95 % t-interval on simulated normal samples of size 5: the count of
    /// intervals containing the true mean is Binomial(N, 0.95); accept within 4.4 binomial
    /// standard errors (α ≈ 1e-5), so the test can fail only on a wrong interval.
    #[test]
    fn t_interval_covers_95_percent() {
        use rand_core::{RngCore, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let mut uniform = || (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
        let trials = 20_000;
        let mut covered = 0;
        for _ in 0..trials {
            // Box–Muller normals with mean 3, sd 2.
            let xs: Vec<f64> = (0..5)
                .map(|_| {
                    let (u1, u2) = (1.0 - uniform(), uniform());
                    3.0 + 2.0 * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
                })
                .collect();
            let ci = mean_ci(&xs, 0.95);
            if (ci.mean - 3.0).abs() <= ci.half_width.unwrap() {
                covered += 1;
            }
        }
        let p = covered as f64 / trials as f64;
        let se = (0.95 * 0.05 / trials as f64).sqrt();
        assert!((p - 0.95).abs() < 4.4 * se, "coverage {p}");
        // A z-interval (ignoring the t correction) would cover only ~88 % at n = 5:
        // this is what the test exists to catch.
        assert!(z_critical(0.05) < t_critical(0.05, 4.0));
    }

    /// Welch's test on the two-sample example of the Wikipedia article "Welch's t-test"
    /// (A1 vs A2): t = -2.46, dof = 24.99, p = 0.021.
    #[test]
    fn welch_matches_the_textbook_example() {
        let a1 = [
            27.5, 21.0, 19.0, 23.6, 17.0, 17.9, 16.9, 20.1, 21.9, 22.6, 23.1, 19.6, 19.0, 21.7,
            21.4,
        ];
        let a2 = [
            27.1, 22.0, 20.8, 23.4, 23.4, 23.5, 25.8, 22.0, 24.8, 20.2, 21.9, 22.1, 22.9, 20.5,
            24.4,
        ];
        let w = welch_t_test(&a1, &a2).unwrap();
        assert!((w.t - -2.46).abs() < 0.005, "{w:?}");
        assert!((w.dof - 24.99).abs() < 0.01, "{w:?}");
        assert!((w.p_value - 0.021).abs() < 0.0005, "{w:?}");
        assert!(welch_t_test(&a1, &a1[..1]).is_none());
    }

    /// Holm's adjusted p-values on a worked example: p = (0.01, 0.04, 0.03, 0.005) gives
    /// sorted 0.005·4 = 0.02, 0.01·3 = 0.03, 0.03·2 = 0.06, max(0.06, 0.04·1) = 0.06.
    #[test]
    fn holm_matches_a_worked_example() {
        let adj = holm_adjust(&[0.01, 0.04, 0.03, 0.005]);
        let want = [0.03, 0.06, 0.06, 0.02];
        for (a, w) in adj.iter().zip(want) {
            assert!((a - w).abs() < 1e-12, "{adj:?}");
        }
        assert_eq!(holm_adjust(&[0.9, 0.8]), vec![1.0, 1.0]);
        assert!(holm_adjust(&[]).is_empty());
    }

    #[test]
    fn line_fit_recovers_a_line() {
        let x = [0.0, 1.0, 2.0, 3.0, 5.0];
        let y: Vec<f64> = x.iter().map(|x| 2.5 - 0.5 * x).collect();
        let f = fit_line(&x, &y).unwrap();
        assert!((f.slope + 0.5).abs() < 1e-12 && (f.intercept - 2.5).abs() < 1e-12);
        assert!(fit_line(&[1.0, 1.0], &[0.0, 1.0]).is_none());
    }

    #[test]
    fn critical_values_match_the_normal_table() {
        assert!((z_critical(0.05) - 1.959964).abs() < 1e-5);
        assert!((z_critical(1e-4) - 3.890592).abs() < 1e-5);
    }
}
