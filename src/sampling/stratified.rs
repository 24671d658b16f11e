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

use super::generator::{LaneValues, SampleGenerator, SampleKey, SampleKeys, Setup};
use super::qmc::LaneGroups;
use super::stream::{ONE_MINUS_EPSILON, SampleStream, next_1d_lanes};
use crate::math::mix64_lanes;
use crate::simd::{Isa, Kernel, Lanes, Mask, VectorU64, WIDTH};

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
    let walk = Walk::of(n);
    let keys = Walk::keys_lanes::<u64, 1>(seed);
    walk.finish(walk.step_lanes(k, keys), keys)
}

/// [`permute`]'s cycle walk for n strata: the bits below the next power of two of n, and the
/// hash's two shifts.
#[derive(Clone, Copy)]
struct Walk {
    n: u64,
    mask: u64,
    shifts: [u32; 2],
}

impl Walk {
    fn of(n: u64) -> Self {
        let bits = match n {
            0 | 1 => 0,
            n => 64 - (n - 1).leading_zeros(),
        };
        let mask = if bits == 64 { u64::MAX } else { (1u64 << bits) - 1 };
        Walk {
            n,
            mask,
            shifts: [bits / 2 + 1, bits / 3 + 1],
        }
    }

    /// The hash's keys from a permutation's seed: the two odd multipliers and the xor.
    #[inline(always)]
    fn keys_lanes<U: VectorU64<N>, const N: usize>(seed: U) -> [U; 3] {
        let a = mix64_lanes(seed).or(U::splat(1));
        let a2 = a.xor(U::splat(0x9E37_79B9_7F4A_7C16)).or(U::splat(1));
        [a, a2, mix64_lanes(seed.xor(U::splat(0x7f4a_7c15)))]
    }

    /// One step of the walk. Each line is a bijection of 0..2^bits: xor with a constant,
    /// multiply by an odd number, xor with a right shift of itself.
    #[inline(always)]
    fn step_lanes<U: VectorU64<N>, const N: usize>(self, x: U, [a, a2, b]: [U; 3]) -> U {
        let mask = U::splat(self.mask);
        let x = x.xor(b.and(mask)).mul(a).and(mask);
        let x = x.xor(x.shr(self.shifts[0]));
        let x = x.mul(a2).and(mask);
        x.xor(x.shr(self.shifts[1]))
    }

    /// The walk continued from `x` (a first step's result) until it lands below n.
    #[inline(always)]
    fn finish(self, mut x: u64, keys: [u64; 3]) -> u64 {
        while x >= self.n {
            x = self.step_lanes(x, keys);
        }
        x
    }
}

/// The strata of one layout group: the permutation's seed from the sample's key hash.
#[inline(always)]
fn group_seed_lanes<U: VectorU64<N>, const N: usize>(base: U, group: usize) -> U {
    mix64_lanes(base.xor(U::splat((group as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15))))
}

/// The key hash every group's permutation seed derives from (the epoch is which run of n
/// samples `index` is in).
#[inline(always)]
fn sample_hash_lanes<U: VectorU64<N>, const N: usize>(seed: U, strategy: U, pixel: U, epoch: U) -> U {
    let h = mix64_lanes(mix64_lanes(seed.xor(U::splat(0x57a7))).xor(strategy));
    mix64_lanes(h.xor(pixel)).xor(epoch)
}

/// The jitter streams' family: the sample's stream with its seed moved.
fn jitter_seed(seed: u64) -> u64 {
    seed ^ 0x57a7_1f1e_d000_0003
}

/// Stratum `cell` of `cells`, jittered by `j`, as a number in [0, 1).
#[inline(always)]
fn unit(cell: u64, cells: u64, j: f32) -> f32 {
    let v = ((cell as f64 + j as f64) / cells as f64) as f32;
    v.min(ONE_MINUS_EPSILON)
}

/// Writes a group's point from its stratum `cell`: one number, or a pair's two on the grid.
#[inline(always)]
fn store_group(out: &mut [f32], start: usize, pair: bool, cell: u64, strata: Strata, j: [f32; 2]) {
    if pair {
        out[start] = unit(cell % strata.nx, strata.nx, j[0]);
        out[start + 1] = unit(cell / strata.nx, strata.ny, j[1]);
    } else {
        out[start] = unit(cell, strata.walk.n, j[0]);
    }
}

/// The strata of n samples: the walk for a single dimension, the grid for a pair.
#[derive(Clone, Copy)]
struct Strata {
    walk: Walk,
    nx: u64,
    ny: u64,
}

