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
    fn critical_values_match_the_normal_table() {
        assert!((z_critical(0.05) - 1.959964).abs() < 1e-5);
        assert!((z_critical(1e-4) - 3.890592).abs() < 1e-5);
    }
}
