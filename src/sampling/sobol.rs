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

use super::generator::{LaneValues, SampleGenerator, SampleKey, SampleKeys, Setup};
use super::qmc::{owen_lanes, scrambled_pair, scrambled_point_lanes, LaneGroups, store_point_lanes};
use crate::math::mix64_lanes;
use crate::simd::{Isa, Kernel, Lanes, Mask, VectorU64};

pub struct Sobol;

pub static SOBOL: Sobol = Sobol;

/// The seed every group of a sample key's sequence derives from (index epoch included).
pub fn sequence_seed(key: &SampleKey, epoch: u64) -> u64 {
    sequence_seed_lanes::<u64, 1>(key.seed, key.strategy, key.pixel, epoch)
}

/// [`sequence_seed`] of every lane's key.
#[inline(always)]
fn sequence_seed_lanes<U: VectorU64<N>, const N: usize>(seed: U, strategy: U, pixel: U, epoch: U) -> U {
    let run = mix64_lanes(seed.xor(U::splat(0x50b0_1d5e_ed00_0001)));
    mix64_lanes(run.xor(strategy).xor(mix64_lanes(pixel.xor(epoch.shl(40)))))
}

/// The seed of layout group `group` of the sequence seeded `sequence` (`owen` hashes it again,
/// so a distinct odd multiple per group suffices).
pub fn group_seed(sequence: u64, group: usize) -> u64 {
    sequence ^ group_key(group)
}

fn group_key(group: usize) -> u64 {
    (group as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15)
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

    /// The packet's sixteen sequences side by side over the lane layer's u64 lanes, in the
    /// CPU's ISA (inactive lanes are computed too; their values are unspecified): the same
    /// numbers as [`Self::fill`] (`lanes_fill_as_single_samples`, `every_isa_fills_as_one_sample`).
    fn fill_lanes(
        &self,
        setup: &Setup,
        keys: &SampleKeys,
        _lanes: Mask,
        dims: usize,
        out: &mut LaneValues,
    ) {
        crate::simd::run(Isa::best(), FillLanes::new(setup, keys, dims, out));
    }
}

/// [`Sobol::fill_lanes`] as a lane kernel: the layout's groups that fall below `dims` (each's
/// first dimension, and whether it is a pair there), and the keys as lanes.
struct FillLanes<'a> {
    groups: LaneGroups,
    keys: &'a SampleKeys,
    out: &'a mut LaneValues,
}

impl<'a> FillLanes<'a> {
    fn new(
        setup: &Setup,
        keys: &'a SampleKeys,
        dims: usize,
        out: &'a mut LaneValues,
    ) -> Self {
        FillLanes {
            groups: LaneGroups::of(setup, dims),
            keys,
            out,
        }
    }
}

impl Kernel for FillLanes<'_> {
    type Out = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        let load = L::U::load;
        let k = &self.keys;
        let index = load(&k.index);
        let sequence =
            sequence_seed_lanes(load(&k.seed), load(&k.strategy), load(&k.pixel), index.shr(32));
        let i = index.and(L::U::splat(0xffff_ffff));
        for (g, &(start, pair)) in self.groups.as_slice().iter().enumerate() {
            let seed = sequence.xor(L::U::splat(group_key(g)));
            let [x, y] = scrambled_point_lanes(owen_lanes(i, seed), seed, pair);
            store_point_lanes([x, y], start, pair, self.out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::generator::assert_every_isa_fills_as_one_sample;
    use crate::simd::WIDTH;
    use crate::sampling::{Dimension, Layout};

    /// Every ISA's packet fill gives each lane's single-sample numbers, for keys that differ
    /// in every field, index epochs past 2³² included (integer lanes: nothing may differ).
    #[test]
    fn every_isa_fills_as_one_sample() {
        let layout = Layout::of(&[Dimension::pair("a"), Dimension::one("b"), Dimension::pair("c")]);
        let setup = Setup::image(layout, None, 64, 64);
        // 6 of the 7 dimensions: the last pair is cut to one.
        let dims = 6;
        let keys: [SampleKey; WIDTH] = std::array::from_fn(|i| SampleKey {
            seed: 9 + (i as u64 % 2),
            strategy: 0x5eed + (i as u64 % 3),
            pixel: i as u64 * 1_000_003,
            index: [0, 1, 7, u32::MAX as u64, 1 << 32, u64::MAX][i % 6].wrapping_sub(i as u64 / 6),
        });
        assert_every_isa_fills_as_one_sample(
            &SOBOL,
            &setup,
            &keys,
            dims,
            |isa, got| crate::simd::run(isa, FillLanes::new(&setup, &SampleKeys::of(&keys), dims, got)),
            "",
        );
    }
}
