//! AVX2: an 8-lane vector is one ymm register, a 16-lane vector two (lanes 0–7, 8–15). FMA is
//! deliberately not enabled, so the path rounds exactly like the others.
#![cfg(target_arch = "x86_64")]

use super::{Kernel, Lanes, NARROW, Vector, Vector64, VectorU64, WIDTH};
use std::arch::x86_64::*;

#[derive(Clone, Copy)]
pub struct Avx2;

/// # Safety
/// The CPU must support avx2.
#[target_feature(enable = "avx2")]
pub unsafe fn entry<K: Kernel>(k: K) -> K::Out {
    k.run::<Avx2>()
}

impl Lanes for Avx2 {
    type V = Y2;
    type W = Y;
    type D = YD;
    type U = YU;
}

/// 8 lanes in one ymm register; also the AVX-512 path's narrow vector. Only ever used inside
/// an `avx2` or `avx512f` entry.
#[derive(Clone, Copy)]
pub struct Y(__m256);

/// 16 lanes in two ymm registers.
#[derive(Clone, Copy)]
pub struct Y2(Y, Y);

/// `v`, unchanged, as a value LLVM cannot see into, so that a store of it stays a plain store.
/// LLVM (22) folds `store(select(m, x, load(p)), p)`, i.e. `select(m, x, old).store(old)`,
/// into one `vmaskmovps`, an AVX masked store that AMD runs as microcode (Zen 2 and Zen 3: 42
/// µops, one per 12 cycles, per uops.info; Zen 4's are slow too, only its AVX-512 masked
/// stores are fast) where a load, a blend and a store take about three µops. 8 % of a bunny
/// `light` pass sat at such stores on a Zen 3 (docs/tracer.md, stop 54). No instruction: the
/// register is only named in the template's comment. `tests/inlined.rs` checks that the
/// binary has no masked store left in dibench's code.
///
/// # Safety
/// The CPU must support avx (only ever inlined into an `avx2` or `avx512f` entry, like an
/// intrinsic).
#[target_feature(enable = "avx")]
#[inline]
unsafe fn opaque(mut v: __m256) -> __m256 {
    // SAFETY: an empty template: no instruction; no memory, flags or stack touched.
    unsafe {
        std::arch::asm!(
            "/* {0} */",
            inout(ymm_reg) v,
            options(pure, nomem, nostack, preserves_flags)
        );
    }
    v
}

/// Mask bits `first..first + 8` of `m` in the sign bits of lanes 0–7 (each lane's other bits
/// are left over), which is all `blendv` reads: one variable shift of the broadcast mask per
/// 8 lanes, where [`expand`] takes an and and a compare, and one broadcast for all of a wide
/// vector's registers.
#[inline(always)]
fn sign_bits(m: __m256i, first: i32) -> __m256 {
    unsafe {
        let shift = _mm256_sub_epi32(
            _mm256_set1_epi32(31 - first),
            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
        );
        _mm256_castsi256_ps(_mm256_sllv_epi32(m, shift))
    }
}

/// [`sign_bits`] for 4 f64 lanes: mask bits `first..first + 4` in their sign bits.
#[inline(always)]
fn sign_bits64(m: __m256i, first: i64) -> __m256d {
    unsafe {
        let shift = _mm256_sub_epi64(
            _mm256_set1_epi64x(63 - first),
            _mm256_setr_epi64x(0, 1, 2, 3),
        );
        _mm256_castsi256_pd(_mm256_sllv_epi64(m, shift))
    }
}

/// Expands 8 mask bits into all-ones / all-zeros lanes.
#[inline(always)]
fn expand(m: u32) -> __m256 {
    unsafe {
        let bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        let v = _mm256_and_si256(_mm256_set1_epi32(m as i32), bit);
        _mm256_castsi256_ps(_mm256_cmpeq_epi32(v, bit))
    }
}

macro_rules! op {
    ($name:ident, $f:ident) => {
        #[inline(always)]
        fn $name(self, o: Self) -> Self {
            unsafe { Y($f(self.0, o.0)) }
        }
    };
}

macro_rules! cmp_select {
    ($name:ident, $p:ident) => {
        #[inline(always)]
        fn $name(self, o: Self, a: Self, b: Self) -> Self {
            // blendv takes its second operand where the compare set the lane's sign bit.
            unsafe { Y(_mm256_blendv_ps(b.0, a.0, _mm256_cmp_ps::<$p>(self.0, o.0))) }
        }
    };
}