impl Strata {
    fn of(setup: &Setup) -> Self {
        let n = setup.spp.unwrap_or(1).max(1);
        let (nx, ny) = grid(n);
        Strata {
            walk: Walk::of(n),
            nx,
            ny,
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
        let strata = Strata::of(setup);
        let n = strata.walk.n;
        let (epoch, k) = (key.index / n, key.index % n);
        let mut jitter = SampleStream::new(jitter_seed(key.seed), key.strategy, key.pixel, key.index);
        let base = sample_hash_lanes::<u64, 1>(key.seed, key.strategy, key.pixel, epoch);
        for (g, &(start, pair)) in LaneGroups::of(setup, out.len()).as_slice().iter().enumerate() {
            let keys = Walk::keys_lanes::<u64, 1>(group_seed_lanes::<u64, 1>(base, g));
            let cell = strata.walk.finish(strata.walk.step_lanes(k, keys), keys);
            let j = if pair { jitter.next_2d() } else { [jitter.next_1d(), 0.0] };
            store_group(out, start, pair, cell, strata, j);
        }
    }

    /// The packet's hashes, first walk steps and jitter streams side by side over the lane
    /// layer's u64 lanes; each lane's walk continues on its own where its first step lands
    /// past n (never when n is a power of two). The same numbers as [`Self::fill`]
    /// (`every_isa_fills_as_one_sample`).
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

/// [`Stratified::fill_lanes`] as a lane kernel.
struct FillLanes<'a> {
    groups: LaneGroups,
    strata: Strata,
    keys: &'a SampleKeys,
    jitter_base: [u64; WIDTH],
    epoch: [u64; WIDTH],
    k: [u64; WIDTH],
    out: &'a mut LaneValues,
}

impl<'a> FillLanes<'a> {
    fn new(
        setup: &Setup,
        keys: &'a SampleKeys,
        dims: usize,
        out: &'a mut LaneValues,
    ) -> Self {
        let strata = Strata::of(setup);
        let n = strata.walk.n;
        FillLanes {
            groups: LaneGroups::of(setup, dims),
            strata,
            keys,
            jitter_base: std::array::from_fn(|i| {
                SampleStream::base(jitter_seed(keys.seed[i]), keys.strategy[i])
            }),
            epoch: keys.index.map(|i| i / n),
            k: keys.index.map(|i| i % n),
            out,
        }
    }
}

impl Kernel for FillLanes<'_> {
    type Out = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        let load = L::U::load;
        let (keys, walk) = (&self.keys, self.strata.walk);
        let (mut state, increment) =
            SampleStream::keyed_lanes(load(&self.jitter_base), load(&keys.pixel), load(&keys.index));
        let base = sample_hash_lanes(load(&keys.seed), load(&keys.strategy), load(&keys.pixel), load(&self.epoch));
        let k = load(&self.k);
        let (mut j0, mut j1) = ([0.0f32; WIDTH], [0.0f32; WIDTH]);
        for (g, &(start, pair)) in self.groups.as_slice().iter().enumerate() {
            let hash = Walk::keys_lanes(group_seed_lanes(base, g));
            let mut first = [0u64; WIDTH];
            walk.step_lanes(k, hash).store(&mut first);
            let mut h = [[0u64; WIDTH]; 3];
            for (h, lanes) in h.iter_mut().zip(hash) {
                lanes.store(h);
            }
            next_1d_lanes::<L::V, L::U>(&mut state, increment, &mut j0);
            if pair {
                next_1d_lanes::<L::V, L::U>(&mut state, increment, &mut j1);
            }
            for i in 0..WIDTH {
                let cell = walk.finish(first[i], [h[0][i], h[1][i], h[2][i]]);
                let mut v = [0.0f32; 2];
                store_group(&mut v, 0, pair, cell, self.strata, [j0[i], j1[i]]);
                self.out[start][i] = v[0];
                if pair {
                    self.out[start + 1][i] = v[1];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::generator::assert_every_isa_fills_as_one_sample;

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

    /// Every ISA's packet fill gives each lane's single-sample numbers, for sample counts whose
    /// walks take more than one step (not powers of two) and keys that differ in every field,
    /// over several epochs (integer lanes and the same f64 arithmetic: nothing may differ).
    #[test]
    fn every_isa_fills_as_one_sample() {
        use crate::sampling::{Dimension, Layout};
        let layout = Layout::of(&[Dimension::pair("a"), Dimension::one("b"), Dimension::pair("c")]);
        for spp in [1, 7, 100, 256, 1000] {
            let setup = Setup::image(layout.clone(), Some(spp), 64, 64);
            // 6 of the 7 dimensions: the last pair is cut to one.
            let dims = 6;
            let keys: [SampleKey; WIDTH] = std::array::from_fn(|i| SampleKey {
                seed: 9 + (i as u64 % 2),
                strategy: 0x5eed + (i as u64 % 3),
                pixel: i as u64 * 1_000_003,
                index: i as u64 * 37 + [0, spp - 1, 5 * spp][i % 3],
            });
            assert_every_isa_fills_as_one_sample(
                &STRATIFIED,
                &setup,
                &keys,
                dims,
                |isa, got| crate::simd::run(isa, FillLanes::new(&setup, &SampleKeys::of(&keys), dims, got)),
                &format!("spp {spp}"),
            );
        }
    }
}
