//! Discrete distributions over indices, both picking i with probability w_i / Σw and summing
//! in f64 so the pmf is exact to f32 precision even with 1e8 weight ratios: by inverted CDF
//! (pbrt-v4 `PiecewiseConstant1D` in its discrete use; O(log n)) and by alias table (O(1)).

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

/// Walker's alias method (Walker 1977) with Vose's O(n) construction (Vose 1991): O(1)
/// sampling of index i with probability w_i / Σw from one uniform number. Built in f64, so
/// the probability each bin hands to its own index and to its alias is exact to f64 rounding,
/// and the reported pmf is the weight's own share (pbrt-v4 `AliasTable` does the same).
#[derive(Clone, Debug)]
pub struct AliasTable {
    bins: Vec<AliasBin>,
    total: f64,
}

#[derive(Clone, Copy, Debug)]
struct AliasBin {
    /// Probability of keeping the bin's own index once the bin is chosen.
    q: f64,
    alias: u32,
    pmf: f32,
}

impl AliasTable {
    /// None if some weight is negative or not finite, or there is no positive total.
    pub fn new(weights: &[f32]) -> Option<Self> {
        if weights.len() >= u32::MAX as usize {
            return None;
        }
        let mut total = 0.0f64;
        for &w in weights {
            if !(w >= 0.0 && w.is_finite()) {
                return None;
            }
            total += w as f64;
        }
        if total <= 0.0 {
            return None;
        }
        let n = weights.len() as f64;
        // Each weight as a multiple of the mean: a bin holds exactly one mean's worth.
        let mut scaled: Vec<f64> = weights.iter().map(|&w| w as f64 / total * n).collect();
        let mut bins: Vec<AliasBin> = weights
            .iter()
            .enumerate()
            .map(|(i, &w)| AliasBin {
                q: 1.0,
                alias: i as u32,
                pmf: (w as f64 / total) as f32,
            })
            .collect();
        let (mut small, mut large): (Vec<u32>, Vec<u32>) =
            (0..weights.len() as u32).partition(|&i| scaled[i as usize] < 1.0);
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            bins[s as usize].q = scaled[s as usize];
            bins[s as usize].alias = l;
            // The large entry gives the small bin what it lacks.
            scaled[l as usize] -= 1.0 - scaled[s as usize];
            if scaled[l as usize] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // What is left is within rounding of one mean: keep it whole (q = 1), except a
        // zero-weight entry, which must never be returned: it hands its bin to the heaviest.
        let heaviest = (0..weights.len())
            .max_by(|&a, &b| weights[a].total_cmp(&weights[b]))
            .unwrap_or(0) as u32;
        for i in small.into_iter().chain(large) {
            let b = &mut bins[i as usize];
            if weights[i as usize] > 0.0 {
                b.q = 1.0;
            } else {
                b.q = 0.0;
                b.alias = heaviest;
            }
        }
        Some(AliasTable { bins, total })
    }

    pub fn len(&self) -> usize {
        self.bins.len()
    }

    pub fn is_empty(&self) -> bool {
        self.bins.is_empty()
    }

    pub fn total(&self) -> f64 {
        self.total
    }

    pub fn pmf(&self, i: usize) -> f32 {
        self.bins[i].pmf
    }

    /// Index with probability pmf(i), for u in [0, 1): the integer part of u·n picks the bin,
    /// the fraction decides between the bin's index and its alias. With a million entries a
    /// 24-bit u would leave the fraction 4 bits; the f64 u of a light selector keeps 28.
    pub fn sample(&self, u: f64) -> usize {
        let x = u * self.bins.len() as f64;
        let i = (x as usize).min(self.bins.len() - 1);
        let b = &self.bins[i];
        // Without a branch: whether a bin keeps its index is a coin flip of bias q, which a
        // branch predictor cannot learn (as a branch it was half a mesh_light `light`
        // pass's light selection).
        std::hint::select_unpredictable(x - (i as f64) < b.q, i, b.alias as usize)
    }

    /// The probability [`Self::sample`] returns i for u uniform on [0, 1), from the table
    /// itself (the bin's own share plus every share aliased to i): what the pmf must equal.
    pub fn implied_probability(&self, i: usize) -> f64 {
        let own = self.bins[i].q;
        let aliased: f64 = self
            .bins
            .iter()
            .filter(|b| b.alias as usize == i && b.q < 1.0)
            .map(|b| 1.0 - b.q)
            .sum();
        (own + aliased) / self.bins.len() as f64
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

    /// The table hands each index exactly its weight's share (the implied probability equals
    /// the pmf to f64 rounding), never returns a zero weight, and survives a 1e8 ratio.
    #[test]
    fn alias_table_is_exact() {
        let w = [1e-8f32, 0.3, 0.0, 1.0, 0.25, 2.5, 0.0, 0.7, 1e-8, 0.0];
        let t = AliasTable::new(&w).unwrap();
        let total: f64 = w.iter().map(|&x| x as f64).sum();
        for (i, &wi) in w.iter().enumerate() {
            let exact = wi as f64 / total;
            let implied = t.implied_probability(i);
            assert!(
                (implied - exact).abs() <= 1e-15,
                "{i}: implied {implied:e} vs {exact:e}"
            );
            assert_eq!(t.pmf(i), exact as f32);
        }
        for k in 0..100_000 {
            let i = t.sample(k as f64 / 100_000.0);
            assert!(w[i] > 0.0, "picked zero-weight entry {i}");
        }
        assert!(t.sample(1.0 - f64::EPSILON) < w.len());
        assert!(AliasTable::new(&[0.0, 0.0]).is_none());
        assert!(AliasTable::new(&[1.0, f32::NAN]).is_none());
        assert!(AliasTable::new(&[1.0, -1.0]).is_none());
        assert!(AliasTable::new(&[]).is_none());
        // Negative control: a table whose alias points elsewhere breaks the equality.
        let mut broken = t.clone();
        let k = broken.bins.iter().position(|b| b.q < 1.0).unwrap();
        broken.bins[k].alias = (broken.bins[k].alias + 1) % w.len() as u32;
        assert!(
            (0..w.len())
                .any(|i| { (broken.implied_probability(i) - w[i] as f64 / total).abs() > 1e-9 })
        );
    }
}
