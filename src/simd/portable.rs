//! The portable path: plain arrays, scalar code with the same semantics as the SIMD paths.

use super::{Lanes, NARROW, Vector, Vector64, VectorU64, WIDTH};

#[derive(Clone, Copy)]
pub struct Portable;

impl Lanes for Portable {
    type V = P<WIDTH>;
    type W = P<NARROW>;
    type D = PD<WIDTH>;
    type U = PU<WIDTH>;
}

/// u64 lanes as a plain array: the portable path's [`Lanes::U`].
#[derive(Clone, Copy)]
pub struct PU<const N: usize>([u64; N]);

impl<const N: usize> PU<N> {
    #[inline(always)]
    fn map(self, f: impl Fn(u64) -> u64) -> Self {
        PU(self.0.map(f))
    }

    #[inline(always)]
    fn map2(self, o: Self, f: impl Fn(u64, u64) -> u64) -> Self {
        let mut r = [0; N];
        for (r, (a, b)) in r.iter_mut().zip(self.0.iter().zip(o.0.iter())) {
            *r = f(*a, *b);
        }
        PU(r)
    }
}

impl<const N: usize> VectorU64<N> for PU<N> {
    #[inline(always)]
    fn splat(x: u64) -> Self {
        PU([x; N])
    }
    #[inline(always)]
    fn load(a: &[u64; N]) -> Self {
        PU(*a)
    }
    #[inline(always)]
    fn store(self, a: &mut [u64; N]) {
        *a = self.0;
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self.map2(o, u64::wrapping_add)
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self.map2(o, u64::wrapping_mul)
    }
    #[inline(always)]
    fn mul32(self, o: Self) -> Self {
        self.map2(o, |a, b| (a as u32 as u64) * (b as u32 as u64))
    }
    #[inline(always)]
    fn xor(self, o: Self) -> Self {
        self.map2(o, |a, b| a ^ b)
    }
    #[inline(always)]
    fn or(self, o: Self) -> Self {
        self.map2(o, |a, b| a | b)
    }
    #[inline(always)]
    fn and(self, o: Self) -> Self {
        self.map2(o, |a, b| a & b)
    }
    #[inline(always)]
    fn shr(self, k: u32) -> Self {
        self.map(|a| a >> k)
    }
    #[inline(always)]
    fn shl(self, k: u32) -> Self {
        self.map(|a| a << k)
    }
    #[inline(always)]
    fn shr_lanes(self, k: Self) -> Self {
        self.map2(k, |a, k| a >> k)
    }
    #[inline(always)]
    fn to_f32(self, a: &mut [f32; N]) {
        for (a, x) in a.iter_mut().zip(self.0) {
            *a = x as f32;
        }
    }
}

/// One u64 is one lane: scalar code calls the code written over lanes with it.
impl VectorU64<1> for u64 {
    #[inline(always)]
    fn splat(x: u64) -> Self {
        x
    }
    #[inline(always)]
    fn load(a: &[u64; 1]) -> Self {
        a[0]
    }
    #[inline(always)]
    fn store(self, a: &mut [u64; 1]) {
        a[0] = self;
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self.wrapping_add(o)
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self.wrapping_mul(o)
    }
    #[inline(always)]
    fn mul32(self, o: Self) -> Self {
        (self as u32 as u64) * (o as u32 as u64)
    }
    #[inline(always)]
    fn xor(self, o: Self) -> Self {
        self ^ o
    }
    #[inline(always)]
    fn or(self, o: Self) -> Self {
        self | o
    }
    #[inline(always)]
    fn and(self, o: Self) -> Self {
        self & o
    }
    #[inline(always)]
    fn shr(self, k: u32) -> Self {
        self >> k
    }
    #[inline(always)]
    fn shl(self, k: u32) -> Self {
        self << k
    }
    #[inline(always)]
    fn shr_lanes(self, k: Self) -> Self {
        self >> k
    }
    #[inline(always)]
    fn to_f32(self, a: &mut [f32; 1]) {
        a[0] = self as f32;
    }
}

/// f64 lanes as a plain array: the portable path's [`Lanes::D`] (see there).
#[derive(Clone, Copy)]
pub struct PD<const N: usize>([f64; N]);

impl<const N: usize> PD<N> {
    #[inline(always)]
    fn map2(self, o: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        let mut r = [0.0; N];
        // Indexed, as measured: an iterator rewrite was not faster (sphere_light, 6 rounds).
        #[allow(clippy::needless_range_loop)]
        for i in 0..N {
            r[i] = f(self.0[i], o.0[i]);
        }
        PD(r)
    }

