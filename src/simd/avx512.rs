//! AVX-512 (F and DQ): one zmm register per 16 lanes, comparisons straight into k-masks; the
//! 8-lane vector is the AVX2 path's ymm type (avx512f implies avx2), compiled here with
//! AVX-512 enabled. DQ is for `vpmullq` (the random streams' 64-bit products); every AVX-512
//! CPU since Skylake-SP has it.
#![cfg(target_arch = "x86_64")]

use super::avx2::Y;
use super::{Kernel, Lanes, Vector, Vector64, VectorU64, WIDTH};
use std::arch::x86_64::*;

#[derive(Clone, Copy)]
pub struct Avx512;

/// The whole kernel is compiled for AVX-512F here; the `#[inline(always)]` lane functions
/// inline into it.
///
/// # Safety
/// The CPU must support avx512f and avx512dq.
#[target_feature(enable = "avx512f,avx512dq")]
pub unsafe fn entry<K: Kernel>(k: K) -> K::Out {
    k.run::<Avx512>()
}

impl Lanes for Avx512 {
    type V = Z;
    type W = Y;
    type D = ZD;
    type U = ZU;
}

#[derive(Clone, Copy)]
pub struct Z(__m512);

macro_rules! op {
    ($name:ident, $f:ident) => {
        #[inline(always)]
        fn $name(self, o: Self) -> Self {
            unsafe { Z($f(self.0, o.0)) }
        }
    };
}

macro_rules! cmp {
    ($name:ident, $p:ident) => {
        #[inline(always)]
        fn $name(self, o: Self) -> u32 {
            unsafe { _mm512_cmp_ps_mask::<$p>(self.0, o.0) as u32 }
        }
    };
}

