//! Deterministic random streams: one PCG32 stream per (seed, strategy, pixel, pass), so an image
//! depends on the seed and never on thread scheduling or tile order.

use crate::math::mix64;
use crate::simd::WIDTH;

/// PCG32 (O'Neill 2014: 64-bit LCG state, XSH-RR output), seeded exactly as
/// `rand_pcg::Pcg32::seed_from_u64` seeds it, so every stream is bit-identical to the crate's
/// (the `matches_rand_pcg` test). Written out because the crate's byte-wise seeding was 12 % of
/// a `light` sample on `cornell` (`perf record`, one thread): one stream is seeded per pixel and
/// pass, and only a handful of values are drawn from each.
pub struct SampleStream {
    state: u64,
    increment: u64,
}

/// PCG's 64-bit LCG multiplier (O'Neill 2014, §4.3.1).
const MULTIPLIER: u64 = 6_364_136_223_846_793_005;
/// The increment of the PCG32 that `SeedableRng::seed_from_u64` draws seed words from.
const SEED_INCREMENT: u64 = 11_634_580_027_462_260_723;

/// XSH-RR: xorshift the high bits down, then rotate by the top five.
#[inline(always)]
fn xsh_rr(state: u64) -> u32 {
    let xsh = (((state >> 18) ^ state) >> 27) as u32;
    xsh.rotate_right((state >> 59) as u32)
}

/// The largest f32 below 1: samples live in [0, 1).
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

impl SampleStream {
    #[inline]
    pub fn new(seed: u64, strategy: u64, pixel: u64, pass: u64) -> Self {
        Self::keyed(Self::base(seed, strategy), pixel, pass)
    }

    /// The part of a stream's key shared by every sample of one (seed, strategy): a render
    /// computes it once per packet, not once per sample.
    #[inline]
    pub fn base(seed: u64, strategy: u64) -> u64 {
        mix64(seed ^ mix64(strategy))
    }

    /// The stream of (`base`, pixel, pass): `new(seed, strategy, pixel, pass)` for
    /// `base = Self::base(seed, strategy)`.
    #[inline]
    pub fn keyed(base: u64, pixel: u64, pass: u64) -> Self {
        Self::from_u64(mix64(
            mix64(base ^ pixel) ^ pass.wrapping_mul(0x9E37_79B9_7F4A_7C15),
        ))
    }

    /// `seed_from_u64`: four words of a PCG32 started at `key` (advanced before each output)
    /// form the little-endian state and stream; the increment is made odd, added once, and the
    /// LCG stepped once.
    #[inline(always)]
    fn from_u64(key: u64) -> Self {
        let mut s = key;
        let mut word = || {
            s = s.wrapping_mul(MULTIPLIER).wrapping_add(SEED_INCREMENT);
            xsh_rr(s) as u64
        };
        let state = word() | word() << 32;
        let increment = (word() | word() << 32) | 1;
        let state = state
            .wrapping_add(increment)
            .wrapping_mul(MULTIPLIER)
            .wrapping_add(increment);
        SampleStream { state, increment }
    }

    /// Sixteen streams side by side: the (state, increment) of `keyed(base[i], pixel[i],
    /// pass[i])` for every lane i, written as plain loops over lanes. Called inside a SIMD
    /// layer kernel they are compiled for its ISA and vectorise; integer operations only, so
    /// every ISA gives the same bits.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // index loops are what vectorise here
    pub fn keyed_lanes(
        base: &[u64; WIDTH],
        pixel: &[u64; WIDTH],
        pass: &[u64; WIDTH],
    ) -> ([u64; WIDTH], [u64; WIDTH]) {
        // Plain loops, not `array::from_fn`: its closure is not inlined into the ISA's entry,
        // and would run as scalar code outside it.
        let mut key = [0u64; WIDTH];
        for i in 0..WIDTH {
            key[i] = mix64(mix64(base[i] ^ pixel[i]) ^ pass[i].wrapping_mul(0x9E37_79B9_7F4A_7C15));
        }
        let mut words = [[0u64; WIDTH]; 4];
        for w in &mut words {
            for (k, w) in key.iter_mut().zip(w.iter_mut()) {
                *k = k.wrapping_mul(MULTIPLIER).wrapping_add(SEED_INCREMENT);
                *w = xsh_rr(*k) as u64;
            }
        }
        let (mut state, mut increment) = ([0u64; WIDTH], [0u64; WIDTH]);
        for i in 0..WIDTH {
            increment[i] = (words[2][i] | words[3][i] << 32) | 1;
            state[i] = (words[0][i] | words[1][i] << 32)
                .wrapping_add(increment[i])
                .wrapping_mul(MULTIPLIER)
                .wrapping_add(increment[i]);
        }
        (state, increment)
    }

    /// [`Self::next_1d`] of each of sixteen streams given as (state, increment) lanes.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    pub fn next_1d_lanes(state: &mut [u64; WIDTH], increment: &[u64; WIDTH]) -> [f32; WIDTH] {
        let mut out = [0.0f32; WIDTH];
        for i in 0..WIDTH {
            let old = state[i];
            state[i] = old.wrapping_mul(MULTIPLIER).wrapping_add(increment[i]);
            out[i] = (xsh_rr(old) >> 8) as f32 * (1.0 / 16_777_216.0);
        }
        out
    }

    #[inline(always)]
    fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(MULTIPLIER).wrapping_add(self.increment);
        xsh_rr(old)
    }

    /// Uniform in [0, 1): the top 24 bits, exactly representable.
    #[inline(always)]
    pub fn next_1d(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    pub fn next_2d(&mut self) -> [f32; 2] {
        [self.next_1d(), self.next_1d()]
    }
}

/// A stable 64-bit id of a name (FNV-1a), so a strategy's random stream does not depend on its
/// position in the registry.
pub fn name_id(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::{RngCore, SeedableRng};

    /// Every stream is the crate's `Pcg32::seed_from_u64(key)` stream, word for word, over keys
    /// that exercise every bit of the state (zero, all ones, SplitMix outputs) — so images made
    /// before the stream was written out are unchanged.
    #[test]
    fn matches_rand_pcg() {
        let keys = (0..2000u64)
            .map(mix64)
            .chain([0, 1, u64::MAX, 1 << 63, 0x5555_5555_5555_5555]);
        for key in keys {
            let mut ours = SampleStream::from_u64(key);
            let mut theirs = rand_pcg::Pcg32::seed_from_u64(key);
            for draw in 0..24 {
                assert_eq!(
                    ours.next_u32(),
                    theirs.next_u32(),
                    "key {key:#x}, draw {draw}"
                );
            }
        }
    }
}
