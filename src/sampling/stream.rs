//! Deterministic random streams: one PCG32 stream per (seed, strategy, pixel, pass), so an image
//! depends on the seed and never on thread scheduling or tile order.

use crate::math::mix64;
use rand_core::{RngCore, SeedableRng};
use rand_pcg::Pcg32;

pub struct SampleStream(Pcg32);

/// The largest f32 below 1: samples live in [0, 1).
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

impl SampleStream {
    pub fn new(seed: u64, strategy: u64, pixel: u64, pass: u64) -> Self {
        let key = mix64(
            mix64(mix64(seed ^ mix64(strategy)) ^ pixel) ^ pass.wrapping_mul(0x9E37_79B9_7F4A_7C15),
        );
        SampleStream(Pcg32::seed_from_u64(key))
    }

    /// Uniform in [0, 1): the top 24 bits, exactly representable.
    pub fn next_1d(&mut self) -> f32 {
        (self.0.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
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