impl Vector<WIDTH> for Z {
    #[inline(always)]
    fn splat(x: f32) -> Self {
        unsafe { Z(_mm512_set1_ps(x)) }
    }
    #[inline(always)]
    fn load(a: &[f32; WIDTH]) -> Self {
        unsafe { Z(_mm512_loadu_ps(a.as_ptr())) }
    }
    #[inline(always)]
    fn store(self, a: &mut [f32; WIDTH]) {
        unsafe { _mm512_storeu_ps(a.as_mut_ptr(), self.0) }
    }
    op!(add, _mm512_add_ps);
    op!(sub, _mm512_sub_ps);
    op!(mul, _mm512_mul_ps);
    op!(div, _mm512_div_ps);
    op!(min, _mm512_min_ps);
    op!(max, _mm512_max_ps);
    #[inline(always)]
    fn abs(self) -> Self {
        unsafe { Z(_mm512_abs_ps(self.0)) }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        unsafe { Z(_mm512_sqrt_ps(self.0)) }
    }
    #[inline(always)]
    fn neg(self) -> Self {
        // avx512f has no xor_ps (that is avx512dq): flip the sign bit as integers.
        unsafe {
            Z(_mm512_castsi512_ps(_mm512_xor_si512(
                _mm512_castps_si512(self.0),
                _mm512_set1_epi32(i32::MIN),
            )))
        }
    }
    /// As the AVX2 path, on k-masks.
    #[inline(always)]
    fn next_f32(self, up: u32) -> Self {
        unsafe {
            let bits = _mm512_castps_si512(self.0);
            let up = up as __mmask16;
            let abs = _mm512_and_si512(bits, _mm512_set1_epi32(0x7fff_ffff));
            let neg = _mm512_cmplt_epi32_mask(bits, _mm512_setzero_si512());
            let away = neg ^ up;
            let one = _mm512_set1_epi32(1);
            let stepped = _mm512_mask_blend_epi32(
                away,
                _mm512_sub_epi32(bits, one),
                _mm512_add_epi32(bits, one),
            );
            let from_zero =
                _mm512_mask_blend_epi32(up, _mm512_set1_epi32(0x8000_0001u32 as i32), one);
            let zero = _mm512_cmpeq_epi32_mask(abs, _mm512_setzero_si512());
            let r = _mm512_mask_blend_epi32(zero, stepped, from_zero);
            let inf = _mm512_set1_epi32(0x7f80_0000);
            let stays =
                _mm512_cmpgt_epi32_mask(abs, inf) | (_mm512_cmpeq_epi32_mask(abs, inf) & away);
            Z(_mm512_castsi512_ps(_mm512_mask_blend_epi32(stays, r, bits)))
        }
    }
    cmp!(lt, _CMP_LT_OQ);
    cmp!(le, _CMP_LE_OQ);
    cmp!(eq, _CMP_EQ_OQ);
    #[inline(always)]
    fn sign(self) -> u32 {
        sign_bits(self.0)
    }
    #[inline(always)]
    fn select(m: u32, a: Self, b: Self) -> Self {
        // mask_blend takes the second operand where the bit is set.
        unsafe { Z(_mm512_mask_blend_ps(m as __mmask16, b.0, a.0)) }
    }
    #[inline(always)]
    fn reduce_min(self) -> f32 {
        unsafe { _mm512_reduce_min_ps(self.0) }
    }
    #[inline(always)]
    fn reduce_max(self) -> f32 {
        unsafe { _mm512_reduce_max_ps(self.0) }
    }
    #[inline(always)]
    fn trunc_u32(self, a: &mut [u32; WIDTH]) {
        unsafe { _mm512_storeu_si512(a.as_mut_ptr() as *mut _, _mm512_cvttps_epi32(self.0)) }
    }
    #[inline(always)]
    fn load_records(rows: &[&[f32; 4]; WIDTH]) -> [Self; 4] {
        unsafe {
            // r[j]'s 128-bit block b is the record of lane 4b + j; a 4×4 transpose within
            // each block then gives component k of lanes 4b..4b + 3 in block b of vector k.
            let q = |i: usize| _mm_loadu_ps(rows[i].as_ptr());
            let r: [__m512; 4] = std::array::from_fn(|j| {
                let v = _mm512_castps128_ps512(q(j));
                let v = _mm512_insertf32x4::<1>(v, q(4 + j));
                let v = _mm512_insertf32x4::<2>(v, q(8 + j));
                _mm512_insertf32x4::<3>(v, q(12 + j))
            });
            let t0 = _mm512_castps_pd(_mm512_unpacklo_ps(r[0], r[1]));
            let t1 = _mm512_castps_pd(_mm512_unpackhi_ps(r[0], r[1]));
            let t2 = _mm512_castps_pd(_mm512_unpacklo_ps(r[2], r[3]));
            let t3 = _mm512_castps_pd(_mm512_unpackhi_ps(r[2], r[3]));
            [
                Z(_mm512_castpd_ps(_mm512_unpacklo_pd(t0, t2))),
                Z(_mm512_castpd_ps(_mm512_unpackhi_pd(t0, t2))),
                Z(_mm512_castpd_ps(_mm512_unpacklo_pd(t1, t3))),
                Z(_mm512_castpd_ps(_mm512_unpackhi_pd(t1, t3))),
            ]
        }
    }
}

/// Sign bits of 16 lanes (avx512f has no movmskps for zmm: compare as integers against 0).
#[inline(always)]
fn sign_bits(v: __m512) -> u32 {
    unsafe { _mm512_cmplt_epi32_mask(_mm512_castps_si512(v), _mm512_setzero_si512()) as u32 }
}

/// 16 f64 lanes in two zmm registers (lanes 0–7, 8–15); k-masks of 8 bits each.
#[derive(Clone, Copy)]
pub struct ZD(__m512d, __m512d);

macro_rules! op64 {
    ($name:ident, $f:ident) => {
        #[inline(always)]
        fn $name(self, o: Self) -> Self {
            unsafe { ZD($f(self.0, o.0), $f(self.1, o.1)) }
        }
    };
}

