//! AVX-512F: one zmm register per 16 lanes, comparisons straight into k-masks.
#![cfg(target_arch = "x86_64")]

use super::{Kernel, Lanes, Mask, WIDTH};
use std::arch::x86_64::*;

#[derive(Clone, Copy)]
pub struct Avx512;

/// The whole kernel is compiled for AVX-512F here; the `#[inline(always)]` lane functions
/// inline into it.
///
/// # Safety
/// The CPU must support avx512f.
#[target_feature(enable = "avx512f")]
pub unsafe fn entry<K: Kernel>(k: K) -> K::Out {
    k.run::<Avx512>()
}

impl Lanes for Avx512 {
    type V = __m512;
    #[inline(always)]
    fn splat(x: f32) -> __m512 {
        unsafe { _mm512_set1_ps(x) }
    }
    #[inline(always)]
    fn load(a: &[f32; WIDTH]) -> __m512 {
        unsafe { _mm512_loadu_ps(a.as_ptr()) }
    }
    #[inline(always)]
    fn store(v: __m512, a: &mut [f32; WIDTH]) {
        unsafe { _mm512_storeu_ps(a.as_mut_ptr(), v) }
    }
    #[inline(always)]
    fn add(a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_add_ps(a, b) }
    }
    #[inline(always)]
    fn sub(a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_sub_ps(a, b) }
    }
    #[inline(always)]
    fn mul(a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_mul_ps(a, b) }
    }
    #[inline(always)]
    fn div(a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_div_ps(a, b) }
    }
    #[inline(always)]
    fn min(a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_min_ps(a, b) }
    }
    #[inline(always)]
    fn max(a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_max_ps(a, b) }
    }
    #[inline(always)]
    fn abs(a: __m512) -> __m512 {
        unsafe { _mm512_abs_ps(a) }
    }
    #[inline(always)]
    fn lt(a: __m512, b: __m512) -> Mask {
        unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(a, b) }
    }
    #[inline(always)]
    fn le(a: __m512, b: __m512) -> Mask {
        unsafe { _mm512_cmp_ps_mask::<_CMP_LE_OQ>(a, b) }
    }
    #[inline(always)]
    fn eq(a: __m512, b: __m512) -> Mask {
        unsafe { _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(a, b) }
    }
    #[inline(always)]
    fn select(m: Mask, a: __m512, b: __m512) -> __m512 {
        // mask_blend takes the second operand where the bit is set.
        unsafe { _mm512_mask_blend_ps(m, b, a) }
    }
}
