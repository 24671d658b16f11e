//! Owen-scrambled Sobol points, one randomized sequence per (seed, strategy, pixel)
//! (Burley 2020, "Practical Hash-based Owen Scrambling"). Sample index k of a pixel is point k
//! of its sequence; each layout group (a `Dimension::pair` or a single dimension) draws from
//! its own copy: a pair takes Sobol dimensions 0 and 1 at a shuffled index, a single dimension
//! Sobol dimension 0 (scrambled van der Corput) at another shuffle, each coordinate Owen-
//! scrambled with its own seed (`qmc`). So the first 2^m samples of a pixel are, in every pair,
//! a (0,m,2)-net, and in every single dimension one point per interval of length 2^-m; a prefix
//! that is not a power of two is a less balanced but still valid point set, and every point is
//! uniform on [0,1)^d over the randomization (an unbiased estimator).
//!
//! The seed's role: a run's seed selects every scramble, so runs with different seeds are
//! independent randomizations, and the strategy id and pixel enter every group's seed, so two
//! strategies or pixels never share points. Past 2^32 samples of a pixel the index wraps into
//! a fresh randomization (an epoch in the seed).

use super::generator::{SampleGenerator, SampleKey, Setup};
use super::qmc::scrambled_pair;
use crate::math::mix64;

pub struct Sobol;

pub static SOBOL: Sobol = Sobol;

/// The seed every group of a sample key's sequence derives from (index epoch included).
pub fn sequence_seed(key: &SampleKey, epoch: u64) -> u64 {
    mix64(mix64(key.seed ^ 0x50b0_1d5e_ed00_0001) ^ key.strategy ^ mix64(key.pixel ^ (epoch << 40)))
}

/// The seed of layout group `group` of the sequence seeded `sequence` (`owen` hashes it again,
/// so a distinct odd multiple per group suffices).
pub fn group_seed(sequence: u64, group: usize) -> u64 {
    sequence ^ (group as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

/// Fills `out` group by group from `setup.layout`: the point of index `i` (of one epoch) with
/// each group's seed from `seed_of(group)`.
pub fn fill_groups(setup: &Setup, i: u32, seed_of: impl Fn(usize) -> u64, out: &mut [f32]) {
    for (g, (start, d)) in setup.layout.offsets().enumerate() {
        if start >= out.len() {
            break;
        }
        let pair = d.width == 2 && start + 1 < out.len();
        let [x, y] = scrambled_pair(i, seed_of(g), pair);
        out[start] = x;
        if pair {
            out[start + 1] = y;
        }
    }
}

impl SampleGenerator for Sobol {
    fn name(&self) -> &'static str {
        "sobol"
    }

    fn describe(&self) -> &'static str {
        "Owen-scrambled Sobol (0,2)-sequence per pixel and layout pair (Burley 2020), seeded per run"
    }

    fn fill(&self, setup: &Setup, key: SampleKey, out: &mut [f32]) {
        let sequence = sequence_seed(&key, key.index >> 32);
        fill_groups(setup, key.index as u32, |g| group_seed(sequence, g), out);
    }
}