macro_rules! cmp64 {
    ($name:ident, $p:ident) => {
        #[inline(always)]
        fn $name(self, o: Self) -> u32 {
            unsafe {
                _mm512_cmp_pd_mask::<$p>(self.0, o.0) as u32
                    | (_mm512_cmp_pd_mask::<$p>(self.1, o.1) as u32) << 8
            }
        }
    };
}

/// The sign bit of every lane as a 64-bit integer.
#[inline(always)]
fn sign64() -> __m512i {
    unsafe { _mm512_set1_epi64(i64::MIN) }
}

/// |x| and −x: avx512f has no and/xor for pd (that is avx512dq), so as integers. Functions,
/// not closures: a closure is not always inlined into the ISA's entry.
#[inline(always)]
fn abs_pd(x: __m512d) -> __m512d {
    unsafe { _mm512_castsi512_pd(_mm512_andnot_si512(sign64(), _mm512_castpd_si512(x))) }
}

#[inline(always)]
fn neg_pd(x: __m512d) -> __m512d {
    unsafe { _mm512_castsi512_pd(_mm512_xor_si512(sign64(), _mm512_castpd_si512(x))) }
}

#[inline(always)]
fn sign_pd(x: __m512d) -> u32 {
    unsafe { _mm512_test_epi64_mask(_mm512_castpd_si512(x), sign64()) as u32 }
}

impl Vector64<WIDTH> for ZD {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        unsafe { ZD(_mm512_set1_pd(x), _mm512_set1_pd(x)) }
    }
    #[inline(always)]
    fn from_f64(a: &[f64; WIDTH]) -> Self {
        unsafe {
            ZD(
                _mm512_loadu_pd(a.as_ptr()),
                _mm512_loadu_pd(a.as_ptr().add(8)),
            )
        }
    }
    #[inline(always)]
    fn from_f32(a: &[f32; WIDTH]) -> Self {
        unsafe {
            ZD(
                _mm512_cvtps_pd(_mm256_loadu_ps(a.as_ptr())),
                _mm512_cvtps_pd(_mm256_loadu_ps(a.as_ptr().add(8))),
            )
        }
    }
    #[inline(always)]
    fn to_f32(self, a: &mut [f32; WIDTH]) {
        // Rounded to nearest, as `as f32`.
        unsafe {
            _mm256_storeu_ps(a.as_mut_ptr(), _mm512_cvtpd_ps(self.0));
            _mm256_storeu_ps(a.as_mut_ptr().add(8), _mm512_cvtpd_ps(self.1));
        }
    }
    #[inline(always)]
    fn to_f64(self, a: &mut [f64; WIDTH]) {
        unsafe {
            _mm512_storeu_pd(a.as_mut_ptr(), self.0);
            _mm512_storeu_pd(a.as_mut_ptr().add(8), self.1);
        }
    }
    op64!(add, _mm512_add_pd);
    op64!(sub, _mm512_sub_pd);
    op64!(mul, _mm512_mul_pd);
    op64!(div, _mm512_div_pd);
    op64!(min, _mm512_min_pd);
    op64!(max, _mm512_max_pd);
    #[inline(always)]
    fn abs(self) -> Self {
        ZD(abs_pd(self.0), abs_pd(self.1))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        unsafe { ZD(_mm512_sqrt_pd(self.0), _mm512_sqrt_pd(self.1)) }
    }
    #[inline(always)]
    fn neg(self) -> Self {
        ZD(neg_pd(self.0), neg_pd(self.1))
    }
    cmp64!(lt, _CMP_LT_OQ);
    cmp64!(le, _CMP_LE_OQ);
    cmp64!(eq, _CMP_EQ_OQ);
    #[inline(always)]
    fn sign(self) -> u32 {
        sign_pd(self.0) | sign_pd(self.1) << 8
    }
    #[inline(always)]
    fn select(m: u32, a: Self, b: Self) -> Self {
        // mask_blend takes the second operand where the bit is set.
        unsafe {
            ZD(
                _mm512_mask_blend_pd(m as __mmask8, b.0, a.0),
                _mm512_mask_blend_pd((m >> 8) as __mmask8, b.1, a.1),
            )
        }
    }
}

