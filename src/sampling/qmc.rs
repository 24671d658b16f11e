//! The building blocks the low-discrepancy generators share: the first two dimensions of the
//! Sobol sequence, a hashed nested-uniform (Owen) scramble in base 2, and 2-D Morton codes.
//!
//! Only Sobol dimensions 0 and 1 are needed: every `Dimension::pair` of a layout gets its own
//! randomized copy of this (0,2)-sequence and every single dimension its own scrambled van der
//! Corput sequence ("padding", Burley 2020 §4, as pbrt-v4's padded and Z-Sobol samplers do).
//! Within one pair the two coordinates share the index, so every aligned block of 2^m points
//! of the pair is a (0,m,2)-net in base 2; across groups the index is shuffled with a different
//! seed, so no two groups are correlated.

use super::generator::{LaneValues, MAX_DIMENSIONS, Setup};
use crate::math::mix64_lanes;
use crate::simd::{VectorU64, WIDTH};

/// Sobol dimension 0 of point `i`, as a 32-bit binary fraction: the van der Corput sequence.
pub fn sobol_0(i: u32) -> u32 {
    i.reverse_bits()
}

/// Sobol dimension 1 of point `i`, as a 32-bit binary fraction. Its generator matrix is the
/// Pascal matrix mod 2: column k is v_k with v_0 = 1/2 and v_{k+1} = v_k ⊕ (v_k >> 1).
pub fn sobol_1(i: u32) -> u32 {
    (sobol_1_reversed_lanes::<u64, 1>(i as u64) as u32).reverse_bits()
}

/// [`sobol_1`] of every lane (each below 2³²), bit-reversed (digit j from the top at bit j),
/// which is what a scramble wants. Digit j is the parity of the index bits k whose positions
/// contain j's (C(k, j) is odd iff j ⊆ k, by Lucas's theorem): a superset-sum transform over
/// the five bits of the position, five shift-mask-xor steps with no table and no branch.
#[inline(always)]
pub fn sobol_1_reversed_lanes<U: VectorU64<N>, const N: usize>(i: U) -> U {
    // (Named functions, not closures, here and below: a closure is not `inline(always)`, and
    // a lane intrinsic left in one is a call, not an instruction.)
    #[inline(always)]
    fn step<U: VectorU64<N>, const N: usize>(z: U, k: u32, m: u64) -> U {
        z.xor(z.shr(k).and(U::splat(m)))
    }
    let z = step(i, 1, 0x5555_5555);
    let z = step(z, 2, 0x3333_3333);
    let z = step(z, 4, 0x0f0f_0f0f);
    let z = step(z, 8, 0x00ff_00ff);
    step(z, 16, 0x0000_ffff)
}

/// [`sobol_1`] bit by bit, the definition the transform is checked against.
pub fn sobol_1_reference(mut i: u32) -> u32 {
    let mut v = 1u32 << 31;
    let mut x = 0;
    while i != 0 {
        if i & 1 != 0 {
            x ^= v;
        }
        i >>= 1;
        v ^= v >> 1;
    }
    x
}

/// The low 32 bits of every lane reversed; each lane must be below 2³² (`u32::reverse_bits`).
#[inline(always)]
pub fn reverse32_lanes<U: VectorU64<N>, const N: usize>(x: U) -> U {
    #[inline(always)]
    fn swap<U: VectorU64<N>, const N: usize>(x: U, k: u32, m: u64) -> U {
        let m = U::splat(m);
        x.shr(k).and(m).or(x.and(m).shl(k))
    }
    let x = x.shr(16).or(x.shl(16)).and(U::splat(0xffff_ffff));
    let x = swap(x, 8, 0x00ff_00ff);
    let x = swap(x, 4, 0x0f0f_0f0f);
    let x = swap(x, 2, 0x3333_3333);
    swap(x, 1, 0x5555_5555)
}