macro_rules! cmp {
    ($name:ident, $p:ident) => {
        #[inline(always)]
        fn $name(self, o: Self) -> u32 {
            unsafe { _mm256_movemask_ps(_mm256_cmp_ps::<$p>(self.0, o.0)) as u32 }
        }
    };
}

impl Y {
    /// Lane i of `a` where bit `first + i` of the broadcast mask `m` is set, else of `b`.
    #[inline(always)]
    fn blend(m: __m256i, first: i32, a: Y, b: Y) -> Y {
        unsafe { Y(_mm256_blendv_ps(b.0, a.0, sign_bits(m, first))) }
    }
}

impl Vector<NARROW> for Y {
    #[inline(always)]
    fn splat(x: f32) -> Self {
        unsafe { Y(_mm256_set1_ps(x)) }
    }
    #[inline(always)]
    fn load(a: &[f32; NARROW]) -> Self {
        unsafe { Y(_mm256_loadu_ps(a.as_ptr())) }
    }
    #[inline(always)]
    fn store(self, a: &mut [f32; NARROW]) {
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), opaque(self.0)) }
    }
    op!(add, _mm256_add_ps);
    op!(sub, _mm256_sub_ps);
    op!(mul, _mm256_mul_ps);
    op!(div, _mm256_div_ps);
    op!(min, _mm256_min_ps);
    op!(max, _mm256_max_ps);
    #[inline(always)]
    fn abs(self) -> Self {
        unsafe { Y(_mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0)) }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        unsafe { Y(_mm256_sqrt_ps(self.0)) }
    }
    #[inline(always)]
    fn neg(self) -> Self {
        unsafe { Y(_mm256_xor_ps(self.0, _mm256_set1_ps(-0.0))) }
    }
    /// `math::next_f32` on integer lanes: ±1 on the bits, ±0 to the smallest subnormal, NaN
    /// and the infinity moved towards unchanged.
    #[inline(always)]
    fn next_f32(self, up: u32) -> Self {
        unsafe {
            let bits = _mm256_castps_si256(self.0);
            let up = _mm256_castps_si256(expand(up));
            let abs = _mm256_and_si256(bits, _mm256_set1_epi32(0x7fff_ffff));
            let neg = _mm256_srai_epi32::<31>(bits);
            // away from zero: up from a positive number, down from a negative one.
            let away = _mm256_xor_si256(neg, up);
            let one = _mm256_set1_epi32(1);
            let stepped = _mm256_blendv_epi8(
                _mm256_sub_epi32(bits, one),
                _mm256_add_epi32(bits, one),
                away,
            );
            let from_zero = _mm256_blendv_epi8(_mm256_set1_epi32(0x8000_0001u32 as i32), one, up);
            let zero = _mm256_cmpeq_epi32(abs, _mm256_setzero_si256());
            let r = _mm256_blendv_epi8(stepped, from_zero, zero);
            let inf = _mm256_set1_epi32(0x7f80_0000);
            let stays = _mm256_or_si256(
                _mm256_cmpgt_epi32(abs, inf),
                _mm256_and_si256(_mm256_cmpeq_epi32(abs, inf), away),
            );
            Y(_mm256_castsi256_ps(_mm256_blendv_epi8(r, bits, stays)))
        }
    }
    cmp!(lt, _CMP_LT_OQ);
    cmp!(le, _CMP_LE_OQ);
    cmp_select!(lt_select, _CMP_LT_OQ);
    cmp_select!(le_select, _CMP_LE_OQ);
    #[inline(always)]
    fn sign_select(self, a: Self, b: Self) -> Self {
        unsafe { Y(_mm256_blendv_ps(b.0, a.0, self.0)) }
    }
    cmp!(eq, _CMP_EQ_OQ);
    #[inline(always)]
    fn sign(self) -> u32 {
        unsafe { _mm256_movemask_ps(self.0) as u32 }
    }
    #[inline(always)]
    fn select(m: u32, a: Self, b: Self) -> Self {
        unsafe { Y::blend(_mm256_set1_epi32(m as i32), 0, a, b) }
    }
    #[inline(always)]
    fn reduce_min(self) -> f32 {
        unsafe {
            let v = _mm256_min_ps(self.0, _mm256_permute2f128_ps::<1>(self.0, self.0));
            let v = _mm256_min_ps(v, _mm256_shuffle_ps::<0b0100_1110>(v, v));
            let v = _mm256_min_ps(v, _mm256_shuffle_ps::<0b1011_0001>(v, v));
            _mm256_cvtss_f32(v)
        }
    }
    #[inline(always)]
    fn reduce_max(self) -> f32 {
        unsafe {
            let v = _mm256_max_ps(self.0, _mm256_permute2f128_ps::<1>(self.0, self.0));
            let v = _mm256_max_ps(v, _mm256_shuffle_ps::<0b0100_1110>(v, v));
            let v = _mm256_max_ps(v, _mm256_shuffle_ps::<0b1011_0001>(v, v));
            _mm256_cvtss_f32(v)
        }
    }
    #[inline(always)]
    fn trunc_u32(self, a: &mut [u32; NARROW]) {
        unsafe { _mm256_storeu_si256(a.as_mut_ptr() as *mut __m256i, _mm256_cvttps_epi32(self.0)) }
    }
    #[inline(always)]
    fn load_records(rows: &[&[f32; 4]; NARROW]) -> [Self; 4] {
        unsafe {
            // r[j]'s 128-bit half b is the record of lane 4b + j; a 4×4 transpose within each
            // half then gives component k of lanes 4b..4b + 3 in half b of vector k.
            let q = |i: usize| _mm_loadu_ps(rows[i].as_ptr());
            let r: [__m256; 4] = std::array::from_fn(|j| {
                _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(q(j)), q(4 + j))
            });
            let t0 = _mm256_castps_pd(_mm256_unpacklo_ps(r[0], r[1]));
            let t1 = _mm256_castps_pd(_mm256_unpackhi_ps(r[0], r[1]));
            let t2 = _mm256_castps_pd(_mm256_unpacklo_ps(r[2], r[3]));
            let t3 = _mm256_castps_pd(_mm256_unpackhi_ps(r[2], r[3]));
            [
                Y(_mm256_castpd_ps(_mm256_unpacklo_pd(t0, t2))),
                Y(_mm256_castpd_ps(_mm256_unpackhi_pd(t0, t2))),
                Y(_mm256_castpd_ps(_mm256_unpacklo_pd(t1, t3))),
                Y(_mm256_castpd_ps(_mm256_unpackhi_pd(t1, t3))),
            ]
        }
    }
}

