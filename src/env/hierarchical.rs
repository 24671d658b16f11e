//! Hierarchical sample warping (Clarberg et al., "Wavelet Importance Sampling", SIGGRAPH 2005;
//! McCool & Harwood 1997): a mip pyramid of texel-weight sums per square tile, descended from
//! the root by splitting the unit square at each 2×2 node — first left/right by the column
//! sums with u₀, then top/bottom within the chosen column with u₁ — and rescaling u into the
//! chosen half. The leaf's texel is chosen with probability weight/total, exactly as the
//! marginal/conditional method, but neighbouring u land in neighbouring texels, so
//! stratification of u carries over. An atlas of several tiles (cube faces, HEALPix base
//! pixels, the two halves of a lat/long map) first picks a tile by its sum with u₀.

use super::cdf::{ONE_BELOW, sample_cumulative};

#[derive(Clone, Debug)]
pub struct HierarchicalWarp {
    /// Tile side (a power of two).
    n: usize,
    /// Cumulative tile sums, starting at 0.
    tile_cdf: Vec<f64>,
    /// Per tile, the pyramid from the finest level (n×n texel weights, row-major) to 1×1.
    levels: Vec<Vec<Vec<f64>>>,
}

impl HierarchicalWarp {
    /// `weights` is the atlas (tiles·n wide, n high, row-major); None when all are zero.
    pub fn new(weights: &[f64], tiles: usize, n: usize) -> Option<Self> {
        assert!(
            n.is_power_of_two(),
            "hierarchical warping needs a power-of-two tile"
        );
        let width = tiles * n;
        let mut levels = Vec::with_capacity(tiles);
        let mut tile_cdf = vec![0.0];
        for t in 0..tiles {
            let mut finest = vec![0.0; n * n];
            for y in 0..n {
                finest[y * n..(y + 1) * n]
                    .copy_from_slice(&weights[y * width + t * n..y * width + (t + 1) * n]);
            }
            let mut pyramid = vec![finest];
            let mut s = n;
            while s > 1 {
                let fine = pyramid.last().unwrap();
                let h = s / 2;
                let coarse: Vec<f64> = (0..h * h)
                    .map(|k| {
                        let (x, y) = (2 * (k % h), 2 * (k / h));
                        fine[y * s + x]
                            + fine[y * s + x + 1]
                            + fine[(y + 1) * s + x]
                            + fine[(y + 1) * s + x + 1]
                    })
                    .collect();
                pyramid.push(coarse);
                s = h;
            }
            tile_cdf.push(tile_cdf.last().unwrap() + pyramid.last().unwrap()[0]);
            levels.push(pyramid);
        }
        (*tile_cdf.last().unwrap() > 0.0).then_some(HierarchicalWarp {
            n,
            tile_cdf,
            levels,
        })
    }

    /// (column, row) of the chosen atlas texel and the offsets (du, dv) ∈ [0, 1)² inside it.
    pub fn sample(&self, u: [f32; 2]) -> ((usize, usize), [f64; 2]) {
        let (tile, mut u0) = sample_cumulative(&self.tile_cdf, u[0] as f64);
        let mut u1 = u[1] as f64;
        let pyramid = &self.levels[tile];
        let (mut x, mut y) = (0usize, 0usize);
        // From the 2×2 level (index len-2) down to the texels (index 0).
        for level in (0..pyramid.len() - 1).rev() {
            let c = &pyramid[level];
            let s = self.n >> level;
            let at = |i: usize, j: usize| c[j * s + i];
            let (x0, y0) = (2 * x, 2 * y);
            let left = at(x0, y0) + at(x0, y0 + 1);
            let right = at(x0 + 1, y0) + at(x0 + 1, y0 + 1);
            let (xi, u0n) = split(left, right, u0);
            x = x0 + xi;
            u0 = u0n;
            let (yi, u1n) = split(at(x, y0), at(x, y0 + 1), u1);
            y = y0 + yi;
            u1 = u1n;
        }
        ((tile * self.n + x, y), [u0, u1])
    }
}

/// Chooses the first half (0) with probability a/(a + b), else the second, and rescales u into
/// the chosen half. Only called on nodes of positive sum; a zero half is never chosen.
fn split(a: f64, b: f64, u: f64) -> (usize, f64) {
    let p = a / (a + b);
    if u < p {
        (0, (u / p).min(ONE_BELOW))
    } else {
        (1, ((u - p) / (1.0 - p)).clamp(0.0, ONE_BELOW))
    }
}
