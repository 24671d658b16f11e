//! The lane layer: f32 vectors of 16 lanes (a ray packet: 1×16 on AVX-512, 2×8 on AVX2) and of
//! 8 lanes (one single ray against the 8 children of a wide node or an 8-triangle leaf block:
//! one ymm register on both AVX2 and AVX-512), f64 vectors of 16 lanes for the sample-path code
//! whose numerics need f64, and plain arrays elsewhere. This module is the
//! only place that touches `std::arch`; kernels are written once, generic over [`Lanes`], and
//! monomorphised inside one `#[target_feature]` entry per ISA ([`run`]), so every intrinsic
//! inlines into the whole kernel (no intrinsic is left as an out-of-line call).
//!
//! All paths perform the same IEEE operations in the same order (no FMA anywhere, min/max
//! with MINPS/MAXPS semantics), so results are bit-identical across ISAs.

mod avx2;
mod avx512;
mod isa;
mod portable;
mod vec3;

pub use isa::Isa;
pub use vec3::{D3, Soa3, V3, add3, cross3, div3, dot3, neg3, normalize3, scale3, select3, sub3};

/// Lane count of a packet: one 4×4 pixel tile (see the assertion in `tracer`).
pub const WIDTH: usize = 16;

/// Lane count of the narrow vector: children of a wide BVH node, triangles of a leaf block.
pub const NARROW: usize = 8;

/// Bit i = lane i of a 16-lane vector.
pub type Mask = u16;

/// An f32 vector of `N` lanes. Comparisons return one bit per lane (bit i = lane i).
pub trait Vector<const N: usize>: Copy {
    fn splat(x: f32) -> Self;
    fn load(a: &[f32; N]) -> Self;
    fn store(self, a: &mut [f32; N]);
    fn add(self, o: Self) -> Self;
    fn sub(self, o: Self) -> Self;
    fn mul(self, o: Self) -> Self;
    fn div(self, o: Self) -> Self;
    /// `if a < b { a } else { b }` per lane (MINPS semantics).
    fn min(self, o: Self) -> Self;
    /// `if a > b { a } else { b }` per lane (MAXPS semantics).
    fn max(self, o: Self) -> Self;
    fn abs(self) -> Self;
    /// The correctly rounded square root (IEEE, so every ISA agrees).
    fn sqrt(self) -> Self;
    /// The sign bit flipped (`-x`, so -0.0 for 0.0: not `0 - x`).
    fn neg(self) -> Self;
    /// Per lane, the next f32 up (bit i of `up` set) or down: [`crate::math::next_f32`] bit for
    /// bit, NaN and infinities included.
    fn next_f32(self, up: u32) -> Self;
    /// Ordered comparisons (false on NaN).
    fn lt(self, o: Self) -> u32;
    fn le(self, o: Self) -> u32;
    fn eq(self, o: Self) -> u32;
    /// Lanes whose sign bit is set (-0.0 included).
    fn sign(self) -> u32;
    /// Lane i = `a` where bit i of `m` is set, else `b`.
    fn select(m: u32, a: Self, b: Self) -> Self;
    /// `select(self.lt(o), a, b)`, the mask kept in the registers: AVX2 has no mask
    /// registers, so a mask that goes out to bits and back costs a movemask, a broadcast and
    /// a shift on the way to the blend; here the compare feeds the blend. Same lanes, bit for
    /// bit.
    #[inline(always)]
    fn lt_select(self, o: Self, a: Self, b: Self) -> Self {
        Self::select(self.lt(o), a, b)
    }
    /// `select(self.le(o), a, b)`, as [`Self::lt_select`].
    #[inline(always)]
    fn le_select(self, o: Self, a: Self, b: Self) -> Self {
        Self::select(self.le(o), a, b)
    }
    /// `select(self.sign(), a, b)`, as [`Self::lt_select`]: AVX2's blend reads the sign bit
    /// itself, so this is one instruction.
    #[inline(always)]
    fn sign_select(self, a: Self, b: Self) -> Self {
        Self::select(self.sign(), a, b)
    }
    /// The smallest lane (for NaN-free lanes the result does not depend on the order).
    fn reduce_min(self) -> f32;
    /// The largest lane (likewise).
    fn reduce_max(self) -> f32;
    /// Each lane truncated toward zero, as `x as u32`, for lanes in [0, 2³¹) (the caller
    /// clamps: outside that range the ISAs differ).
    fn trunc_u32(self, a: &mut [u32; N]);
    /// Lane i's four-float record `rows[i]`, transposed: vector k holds component k of every
    /// lane's record (an array of 16-byte structures read as a structure of arrays). The
    /// 16- and 8-lane vectors load each record whole and transpose in registers: written
    /// lane by lane into an array and loaded back, the lanes' 4·N stores stall the loads
    /// (no store-to-load forwarding from many stores into one load).
    #[inline(always)]
    fn load_records(rows: &[&[f32; 4]; N]) -> [Self; 4] {
        let mut a = [[0.0f32; N]; 4];
        for i in 0..N {
            for k in 0..4 {
                a[k][i] = rows[i][k];
            }
        }
        [
            Self::load(&a[0]),
            Self::load(&a[1]),
            Self::load(&a[2]),
            Self::load(&a[3]),
        ]
    }
    /// [`Self::load_records`] of the records `table[idx[i]]`: one bounds check for all the
    /// lanes (on their largest index) instead of one per lane, and each lane's address taken
    /// straight from its index. Checked lane by lane, with each index split into line and
    /// slot, the gather was 42 % of the environment warp's instructions (docs/tracer.md,
    /// stop 57).
    #[inline(always)]
    fn load_records_at(table: &[[f32; 4]], idx: &[u32; N]) -> [Self; 4] {
        let top = idx.iter().fold(0, |m, &i| m.max(i)) as usize;
        assert!(
            top < table.len(),
            "record {top} of a table of {}",
            table.len()
        );
        // SAFETY: every idx[i] ≤ top < table.len().
        Self::load_records(&std::array::from_fn(|i| unsafe {
            table.get_unchecked(idx[i] as usize)
        }))
    }
}