macro_rules! both {
    ($name:ident) => {
        #[inline(always)]
        fn $name(self, o: Self) -> Self {
            Y2(self.0.$name(o.0), self.1.$name(o.1))
        }
    };
}

macro_rules! both_cmp {
    ($name:ident) => {
        #[inline(always)]
        fn $name(self, o: Self) -> u32 {
            self.0.$name(o.0) | (self.1.$name(o.1) << 8)
        }
    };
}

impl Vector<WIDTH> for Y2 {
    #[inline(always)]
    fn splat(x: f32) -> Self {
        Y2(Y::splat(x), Y::splat(x))
    }
    #[inline(always)]
    fn load(a: &[f32; WIDTH]) -> Self {
        let (lo, hi) = a.split_at(NARROW);
        Y2(
            Y::load(lo.try_into().unwrap()),
            Y::load(hi.try_into().unwrap()),
        )
    }
    #[inline(always)]
    fn store(self, a: &mut [f32; WIDTH]) {
        let (lo, hi) = a.split_at_mut(NARROW);
        self.0.store(lo.try_into().unwrap());
        self.1.store(hi.try_into().unwrap());
    }
    both!(add);
    both!(sub);
    both!(mul);
    both!(div);
    both!(min);
    both!(max);
    #[inline(always)]
    fn abs(self) -> Self {
        Y2(self.0.abs(), self.1.abs())
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Y2(self.0.sqrt(), self.1.sqrt())
    }
    #[inline(always)]
    fn neg(self) -> Self {
        Y2(self.0.neg(), self.1.neg())
    }
    #[inline(always)]
    fn next_f32(self, up: u32) -> Self {
        Y2(self.0.next_f32(up & 0xff), self.1.next_f32(up >> 8))
    }
    both_cmp!(lt);
    both_cmp!(le);
    both_cmp!(eq);
    #[inline(always)]
    fn lt_select(self, o: Self, a: Self, b: Self) -> Self {
        Y2(
            self.0.lt_select(o.0, a.0, b.0),
            self.1.lt_select(o.1, a.1, b.1),
        )
    }
    #[inline(always)]
    fn le_select(self, o: Self, a: Self, b: Self) -> Self {
        Y2(
            self.0.le_select(o.0, a.0, b.0),
            self.1.le_select(o.1, a.1, b.1),
        )
    }
    #[inline(always)]
    fn sign_select(self, a: Self, b: Self) -> Self {
        Y2(self.0.sign_select(a.0, b.0), self.1.sign_select(a.1, b.1))
    }
    #[inline(always)]
    fn sign(self) -> u32 {
        self.0.sign() | (self.1.sign() << 8)
    }
    #[inline(always)]
    fn select(m: u32, a: Self, b: Self) -> Self {
        // One broadcast of the mask for both registers.
        let m = unsafe { _mm256_set1_epi32(m as i32) };
        Y2(Y::blend(m, 0, a.0, b.0), Y::blend(m, 8, a.1, b.1))
    }
    #[inline(always)]
    fn reduce_min(self) -> f32 {
        self.0.min(self.1).reduce_min()
    }
    #[inline(always)]
    fn reduce_max(self) -> f32 {
        self.0.max(self.1).reduce_max()
    }
    #[inline(always)]
    fn trunc_u32(self, a: &mut [u32; WIDTH]) {
        let (lo, hi) = a.split_at_mut(NARROW);
        self.0.trunc_u32(lo.try_into().expect("8 lanes"));
        self.1.trunc_u32(hi.try_into().expect("8 lanes"));
    }
    #[inline(always)]
    fn load_records(rows: &[&[f32; 4]; WIDTH]) -> [Self; 4] {
        let lo = Y::load_records(rows[..NARROW].try_into().expect("8 lanes"));
        let hi = Y::load_records(rows[NARROW..].try_into().expect("8 lanes"));
        std::array::from_fn(|k| Y2(lo[k], hi[k]))
    }
}