/// A bijection of 32-bit words in which output bit p is input bit p flipped by a function of
/// the input bits below p (and of `seed`): each step is such a map — adding a constant (the
/// carry comes from below), xor with the word times an even constant (its bit p depends on
/// bits below p), multiplying by an odd constant — and so is their composition. Applied to a
/// bit-reversed fraction it is a nested uniform scramble: digit k is flipped by a hash of the
/// digits before it (Laine & Karras 2011; Burley 2020). Four 32-bit words of a hash of the
/// seed enter as additive and multiplicative constants. Over u64 lanes holding 32-bit words;
/// the result is below 2³².
#[inline(always)]
fn lower_triangular_hash_lanes<U: VectorU64<N>, const N: usize>(x: U, seed: U) -> U {
    // One 64-bit hash of the seed gives the four constants (the second pair by a multiply,
    // which keeps them well mixed at the cost of one instruction instead of another hash).
    let s = mix64_lanes(seed);
    let t = s.mul(U::splat(0xD1B5_4A32_D192_ED03));
    let b = s.shr(32).or(U::splat(1));
    let c = t.shr(32).and(U::splat(!1));
    let d = t.xor(s.shr(17));
    // The low 32 bits of a sum, a xor and a `mul32` depend on the operands' low 32 bits
    // alone, so the words need one mask, at the end.
    let x = x.add(s);
    let x = x.xor(x.mul32(U::splat(0x6d2b_79f4)));
    let x = x.mul32(b);
    let x = x.xor(x.mul32(c));
    let x = x.add(d);
    let x = x.xor(x.mul32(U::splat(0xa3b1_95c8)));
    let x = x.xor(x.mul32(U::splat(0x3c6e_f372 & !1)));
    x.and(U::splat(0xffff_ffff))
}

/// Owen scramble of the 32-bit binary fraction `x` with `seed`: the binary digit at depth k
/// (from the most significant) is flipped by a hash of the k − 1 digits above it and the
/// seed. Applied to a sample index it is a shuffle that maps every aligned block of 2^m
/// indices onto an aligned block of 2^m indices (the bits from m up depend only on bits from
/// m up), so a prefix of 2^m points of a (0,2)-sequence stays a (0,m,2)-net.
pub fn owen(x: u32, seed: u64) -> u32 {
    owen_lanes::<u64, 1>(x as u64, seed) as u32
}

/// [`owen`] of every lane (each below 2³²), with each lane's seed.
#[inline(always)]
pub fn owen_lanes<U: VectorU64<N>, const N: usize>(x: U, seed: U) -> U {
    reverse32_lanes(lower_triangular_hash_lanes(reverse32_lanes(x), seed))
}

/// A 32-bit fraction as an f32 in [0, 1): its top 24 bits, exactly representable.
pub fn to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * UNIT
}

/// 2^-24: one step of [`to_unit`]'s 24-bit grid.
const UNIT: f32 = 1.0 / 16_777_216.0;

/// [`to_unit`] of every lane (each below 2³²), into `out`.
#[inline(always)]
pub fn to_unit_lanes<U: VectorU64<N>, const N: usize>(x: U, out: &mut [f32; N]) {
    x.shr(8).to_f32(out);
    for o in out.iter_mut() {
        *o *= UNIT;
    }
}

/// The layout groups a packet fill writes: each group's first dimension below `dims`, and
/// whether it is a pair there (both of its dimensions below `dims`).
#[derive(Clone, Copy)]
pub struct LaneGroups {
    groups: [(usize, bool); MAX_DIMENSIONS],
    count: usize,
}

impl LaneGroups {
    pub fn of(setup: &Setup, dims: usize) -> Self {
        let dims = dims.min(MAX_DIMENSIONS);
        let mut groups = [(0, false); MAX_DIMENSIONS];
        let mut count = 0;
        for (start, d) in setup.layout.offsets().take_while(|(s, _)| *s < dims) {
            groups[count] = (start, d.width == 2 && start + 1 < dims);
            count += 1;
        }
        LaneGroups { groups, count }
    }