/// An f64 vector of `N` lanes, for the sample-path code whose numerics need f64 (sphere cones,
/// ray/sphere roots): the IEEE operations of [`Vector`] (no FMA, MINPD/MAXPD semantics) and
/// exact conversions from f32 lanes, rounding ones back.
pub trait Vector64<const N: usize>: Copy {
    fn splat(x: f64) -> Self;
    fn from_f64(a: &[f64; N]) -> Self;
    /// Each f32 lane, exactly.
    fn from_f32(a: &[f32; N]) -> Self;
    /// Each lane rounded to the nearest f32 (`as f32`).
    fn to_f32(self, a: &mut [f32; N]);
    fn to_f64(self, a: &mut [f64; N]);
    fn add(self, o: Self) -> Self;
    fn sub(self, o: Self) -> Self;
    fn mul(self, o: Self) -> Self;
    fn div(self, o: Self) -> Self;
    /// `if a < b { a } else { b }` per lane.
    fn min(self, o: Self) -> Self;
    /// `if a > b { a } else { b }` per lane.
    fn max(self, o: Self) -> Self;
    /// The sign bit cleared.
    fn abs(self) -> Self;
    fn sqrt(self) -> Self;
    /// The sign bit flipped.
    fn neg(self) -> Self;
    fn lt(self, o: Self) -> u32;
    fn le(self, o: Self) -> u32;
    fn eq(self, o: Self) -> u32;
    /// Lanes whose sign bit is set (-0.0 included).
    fn sign(self) -> u32;
    /// Lane i = `a` where bit i of `m` is set, else `b`.
    fn select(m: u32, a: Self, b: Self) -> Self;
    /// `select(self.lt(o), a, b)`, the mask kept in the registers ([`Vector::lt_select`]).
    #[inline(always)]
    fn lt_select(self, o: Self, a: Self, b: Self) -> Self {
        Self::select(self.lt(o), a, b)
    }
    /// `select(self.le(o), a, b)`, likewise.
    #[inline(always)]
    fn le_select(self, o: Self, a: Self, b: Self) -> Self {
        Self::select(self.le(o), a, b)
    }
    /// `select(self.sign(), a, b)`, likewise ([`Vector::sign_select`]).
    #[inline(always)]
    fn sign_select(self, a: Self, b: Self) -> Self {
        Self::select(self.sign(), a, b)
    }
}