/// 16 u64 lanes in two zmm registers (lanes 0–7, 8–15).
#[derive(Clone, Copy)]
pub struct ZU(__m512i, __m512i);

macro_rules! opu {
    ($name:ident, $f:ident) => {
        #[inline(always)]
        fn $name(self, o: Self) -> Self {
            unsafe { ZU($f(self.0, o.0), $f(self.1, o.1)) }
        }
    };
}

/// The low 64 bits of a·b per lane: avx512dq's `vpmullq`. Built from three 32-bit products
/// before, it made the random streams' seeding a chain of long dependencies: `vpmullq` gave
/// cornell's `light` 3–5 % more samples/s on an AMD EPYC (docs/tracer.md, stop 36).
#[inline(always)]
fn mullo_epi64(a: __m512i, b: __m512i) -> __m512i {
    unsafe { _mm512_mullo_epi64(a, b) }
}

impl VectorU64<WIDTH> for ZU {
    #[inline(always)]
    fn splat(x: u64) -> Self {
        unsafe { ZU(_mm512_set1_epi64(x as i64), _mm512_set1_epi64(x as i64)) }
    }
    #[inline(always)]
    fn load(a: &[u64; WIDTH]) -> Self {
        unsafe {
            let p = a.as_ptr() as *const __m512i;
            ZU(_mm512_loadu_si512(p), _mm512_loadu_si512(p.add(1)))
        }
    }
    #[inline(always)]
    fn store(self, a: &mut [u64; WIDTH]) {
        unsafe {
            let p = a.as_mut_ptr() as *mut __m512i;
            _mm512_storeu_si512(p, self.0);
            _mm512_storeu_si512(p.add(1), self.1);
        }
    }
    opu!(add, _mm512_add_epi64);
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        ZU(mullo_epi64(self.0, o.0), mullo_epi64(self.1, o.1))
    }
    opu!(mul32, _mm512_mul_epu32);
    opu!(xor, _mm512_xor_si512);
    opu!(or, _mm512_or_si512);
    opu!(and, _mm512_and_si512);
    opu!(shr_lanes, _mm512_srlv_epi64);
    #[inline(always)]
    fn rotr32(self, k: Self) -> Self {
        // Each 64-bit lane is two 32-bit words: the low one rotated by k (< 32), the high one
        // by k's zero high word, then cleared.
        unsafe {
            let low = _mm512_set1_epi64(0xffff_ffff);
            ZU(
                _mm512_and_si512(_mm512_rorv_epi32(self.0, k.0), low),
                _mm512_and_si512(_mm512_rorv_epi32(self.1, k.1), low),
            )
        }
    }
    #[inline(always)]
    fn shr(self, k: u32) -> Self {
        unsafe {
            let k = _mm_cvtsi32_si128(k as i32);
            ZU(_mm512_srl_epi64(self.0, k), _mm512_srl_epi64(self.1, k))
        }
    }
    #[inline(always)]
    fn shl(self, k: u32) -> Self {
        unsafe {
            let k = _mm_cvtsi32_si128(k as i32);
            ZU(_mm512_sll_epi64(self.0, k), _mm512_sll_epi64(self.1, k))
        }
    }
    #[inline(always)]
    fn to_f32(self, a: &mut [f32; WIDTH]) {
        unsafe {
            // Below 2³¹, so the low 32 bits as i32 are the value.
            let lo = _mm512_cvtepi64_epi32(self.0);
            let hi = _mm512_cvtepi64_epi32(self.1);
            let both = _mm512_inserti64x4::<1>(_mm512_castsi256_si512(lo), hi);
            _mm512_storeu_ps(a.as_mut_ptr(), _mm512_cvtepi32_ps(both));
        }
    }
}