/// 16 f64 lanes in four ymm registers (lanes 0–3, 4–7, 8–11, 12–15). Only ever used inside an
/// `avx2` entry.
#[derive(Clone, Copy)]
pub struct YD([__m256d; 4]);

macro_rules! op64 {
    ($name:ident, $f:ident) => {
        #[inline(always)]
        fn $name(self, o: Self) -> Self {
            let (a, b) = (self.0, o.0);
            unsafe {
                YD([
                    $f(a[0], b[0]),
                    $f(a[1], b[1]),
                    $f(a[2], b[2]),
                    $f(a[3], b[3]),
                ])
            }
        }
    };
}

macro_rules! cmp_select64 {
    ($name:ident, $p:ident) => {
        #[inline(always)]
        fn $name(self, o: Self, a: Self, b: Self) -> Self {
            let (x, y, a, b) = (self.0, o.0, a.0, b.0);
            unsafe {
                YD([
                    _mm256_blendv_pd(b[0], a[0], _mm256_cmp_pd::<$p>(x[0], y[0])),
                    _mm256_blendv_pd(b[1], a[1], _mm256_cmp_pd::<$p>(x[1], y[1])),
                    _mm256_blendv_pd(b[2], a[2], _mm256_cmp_pd::<$p>(x[2], y[2])),
                    _mm256_blendv_pd(b[3], a[3], _mm256_cmp_pd::<$p>(x[3], y[3])),
                ])
            }
        }
    };
}

macro_rules! cmp64 {
    ($name:ident, $p:ident) => {
        #[inline(always)]
        fn $name(self, o: Self) -> u32 {
            let (a, b) = (self.0, o.0);
            unsafe {
                _mm256_movemask_pd(_mm256_cmp_pd::<$p>(a[0], b[0])) as u32
                    | (_mm256_movemask_pd(_mm256_cmp_pd::<$p>(a[1], b[1])) as u32) << 4
                    | (_mm256_movemask_pd(_mm256_cmp_pd::<$p>(a[2], b[2])) as u32) << 8
                    | (_mm256_movemask_pd(_mm256_cmp_pd::<$p>(a[3], b[3])) as u32) << 12
            }
        }
    };
}

impl YD {
    op64!(andnot, _mm256_andnot_pd);
    op64!(xor, _mm256_xor_pd);
}

