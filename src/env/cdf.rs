//! Marginal/conditional inversion over a grid of texel weights (pbrt-v4
//! `PiecewiseConstant2D`): a row by the marginal CDF of row sums, then a column by that row's
//! conditional CDF, each with the continuous offset inside the chosen cell. Sums in f64, so
//! 1e5 dynamic range between sun and sky keeps exact row and column probabilities.

/// Cumulative sums of a grid of non-negative weights, `width` per row.
#[derive(Clone, Debug)]
pub struct MarginalConditional {
    width: usize,
    /// Per row: width + 1 cumulative sums, starting at 0.
    conditional: Vec<f64>,
    /// height + 1 cumulative row sums, starting at 0.
    marginal: Vec<f64>,
}

/// Index i with cdf[i] ≤ u·total < cdf[i+1], and the offset of u inside that cell, for a
/// cumulative array starting at 0 with a positive total. Cells of zero width are never chosen.
pub fn sample_cumulative(cdf: &[f64], u: f64) -> (usize, f64) {
    let n = cdf.len() - 1;
    let target = u * cdf[n];
    let i = cdf[1..].partition_point(|&c| c <= target).min(n - 1);
    let width = cdf[i + 1] - cdf[i];
    let offset = ((target - cdf[i]) / width).clamp(0.0, ONE_BELOW);
    (i, offset)
}

/// The largest f64 below 1.
pub const ONE_BELOW: f64 = 1.0 - f64::EPSILON / 2.0;

impl MarginalConditional {
    /// None when every weight is zero (no texel can be sampled).
    pub fn new(weights: &[f64], width: usize) -> Option<Self> {
        let height = weights.len() / width;
        let mut conditional = Vec::with_capacity(height * (width + 1));
        let mut marginal = Vec::with_capacity(height + 1);
        marginal.push(0.0);
        for row in weights.chunks_exact(width) {
            let mut acc = 0.0;
            conditional.push(0.0);
            for &w in row {
                acc += w;
                conditional.push(acc);
            }
            marginal.push(marginal.last().unwrap() + acc);
        }
        (*marginal.last().unwrap() > 0.0).then_some(MarginalConditional {
            width,
            conditional,
            marginal,
        })
    }

    /// (column, row) of the chosen texel and the offsets (du, dv) ∈ [0, 1)² inside it:
    /// u[1] picks the row, u[0] the column.
    pub fn sample(&self, u: [f32; 2]) -> ((usize, usize), [f64; 2]) {
        let (row, dv) = sample_cumulative(&self.marginal, u[1] as f64);
        let stride = self.width + 1;
        let cond = &self.conditional[row * stride..(row + 1) * stride];
        let (col, du) = sample_cumulative(cond, u[0] as f64);
        ((col, row), [du, dv])
    }
}
