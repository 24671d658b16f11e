//! Stratified (jittered) samples per pixel: with N samples per pixel known up front, every
//! layout group is stratified on its own — a single dimension into N intervals of length 1/N,
//! a pair into an nx × ny grid of N cells (nx the largest divisor of N not above √N) — and
//! sample k of the pixel takes, in each group, the stratum π_g(k) of a random permutation π_g
//! of 0..N (one per seed, strategy, pixel and group, so the groups are not correlated:
//! "padding"), jittered uniformly inside it. Every N consecutive samples (0..N, N..2N, …) put
//! one point in each stratum; past N the permutation is redrawn.
//!
//! It needs N: under a time budget (`Setup::spp` None) `check` refuses, and `compare` says that
//! `--sampler stratified` needs a fixed sample count.

use super::generator::{SampleGenerator, SampleKey, Setup};
use super::stream::SampleStream;
use crate::math::mix64;

pub struct Stratified;

pub static STRATIFIED: Stratified = Stratified;

/// A bijection of 0..n keyed by `seed` (for n ≥ 1): an invertible hash of the bits below the
/// next power of two, walked until it lands below n (each step is a bijection on 0..2^b, so
/// the cycle through k returns below n).
pub fn permute(k: u64, n: u64, seed: u64) -> u64 {
    debug_assert!(k < n);
    if n <= 1 {
        return 0;
    }
    let bits = 64 - (n - 1).leading_zeros();
    let mask = if bits == 64 { u64::MAX } else { (1u64 << bits) - 1 };
    let (a, b) = (mix64(seed) | 1, mix64(seed ^ 0x7f4a_7c15));
    let mut x = k;
    loop {
        // Each line is a bijection of 0..2^bits: xor with a constant, multiply by an odd
        // number, xor with a right shift of itself.
        x ^= b & mask;
        x = x.wrapping_mul(a) & mask;
        x ^= x >> (bits / 2 + 1);
        x = x.wrapping_mul((a ^ 0x9E37_79B9_7F4A_7C16) | 1) & mask;
        x ^= x >> (bits / 3 + 1);
        if x < n {
            return x;
        }
    }
}

/// The grid a pair uses for n strata: nx · ny = n with nx ≤ ny as close as n allows.
pub fn grid(n: u64) -> (u64, u64) {
    let mut nx = (n as f64).sqrt() as u64;
    while nx > 1 && !n.is_multiple_of(nx) {
        nx -= 1;
    }
    let nx = nx.max(1);
    (nx, n / nx)
}

impl SampleGenerator for Stratified {
    fn name(&self) -> &'static str {
        "stratified"
    }

    fn describe(&self) -> &'static str {
        "jittered strata per pixel and layout group, randomly matched across groups (needs a fixed sample count)"
    }

    fn check(&self, setup: &Setup) -> Result<(), String> {
        match setup.spp {
            Some(n) if n >= 1 => Ok(()),
            _ => Err(
                "`stratified` needs the sample count per pixel up front (a fixed --spp); \
                 a time budget does not know it"
                    .into(),
            ),
        }
    }

    fn fill(&self, setup: &Setup, key: SampleKey, out: &mut [f32]) {
        let n = setup.spp.unwrap_or(1).max(1);
        let (epoch, k) = (key.index / n, key.index % n);
        let mut jitter = SampleStream::new(key.seed ^ 0x57a7_1f1e_d000_0003, key.strategy, key.pixel, key.index);
        let base = mix64(mix64(mix64(key.seed ^ 0x57a7) ^ key.strategy) ^ key.pixel) ^ epoch;
        let unit = |cell: u64, cells: u64, j: f32| -> f32 {
            let v = ((cell as f64 + j as f64) / cells as f64) as f32;
            v.min(super::stream::ONE_MINUS_EPSILON)
        };
        for (g, (start, d)) in setup.layout.offsets().enumerate() {
            if start >= out.len() {
                break;
            }
            let cell = permute(k, n, mix64(base ^ (g as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15)));
            if d.width == 2 && start + 1 < out.len() {
                let (nx, ny) = grid(n);
                let [jx, jy] = jitter.next_2d();
                out[start] = unit(cell % nx, nx, jx);
                out[start + 1] = unit(cell / nx, ny, jy);
            } else {
                out[start] = unit(cell, n, jitter.next_1d());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permute_is_a_bijection() {
        for n in [1u64, 2, 3, 7, 16, 100, 257] {
            for seed in 0..5 {
                let mut v: Vec<u64> = (0..n).map(|k| permute(k, n, seed)).collect();
                v.sort_unstable();
                assert_eq!(v, (0..n).collect::<Vec<_>>(), "n {n}");
            }
        }
        assert_eq!(grid(16), (4, 4));
        assert_eq!(grid(8), (2, 4));
        assert_eq!(grid(7), (1, 7));
    }
}