/// A u64 vector of `N` lanes with wrapping arithmetic, for the random streams' 64-bit state
/// (PCG32 and splitmix64 over a packet's lanes, #19 item 8): integer operations only, so every
/// ISA gives the same bits. (LLVM vectorised plain u64 arrays only in part: it ran the PCG
/// output's shifts and rotate lane by lane as scalar code.)
pub trait VectorU64<const N: usize>: Copy {
    fn splat(x: u64) -> Self;
    fn load(a: &[u64; N]) -> Self;
    fn store(self, a: &mut [u64; N]);
    /// `wrapping_add` per lane.
    fn add(self, o: Self) -> Self;
    /// `wrapping_mul` per lane: the low 64 bits of the product.
    fn mul(self, o: Self) -> Self;
    /// The full 64-bit product of each lane's low 32 bits (the high halves are ignored): one
    /// `pmuludq`, for arithmetic on 32-bit words held in u64 lanes.
    fn mul32(self, o: Self) -> Self;
    fn xor(self, o: Self) -> Self;
    fn or(self, o: Self) -> Self;
    fn and(self, o: Self) -> Self;
    /// Every lane shifted right by `k` < 64.
    fn shr(self, k: u32) -> Self;
    /// Every lane shifted left by `k` < 64.
    fn shl(self, k: u32) -> Self;
    /// Each lane shifted right by the same lane of `k` (each < 64).
    fn shr_lanes(self, k: Self) -> Self;
    /// Each lane, which must be below 2³¹, rounded to the nearest f32 (`as f32`).
    fn to_f32(self, a: &mut [f32; N]);
    /// Each lane's low 32 bits rotated right by the same lane of `k` (each < 32), as a lane
    /// below 2³² (`(x as u32).rotate_right(k as u32) as u64`; the high halves of `self` are
    /// ignored). By default the word doubled into 64 bits and shifted; AVX-512 rotates 32-bit
    /// words in one instruction (`vprorvd`).
    #[inline(always)]
    fn rotr32(self, k: Self) -> Self {
        let low = Self::splat(0xffff_ffff);
        let x = self.and(low);
        x.or(x.shl(32)).shr_lanes(k).and(low)
    }
}

/// One ISA's vector types. A zero-sized type, so a kernel names its ISA once.
pub trait Lanes: Copy {
    /// 16 lanes: a packet.
    type V: Vector<WIDTH>;
    /// 8 lanes: a wide node's children or a leaf block's triangles.
    type W: Vector<NARROW>;
    /// 16 f64 lanes: two zmm registers on AVX-512, four ymm on AVX2, an array on the portable
    /// path. (Portable arrays on every ISA vectorised only in part in a kernel as large as the
    /// spherical rectangle's, with scalar `sd` instructions and spills: docs/tracer.md.)
    type D: Vector64<WIDTH>;
    /// 16 u64 lanes: two zmm registers on AVX-512, four ymm on AVX2, an array on the portable
    /// path.
    type U: VectorU64<WIDTH>;
}