    #[inline(always)]
    fn bits(self, o: Self, f: impl Fn(f64, f64) -> bool) -> u32 {
        let mut m = 0;
        for i in 0..N {
            m |= (f(self.0[i], o.0[i]) as u32) << i;
        }
        m
    }
}

impl<const N: usize> Vector64<N> for PD<N> {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        PD([x; N])
    }
    #[inline(always)]
    fn from_f64(a: &[f64; N]) -> Self {
        PD(*a)
    }
    #[inline(always)]
    fn from_f32(a: &[f32; N]) -> Self {
        let mut r = [0.0; N];
        for i in 0..N {
            r[i] = a[i] as f64;
        }
        PD(r)
    }
    #[inline(always)]
    fn to_f32(self, a: &mut [f32; N]) {
        #[allow(clippy::needless_range_loop)]
        for i in 0..N {
            a[i] = self.0[i] as f32;
        }
    }
    #[inline(always)]
    fn to_f64(self, a: &mut [f64; N]) {
        *a = self.0;
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self.map2(o, |x, y| x + y)
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self.map2(o, |x, y| x - y)
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self.map2(o, |x, y| x * y)
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        self.map2(o, |x, y| x / y)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        self.map2(o, |x, y| if x < y { x } else { y })
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        self.map2(o, |x, y| if x > y { x } else { y })
    }
    #[inline(always)]
    fn abs(self) -> Self {
        let mut r = self.0;
        for x in &mut r {
            *x = x.abs();
        }
        PD(r)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        let mut r = self.0;
        for x in &mut r {
            *x = x.sqrt();
        }
        PD(r)
    }
    #[inline(always)]
    fn neg(self) -> Self {
        let mut r = self.0;
        for x in &mut r {
            *x = -*x;
        }
        PD(r)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> u32 {
        self.bits(o, |x, y| x < y)
    }
    #[inline(always)]
    fn le(self, o: Self) -> u32 {
        self.bits(o, |x, y| x <= y)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> u32 {
        self.bits(o, |x, y| x == y)
    }
    #[inline(always)]
    fn sign(self) -> u32 {
        self.bits(self, |x, _| x.is_sign_negative())
    }
    #[inline(always)]
    fn select(m: u32, a: Self, b: Self) -> Self {
        // By bit masks, which vectorise into blends (a branch per lane would not).
        let mut r = [0.0; N];
        for (i, x) in r.iter_mut().enumerate() {
            let keep = 0u64.wrapping_sub((m >> i & 1) as u64);
            *x = f64::from_bits((a.0[i].to_bits() & keep) | (b.0[i].to_bits() & !keep));
        }
        PD(r)
    }
}

#[derive(Clone, Copy)]
pub struct P<const N: usize>([f32; N]);

impl<const N: usize> P<N> {
    #[inline(always)]
    fn map2(self, o: Self, f: impl Fn(f32, f32) -> f32) -> Self {
        P(std::array::from_fn(|i| f(self.0[i], o.0[i])))
    }

    #[inline(always)]
    fn bits(self, o: Self, f: impl Fn(f32, f32) -> bool) -> u32 {
        let mut m = 0;
        for i in 0..N {
            m |= (f(self.0[i], o.0[i]) as u32) << i;
        }
        m
    }
}

impl<const N: usize> Vector<N> for P<N> {
    #[inline(always)]
    fn splat(x: f32) -> Self {
        P([x; N])
    }
    #[inline(always)]
    fn load(a: &[f32; N]) -> Self {
        P(*a)
    }
    #[inline(always)]
    fn store(self, a: &mut [f32; N]) {
        *a = self.0;
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self.map2(o, |x, y| x + y)
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self.map2(o, |x, y| x - y)
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self.map2(o, |x, y| x * y)
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        self.map2(o, |x, y| x / y)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        self.map2(o, |x, y| if x < y { x } else { y })
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        self.map2(o, |x, y| if x > y { x } else { y })
    }
    #[inline(always)]
    fn abs(self) -> Self {
        P(self.0.map(f32::abs))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        P(self.0.map(f32::sqrt))
    }
    #[inline(always)]
    fn neg(self) -> Self {
        P(self.0.map(|x| -x))
    }
    #[inline(always)]
    fn next_f32(self, up: u32) -> Self {
        P(std::array::from_fn(|i| {
            crate::math::next_f32(self.0[i], up >> i & 1 != 0)
        }))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> u32 {
        self.bits(o, |x, y| x < y)
    }
    #[inline(always)]
    fn le(self, o: Self) -> u32 {
        self.bits(o, |x, y| x <= y)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> u32 {
        self.bits(o, |x, y| x == y)
    }
    #[inline(always)]
    fn sign(self) -> u32 {
        self.bits(self, |x, _| x.is_sign_negative())
    }
    #[inline(always)]
    fn reduce_min(self) -> f32 {
        let mut m = self.0[0];
        for &x in &self.0[1..] {
            m = if x < m { x } else { m };
        }
        m
    }
    #[inline(always)]
    fn reduce_max(self) -> f32 {
        let mut m = self.0[0];
        for &x in &self.0[1..] {
            m = if x > m { x } else { m };
        }
        m
    }
    #[inline(always)]
    fn trunc_u32(self, a: &mut [u32; N]) {
        for (o, x) in a.iter_mut().zip(self.0) {
            *o = x as u32;
        }
    }
    #[inline(always)]
    fn select(m: u32, a: Self, b: Self) -> Self {
        P(std::array::from_fn(|i| {
            if m & (1 << i) != 0 { a.0[i] } else { b.0[i] }
        }))
    }
}

/// One f64 is a one-lane f64 vector, as [`Vector<1> for f32`](Vector) is for f32: scalar code
/// runs the f64 kernels written over lanes (the spherical rectangle, its trigonometry).
impl Vector64<1> for f64 {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn from_f64(a: &[f64; 1]) -> Self {
        a[0]
    }
    #[inline(always)]
    fn from_f32(a: &[f32; 1]) -> Self {
        a[0] as f64
    }
    #[inline(always)]
    fn to_f32(self, a: &mut [f32; 1]) {
        a[0] = self as f32;
    }
    #[inline(always)]
    fn to_f64(self, a: &mut [f64; 1]) {
        a[0] = self;
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self + o
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self - o
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self * o
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        self / o
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        if self < o { self } else { o }
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        if self > o { self } else { o }
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f64::abs(self)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn neg(self) -> Self {
        -self
    }
    #[inline(always)]
    fn lt(self, o: Self) -> u32 {
        (self < o) as u32
    }
    #[inline(always)]
    fn le(self, o: Self) -> u32 {
        (self <= o) as u32
    }
    #[inline(always)]
    fn eq(self, o: Self) -> u32 {
        (self == o) as u32
    }
    #[inline(always)]
    fn sign(self) -> u32 {
        self.is_sign_negative() as u32
    }
    #[inline(always)]
    fn select(m: u32, a: Self, b: Self) -> Self {
        let keep = 0u64.wrapping_sub((m & 1) as u64);
        f64::from_bits((a.to_bits() & keep) | (b.to_bits() & !keep))
    }
}

/// One f32 is a one-lane vector: scalar code calls a kernel written over lanes with it, so the
/// scalar path and the lanes run one piece of code (as Mitsuba 3's warps do over `Float`), with
/// the same operations in the same order and hence the same results.
impl Vector<1> for f32 {
    #[inline(always)]
    fn splat(x: f32) -> Self {
        x
    }
    #[inline(always)]
    fn load(a: &[f32; 1]) -> Self {
        a[0]
    }
    #[inline(always)]
    fn store(self, a: &mut [f32; 1]) {
        a[0] = self;
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self + o
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self - o
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self * o
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        self / o
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        if self < o { self } else { o }
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        if self > o { self } else { o }
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn neg(self) -> Self {
        -self
    }
    #[inline(always)]
    fn next_f32(self, up: u32) -> Self {
        crate::math::next_f32(self, up & 1 != 0)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> u32 {
        (self < o) as u32
    }
    #[inline(always)]
    fn le(self, o: Self) -> u32 {
        (self <= o) as u32
    }
    #[inline(always)]
    fn eq(self, o: Self) -> u32 {
        (self == o) as u32
    }
    #[inline(always)]
    fn sign(self) -> u32 {
        self.is_sign_negative() as u32
    }
    /// By bit masks, not a branch: the lanes' selects take data-dependent sides (a quadrant, a
    /// half plane), which a branch would mispredict about half the time.
    #[inline(always)]
    fn select(m: u32, a: Self, b: Self) -> Self {
        let keep = 0u32.wrapping_sub(m & 1);
        f32::from_bits((a.to_bits() & keep) | (b.to_bits() & !keep))
    }
    #[inline(always)]
    fn reduce_min(self) -> f32 {
        self
    }
    #[inline(always)]
    fn reduce_max(self) -> f32 {
        self
    }
    #[inline(always)]
    fn trunc_u32(self, a: &mut [u32; 1]) {
        a[0] = self as u32;
    }
}