impl Vector64<WIDTH> for YD {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        unsafe { YD([_mm256_set1_pd(x); 4]) }
    }
    #[inline(always)]
    fn from_f64(a: &[f64; WIDTH]) -> Self {
        let p = a.as_ptr();
        unsafe {
            YD([
                _mm256_loadu_pd(p),
                _mm256_loadu_pd(p.add(4)),
                _mm256_loadu_pd(p.add(8)),
                _mm256_loadu_pd(p.add(12)),
            ])
        }
    }
    #[inline(always)]
    fn from_f32(a: &[f32; WIDTH]) -> Self {
        let p = a.as_ptr();
        unsafe {
            YD([
                _mm256_cvtps_pd(_mm_loadu_ps(p)),
                _mm256_cvtps_pd(_mm_loadu_ps(p.add(4))),
                _mm256_cvtps_pd(_mm_loadu_ps(p.add(8))),
                _mm256_cvtps_pd(_mm_loadu_ps(p.add(12))),
            ])
        }
    }
    #[inline(always)]
    fn to_f32(self, a: &mut [f32; WIDTH]) {
        // Rounded to nearest, as `as f32`.
        let p = a.as_mut_ptr();
        unsafe {
            _mm_storeu_ps(p, _mm256_cvtpd_ps(self.0[0]));
            _mm_storeu_ps(p.add(4), _mm256_cvtpd_ps(self.0[1]));
            _mm_storeu_ps(p.add(8), _mm256_cvtpd_ps(self.0[2]));
            _mm_storeu_ps(p.add(12), _mm256_cvtpd_ps(self.0[3]));
        }
    }
    #[inline(always)]
    fn to_f64(self, a: &mut [f64; WIDTH]) {
        let p = a.as_mut_ptr();
        unsafe {
            _mm256_storeu_pd(p, self.0[0]);
            _mm256_storeu_pd(p.add(4), self.0[1]);
            _mm256_storeu_pd(p.add(8), self.0[2]);
            _mm256_storeu_pd(p.add(12), self.0[3]);
        }
    }
    op64!(add, _mm256_add_pd);
    op64!(sub, _mm256_sub_pd);
    op64!(mul, _mm256_mul_pd);
    op64!(div, _mm256_div_pd);
    op64!(min, _mm256_min_pd);
    op64!(max, _mm256_max_pd);
    #[inline(always)]
    fn abs(self) -> Self {
        Self::splat(-0.0).andnot(self)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        let a = self.0;
        unsafe {
            YD([
                _mm256_sqrt_pd(a[0]),
                _mm256_sqrt_pd(a[1]),
                _mm256_sqrt_pd(a[2]),
                _mm256_sqrt_pd(a[3]),
            ])
        }
    }
    #[inline(always)]
    fn neg(self) -> Self {
        Self::splat(-0.0).xor(self)
    }
    cmp64!(lt, _CMP_LT_OQ);
    cmp64!(le, _CMP_LE_OQ);
    cmp64!(eq, _CMP_EQ_OQ);
    cmp_select64!(lt_select, _CMP_LT_OQ);
    cmp_select64!(le_select, _CMP_LE_OQ);
    #[inline(always)]
    fn sign_select(self, a: Self, b: Self) -> Self {
        let (x, a, b) = (self.0, a.0, b.0);
        unsafe {
            YD([
                _mm256_blendv_pd(b[0], a[0], x[0]),
                _mm256_blendv_pd(b[1], a[1], x[1]),
                _mm256_blendv_pd(b[2], a[2], x[2]),
                _mm256_blendv_pd(b[3], a[3], x[3]),
            ])
        }
    }
    #[inline(always)]
    fn sign(self) -> u32 {
        let a = self.0;
        unsafe {
            _mm256_movemask_pd(a[0]) as u32
                | (_mm256_movemask_pd(a[1]) as u32) << 4
                | (_mm256_movemask_pd(a[2]) as u32) << 8
                | (_mm256_movemask_pd(a[3]) as u32) << 12
        }
    }
    #[inline(always)]
    fn select(m: u32, a: Self, b: Self) -> Self {
        let (a, b) = (a.0, b.0);
        unsafe {
            let m = _mm256_set1_epi64x(m as i64);
            YD([
                _mm256_blendv_pd(b[0], a[0], sign_bits64(m, 0)),
                _mm256_blendv_pd(b[1], a[1], sign_bits64(m, 4)),
                _mm256_blendv_pd(b[2], a[2], sign_bits64(m, 8)),
                _mm256_blendv_pd(b[3], a[3], sign_bits64(m, 12)),
            ])
        }
    }
}

