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

use super::generator::{LaneValues, SampleGenerator, SampleKey, SampleKeys, Setup};
use super::qmc::{ceil_log2, morton_2d, owen_lanes, scrambled_point_lanes, to_unit, LaneGroups, store_point_lanes};
use crate::math::mix64_lanes;
use crate::simd::{Isa, Kernel, Lanes, Mask, VectorU64, WIDTH};

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

/// Word d holds digit d's image under every permutation: bits 2r..2r+2 are
/// `PERMUTATIONS[r][d]`, so a lane's lookup is two variable shifts instead of a gather.
const DIGIT_IMAGES: [u64; 4] = digit_images();

const fn digit_images() -> [u64; 4] {
    let mut w = [0u64; 4];
    let mut r = 0;
    while r < 24 {
        let mut d = 0;
        while d < 4 {
            w[d] |= (PERMUTATIONS[r][d] as u64) << (2 * r);
            d += 1;
        }
        r += 1;
    }
    w
}

/// `PERMUTATIONS[r][digit]` of every lane (r < 24, digit < 4).
#[inline(always)]
fn permute_digit_lanes<U: VectorU64<N>, const N: usize>(r: U, digit: U) -> U {
    // (A named function, not a closure: a closure is not `inline(always)`.)
    #[inline(always)]
    fn image<U: VectorU64<N>, const N: usize>(d: usize, shift: U) -> U {
        U::splat(DIGIT_IMAGES[d]).shr_lanes(shift).and(U::splat(3))
    }
    let shift = r.shl(1);
    // The four images of this lane's permutation as one byte, then the digit's one.
    let code = image(0, shift)
        .or(image(1, shift).shl(2))
        .or(image(2, shift).shl(4))
        .or(image(3, shift).shl(6));
    code.shr_lanes(digit.shl(1)).and(U::splat(3))
}

/// The Morton code of every lane's pixel with its digits permuted in base 4 from the top for
/// one dimension group (each digit by the permutation a hash of the digits above it, the
/// depth and the group's seed picks).
#[inline(always)]
fn permuted_pixel_lanes<U: VectorU64<N>, const N: usize>(morton: U, log2_res: u32, group_seed: U) -> U {
    let mut pixel_part = U::splat(0);
    let salt = group_seed.shr(23);
    for k in (0..log2_res).rev() {
        let digit = morton.shr(2 * k).and(U::splat(3));
        let higher = morton.shr(2 * k + 2);
        // A one-multiply hash of the prefix, the depth and the group's (already hashed) seed,
        // its top bits mapped onto 0..24 by a multiply (Lemire's range reduction). The digits'
        // hashes are independent of each other, so they pipeline.
        let h = higher
            .xor(U::splat((k as u64 + 1) << 58))
            .xor(group_seed)
            .mul(U::splat(0x9E37_79B9_7F4A_7C15))
            .xor(salt);
        let h = h.xor(h.shr(29)).mul(U::splat(0xBF58_476D_1CE4_E5B9));
        let r = h.shr(32).mul32(U::splat(24)).shr(32);
        pixel_part = pixel_part.or(permute_digit_lanes(r, digit).shl(2 * k));
    }
    pixel_part
}

/// What one render fixes for every sample: log2 of the image's side (a power of two that
/// covers it) and of the per-pixel block.
#[derive(Clone, Copy)]
struct Blocks {
    log2_res: u32,
    log2_block: u32,
}

impl Blocks {
    fn of(setup: &Setup) -> Self {
        Blocks {
            log2_res: ceil_log2(setup.width.max(setup.height) as u64),
            log2_block: setup
                .spp
                .map_or(DEFAULT_LOG2_BLOCK, |n| ceil_log2(n).min(32)),
        }
    }
}

/// The seed every group of a sample derives from; past the block the index wraps into a
/// fresh randomization (the epoch).
#[inline(always)]
fn run_seed_lanes<U: VectorU64<N>, const N: usize>(seed: U, strategy: U, index: U, b: Blocks) -> U {
    let epoch = index.shr(b.log2_block);
    mix64_lanes(mix64_lanes(seed.xor(U::splat(0x250b_01e5_0000_0002))).xor(strategy).xor(epoch))
}