/// Asks the cache for the `size_of::<T>()` bytes at `p` (one prefetch per 64-byte line), so a
/// traversal can start the memory reads of the nodes it will visit next while it works on the
/// current one. A hint only: no value depends on it, and an address that is not mapped is
/// ignored by the CPU (`prefetcht0` never faults), so the pointer need not be dereferenceable.
#[inline(always)]
pub fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let mut off = 0;
        while off < std::mem::size_of::<T>() {
            // SAFETY: prefetch is a hint; it reads nothing architecturally and cannot fault.
            // SSE is in the x86-64 baseline.
            unsafe { _mm_prefetch::<_MM_HINT_T0>((p as *const i8).wrapping_add(off)) };
            off += 64;
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// A computation generic over the lane types; [`run`] instantiates it for one ISA. Mark `run`
/// (and every function it calls on lanes) `#[inline(always)]`: only code inlined into the ISA's
/// `#[target_feature]` entry is compiled for it, and an intrinsic outside it is a call.
pub trait Kernel {
    type Out;
    fn run<L: Lanes>(self) -> Self::Out;
}

/// Runs a kernel on an ISA. `Isa` values only come from [`Isa::detect`] / [`Isa::parse`],
/// which check the CPU, so the unsafe calls below never execute unsupported instructions.
#[inline]
pub fn run<K: Kernel>(isa: Isa, k: K) -> K::Out {
    match isa {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 if isa.supported() => {
            // SAFETY: the CPU reports avx512f and avx512dq.
            unsafe { avx512::entry(k) }
        }
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 if isa.supported() => {
            // SAFETY: the CPU reports avx2.
            unsafe { avx2::entry(k) }
        }
        _ => k.run::<portable::Portable>(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Probe<const N: usize>([f32; N], [f32; N]);

    fn probe<V: Vector<N>, const N: usize>(a: [f32; N], b: [f32; N]) -> (Vec<[f32; N]>, Vec<u32>) {
        let (x, y) = (V::load(&a), V::load(&b));
        let vs = [
            x.add(y),
            x.sub(y),
            x.mul(y),
            x.div(y),
            x.min(y),
            x.max(y),
            x.abs(),
            x.abs().sqrt(),
            x.neg(),
            x.next_f32(0b0110_1001_0011_1100 & ((1u64 << N) - 1) as u32),
            y.next_f32(!0b0110_1001_0011_1100 & ((1u64 << N) - 1) as u32),
            V::select(0b1010_0101_1100_0011 & ((1u64 << N) - 1) as u32, x, y),
            V::splat(a[1]),
            V::splat(x.reduce_min()),
            V::splat(y.reduce_max()),
        ];
        let out = vs
            .iter()
            .map(|&v| {
                let mut o = [0.0; N];
                v.store(&mut o);
                o
            })
            .collect();
        // Truncation on [0, 1e9] (in its range), after the masks.
        let mut t = [0u32; N];
        x.abs().min(V::splat(1e9)).trunc_u32(&mut t);
        let mut bits = vec![x.lt(y), x.le(y), x.eq(y), x.sign()];
        bits.extend(t);
        (out, bits)
    }

    impl<const N: usize> Kernel for Probe<N> {
        type Out = [(Vec<[f32; N]>, Vec<u32>); 2];
        fn run<L: Lanes>(self) -> Self::Out {
            let wide = {
                let a: [f32; WIDTH] = std::array::from_fn(|i| self.0[i % N]);
                let b: [f32; WIDTH] = std::array::from_fn(|i| self.1[i % N]);
                let (v, m) = probe::<L::V, WIDTH>(a, b);
                (v.iter().map(|x| std::array::from_fn(|i| x[i])).collect(), m)
            };
            let narrow = {
                let a: [f32; NARROW] = std::array::from_fn(|i| self.0[i % N]);
                let b: [f32; NARROW] = std::array::from_fn(|i| self.1[i % N]);
                let (v, m) = probe::<L::W, NARROW>(a, b);
                (
                    v.iter()
                        .map(|x| std::array::from_fn(|i| x[i % NARROW]))
                        .collect(),
                    m,
                )
            };
            [wide, narrow]
        }
    }

    /// Every available ISA gives bit-identical results to the portable path, at both widths.
    #[test]
    fn isas_agree_bit_for_bit() {
        let a: [f32; WIDTH] = std::array::from_fn(|i| match i {
            3 => -0.0,
            5 => f32::INFINITY,
            6 => -9.5,
            _ => (i as f32 - 7.5) * 0.37,
        });
        let b: [f32; WIDTH] = std::array::from_fn(|i| {
            if i % 3 == 0 {
                a[i]
            } else {
                1.0 + i as f32 * -0.21
            }
        });
        let want = run(Isa::Portable, Probe(a, b));
        assert_eq!(want[0].1[2].count_ones(), 6);
        assert_eq!(want[0].1[3] & 0b1000, 0b1000, "-0.0 has its sign bit");
        assert_eq!(want[0].0[13][0], -9.5, "reduce_min");
        for isa in Isa::available() {
            let got = run(isa, Probe(a, b));
            for (g, w) in got.iter().zip(&want) {
                for (x, y) in g.0.iter().zip(&w.0) {
                    let (x, y): (Vec<u32>, Vec<u32>) = (
                        x.iter().map(|f| f.to_bits()).collect(),
                        y.iter().map(|f| f.to_bits()).collect(),
                    );
                    assert_eq!(x, y, "{isa:?}");
                }
                assert_eq!(g.1, w.1, "{isa:?}");
            }
        }
    }

    /// `select` over every mask of 16 lanes: f32 lanes (both widths) and f64 lanes, lane i
    /// from `a` exactly where bit i is set. Returns the first mask that picked wrongly, per
    /// vector kind. The mask is rotated left by `.0` bits before `select` sees it: 0 in the
    /// test, 1 in its control (an off-by-one).
    struct EveryMask(u32);

    impl Kernel for EveryMask {
        type Out = [Option<u32>; 3];
        fn run<L: Lanes>(self) -> Self::Out {
            let a: [f32; WIDTH] = std::array::from_fn(|i| i as f32 + 1.0);
            let b = a.map(|x| -x);
            let (va, vb) = (L::V::load(&a), L::V::load(&b));
            let (na, nb) = (
                L::W::load(a[..NARROW].try_into().unwrap()),
                L::W::load(b[..NARROW].try_into().unwrap()),
            );
            let (da, db) = (L::D::from_f32(&a), L::D::from_f32(&b));
            let right = |m: u32, got: &[f32]| {
                got.iter()
                    .enumerate()
                    .all(|(i, &g)| g == if m >> i & 1 != 0 { a[i] } else { b[i] })
            };
            let mut wrong = [None; 3];
            for m in 0..1u32 << WIDTH {
                let mut w = [0.0; WIDTH];
                let given = (m as u16).rotate_left(self.0) as u32;
                L::V::select(given, va, vb).store(&mut w);
                let mut n = [0.0; NARROW];
                L::W::select(given & 0xff, na, nb).store(&mut n);
                let mut d = [0.0; WIDTH];
                L::D::select(given, da, db).to_f32(&mut d);
                for (k, ok) in [right(m, &w), right(m, &n), right(m, &d)]
                    .into_iter()
                    .enumerate()
                {
                    if !ok && wrong[k].is_none() {
                        wrong[k] = Some(m);
                    }
                }
            }
            wrong
        }
    }

    /// Every ISA's `select` takes lane i from its first operand exactly where mask bit i is
    /// set, for all 2¹⁶ masks (the AVX2 path shifts each lane's bit into its sign, the AVX-512
    /// path reads a k mask, the portable path tests bits: an off-by-one in any of them moves
    /// a lane). Control: a mask off by one bit is caught at every width on every ISA.
    #[test]
    fn select_takes_each_lane_by_its_mask_bit() {
        for isa in Isa::available() {
            assert_eq!(
                run(isa, EveryMask(0)),
                [None; 3],
                "{isa:?}: first wrong mask"
            );
            let off_by_one = run(isa, EveryMask(1));
            assert!(
                off_by_one.iter().all(Option::is_some),
                "{isa:?}: {off_by_one:?}"
            );
        }
    }

    /// `lt_select`, `le_select` and `sign_select` at both f32 widths and on f64 lanes, against
    /// each lane's comparison in Rust (`<`, `<=`, `is_sign_negative`) on operands with ties,
    /// ±0, NaN of both signs, infinities and subnormals. Returns the first wrong case, if any.
    /// `.0` swaps `lt_select` and `le_select` (the control).
    struct FusedSelects(bool);

    impl Kernel for FusedSelects {
        type Out = Option<String>;
        fn run<L: Lanes>(self) -> Self::Out {
            let nan = f32::NAN;
            let a: [f32; WIDTH] = [
                -0.0,
                0.0,
                1.0,
                nan,
                -nan,
                f32::INFINITY,
                -f32::INFINITY,
                2.5,
                -3.0,
                1e-40,
                -1e-40,
                7.0,
                0.0,
                -1.0,
                3.0,
                nan,
            ];
            let b: [f32; WIDTH] = [
                0.0,
                -0.0,
                1.0,
                1.0,
                0.0,
                f32::INFINITY,
                0.0,
                2.5,
                3.0,
                0.0,
                0.0,
                6.0,
                nan,
                -1.0,
                4.0,
                0.0,
            ];
            let p: [f32; WIDTH] = std::array::from_fn(|i| i as f32 + 1.0);
            let q = p.map(|x| -x);
            let want = |k: usize, i: usize| {
                let take = match k {
                    0 => a[i] < b[i],
                    1 => a[i] <= b[i],
                    _ => a[i].is_sign_negative(),
                };
                if take { p[i] } else { q[i] }
            };
            let swap = self.0;
            let double = |k: usize| {
                let (x, y) = (L::D::from_f32(&a), L::D::from_f32(&b));
                let (vp, vq) = (L::D::from_f32(&p), L::D::from_f32(&q));
                let mut o = [0.0; WIDTH];
                match (k, swap) {
                    (0, false) | (1, true) => x.lt_select(y, vp, vq),
                    (0, true) | (1, false) => x.le_select(y, vp, vq),
                    _ => x.sign_select(vp, vq),
                }
                .to_f32(&mut o);
                o.to_vec()
            };
            let (wide, narrow) = (
                |k| fused::<L::V, WIDTH>(k, swap, [&a, &b, &p, &q]),
                |k| fused::<L::W, NARROW>(k, swap, [&a, &b, &p, &q]),
            );
            for k in 0..3 {
                for (kind, got) in [("f32", wide(k)), ("narrow", narrow(k)), ("f64", double(k))] {
                    for (i, &g) in got.iter().enumerate() {
                        if g != want(k, i) {
                            let op = ["lt_select", "le_select", "sign_select"][k];
                            return Some(format!("{op} {kind} lane {i}: {} vs {}", a[i], b[i]));
                        }
                    }
                }
            }
            None
        }
    }

    /// Fused select `k` (0 `lt_select`, 1 `le_select`, 2 `sign_select`; 0 and 1 swapped with
    /// `swap`) of the first N lanes of `[a, b, p, q]`: `a` against `b`, taking `p` or `q`.
    fn fused<V: Vector<N>, const N: usize>(
        k: usize,
        swap: bool,
        v: [&[f32; WIDTH]; 4],
    ) -> Vec<f32> {
        let [x, y, vp, vq] = v.map(|r| V::load(r[..N].try_into().unwrap()));
        let mut o = [0.0; N];
        match (k, swap) {
            (0, false) | (1, true) => x.lt_select(y, vp, vq),
            (0, true) | (1, false) => x.le_select(y, vp, vq),
            _ => x.sign_select(vp, vq),
        }
        .store(&mut o);
        o.to_vec()
    }

    /// Every ISA's fused compare-and-select takes the lanes its comparison (or sign bit) says,
    /// as `select` of the comparison does (the AVX2 path feeds the compare to the blend
    /// directly, the others go through mask bits). Control: `lt_select` and `le_select`
    /// swapped is caught (the operands hold ties) on every ISA.
    #[test]
    fn fused_selects_take_the_lanes_their_comparison_says() {
        for isa in Isa::available() {
            assert_eq!(run(isa, FusedSelects(false)), None, "{isa:?}");
            assert!(run(isa, FusedSelects(true)).is_some(), "{isa:?}: control");
        }
    }

    struct Records<'a>(&'a [[f32; 4]], [usize; WIDTH]);

    /// Each width's records by address ([`Vector::load_records`]) and by index
    /// ([`Vector::load_records_at`]), the narrow ones of the lanes in reverse.
    type RecordLanes = ([[f32; WIDTH]; 4], [[f32; NARROW]; 4]);

    impl Kernel for Records<'_> {
        type Out = [RecordLanes; 2];
        fn run<L: Lanes>(self) -> Self::Out {
            let rows: [&[f32; 4]; WIDTH] = std::array::from_fn(|i| &self.0[self.1[i]]);
            let narrow: [&[f32; 4]; NARROW] = std::array::from_fn(|i| rows[WIDTH - 1 - i]);
            let at: [u32; WIDTH] = self.1.map(|i| i as u32);
            let narrow_at: [u32; NARROW] = std::array::from_fn(|i| at[WIDTH - 1 - i]);
            let mut out = [([[0.0; WIDTH]; 4], [[0.0; NARROW]; 4]); 2];
            let wide = [
                L::V::load_records(&rows),
                L::V::load_records_at(self.0, &at),
            ];
            let thin = [
                L::W::load_records(&narrow),
                L::W::load_records_at(self.0, &narrow_at),
            ];
            for (o, (w, n)) in out.iter_mut().zip(wide.into_iter().zip(thin)) {
                for (k, v) in w.into_iter().enumerate() {
                    v.store(&mut o.0[k]);
                }
                for (k, v) in n.into_iter().enumerate() {
                    v.store(&mut o.1[k]);
                }
            }
            out
        }
    }

    /// Records read over lanes are each lane's record, component by component, at both
    /// widths on every ISA (lanes reading the same record among them, one the table's last),
    /// whether given by address or by index. Control: the scalar formula's answer is checked
    /// directly, so a transposition that swaps lanes or components (the ISAs' shuffles), or
    /// an index taken as another lane's, fails here.
    #[test]
    fn records_over_lanes_are_each_lanes_record() {
        let table: Vec<[f32; 4]> = (0..40)
            .map(|r| std::array::from_fn(|k| r as f32 + 0.25 * k as f32))
            .collect();
        let mut at: [usize; WIDTH] = std::array::from_fn(|i| (i * 7 + 3) % 40);
        at[9] = at[2];
        at[5] = 39;
        for isa in Isa::available() {
            for (w, n) in run(isa, Records(&table, at)) {
                for k in 0..4 {
                    for i in 0..WIDTH {
                        assert_eq!(w[k][i].to_bits(), table[at[i]][k].to_bits(), "{isa:?}");
                    }
                    for i in 0..NARROW {
                        let want = table[at[WIDTH - 1 - i]][k];
                        assert_eq!(n[k][i].to_bits(), want.to_bits(), "{isa:?}");
                    }
                }
            }
        }
    }

    struct Indexed<'a>(&'a [[f32; 4]], [u32; WIDTH]);

    impl Kernel for Indexed<'_> {
        type Out = f32;
        fn run<L: Lanes>(self) -> f32 {
            L::V::load_records_at(self.0, &self.1)[0].reduce_max()
        }
    }

    /// An index past the table's end stops `load_records_at` (its one check for all lanes
    /// covers every lane, not only the first or the last), on every ISA; the largest index
    /// still in the table reads it. Control: the same index one lower is accepted.
    #[test]
    fn indexed_records_are_bounds_checked_on_every_lane() {
        let table = vec![[1.0f32, 2.0, 3.0, 4.0]; 40];
        for isa in Isa::available() {
            for lane in [0, 7, 8, WIDTH - 1] {
                let mut at = [0u32; WIDTH];
                at[lane] = 39;
                assert_eq!(run(isa, Indexed(&table, at)), 1.0, "{isa:?}: control");
                at[lane] = 40;
                let caught = std::panic::catch_unwind(|| run(isa, Indexed(&table, at)));
                assert!(caught.is_err(), "{isa:?}: lane {lane} read past the table");
            }
        }
    }

    struct Step<'a>(&'a [f32], u32);

    impl Kernel for Step<'_> {
        type Out = Vec<u32>;
        fn run<L: Lanes>(self) -> Vec<u32> {
            let mut out = Vec::new();
            for c in self.0.chunks_exact(WIDTH) {
                let mut o = [0.0; WIDTH];
                L::V::load(c.try_into().unwrap())
                    .next_f32(self.1)
                    .store(&mut o);
                out.extend(o.map(f32::to_bits));
            }
            out
        }
    }

    /// The lanes' `next_f32` is `math::next_f32` on every ISA: zeros, subnormals, extremes,
    /// infinities, NaN and a spread of bit patterns, each lane up or down by its mask bit.
    #[test]
    fn lane_next_f32_is_the_scalar_one() {
        let mut xs = crate::math::tests::SPECIAL_F32.to_vec();
        xs.extend((0..4096u64).map(|i| f32::from_bits((crate::math::mix64(i) >> 32) as u32)));
        for up in [0xffff, 0, 0b1010_0110_0101_1001, 0b0101_1001_1010_0110] {
            let want: Vec<u32> = xs
                .iter()
                .enumerate()
                .map(|(i, &x)| crate::math::next_f32(x, up >> (i % WIDTH) & 1 != 0).to_bits())
                .collect();
            for isa in Isa::available() {
                assert_eq!(run(isa, Step(&xs, up)), want, "{isa:?} up={up:#x}");
            }
        }
    }

    /// Every u64 lane operation of `a` and `b` (shift counts from `b`'s low six bits).
    struct ProbeU64<'a>(&'a [u64; WIDTH], &'a [u64; WIDTH]);

    impl Kernel for ProbeU64<'_> {
        type Out = (Vec<[u64; WIDTH]>, [u32; WIDTH]);
        fn run<L: Lanes>(self) -> Self::Out {
            let (x, y) = (L::U::load(self.0), L::U::load(self.1));
            let k = y.and(L::U::splat(63));
            let vs = [
                x.add(y),
                x.mul(y),
                x.mul32(y),
                x.xor(y),
                x.or(y),
                x.and(y),
                x.shr(0),
                x.shr(1),
                x.shr(33),
                x.shr(63),
                x.shl(0),
                x.shl(31),
                x.shl(63),
                x.shr_lanes(k),
                L::U::splat(self.0[3]),
            ];
            let out = vs
                .iter()
                .map(|v| {
                    let mut o = [0; WIDTH];
                    v.store(&mut o);
                    o
                })
                .collect();
            // Below 2^31: 0, 1, 2^24 + 1 (rounds to even), 2^31 − 1 (rounds up), …
            let mut f = [0.0f32; WIDTH];
            x.shr(33).to_f32(&mut f);
            (out, f.map(f32::to_bits))
        }
    }

    /// The u64 lanes are u64 arithmetic on every ISA (products whose cross terms carry, shifts
    /// by 0 and 63, each lane by its own count), and their f32 conversion is `as f32`.
    #[test]
    fn u64_lanes_are_wrapping_u64_arithmetic() {
        let mut checked = 0;
        for round in 0..64u64 {
            let a: [u64; WIDTH] = std::array::from_fn(|i| match (i as u64 + round) % 8 {
                0 => u64::MAX,
                1 => 0,
                2 => 0xffff_ffff,
                3 => ((1u64 << 24) + 1) << 33,
                4 => ((1u64 << 31) - 1) << 33,
                _ => crate::math::mix64(round * 16 + i as u64),
            });
            let b: [u64; WIDTH] = std::array::from_fn(|i| match (i as u64 + 3 * round) % 5 {
                0 => u64::MAX,
                1 => 1 << 32,
                _ => crate::math::mix64(!(round * 16 + i as u64)),
            });
            let scalar =
                |f: fn(u64, u64) -> u64| -> [u64; WIDTH] { std::array::from_fn(|i| f(a[i], b[i])) };
            let want = [
                scalar(u64::wrapping_add),
                scalar(u64::wrapping_mul),
                scalar(|a, b| (a as u32 as u64) * (b as u32 as u64)),
                scalar(|a, b| a ^ b),
                scalar(|a, b| a | b),
                scalar(|a, b| a & b),
                scalar(|a, _| a),
                scalar(|a, _| a >> 1),
                scalar(|a, _| a >> 33),
                scalar(|a, _| a >> 63),
                scalar(|a, _| a),
                scalar(|a, _| a << 31),
                scalar(|a, _| a << 63),
                scalar(|a, b| a >> (b & 63)),
                [a[3]; WIDTH],
            ];
            let want_f = a.map(|a| ((a >> 33) as f32).to_bits());
            for isa in Isa::ALL {
                let (got, got_f) = run(isa, ProbeU64(&a, &b));
                for (op, (g, w)) in got.iter().zip(&want).enumerate() {
                    assert_eq!(g, w, "{isa:?} operation {op}, round {round}");
                }
                assert_eq!(got_f, want_f, "{isa:?} to_f32, round {round}");
                checked += 1;
            }
        }
        assert!(checked >= 64, "{checked}");
    }
}