    /// (first dimension, pair) of each group, in layout order.
    pub fn as_slice(&self) -> &[(usize, bool)] {
        &self.groups[..self.count]
    }
}

/// Writes one group's point of every lane (32-bit fractions) as numbers in [0, 1) into
/// dimension `start`, and its second coordinate into `start + 1` for a pair.
#[inline(always)]
pub fn store_point_lanes<U: VectorU64<WIDTH>>(
    point: [U; 2],
    start: usize,
    pair: bool,
    out: &mut LaneValues,
) {
    to_unit_lanes(point[0], &mut out[start]);
    if pair {
        to_unit_lanes(point[1], &mut out[start + 1]);
    }
}

/// One randomized point of a (0,2)-sequence pair, as used by every layout group: the index `i`
/// Owen-shuffled with `seed`, then Sobol dimensions 0 and 1 of it, each Owen-scrambled with its
/// own seed derived from `seed`. Equal to
/// `[owen(sobol_0(j), seed ^ A), owen(sobol_1(j), seed ^ B)]` with `j = owen(i, seed)`, with
/// the bit reversals that cancel left out (owen ∘ sobol_0 = reverse ∘ hash, since sobol_0 is
/// itself a reversal). `pair` false: only the first coordinate.
pub fn scrambled_pair(i: u32, seed: u64, pair: bool) -> [f32; 2] {
    scrambled_point(owen(i, seed), seed, pair)
}

/// Sobol point `j` (dimensions 0 and 1, or 0 alone), each coordinate Owen-scrambled with a seed
/// derived from `seed`; no index shuffle (Z-Sobol permutes its index itself).
pub fn scrambled_point(j: u32, seed: u64, pair: bool) -> [f32; 2] {
    let [x, y] = scrambled_point_lanes::<u64, 1>(j as u64, seed, pair);
    [to_unit(x as u32), to_unit(y as u32)]
}

/// [`scrambled_point`] of every lane, as 32-bit fractions (the second 0 when `pair` is false).
/// owen(sobol_1(j)) is reverse(hash(reverse(sobol_1(j)))), and the transform gives
/// sobol_1(j) already reversed.
#[inline(always)]
pub fn scrambled_point_lanes<U: VectorU64<N>, const N: usize>(j: U, seed: U, pair: bool) -> [U; 2] {
    let x = reverse32_lanes(lower_triangular_hash_lanes(
        j,
        seed.xor(U::splat(0xa5a5_0001)),
    ));
    let y = if pair {
        let z = sobol_1_reversed_lanes(j);
        reverse32_lanes(lower_triangular_hash_lanes(
            z,
            seed.xor(U::splat(0xa5a5_0002)),
        ))
    } else {
        U::splat(0)
    };
    [x, y]
}