/// One layout group's point (its first dimension `start`), as 32-bit fractions, of every lane:
/// the permuted global index — Morton digits permuted, then the index digits within the
/// pixel's block Owen-shuffled in base 2 (seeded by the permuted pixel part, so pixels differ)
/// — and the Sobol point of its low 32 bits, scrambled with a seed that takes the bits above
/// (so large images still get distinct points).
#[inline(always)]
fn group_point_lanes<U: VectorU64<N>, const N: usize>(
    morton: U,
    index: U,
    run: U,
    start: usize,
    pair: bool,
    b: Blocks,
) -> [U; 2] {
    // pbrt keys a group by its first dimension; so does this (stable under layout edits after
    // it). (`run` is a full hash; the scrambles hash their seeds again.)
    let gseed = run.xor(U::splat((start as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15)));
    let pixel_part = permuted_pixel_lanes(morton, b.log2_res, gseed);
    // log2_block ≤ 32, so the index digits are an Owen shuffle of 32-bit words.
    let mask = U::splat((1u64 << b.log2_block) - 1);
    let shuffle_seed = gseed.xor(pixel_part.mul(U::splat(0xD6E8_FEB8_6659_FD93)));
    let shuffled = owen_lanes(index.and(mask), shuffle_seed).and(mask);
    let global = pixel_part.shl(b.log2_block).or(shuffled);
    // The point's seed: the group's, or a hash of it with the index's bits above 32 where
    // there are any. hi < 2³², so hi + 2³² − 1 carries into bit 32 exactly when hi ≠ 0, and
    // the mask is that bit negated (no compare or branch per lane).
    let hi = global.shr(32);
    let nonzero = hi.add(U::splat(0xffff_ffff)).shr(32);
    let all = nonzero.xor(U::splat(u64::MAX)).add(U::splat(1));
    let wide = mix64_lanes(gseed.xor(hi));
    let seed = gseed.xor(gseed.xor(wide).and(all));
    scrambled_point_lanes(global.and(U::splat(0xffff_ffff)), seed, pair)
}

impl SampleGenerator for ZSobol {
    fn name(&self) -> &'static str {
        "zsobol"
    }

    fn describe(&self) -> &'static str {
        "Z-Sobol: Owen-scrambled Sobol over the image in randomly permuted Morton order (Ahmed & Wonka 2020)"
    }

    fn fill(&self, setup: &Setup, key: SampleKey, out: &mut [f32]) {
        let b = Blocks::of(setup);
        let morton = pixel_morton(setup, key.pixel);
        let run = run_seed_lanes::<u64, 1>(key.seed, key.strategy, key.index, b);
        for (start, d) in setup.layout.offsets() {
            if start >= out.len() {
                break;
            }
            let pair = d.width == 2 && start + 1 < out.len();
            let [u, v] = group_point_lanes::<u64, 1>(morton, key.index, run, start, pair, b);
            out[start] = to_unit(u as u32);
            if pair {
                out[start + 1] = to_unit(v as u32);
            }
        }
    }

    /// The packet's sixteen samples side by side over the lane layer's u64 lanes, in the
    /// CPU's ISA (inactive lanes are computed too; their values are unspecified): the same code
    /// as [`Self::fill`], so the same numbers (`lanes_fill_as_single_samples`,
    /// `every_isa_fills_as_one_sample`).
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

/// The Morton code of a scan-line pixel index (0 for a sample tied to no pixel).
fn pixel_morton(setup: &Setup, pixel: u64) -> u64 {
    match pixel {
        u64::MAX => 0,
        p => morton_2d(
            (p % setup.width as u64) as u32,
            (p / setup.width as u64) as u32,
        ),
    }
}

/// [`ZSobol::fill_lanes`] as a lane kernel: the layout's groups below `dims` (each's first
/// dimension, and whether it is a pair there) and the keys as lanes.
struct FillLanes<'a> {
    groups: LaneGroups,
    blocks: Blocks,
    keys: &'a SampleKeys,
    morton: [u64; WIDTH],
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
            blocks: Blocks::of(setup),
            keys,
            morton: keys.pixel.map(|p| pixel_morton(setup, p)),
            out,
        }
    }
}

