//! A discrete distribution by inverted CDF (pbrt-v4 `PiecewiseConstant1D` in its discrete use):
//! picks index i with probability w_i / Σw. Sums in f64 so the pmf is exact to f32 precision
//! even with 1e8 weight ratios.

#[derive(Clone, Debug)]
pub struct DiscreteDistribution {
    cdf: Vec<f64>,
    pmf: Vec<f32>,
    total: f64,
}

impl DiscreteDistribution {
    /// None if there is no positive, finite total weight.
    pub fn new(weights: &[f32]) -> Option<Self> {
        let mut cdf = Vec::with_capacity(weights.len() + 1);
        let mut acc = 0.0f64;
        cdf.push(0.0);
        for &w in weights {
            if !(w >= 0.0 && w.is_finite()) {
                return None;
            }
            acc += w as f64;
            cdf.push(acc);
        }
        if acc <= 0.0 {
            return None;
        }
        let pmf = weights.iter().map(|&w| (w as f64 / acc) as f32).collect();
        Some(DiscreteDistribution {
            cdf,
            pmf,
            total: acc,
        })
    }

    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    pub fn total(&self) -> f64 {
        self.total
    }

    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf[i]
    }

    /// Index with probability pmf(i), for u in [0, 1). Zero-weight entries are never returned.
    pub fn sample(&self, u: f32) -> usize {
        let target = u as f64 * self.total;
        // First i with cdf[i + 1] > target: entries of zero weight have cdf[i+1] == cdf[i].
        let i = self.cdf[1..].partition_point(|&c| c <= target);
        i.min(self.pmf.len() - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn never_picks_zero_weight_and_rejects_bad_weights() {
        let d = DiscreteDistribution::new(&[0.0, 1.0, 0.0, 3.0, 0.0]).unwrap();
        for k in 0..1000 {
            let i = d.sample(k as f32 / 1000.0);
            assert!(d.pmf(i) > 0.0, "picked zero-weight entry {i}");
        }
        assert_eq!(d.sample(0.0), 1);
        assert_eq!(d.sample(super::super::stream::ONE_MINUS_EPSILON), 3);
        assert!((d.pmf(3) - 0.75).abs() < 1e-7);
        assert!(DiscreteDistribution::new(&[0.0, 0.0]).is_none());
        assert!(DiscreteDistribution::new(&[1.0, f32::NAN]).is_none());
        assert!(DiscreteDistribution::new(&[]).is_none());
    }
}
