//! Z-Sobol (Ahmed & Wonka 2020, "Screen-Space Blue-Noise Diffusion of Monte Carlo Sampling
//! Error via Hierarchical Ordering of Pixels"; pbrt-v4's `ZSobolSampler`): one Owen-scrambled
//! Sobol sequence for the whole image, each pixel taking a block of 2^L consecutive indices in
//! Morton (Z) order, with the Morton code's base-4 digits randomly permuted — each digit by a
//! permutation of {0,1,2,3} chosen by a hash of the digits above it, the dimension group and
//! the seed — so the four pixels of every 2×2 quad (and quad of quads) share one net in a
//! random order, which spreads the error as blue noise across pixels.
//!
//! Differences from pbrt-v4, by design: the sample-index digits below the Morton code are
//! scrambled in base 2 (an Owen shuffle of the index), not base 4, so *every* prefix of 2^m
//! samples of a pixel is a (0,m,2)-net in each pair (pbrt's base-4 digits guarantee it for
//! powers of 4); and L is ⌈log2 spp⌉ when the sample count is known (`Setup::spp`), else 16
//! (65 536 samples per block; past it the index wraps into a fresh randomization). Under a
//! time budget the spp is not known, so the pixels' blocks are 2^16 apart and the cross-pixel
//! (blue-noise) part of the construction only takes effect once a pixel completes its block:
//! at equal time Z-Sobol is then a per-pixel Owen-Sobol with a differently hashed scramble.
//! The Sobol point is taken from the low 32 bits of the permuted index; the bits above seed
//! the coordinates' scrambles, so large images still get distinct points.

use super::generator::{SampleGenerator, SampleKey, Setup};
use super::qmc::{ceil_log2, morton_2d, owen, scrambled_point};
use crate::math::mix64;

pub struct ZSobol;

pub static ZSOBOL: ZSobol = ZSobol;

/// log2 of the per-pixel block when the sample count is unknown.
pub const DEFAULT_LOG2_BLOCK: u32 = 16;

/// The 24 permutations of {0,1,2,3}, in lexicographic order.
const PERMUTATIONS: [[u8; 4]; 24] = permutations();

const fn permutations() -> [[u8; 4]; 24] {
    let mut out = [[0u8; 4]; 24];
    let mut n = 0;
    let mut code = 0u32;
    // Every word of four base-4 digits whose digits are distinct, in increasing order.
    while code < 256 {
        let d = [
            (code >> 6) as u8 & 3,
            (code >> 4) as u8 & 3,
            (code >> 2) as u8 & 3,
            code as u8 & 3,
        ];
        if d[0] != d[1] && d[0] != d[2] && d[0] != d[3] && d[1] != d[2] && d[1] != d[3] && d[2] != d[3]
        {
            out[n] = d;
            n += 1;
        }
        code += 1;
    }
    out
}

/// The permuted global index of sample `index` of the pixel of Morton code `morton` for one
/// dimension group: Morton
/// digits (above bit `log2_block`) permuted in base 4 from the top, then the index digits
/// Owen-shuffled in base 2 (seeded by the permuted pixel part, so pixels differ).
pub fn permuted_index(
    morton: u64,
    log2_res: u32,
    log2_block: u32,
    index: u64,
    group_seed: u64,
) -> u64 {
    let mut pixel_part = 0u64;
    for k in (0..log2_res).rev() {
        let digit = (morton >> (2 * k)) & 3;
        let higher = morton >> (2 * k + 2);
        // A one-multiply hash of the prefix, the depth and the group's (already hashed) seed,
        // its top bits mapped onto 0..24 by a multiply (Lemire's range reduction). The digits'
        // hashes are independent of each other, so they pipeline.
        let h = ((higher ^ ((k as u64 + 1) << 58)) ^ group_seed)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (group_seed >> 23);
        let h = (h ^ (h >> 29)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        let p = PERMUTATIONS[(((h >> 32) * 24) >> 32) as usize];
        pixel_part |= (p[digit as usize] as u64) << (2 * k);
    }
    let mask = if log2_block >= 64 { u64::MAX } else { (1u64 << log2_block) - 1 };
    let within = index & mask;
    // Index digits: an Owen shuffle of the low 32 bits (log2_block ≤ 32 here), seeded by the
    // permuted pixel code so each pixel's order differs.
    let shuffled = owen(within as u32, group_seed ^ pixel_part.wrapping_mul(0xD6E8_FEB8_6659_FD93)) as u64 & mask;
    (pixel_part << log2_block) | shuffled
}

impl SampleGenerator for ZSobol {
    fn name(&self) -> &'static str {
        "zsobol"
    }

    fn describe(&self) -> &'static str {
        "Z-Sobol: Owen-scrambled Sobol over the image in randomly permuted Morton order (Ahmed & Wonka 2020)"
    }

    fn fill(&self, setup: &Setup, key: SampleKey, out: &mut [f32]) {
        let (x, y) = match key.pixel {
            u64::MAX => (0, 0),
            p => ((p % setup.width as u64) as u32, (p / setup.width as u64) as u32),
        };
        let log2_res = ceil_log2(setup.width.max(setup.height) as u64);
        let log2_block = setup
            .spp
            .map_or(DEFAULT_LOG2_BLOCK, |n| ceil_log2(n).min(32));
        // Past the block the index wraps into a fresh randomization.
        let epoch = if log2_block >= 64 { 0 } else { key.index >> log2_block };
        let morton = morton_2d(x, y);
        let run = mix64(mix64(key.seed ^ 0x250b_01e5_0000_0002) ^ key.strategy ^ epoch);
        for (start, d) in setup.layout.offsets() {
            if start >= out.len() {
                break;
            }
            // pbrt keys a group by its first dimension; so does this (stable under layout edits
            // after it).
            // (`run` is a full hash; the scrambles hash their seeds again.)
            let gseed = run ^ (start as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            let global = permuted_index(morton, log2_res, log2_block, key.index, gseed);
            let i = global as u32;
            let s = match global >> 32 {
                0 => gseed,
                hi => mix64(gseed ^ hi),
            };
            let pair = d.width == 2 && start + 1 < out.len();
            let [u, v] = scrambled_point(i, s, pair);
            out[start] = u;
            if pair {
                out[start + 1] = v;
            }
        }
    }
}