impl Kernel for FillLanes<'_> {
    type Out = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        let load = L::U::load;
        let (k, b) = (&self.keys, self.blocks);
        let (index, morton) = (load(&k.index), load(&self.morton));
        let run = run_seed_lanes(load(&k.seed), load(&k.strategy), index, b);
        for &(start, pair) in self.groups.as_slice() {
            let [x, y] = group_point_lanes(morton, index, run, start, pair, b);
            store_point_lanes([x, y], start, pair, self.out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::generator::assert_every_isa_fills_as_one_sample;
    use crate::sampling::{Dimension, Layout};

    /// The packed lookup is the permutation table, entry by entry.
    #[test]
    fn digit_images_are_the_permutations() {
        for (r, p) in PERMUTATIONS.iter().enumerate() {
            for (d, &image) in p.iter().enumerate() {
                assert_eq!(permute_digit_lanes::<u64, 1>(r as u64, d as u64), image as u64, "{r} {d}");
            }
        }
    }

    /// The construction as first written, digit by digit with the permutation table and a
    /// branch for the index's high bits: the definition the lane code must keep.
    fn reference_fill(setup: &Setup, key: SampleKey, out: &mut [f32]) {
        use crate::math::mix64;
        use crate::sampling::qmc::{owen, scrambled_point};
        let permuted_index = |morton: u64, log2_res: u32, log2_block: u32, index: u64, group_seed: u64| {
            let mut pixel_part = 0u64;
            for k in (0..log2_res).rev() {
                let digit = (morton >> (2 * k)) & 3;
                let higher = morton >> (2 * k + 2);
                let h = ((higher ^ ((k as u64 + 1) << 58)) ^ group_seed)
                    .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                    ^ (group_seed >> 23);
                let h = (h ^ (h >> 29)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                let p = PERMUTATIONS[(((h >> 32) * 24) >> 32) as usize];
                pixel_part |= (p[digit as usize] as u64) << (2 * k);
            }
            let mask = (1u64 << log2_block) - 1;
            let seed = group_seed ^ pixel_part.wrapping_mul(0xD6E8_FEB8_6659_FD93);
            let shuffled = owen((index & mask) as u32, seed) as u64 & mask;
            (pixel_part << log2_block) | shuffled
        };
        let (x, y) = match key.pixel {
            u64::MAX => (0, 0),
            p => ((p % setup.width as u64) as u32, (p / setup.width as u64) as u32),
        };
        let log2_res = ceil_log2(setup.width.max(setup.height) as u64);
        let log2_block = setup.spp.map_or(DEFAULT_LOG2_BLOCK, |n| ceil_log2(n).min(32));
        let epoch = key.index >> log2_block;
        let morton = morton_2d(x, y);
        let run = mix64(mix64(key.seed ^ 0x250b_01e5_0000_0002) ^ key.strategy ^ epoch);
        let len = out.len();
        for (start, d) in setup.layout.offsets().take_while(|(s, _)| *s < len) {
            let gseed = run ^ (start as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            let global = permuted_index(morton, log2_res, log2_block, key.index, gseed);
            let s = match global >> 32 {
                0 => gseed,
                hi => mix64(gseed ^ hi),
            };
            let pair = d.width == 2 && start + 1 < len;
            let [u, v] = scrambled_point(global as u32, s, pair);
            out[start] = u;
            if pair {
                out[start + 1] = v;
            }
        }
    }

    /// The generator is its first definition, on images whose global indices stay below 2³²
    /// and on one whose indices pass it (2000 × 1100 pixels, 2^16-sample blocks).
    #[test]
    fn fills_are_the_reference_construction() {
        let layout = Layout::of(&[Dimension::pair("a"), Dimension::one("b"), Dimension::pair("c")]);
        let mut wide = 0;
        for setup in [
            Setup::image(layout.clone(), None, 2000, 1100),
            Setup::image(layout.clone(), Some(16), 64, 64),
            Setup::image(layout, Some(1), 3, 5),
        ] {
            let pixels = setup.width as u64 * setup.height as u64;
            for n in 0..400u64 {
                let key = SampleKey {
                    seed: n % 3,
                    strategy: 0x5eed,
                    pixel: if n == 7 { u64::MAX } else { crate::math::mix64(n) % pixels },
                    index: [n % 20, (1 << 16) + n, u64::MAX - n][n as usize % 3],
                };
                let (mut got, mut want) = ([0.0f32; 5], [0.0f32; 5]);
                ZSOBOL.fill(&setup, key, &mut got);
                reference_fill(&setup, key, &mut want);
                assert_eq!(got.map(f32::to_bits), want.map(f32::to_bits), "{key:?} {}x{}", setup.width, setup.height);
                wide += (setup.width == 2000 && pixel_morton(&setup, key.pixel) << 16 >> 32 != 0) as u32;
            }
        }
        assert!(wide > 100, "only {wide} samples had global indices past 2^32");
    }

    /// Every ISA's packet fill gives each lane's single-sample numbers: keys that differ in
    /// every field, pixels all over an image whose global indices pass 2³² (a 2¹¹-pixel side
    /// and 2^16-sample blocks under a time budget), and epochs.
    #[test]
    fn every_isa_fills_as_one_sample() {
        let layout = Layout::of(&[Dimension::pair("a"), Dimension::one("b"), Dimension::pair("c")]);
        for setup in [Setup::image(layout.clone(), None, 2000, 1100), Setup::image(layout, Some(5), 13, 7)] {
            let dims = 6;
            let pixels = setup.width as u64 * setup.height as u64;
            let keys: [SampleKey; WIDTH] = std::array::from_fn(|i| SampleKey {
                seed: 9 + (i as u64 % 2),
                strategy: 0x5eed + (i as u64 % 3),
                pixel: if i == 15 { u64::MAX } else { (i as u64 * 1_000_003) % pixels },
                index: [0, 1, 7, 8, 1 << 16, u64::MAX][i % 6].wrapping_sub(i as u64 / 6),
            });
            assert_every_isa_fills_as_one_sample(
                &ZSOBOL,
                &setup,
                &keys,
                dims,
                |isa, got| crate::simd::run(isa, FillLanes::new(&setup, &SampleKeys::of(&keys), dims, got)),
                &format!("{}x{}", setup.width, setup.height),
            );
        }
    }
}
