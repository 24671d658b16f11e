//! Deterministic random streams: one PCG32 stream per (seed, strategy, pixel, pass), so an image
//! depends on the seed and never on thread scheduling or tile order.

use crate::math::{mix64, mix64_lanes};
use crate::simd::{Vector, VectorU64, WIDTH};

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

/// XSH-RR of every lane (O'Neill 2014, §6.3.1): xorshift the high bits down, then rotate the
/// 32-bit word by the top five bits; each output in the low half of its lane. The rotation is
/// the word doubled into 64 bits and shifted right.
#[inline(always)]
fn xsh_rr<U: VectorU64<N>, const N: usize>(state: U) -> U {
    let low = U::splat(0xffff_ffff);
    let xsh = state.shr(18).xor(state).shr(27).and(low);
    xsh.or(xsh.shl(32)).shr_lanes(state.shr(59)).and(low)
}

/// One LCG step of every lane.
#[inline(always)]
fn step<U: VectorU64<N>, const N: usize>(state: U, increment: U) -> U {
    state.mul(U::splat(MULTIPLIER)).add(increment)
}

/// `seed_from_u64` of every lane: four words of a PCG32 started at `key` (advanced before
/// each output) form the little-endian state and stream; the increment is made odd, added
/// once, and the LCG stepped once. Returns (state, increment).
#[inline(always)]
fn seeded<U: VectorU64<N>, const N: usize>(key: U) -> (U, U) {
    let seed_increment = U::splat(SEED_INCREMENT);
    let s1 = step(key, seed_increment);
    let s2 = step(s1, seed_increment);
    let s3 = step(s2, seed_increment);
    let s4 = step(s3, seed_increment);
    let state = xsh_rr(s1).or(xsh_rr(s2).shl(32));
    let increment = xsh_rr(s3).or(xsh_rr(s4).shl(32)).or(U::splat(1));
    (step(state.add(increment), increment), increment)
}

/// The largest f32 below 1: samples live in [0, 1).
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// 2⁻²⁴: a 24-bit integer times it is exactly its value as a fraction in [0, 1).
const TO_UNIT: f32 = 1.0 / 16_777_216.0;

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
        let (state, increment) = Self::keyed_lanes(base, pixel, pass);
        SampleStream { state, increment }
    }

    /// [`Self::keyed`] of every lane, written once over lanes (scalar code is one `u64`
    /// lane): the (state, increment) of each lane's stream. Integer operations only, so every
    /// ISA gives the same bits.
    #[inline(always)]
    pub fn keyed_lanes<U: VectorU64<N>, const N: usize>(base: U, pixel: U, pass: U) -> (U, U) {
        let pass = pass.mul(U::splat(0x9E37_79B9_7F4A_7C15));
        seeded(mix64_lanes(mix64_lanes(base.xor(pixel)).xor(pass)))
    }

    /// `seed_from_u64(key)`.
    #[cfg(test)]
    fn from_u64(key: u64) -> Self {
        let (state, increment) = seeded(key);
        SampleStream { state, increment }
    }

    /// Every lane's next output as its top 24 bits (an integer below 2²⁴; times 2⁻²⁴ it is
    /// [`Self::next_1d`]), its state stepped.
    #[inline(always)]
    pub fn next_24_lanes<U: VectorU64<N>, const N: usize>(state: &mut U, increment: U) -> U {
        let old = *state;
        *state = step(old, increment);
        xsh_rr(old).shr(8)
    }

    #[cfg(test)]
    fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = step(old, self.increment);
        xsh_rr(old) as u32
    }

    /// Uniform in [0, 1): the top 24 bits, exactly representable.
    #[inline(always)]
    pub fn next_1d(&mut self) -> f32 {
        Self::next_24_lanes(&mut self.state, self.increment) as f32 * TO_UNIT
    }

    pub fn next_2d(&mut self) -> [f32; 2] {
        [self.next_1d(), self.next_1d()]
    }
}

/// [`SampleStream::next_1d`] of the streams of `state` (lanes), as f32 lanes in `out`.
#[inline(always)]
pub fn next_1d_lanes<V: Vector<WIDTH>, U: VectorU64<WIDTH>>(
    state: &mut U,
    increment: U,
    out: &mut [f32; WIDTH],
) {
    SampleStream::next_24_lanes(state, increment).to_f32(out);
    V::load(out).mul(V::splat(TO_UNIT)).store(out);
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
