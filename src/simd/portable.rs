//! The portable path: plain arrays, scalar code with the same semantics as the SIMD paths.

use super::{Lanes, Mask, WIDTH};

#[derive(Clone, Copy)]
pub struct Portable;

type V = [f32; WIDTH];

#[inline(always)]
fn map2(a: V, b: V, f: impl Fn(f32, f32) -> f32) -> V {
    std::array::from_fn(|i| f(a[i], b[i]))
}

#[inline(always)]
fn cmp(a: V, b: V, f: impl Fn(f32, f32) -> bool) -> Mask {
    let mut m = 0;
    for i in 0..WIDTH {
        m |= (f(a[i], b[i]) as Mask) << i;
    }
    m
}

impl Lanes for Portable {
    type V = V;
    #[inline(always)]
    fn splat(x: f32) -> V {
        [x; WIDTH]
    }
    #[inline(always)]
    fn load(a: &V) -> V {
        *a
    }
    #[inline(always)]
    fn store(v: V, a: &mut V) {
        *a = v;
    }
    #[inline(always)]
    fn add(a: V, b: V) -> V {
        map2(a, b, |x, y| x + y)
    }
    #[inline(always)]
    fn sub(a: V, b: V) -> V {
        map2(a, b, |x, y| x - y)
    }
    #[inline(always)]
    fn mul(a: V, b: V) -> V {
        map2(a, b, |x, y| x * y)
    }
    #[inline(always)]
    fn div(a: V, b: V) -> V {
        map2(a, b, |x, y| x / y)
    }
    #[inline(always)]
    fn min(a: V, b: V) -> V {
        map2(a, b, |x, y| if x < y { x } else { y })
    }
    #[inline(always)]
    fn max(a: V, b: V) -> V {
        map2(a, b, |x, y| if x > y { x } else { y })
    }
    #[inline(always)]
    fn abs(a: V) -> V {
        a.map(f32::abs)
    }
    #[inline(always)]
    fn lt(a: V, b: V) -> Mask {
        cmp(a, b, |x, y| x < y)
    }
    #[inline(always)]
    fn le(a: V, b: V) -> Mask {
        cmp(a, b, |x, y| x <= y)
    }
    #[inline(always)]
    fn eq(a: V, b: V) -> Mask {
        cmp(a, b, |x, y| x == y)
    }
    #[inline(always)]
    fn select(m: Mask, a: V, b: V) -> V {
        std::array::from_fn(|i| if m & (1 << i) != 0 { a[i] } else { b[i] })
    }
}