/// Interleaves the bits of x (even positions) and y (odd positions).
pub fn morton_2d(x: u32, y: u32) -> u64 {
    fn spread(v: u32) -> u64 {
        let mut v = v as u64;
        v = (v | (v << 16)) & 0x0000_ffff_0000_ffff;
        v = (v | (v << 8)) & 0x00ff_00ff_00ff_00ff;
        v = (v | (v << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
        v = (v | (v << 2)) & 0x3333_3333_3333_3333;
        v = (v | (v << 1)) & 0x5555_5555_5555_5555;
        v
    }
    spread(x) | (spread(y) << 1)
}

/// ⌈log2 n⌉ for n ≥ 1 (0 for n ≤ 1).
pub fn ceil_log2(n: u64) -> u32 {
    if n <= 1 {
        0
    } else {
        64 - (n - 1).leading_zeros()
    }
}

/// Whether `points` (2-D, as 32-bit fractions) form a (0,m,2)-net in base 2, 2^m of them:
/// for every split m = a + b, each of the 2^m elementary intervals of size 2^-a × 2^-b
/// holds exactly one point. For the tests and the dimension-pair checks.
pub fn is_02_net(points: &[[u32; 2]]) -> bool {
    let n = points.len();
    if !n.is_power_of_two() {
        return false;
    }
    let m = n.trailing_zeros();
    for a in 0..=m {
        let b = m - a;
        let mut seen = vec![false; n];
        for p in points {
            let ix = if a == 0 {
                0
            } else {
                (p[0] >> (32 - a)) as usize
            };
            let iy = if b == 0 {
                0
            } else {
                (p[1] >> (32 - b)) as usize
            };
            let cell = (ix << b) | iy;
            if std::mem::replace(&mut seen[cell], true) {
                return false;
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transform_and_shortcuts_match_their_definitions() {
        let mut x = 0x1234_5678u32;
        for i in (0..5000u32).chain([u32::MAX, 1 << 31, 0xdead_beef]) {
            assert_eq!(sobol_1(i), sobol_1_reference(i), "{i}");
            x = x.wrapping_mul(747796405).wrapping_add(2891336453);
            for (i, seed) in [(i, 9u64), (x, x as u64)] {
                let j = owen(i, seed);
                let [a, b] = scrambled_pair(i, seed, true);
                assert_eq!(a, to_unit(owen(sobol_0(j), seed ^ 0xa5a5_0001)));
                assert_eq!(b, to_unit(owen(sobol_1(j), seed ^ 0xa5a5_0002)));
            }
        }
    }

    #[test]
    fn sobol_first_points() {
        let half = 1u32 << 31;
        let d1: Vec<u32> = (0..4).map(sobol_1).collect();
        assert_eq!(d1, [0, half, half + (half >> 1), half >> 1]);
        assert_eq!(sobol_0(1), half);
        assert_eq!(sobol_0(2), half >> 1);
    }

    /// Every aligned block of 2^m points of (dim 0, dim 1) is a (0,m,2)-net, unscrambled and
    /// scrambled; the negative control: dims (0, 0) — a pair that reused one dimension — is not.
    #[test]
    fn sobol_pairs_are_02_nets() {
        for m in 1..=8u32 {
            let n = 1u32 << m;
            for block in [0u32, 1, 5] {
                let pts: Vec<[u32; 2]> = (block * n..(block + 1) * n)
                    .map(|i| [sobol_0(i), sobol_1(i)])
                    .collect();
                assert!(is_02_net(&pts), "m {m} block {block}");
            }
            for seed in 0..20u64 {
                let pts: Vec<[u32; 2]> = (0..n)
                    .map(|i| {
                        let j = owen(i, seed);
                        [owen(sobol_0(j), seed ^ 1), owen(sobol_1(j), seed ^ 2)]
                    })
                    .collect();
                assert!(is_02_net(&pts), "scrambled m {m} seed {seed}");
            }
            let reused: Vec<[u32; 2]> = (0..n).map(|i| [sobol_0(i), sobol_0(i)]).collect();
            assert!(
                m == 1 || !is_02_net(&reused),
                "m {m}: the net test cannot see a reused dimension"
            );
        }
    }

    /// The index shuffle maps aligned blocks onto aligned blocks (a bijection there).
    #[test]
    fn owen_index_shuffle_keeps_blocks() {
        for seed in 0..10u64 {
            for m in [1u32, 4, 7] {
                let mut got: Vec<u32> = (0..1u32 << m).map(|i| owen(i, seed)).collect();
                let hi = got[0] >> m;
                assert!(got.iter().all(|j| j >> m == hi));
                got.sort_unstable();
                got.dedup();
                assert_eq!(got.len(), 1 << m);
            }
        }
    }

    #[test]
    fn morton_and_log2() {
        assert_eq!(morton_2d(0b11, 0b01), 0b0111);
        assert_eq!(morton_2d(0, 1), 2);
        assert_eq!(
            (ceil_log2(1), ceil_log2(2), ceil_log2(3), ceil_log2(256)),
            (0, 1, 2, 8)
        );
    }
}
