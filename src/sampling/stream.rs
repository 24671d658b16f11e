//! Deterministic random streams: one PCG32 stream per (seed, strategy, pixel, pass), so an image
//! depends on the seed and never on thread scheduling or tile order.

use crate::math::mix64_lanes;
use crate::simd::{Vector, VectorU64, WIDTH};

/// PCG32 (O'Neill 2014: 64-bit LCG state, XSH-RR output). A key's stream is the crate's
/// `rand_pcg::Pcg32::new(state, stream)` (the `matches_rand_pcg` test), its LCG stream (the
/// increment) hashed from (seed, strategy, pixel) and its start from that and the pass
/// ([`SampleStream::key_words`]). One stream is seeded per pixel and pass and only a handful
/// of values are drawn from each, so seeding is much of the cost: here it is two SplitMix64
/// finalisers and one LCG step. (`seed_from_u64`'s seeding, which the streams followed up to
/// stop 42, draws four words from a second PCG32 on top: five more 64-bit multiplies and four
/// output permutations per sample, which AVX2 emulates; docs/tracer.md, stop 43.)
pub struct SampleStream {
    state: u64,
    increment: u64,
}

/// PCG's 64-bit LCG multiplier (O'Neill 2014, §4.3.1).
const MULTIPLIER: u64 = 6_364_136_223_846_793_005;

/// XSH-RR of every lane (O'Neill 2014, §6.3.1): xorshift the high bits down, then rotate the
/// 32-bit word by the top five bits; each output in the low half of its lane.
#[inline(always)]
fn xsh_rr<U: VectorU64<N>, const N: usize>(state: U) -> U {
    state.shr(18).xor(state).shr(27).rotr32(state.shr(59))
}

/// One LCG step of every lane.
#[inline(always)]
fn step<U: VectorU64<N>, const N: usize>(state: U, increment: U) -> U {
    state.mul(U::splat(MULTIPLIER)).add(increment)
}

/// `rand_pcg::Pcg32::new(state, stream)` of every lane: the increment is the stream made odd,
/// added to the state once, and the LCG stepped once. Returns (state, increment).
#[inline(always)]
fn pcg32_new<U: VectorU64<N>, const N: usize>(state: U, stream: U) -> (U, U) {
    let increment = stream.shl(1).or(U::splat(1));
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
        Self::base_lanes(seed, strategy)
    }

    /// [`Self::base`] of every lane.
    #[inline(always)]
    pub fn base_lanes<U: VectorU64<N>, const N: usize>(seed: U, strategy: U) -> U {
        mix64_lanes(seed.xor(mix64_lanes(strategy)))
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
        Self::streamed_lanes(Self::stream_word(base, pixel), pass)
    }

    /// The PCG32 (state, stream) words of a key: the stream is a hash of (`base`, pixel), so
    /// each pixel draws from an LCG sequence of its own, and the start is a hash of that and
    /// the pass, so a pixel's passes start at unrelated points of it (two passes' draws
    /// overlap with a chance of about draws/2⁶⁴ per pair).
    #[inline(always)]
    pub fn key_words<U: VectorU64<N>, const N: usize>(base: U, pixel: U, pass: U) -> (U, U) {
        let stream = Self::stream_word(base, pixel);
        (Self::start_word(stream, pass), stream)
    }

    /// A key's stream word, from (`base`, pixel) alone: a packet of one pixel's samples
    /// hashes it once.
    #[inline(always)]
    pub fn stream_word<U: VectorU64<N>, const N: usize>(base: U, pixel: U) -> U {
        mix64_lanes(base.xor(pixel))
    }

    #[inline(always)]
    fn start_word<U: VectorU64<N>, const N: usize>(stream: U, pass: U) -> U {
        mix64_lanes(stream.xor(pass.mul(U::splat(0x9E37_79B9_7F4A_7C15))))
    }

    /// [`Self::keyed_lanes`] from each lane's [`Self::stream_word`] and pass.
    #[inline(always)]
    pub fn streamed_lanes<U: VectorU64<N>, const N: usize>(stream: U, pass: U) -> (U, U) {
        pcg32_new(Self::start_word(stream, pass), stream)
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
    use crate::math::mix64;
    use rand_core::RngCore;

    /// Every stream is the crate's `Pcg32::new(state, stream)` stream, word for word, over
    /// words that exercise every bit (zero, all ones, SplitMix outputs).
    #[test]
    fn matches_rand_pcg() {
        let words = (0..2000u64).map(|i| (mix64(i), mix64(i ^ 0x5eed))).chain([
            (0, 0),
            (1, u64::MAX),
            (u64::MAX, 1 << 63),
            (0x5555_5555_5555_5555, 0),
        ]);
        for (state, stream) in words {
            let (s, increment) = pcg32_new(state, stream);
            let mut ours = SampleStream {
                state: s,
                increment,
            };
            let mut theirs = rand_pcg::Pcg32::new(state, stream);
            for draw in 0..24 {
                assert_eq!(
                    ours.next_u32(),
                    theirs.next_u32(),
                    "words {state:#x} {stream:#x}, draw {draw}"
                );
            }
        }
    }

    /// The streams of a block of pixels and passes (neighbouring keys, the most alike) share
    /// no pair of consecutive outputs, within a stream or across streams, and the first
    /// outputs of neighbouring passes and of neighbouring pixels do not correlate
    /// (|r| < 5/√n). Controls: a key that ignores the pass (each pixel's passes one stream)
    /// and one that ignores the pixel are caught.
    #[test]
    fn neighbouring_keys_give_unrelated_streams() {
        fn check(words: impl Fn(u64, u64, u64) -> (u64, u64)) -> Result<(), String> {
            let (pixels, passes, draws) = (64usize, 128usize, 8);
            let base = SampleStream::base(3, 0x11);
            let mut seen = std::collections::HashSet::new();
            let mut first = vec![vec![0.0f64; passes]; pixels];
            for (pixel, row) in first.iter_mut().enumerate() {
                for (pass, x) in row.iter_mut().enumerate() {
                    let (state, stream) = words(base, pixel as u64, pass as u64);
                    let (state, increment) = pcg32_new(state, stream);
                    let mut s = SampleStream { state, increment };
                    let out: Vec<u64> = (0..draws).map(|_| s.next_u32() as u64).collect();
                    *x = out[0] as f64;
                    for pair in out.windows(2) {
                        if !seen.insert(pair[0] << 32 | pair[1]) {
                            return Err(format!("pixel {pixel} pass {pass} repeats a pair"));
                        }
                    }
                }
            }
            let by_pass: (Vec<f64>, Vec<f64>) = first
                .iter()
                .flat_map(|row| row.windows(2).map(|w| (w[0], w[1])))
                .unzip();
            let by_pixel: (Vec<f64>, Vec<f64>) = first
                .windows(2)
                .flat_map(|w| w[0].iter().copied().zip(w[1].iter().copied()))
                .unzip();
            for (what, (a, b)) in [("passes", by_pass), ("pixels", by_pixel)] {
                let r = crate::stats::correlation(&a, &b);
                if r.abs() >= 5.0 / (a.len() as f64).sqrt() {
                    return Err(format!("neighbouring {what} correlate: r = {r}"));
                }
            }
            Ok(())
        }
        check(SampleStream::key_words).unwrap();
        assert!(check(|b, px, _| SampleStream::key_words(b, px, 0)).is_err());
        assert!(check(|b, _, pass| SampleStream::key_words(b, 0, pass)).is_err());
    }
}
