//! Three-vectors of 16 lanes (structure of arrays) for sample-path kernels, with glam's
//! `Vec3` operations in glam's order (`dot` is `(x·x' + y·y') + z·z'`, `normalize` multiplies
//! by `1 / length`), so a kernel over lanes rounds exactly as the scalar code it mirrors.

use super::{Vector, Vector64, WIDTH};
use glam::Vec3;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Per-lane components of 16 vectors.
#[derive(Clone, Copy)]
pub struct V3<V> {
    pub x: V,
    pub y: V,
    pub z: V,
}

/// 16 vectors as three lane arrays, the layout [`V3`] loads from and stores to.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Soa3 {
    pub x: [f32; WIDTH],
    pub y: [f32; WIDTH],
    pub z: [f32; WIDTH],
}

impl Soa3 {
    /// `v` in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3) -> Self {
        Soa3 {
            x: [v.x; WIDTH],
            y: [v.y; WIDTH],
            z: [v.z; WIDTH],
        }
    }

    #[inline(always)]
    pub fn set(&mut self, lane: usize, v: Vec3) {
        self.x[lane] = v.x;
        self.y[lane] = v.y;
        self.z[lane] = v.z;
    }

    #[inline(always)]
    pub fn get(&self, lane: usize) -> Vec3 {
        Vec3::new(self.x[lane], self.y[lane], self.z[lane])
    }
}

impl<V: Vector<WIDTH>> V3<V> {
    #[inline(always)]
    pub fn load(a: &Soa3) -> Self {
        V3 {
            x: V::load(&a.x),
            y: V::load(&a.y),
            z: V::load(&a.z),
        }
    }

    #[inline(always)]
    pub fn store(self, a: &mut Soa3) {
        self.x.store(&mut a.x);
        self.y.store(&mut a.y);
        self.z.store(&mut a.z);
    }

    #[inline(always)]
    pub fn splat(v: Vec3) -> Self {
        V3 {
            x: V::splat(v.x),
            y: V::splat(v.y),
            z: V::splat(v.z),
        }
    }

    /// Every component times the lane's scalar (`Vec3 * f32`).
    #[inline(always)]
    pub fn scale(self, s: V) -> Self {
        V3 {
            x: self.x.mul(s),
            y: self.y.mul(s),
            z: self.z.mul(s),
        }
    }

    #[inline(always)]
    pub fn dot(self, o: Self) -> V {
        self.x.mul(o.x).add(self.y.mul(o.y)).add(self.z.mul(o.z))
    }

    #[inline(always)]
    pub fn abs(self) -> Self {
        V3 {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }

    /// Lane i = `a`'s where bit i of `m` is set, else `b`'s.
    #[inline(always)]
    pub fn select(m: u32, a: Self, b: Self) -> Self {
        V3 {
            x: V::select(m, a.x, b.x),
            y: V::select(m, a.y, b.y),
            z: V::select(m, a.z, b.z),
        }
    }
}

macro_rules! componentwise {
    ($trait:ident, $f:ident) => {
        impl<V: Vector<WIDTH>> $trait for V3<V> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                V3 {
                    x: self.x.$f(o.x),
                    y: self.y.$f(o.y),
                    z: self.z.$f(o.z),
                }
            }
        }
    };
}

componentwise!(Add, add);
componentwise!(Sub, sub);
// Component-wise product.
componentwise!(Mul, mul);

/// Every component divided by the lane's scalar (`Vec3 / f32`: three divisions, not a
/// reciprocal).
impl<V: Vector<WIDTH>> Div<V> for V3<V> {
    type Output = Self;
    #[inline(always)]
    fn div(self, s: V) -> Self {
        V3 {
            x: self.x.div(s),
            y: self.y.div(s),
            z: self.z.div(s),
        }
    }
}

/// The sign bits flipped (`-v`).
impl<V: Vector<WIDTH>> Neg for V3<V> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        V3 {
            x: self.x.neg(),
            y: self.y.neg(),
            z: self.z.neg(),
        }
    }
}

/// f64 three-vectors over lanes (`[x, y, z]`), for the kernels whose numerics need f64, with
/// glam's `DVec3` operations in glam's order. Functions, not closures: a closure is not always
/// inlined into the ISA's entry, and outside it its vector operations are calls.
pub type D3<D> = [D; 3];

/// `(x·x′ + y·y′) + z·z′`.
#[inline(always)]
pub fn dot3<D: Vector64<N>, const N: usize>(a: D3<D>, b: D3<D>) -> D {
    a[0].mul(b[0]).add(a[1].mul(b[1])).add(a[2].mul(b[2]))
}

#[inline(always)]
pub fn cross3<D: Vector64<N>, const N: usize>(a: D3<D>, b: D3<D>) -> D3<D> {
    [
        a[1].mul(b[2]).sub(b[1].mul(a[2])),
        a[2].mul(b[0]).sub(b[2].mul(a[0])),
        a[0].mul(b[1]).sub(b[0].mul(a[1])),
    ]
}

#[inline(always)]
pub fn scale3<D: Vector64<N>, const N: usize>(a: D3<D>, s: D) -> D3<D> {
    [a[0].mul(s), a[1].mul(s), a[2].mul(s)]
}

/// Each component divided by `s` (not multiplied by 1/s).
#[inline(always)]
pub fn div3<D: Vector64<N>, const N: usize>(a: D3<D>, s: D) -> D3<D> {
    [a[0].div(s), a[1].div(s), a[2].div(s)]
}

/// `a` times 1/|a|, as glam normalises.
#[inline(always)]
pub fn normalize3<D: Vector64<N>, const N: usize>(a: D3<D>) -> D3<D> {
    scale3(a, D::splat(1.0).div(dot3(a, a).sqrt()))
}

#[inline(always)]
pub fn add3<D: Vector64<N>, const N: usize>(a: D3<D>, b: D3<D>) -> D3<D> {
    [a[0].add(b[0]), a[1].add(b[1]), a[2].add(b[2])]
}

#[inline(always)]
pub fn sub3<D: Vector64<N>, const N: usize>(a: D3<D>, b: D3<D>) -> D3<D> {
    [a[0].sub(b[0]), a[1].sub(b[1]), a[2].sub(b[2])]
}

#[inline(always)]
pub fn neg3<D: Vector64<N>, const N: usize>(a: D3<D>) -> D3<D> {
    [a[0].neg(), a[1].neg(), a[2].neg()]
}

/// Per lane, `a` where `m` has the lane's bit, else `b`.
#[inline(always)]
pub fn select3<D: Vector64<N>, const N: usize>(m: u32, a: D3<D>, b: D3<D>) -> D3<D> {
    [
        D::select(m, a[0], b[0]),
        D::select(m, a[1], b[1]),
        D::select(m, a[2], b[2]),
    ]
}