/// 16 u64 lanes in four ymm registers (lanes 0–3, 4–7, 8–11, 12–15).
#[derive(Clone, Copy)]
pub struct YU([__m256i; 4]);

macro_rules! opu {
    ($name:ident, $f:ident) => {
        #[inline(always)]
        fn $name(self, o: Self) -> Self {
            let (a, b) = (self.0, o.0);
            unsafe {
                YU([
                    $f(a[0], b[0]),
                    $f(a[1], b[1]),
                    $f(a[2], b[2]),
                    $f(a[3], b[3]),
                ])
            }
        }
    };
}

/// The low 64 bits of a·b per lane from 32-bit products (AVX2 has no 64-bit multiply):
/// lo·lo + (hi·lo + lo·hi)·2³².
#[inline(always)]
fn mullo_epi64(a: __m256i, b: __m256i) -> __m256i {
    unsafe {
        let lo = _mm256_mul_epu32(a, b);
        let cross = _mm256_add_epi64(
            _mm256_mul_epu32(_mm256_srli_epi64::<32>(a), b),
            _mm256_mul_epu32(a, _mm256_srli_epi64::<32>(b)),
        );
        _mm256_add_epi64(lo, _mm256_slli_epi64::<32>(cross))
    }
}

/// The low 32 bits of the four u64 lanes of `a` and of `b`, as eight i32 lanes (a's first).
#[inline(always)]
fn low_halves(a: __m256i, b: __m256i) -> __m256i {
    unsafe {
        let even = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
        let (a, b) = (
            _mm256_permutevar8x32_epi32(a, even),
            _mm256_permutevar8x32_epi32(b, even),
        );
        _mm256_permute2x128_si256::<0x20>(a, b)
    }
}

impl VectorU64<WIDTH> for YU {
    #[inline(always)]
    fn splat(x: u64) -> Self {
        unsafe { YU([_mm256_set1_epi64x(x as i64); 4]) }
    }
    #[inline(always)]
    fn load(a: &[u64; WIDTH]) -> Self {
        let p = a.as_ptr() as *const __m256i;
        unsafe {
            YU([
                _mm256_loadu_si256(p),
                _mm256_loadu_si256(p.add(1)),
                _mm256_loadu_si256(p.add(2)),
                _mm256_loadu_si256(p.add(3)),
            ])
        }
    }
    #[inline(always)]
    fn store(self, a: &mut [u64; WIDTH]) {
        let p = a.as_mut_ptr() as *mut __m256i;
        unsafe {
            for (i, v) in self.0.iter().enumerate() {
                _mm256_storeu_si256(p.add(i), *v);
            }
        }
    }
    opu!(add, _mm256_add_epi64);
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        let (a, b) = (self.0, o.0);
        YU([
            mullo_epi64(a[0], b[0]),
            mullo_epi64(a[1], b[1]),
            mullo_epi64(a[2], b[2]),
            mullo_epi64(a[3], b[3]),
        ])
    }
    opu!(mul32, _mm256_mul_epu32);
    opu!(xor, _mm256_xor_si256);
    opu!(or, _mm256_or_si256);
    opu!(and, _mm256_and_si256);
    opu!(shr_lanes, _mm256_srlv_epi64);
    #[inline(always)]
    fn shr(self, k: u32) -> Self {
        unsafe {
            let k = _mm_cvtsi32_si128(k as i32);
            YU(self.0.map(|v| _mm256_srl_epi64(v, k)))
        }
    }
    #[inline(always)]
    fn shl(self, k: u32) -> Self {
        unsafe {
            let k = _mm_cvtsi32_si128(k as i32);
            YU(self.0.map(|v| _mm256_sll_epi64(v, k)))
        }
    }
    #[inline(always)]
    fn to_f32(self, a: &mut [f32; WIDTH]) {
        let v = self.0;
        unsafe {
            // Below 2³¹, so the low 32 bits as i32 are the value.
            let (lo, hi) = (low_halves(v[0], v[1]), low_halves(v[2], v[3]));
            _mm256_storeu_ps(a.as_mut_ptr(), _mm256_cvtepi32_ps(lo));
            _mm256_storeu_ps(a.as_mut_ptr().add(8), _mm256_cvtepi32_ps(hi));
        }
    }
}
