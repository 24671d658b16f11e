//! AVX2: a 16-lane vector is two ymm registers (lanes 0–7, 8–15). FMA is deliberately not
//! enabled, so the path rounds exactly like the others.
#![cfg(target_arch = "x86_64")]

use super::{Kernel, Lanes, Mask, WIDTH};
use std::arch::x86_64::*;

#[derive(Clone, Copy)]
pub struct Avx2;

/// # Safety
/// The CPU must support avx2.
#[target_feature(enable = "avx2")]
pub unsafe fn entry<K: Kernel>(k: K) -> K::Out {
    k.run::<Avx2>()
}

#[derive(Clone, Copy)]
pub struct V2(__m256, __m256);

macro_rules! both {
    ($f:ident, $a:expr, $b:expr) => {
        unsafe { V2($f($a.0, $b.0), $f($a.1, $b.1)) }
    };
}

#[inline(always)]
fn bits(lo: __m256, hi: __m256) -> Mask {
    unsafe { (_mm256_movemask_ps(lo) as u32 | ((_mm256_movemask_ps(hi) as u32) << 8)) as Mask }
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

impl Lanes for Avx2 {
    type V = V2;
    #[inline(always)]
    fn splat(x: f32) -> V2 {
        unsafe { V2(_mm256_set1_ps(x), _mm256_set1_ps(x)) }
    }
    #[inline(always)]
    fn load(a: &[f32; WIDTH]) -> V2 {
        unsafe {
            V2(
                _mm256_loadu_ps(a.as_ptr()),
                _mm256_loadu_ps(a.as_ptr().add(8)),
            )
        }
    }
    #[inline(always)]
    fn store(v: V2, a: &mut [f32; WIDTH]) {
        unsafe {
            _mm256_storeu_ps(a.as_mut_ptr(), v.0);
            _mm256_storeu_ps(a.as_mut_ptr().add(8), v.1);
        }
    }
    #[inline(always)]
    fn add(a: V2, b: V2) -> V2 {
        both!(_mm256_add_ps, a, b)
    }
    #[inline(always)]
    fn sub(a: V2, b: V2) -> V2 {
        both!(_mm256_sub_ps, a, b)
    }
    #[inline(always)]
    fn mul(a: V2, b: V2) -> V2 {
        both!(_mm256_mul_ps, a, b)
    }
    #[inline(always)]
    fn div(a: V2, b: V2) -> V2 {
        both!(_mm256_div_ps, a, b)
    }
    #[inline(always)]
    fn min(a: V2, b: V2) -> V2 {
        both!(_mm256_min_ps, a, b)
    }
    #[inline(always)]
    fn max(a: V2, b: V2) -> V2 {
        both!(_mm256_max_ps, a, b)
    }
    #[inline(always)]
    fn abs(a: V2) -> V2 {
        unsafe {
            let sign = _mm256_set1_ps(-0.0);
            V2(_mm256_andnot_ps(sign, a.0), _mm256_andnot_ps(sign, a.1))
        }
    }
    #[inline(always)]
    fn lt(a: V2, b: V2) -> Mask {
        unsafe {
            bits(
                _mm256_cmp_ps::<_CMP_LT_OQ>(a.0, b.0),
                _mm256_cmp_ps::<_CMP_LT_OQ>(a.1, b.1),
            )
        }
    }
    #[inline(always)]
    fn le(a: V2, b: V2) -> Mask {
        unsafe {
            bits(
                _mm256_cmp_ps::<_CMP_LE_OQ>(a.0, b.0),
                _mm256_cmp_ps::<_CMP_LE_OQ>(a.1, b.1),
            )
        }
    }
    #[inline(always)]
    fn eq(a: V2, b: V2) -> Mask {
        unsafe {
            bits(
                _mm256_cmp_ps::<_CMP_EQ_OQ>(a.0, b.0),
                _mm256_cmp_ps::<_CMP_EQ_OQ>(a.1, b.1),
            )
        }
    }
    #[inline(always)]
    fn select(m: Mask, a: V2, b: V2) -> V2 {
        unsafe {
            V2(
                _mm256_blendv_ps(b.0, a.0, expand(m as u32 & 0xff)),
                _mm256_blendv_ps(b.1, a.1, expand(m as u32 >> 8)),
            )
        }
    }
}
