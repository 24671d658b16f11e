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

/// Index i with cdf[i] ≤ u·total < cdf[i+1], and the offset of u inside that cell, for N lanes
/// in lockstep, each lane in its own cumulative array (starting at 0, with a positive total) of
/// `len + 1` entries from `data[start[i]]`. Cells of zero width are never chosen. The
/// search is branch-free (the halving search of Khuong & Morin, "Array Layouts for
/// Comparison-Based Searching", 2017): every lane takes the same
/// ⌈log₂ len⌉ steps, so the lanes' loads overlap instead of each waiting behind the branch
/// mispredictions of the one before. It finds the same index as `partition_point`, the unique
/// first entry above the target in a non-decreasing array.
#[inline(always)]
pub fn sample_cumulative_lanes<const N: usize>(
    data: &[f64],
    start: [usize; N],
    len: usize,
    u: [f64; N],
) -> ([usize; N], [f64; N]) {
    let mut target = [0.0f64; N];
    for i in 0..N {
        target[i] = u[i] * data[start[i] + len];
    }
    // The answer j (first entry of cdf[1..] above the target) lies in [base, base + size].
    let mut base = [0usize; N];
    let mut size = len;
    while size > 1 {
        let half = size / 2;
        for i in 0..N {
            let mid = base[i] + half;
            // A conditional move: as a branch it is taken half the time, at random.
            base[i] = std::hint::select_unpredictable(
                data[start[i] + 1 + mid] <= target[i],
                mid,
                base[i],
            );
        }
        size -= half;
    }
    let mut offset = [0.0f64; N];
    for i in 0..N {
        let cdf = &data[start[i]..=start[i] + len];
        let j = (base[i] + (cdf[1 + base[i]] <= target[i]) as usize).min(len - 1);
        base[i] = j;
        offset[i] = cell_offset(cdf, j, target[i]);
    }
    (base, offset)
}

/// The offset of `target` inside cell i of `cdf`, in [0, 1).
#[inline(always)]
fn cell_offset(cdf: &[f64], i: usize, target: f64) -> f64 {
    let width = cdf[i + 1] - cdf[i];
    ((target - cdf[i]) / width).clamp(0.0, ONE_BELOW)
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
    /// Through the lockstep search of one lane ([`Self::sample_lanes`]): as a branch, each
    /// step of a binary search is mispredicted half the time.
    pub fn sample(&self, u: [f32; 2]) -> ((usize, usize), [f64; 2]) {
        let (col, row, du, dv) = self.sample_lanes([[u[0]], [u[1]]]);
        ((col[0], row[0]), [du[0], dv[0]])
    }

    /// [`Self::sample`] of N lanes (u[0] the columns', u[1] the rows'), searched in lockstep
    /// ([`sample_cumulative_lanes`]): (columns, rows, du, dv).
    #[inline(always)]
    #[allow(clippy::type_complexity)]
    pub fn sample_lanes<const N: usize>(
        &self,
        u: [[f32; N]; 2],
    ) -> ([usize; N], [usize; N], [f64; N], [f64; N]) {
        let height = self.marginal.len() - 1;
        let (row, dv) =
            sample_cumulative_lanes(&self.marginal, [0; N], height, u[1].map(f64::from));
        let stride = self.width + 1;
        let (col, du) = sample_cumulative_lanes(
            &self.conditional,
            row.map(|r| r * stride),
            self.width,
            u[0].map(f64::from),
        );
        (col, row, du, dv)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream::SampleStream;

    /// Index i with cdf[i] ≤ u·total < cdf[i+1], and the offset of u inside that cell, for a
    /// cumulative array starting at 0 with a positive total. Cells of zero width are never chosen.
    /// The definition [`sample_cumulative_lanes`] is tested against.
    fn sample_cumulative(cdf: &[f64], u: f64) -> (usize, f64) {
        let n = cdf.len() - 1;
        let target = u * cdf[n];
        let i = cdf[1..].partition_point(|&c| c <= target).min(n - 1);
        (i, cell_offset(cdf, i, target))
    }

    type Search = fn(&[f64], [usize; 8], usize, [f64; 8]) -> ([usize; 8], [f64; 8]);

    /// Where `search` of 8 lanes leaves [`sample_cumulative`] lane by lane (index, and offset
    /// bit for bit), over rows of 8, 7, 5 and 1 cells with empty cells at the start, middle
    /// and end, and with u on the cells' boundaries (u = k/16 and sums of few bits, so u·total
    /// is exact there), at 0 and just below 1.
    fn lanes_mismatch(search: Search) -> Option<String> {
        let rows: [&[f64]; 4] = [
            &[0.0, 0.0, 0.0, 1.0, 3.0, 3.0, 4.0, 4.0, 4.0],
            &[0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0],
            &[0.0, 5.0, 5.0, 5.0, 5.0, 5.0, 6.0, 8.0, 8.0],
            &[0.0, 0.5, 0.75, 0.75, 1.5, 1.5, 1.5, 2.0, 2.0],
        ];
        let mut rng = SampleStream::new(7, 3, 1, 2);
        let below_one = f64::from(crate::sampling::stream::ONE_MINUS_EPSILON);
        for round in 0..4000 {
            // Lengths of a power of two and not (the search halves unevenly), down to one.
            let len = [8, 7, 5, 1][round % 4];
            let data: Vec<f64> = rows.iter().flat_map(|r| &r[..=len]).copied().collect();
            let start: [usize; 8] = std::array::from_fn(|i| ((i + round) % 4) * (len + 1));
            let u: [f64; 8] = std::array::from_fn(|i| match (round + i) % 4 {
                0 => (rng.next_2d()[0] * 16.0).floor() as f64 / 16.0,
                1 => [0.0, below_one][i % 2],
                _ => rng.next_2d()[0] as f64,
            });
            let (got, offset) = search(&data, start, len, u);
            for i in 0..8 {
                let want = sample_cumulative(&data[start[i]..=start[i] + len], u[i]);
                if (got[i], offset[i].to_bits()) != (want.0, want.1.to_bits()) {
                    return Some(format!(
                        "row at {} u {}: ({}, {}) against {want:?}",
                        start[i], u[i], got[i], offset[i]
                    ));
                }
            }
        }
        None
    }

    /// The lockstep search over lanes is the scalar inversion, bit for bit.
    #[test]
    fn lanes_are_the_scalar_inversion() {
        assert_eq!(lanes_mismatch(sample_cumulative_lanes::<8>), None);
    }

    /// Control: a search that differs from `partition_point` only where u·total falls exactly
    /// on a cumulative sum (first entry at or above it, not above it) is caught.
    #[test]
    fn a_search_wrong_on_ties_is_caught() {
        fn ties_left(
            data: &[f64],
            start: [usize; 8],
            len: usize,
            u: [f64; 8],
        ) -> ([usize; 8], [f64; 8]) {
            let (mut j, mut offset) = ([0; 8], [0.0; 8]);
            for i in 0..8 {
                let cdf = &data[start[i]..=start[i] + len];
                let target = u[i] * cdf[len];
                j[i] = cdf[1..].partition_point(|&c| c < target).min(len - 1);
                offset[i] = cell_offset(cdf, j[i], target);
            }
            (j, offset)
        }
        assert!(lanes_mismatch(ties_left).is_some());
    }
}
