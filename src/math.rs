//! Small numeric helpers shared by geometry, samplers and the renderer.

use crate::simd::{V3, Vector, Vector64, VectorU64, WIDTH};
use glam::Vec3;

/// An orthonormal frame around a unit normal (Duff et al., "Building an Orthonormal Basis,
/// Revisited", JCGT 2017): branch-free apart from the sign, no normalisation needed.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
}

impl Frame {
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    /// [`Self::from_normal`] over lanes, bit for bit: the (s, t) of each lane's unit normal.
    #[inline(always)]
    pub fn from_normal_lanes<V: Vector<WIDTH>>(n: V3<V>) -> (V3<V>, V3<V>) {
        let sign = n.z.sign_select(V::splat(-1.0), V::splat(1.0));
        let a = V::splat(-1.0).div(sign.add(n.z));
        let b = n.x.mul(n.y).mul(a);
        let s = V3 {
            x: V::splat(1.0).add(sign.mul(n.x).mul(n.x).mul(a)),
            y: sign.mul(b),
            z: sign.neg().mul(n.x),
        };
        let t = V3 {
            x: b,
            y: sign.add(n.y.mul(n.y).mul(a)),
            z: n.y.neg(),
        };
        (s, t)
    }

    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }

    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
}

/// atan2(y, x) in (−π, π], written once over lanes and used by scalar code as one lane (`f32`),
/// so a lookup computed over lanes and one computed alone give the same bits on every ISA and
/// C library. The octant reduction a = min/max(|x|, |y|), then atan a by Cephes' `atanf`
/// (Moshier 1989: the polynomial below tan(π/8), π/4 + atan((a − 1)/(a + 1)) above); within
/// 3.5 ulps (3.16 measured, see the test). atan2(0, 0) is 0 (no division by zero: the ratio is taken as 0).
#[inline(always)]
pub fn atan2<V: Vector<N>, const N: usize>(y: V, x: V) -> V {
    use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    let zero = V::splat(0.0);
    let one = V::splat(1.0);
    // hi ≥ 0, so hi ≤ 0 is hi = 0.
    let a = lo.div(hi.le_select(zero, one, hi));
    let tan_pi_8 = V::splat(0.414_213_57);
    let t = tan_pi_8.lt_select(a, a.sub(one).div(a.add(one)), a);
    let z = t.mul(t);
    let p = V::splat(8.053_744_5e-2)
        .mul(z)
        .add(V::splat(-1.387_768_6e-1))
        .mul(z)
        .add(V::splat(1.997_771_1e-1))
        .mul(z)
        .add(V::splat(-3.333_295e-1))
        .mul(z)
        .mul(t)
        .add(t);
    let r = tan_pi_8.lt_select(a, V::splat(FRAC_PI_4).add(p), p);
    // Back to the octant, the half plane and the sign of y.
    let r = ax.lt_select(ay, V::splat(FRAC_PI_2).sub(r), r);
    let r = x.lt_select(zero, V::splat(PI).sub(r), r);
    y.sign_select(r.neg(), r)
}

/// x rounded to the nearest integer (ties to even) by adding and subtracting 1.5·2⁵²: IEEE
/// additions only, so every ISA and the scalar path agree. For |x| < 2⁵¹.
#[inline(always)]
fn round64<D: Vector64<N>, const N: usize>(x: D) -> D {
    const SHIFT: f64 = 6_755_399_441_055_744.0;
    x.add(D::splat(SHIFT)).sub(D::splat(SHIFT))
}

/// The polynomial with coefficients `k`, highest power first, at `z` by Horner's rule:
/// (k₀·z + k₁)·z + … + kₙ, one product and one sum per step.
#[inline(always)]
fn horner<D: Vector64<N>, const N: usize, const K: usize>(z: D, k: [f64; K]) -> D {
    let mut acc = D::splat(k[0]);
    for &c in &k[1..] {
        acc = acc.mul(z).add(D::splat(c));
    }
    acc
}

/// (sin x, cos x) in f64, written once over lanes and used by scalar code as one lane (`f64`),
/// so the spherical rectangle sampled over lanes and alone gives the same bits on every ISA
/// and C library. Cody–Waite reduction by π/2 in three parts (fdlibm's `pio2_1`, `pio2_2`,
/// `pio2_2t`: exact products for |n| < 2²⁰), then fdlibm's minimax kernels on [−π/4, π/4]
/// (`__kernel_sin`, `__kernel_cos`, Sun Microsystems 1993) and the quadrant's swap and signs.
/// Within 1 ulp of libm for |x| ≤ 64π (the test; the samplers need [0, 2π]); far beyond, the
/// reduction's two roundings add about an ulp (2 at x ≈ 3800).
#[inline(always)]
pub fn sin_cos64<D: Vector64<N>, const N: usize>(x: D) -> (D, D) {
    let c = D::splat;
    let pio2_1 = f64::from_bits(0x3FF9_21FB_5440_0000);
    let pio2_2 = f64::from_bits(0x3DD0_B461_1A60_0000);
    let pio2_2t = f64::from_bits(0x3BA3_198A_2E03_7073);
    let n = round64(x.mul(c(std::f64::consts::FRAC_2_PI)));
    let z = x
        .sub(n.mul(c(pio2_1)))
        .sub(n.mul(c(pio2_2)))
        .sub(n.mul(c(pio2_2t)));
    let zz = z.mul(z);
    // sin z = z + z³·(S1 + z²·(S2 + … + z²·S6))
    let ps = horner(
        zz,
        [
            1.589_690_995_211_55e-10,
            -2.505_076_025_340_686_3e-8,
            2.755_731_370_707_006_8e-6,
            -1.984_126_982_985_795e-4,
            8.333_333_333_322_49e-3,
            -1.666_666_666_666_663_2e-1,
        ],
    );
    let sin = z.add(z.mul(zz).mul(ps));
    // cos z = 1 − z²/2 + z⁴·(C1 + z²·(C2 + … + z²·C6))
    let pc = horner(
        zz,
        [
            -1.135_964_755_778_819_5e-11,
            2.087_572_321_298_175e-9,
            -2.755_731_435_139_066_3e-7,
            2.480_158_728_947_673e-5,
            -1.388_888_888_887_411e-3,
            4.166_666_666_666_66e-2,
        ],
    );
    // fdlibm's two forms: 1 − (z²/2 − z²·r) below |z| = 0.3; above, z²/2 = qx + hz with qx its
    // high half (Dekker), so that 1 − qx is exact and the rounding falls on the small terms.
    let zr = zz.mul(zz.mul(pc));
    let h = c(0.5).mul(zz);
    let near = c(1.0).sub(h.sub(zr));
    let split = h.mul(c(134_217_729.0));
    let qx = split.sub(split.sub(h));
    let far = c(1.0).sub(qx).sub(h.sub(qx).sub(zr));
    let cos = zz.lt_select(c(0.09), near, far);
    // The quadrant n mod 4, exactly: n − 4·⌊n/4⌋, with ⌊n/4⌋ = round(n/4 − 3/8) for integer n.
    let q = n.sub(c(4.0).mul(round64(n.mul(c(0.25)).sub(c(0.375)))));
    let odd = q.eq(c(1.0)) | q.eq(c(3.0));
    let (s, co) = (D::select(odd, cos, sin), D::select(odd, sin, cos));
    let sin_neg = q.eq(c(2.0)) | q.eq(c(3.0));
    let cos_neg = q.eq(c(1.0)) | q.eq(c(2.0));
    (
        D::select(sin_neg, s.neg(), s),
        D::select(cos_neg, co.neg(), co),
    )
}

/// fdlibm's rational R(z) for asin on [0, 1/4]: asin x ≈ x + x·R(x²) for |x| ≤ 1/2.
#[inline(always)]
fn asin_r<D: Vector64<N>, const N: usize>(z: D) -> D {
    let p = horner(
        z,
        [
            3.479_331_075_960_212e-5,
            7.915_349_942_898_145e-4,
            -4.005_553_450_067_941e-2,
            2.012_125_321_348_629_3e-1,
            -3.255_658_186_224_009e-1,
            1.666_666_666_666_666_6e-1,
        ],
    )
    .mul(z);
    let q = horner(
        z,
        [
            7.703_815_055_590_194e-2,
            -6.882_839_716_054_533e-1,
            2.020_945_760_233_505_7,
            -2.403_394_911_734_414,
            1.0,
        ],
    );
    p.div(q)
}

/// acos x in f64 for x ∈ [−1, 1], written once over lanes (see [`sin_cos64`]). fdlibm's
/// `e_acos` (Sun Microsystems 1993) without its branches: |x| ≤ 1/2 by π/2 − asin x; beyond,
/// by 2·asin √((1 − |x|)/2), with √ split in two (Dekker) where x > 0 so that small results
/// keep their relative accuracy. Within 1 ulp of libm (the test).
#[inline(always)]
pub fn acos64<D: Vector64<N>, const N: usize>(x: D) -> D {
    let c = D::splat;
    let pio2_hi = std::f64::consts::FRAC_PI_2;
    let pio2_lo = 6.123_233_995_736_766e-17;
    let ax = x.abs();
    let z = ax.le_select(c(0.5), x.mul(x), c(1.0).sub(ax).mul(c(0.5)));
    let r = asin_r(z);
    let near = c(pio2_hi).sub(x.sub(c(pio2_lo).sub(x.mul(r))));
    let s = z.sqrt();
    // x < −1/2: π − 2·(s + s·R)
    let below = c(std::f64::consts::PI).sub(c(2.0).mul(s.add(r.mul(s).sub(c(pio2_lo)))));
    // x > 1/2: 2·(df + (s·R + (z − df²)/(s + df))), df the high half of s (exact square).
    let split = s.mul(c(134_217_729.0));
    let df = split.sub(split.sub(s));
    // s ≥ 0, so s ≤ 0 is s = 0.
    let tail = z
        .sub(df.mul(df))
        .div(s.le_select(c(0.0), c(1.0), s.add(df)));
    let above = c(2.0).mul(df.add(r.mul(s).add(tail)));
    let far = x.sign_select(below, above);
    ax.le_select(c(0.5), near, far)
}

/// asin x in f64 for x ∈ [−1, 1], written once over lanes (see [`sin_cos64`]). fdlibm's
/// `e_asin` (Sun Microsystems 1993) without its branches: |x| < 1/2 by x + x·R(x²); beyond, by
/// π/2 − 2·asin √((1 − |x|)/2), with √ split in two (Dekker) below |x| = 0.975 so that the
/// result keeps its low bits. Within 1 ulp of libm (the test).
#[inline(always)]
pub fn asin64<D: Vector64<N>, const N: usize>(x: D) -> D {
    let c = D::splat;
    let pio2_hi = std::f64::consts::FRAC_PI_2;
    let pio2_lo = 6.123_233_995_736_766e-17;
    let pio4_hi = std::f64::consts::FRAC_PI_4;
    let ax = x.abs();
    let z = ax.lt_select(c(0.5), x.mul(x), c(1.0).sub(ax).mul(c(0.5)));
    let r = asin_r(z);
    let near = x.add(x.mul(r));
    let s = z.sqrt();
    // |x| ≥ 0.975: π/2 − (2·(s + s·R) − π/2_lo).
    let top = c(pio2_hi).sub(c(2.0).mul(s.add(s.mul(r))).sub(c(pio2_lo)));
    // Else π/4 − ((2·s·R − (π/2_lo − 2·tail)) − (π/4 − 2·df)), df the high half of s (an
    // exact square) and tail = (z − df²)/(s + df) what it leaves of √z.
    let split = s.mul(c(134_217_729.0));
    let df = split.sub(split.sub(s));
    // s ≥ 0, so s ≤ 0 is s = 0.
    let tail = z
        .sub(df.mul(df))
        .div(s.le_select(c(0.0), c(1.0), s.add(df)));
    let p = c(2.0).mul(s).mul(r).sub(c(pio2_lo).sub(c(2.0).mul(tail)));
    let q = c(pio4_hi).sub(c(2.0).mul(df));
    let mid = c(pio4_hi).sub(p.sub(q));
    let far = c(0.975).le_select(ax, top, mid);
    let far = x.sign_select(far.neg(), far);
    ax.lt_select(c(0.5), near, far)
}

/// atan2(y, x) in f64 for y ≥ 0, written once over lanes, by the inverse sine or cosine of the
/// point's direction on the unit circle, whichever is well conditioned there: asin(y/r) where
/// |x| > r/2 (θ within π/3 of 0 or π, so small angles keep their relative accuracy), acos(x/r)
/// between. 0 at the origin, as atan2(0, 0). Within 3 ulps of libm (the test).
#[inline(always)]
pub fn atan2_64_upper<D: Vector64<N>, const N: usize>(y: D, x: D) -> D {
    let c = D::splat;
    let r = x.mul(x).add(y.mul(y)).sqrt();
    // r ≥ 0, so r ≤ 0 is the origin.
    let (zero, one) = (c(0.0), c(1.0));
    let rr = r.le_select(zero, one, r);
    let (sy, sx) = (y.div(rr).min(one), x.div(rr).max(c(-1.0)).min(one));
    let a = asin64(sy);
    let flat = x.sign_select(c(std::f64::consts::PI).sub(a), a);
    let t = x.abs().le_select(rr.mul(c(0.5)), acos64(sx), flat);
    r.le_select(zero, zero, t)
}

/// γₙ = nε/(1 − nε) with ε = 2⁻²⁴: a bound on the relative error of n chained f32 operations
/// (Higham, "Accuracy and Stability of Numerical Algorithms", §3.1; pbrt-v4 §6.8.1).
pub fn gamma(n: u32) -> f32 {
    let e = n as f32 * (0.5 * f32::EPSILON);
    e / (1.0 - e)
}

/// The origin of a ray leaving a computed surface point `p` towards the side of unit normal
/// `n`: `p` is pushed along `n` just past its own error box `p_error` (absolute, per axis), then
/// rounded away from the surface, so the true surface lies behind the origin and the ray
/// cannot re-hit it (pbrt-v4 `OffsetRayOrigin`, §6.8.6). The offset scales with the point's
/// actual error, not with a scene epsilon or a fixed count of ulps: a point 1e5 from the
/// origin moves by its few-ulp error (~0.05), not by the ~2 units that a 256-ulp offset would,
/// and a receiver 1e-6 below a light stays below it. A point with no error is not moved.
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, n: Vec3) -> Vec3 {
    let d = n.abs().dot(p_error);
    let offset = n * d;
    let po = (p + offset).to_array();
    let off = offset.to_array();
    Vec3::from_array(std::array::from_fn(|k| {
        let stepped = next_f32(po[k], off[k] > 0.0);
        // A zero or NaN offset does not move the point.
        if off[k].abs() > 0.0 { stepped } else { po[k] }
    }))
}

/// [`offset_ray_origin`] over 16 lanes, bit for bit.
#[inline(always)]
pub fn offset_ray_origin_lanes<V: Vector<WIDTH>>(p: V3<V>, p_error: V3<V>, n: V3<V>) -> V3<V> {
    let d = n.abs().dot(p_error);
    let offset = n.scale(d);
    let po = p + offset;
    V3 {
        x: step_off(po.x, offset.x),
        y: step_off(po.y, offset.y),
        z: step_off(po.z, offset.z),
    }
}

/// One axis of [`offset_ray_origin_lanes`]: `po` one ulp further along `off`, unless `off` is
/// zero or NaN.
#[inline(always)]
fn step_off<V: Vector<WIDTH>>(po: V, off: V) -> V {
    let zero = V::splat(0.0);
    zero.lt_select(off.abs(), po.next_f32(zero.lt(off)), po)
}

/// `x.next_up()` if `up`, else `x.next_down()`, bit for bit (the `next_f32_is_std` test),
/// written as integer selects: the normal's signs are as good as random from point to point,
/// and std's branches mispredicted enough to make this function 7 % of a `light` sample on
/// `cornell` (`perf record`, one thread).
#[inline]
pub fn next_f32(x: f32, up: bool) -> f32 {
    let bits = x.to_bits();
    let abs = bits & 0x7fff_ffff;
    // Up from a positive number, or down from a negative one, moves away from zero.
    let away = (bits >> 31 == 0) == up;
    let stepped = if away {
        bits.wrapping_add(1)
    } else {
        bits.wrapping_sub(1)
    };
    let from_zero = if up { 1 } else { 0x8000_0001 };
    let r = if abs == 0 { from_zero } else { stepped };
    // NaN, and the infinity one is moving towards, stay.
    let stays = abs > 0x7f80_0000 || (abs == 0x7f80_0000 && away);
    f32::from_bits(if stays { bits } else { r })
}

/// Luminance with Rec. 709 weights: the scalar that light selection and relMSE use.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// SplitMix64 finaliser: turns (seed, pixel, pass) tuples into independent stream seeds.
#[inline]
pub fn mix64(z: u64) -> u64 {
    mix64_lanes(z)
}

/// [`mix64`] of every lane, written once over lanes (scalar code is one `u64` lane).
#[inline(always)]
pub fn mix64_lanes<U: VectorU64<N>, const N: usize>(z: U) -> U {
    let z = z.add(U::splat(0x9E37_79B9_7F4A_7C15));
    let z = z.xor(z.shr(30)).mul(U::splat(0xBF58_476D_1CE4_E5B9));
    let z = z.xor(z.shr(27)).mul(U::splat(0x94D0_49BB_1331_11EB));
    z.xor(z.shr(31))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The worst error of `f` in ulps of f64 atan2 over directions all round the circle (every
    /// octant boundary included), at radii from 1e-30 to 1e30.
    fn worst_atan2(f: impl Fn(f32, f32) -> f32) -> f64 {
        let n = 1 << 18;
        let mut worst: f64 = 0.0;
        for i in 0..=n {
            let a = std::f64::consts::TAU * i as f64 / n as f64 - std::f64::consts::PI;
            for r in [1.0f64, 1e-30, 3e7, 1e30] {
                let (y, x) = ((r * a.sin()) as f32, (r * a.cos()) as f32);
                let want = (y as f64).atan2(x as f64);
                let got = f(y, x) as f64;
                let w = (want as f32).abs();
                let spacing = if w == 0.0 {
                    f32::from_bits(1) as f64
                } else {
                    (f32::from_bits(w.to_bits() + 1) - w) as f64
                };
                worst = worst.max((got - want).abs() / spacing);
            }
        }
        worst
    }

    /// The worst error of `f` in ulps of f64, against the C library's `want`, at `xs`.
    fn worst_ulps(
        xs: impl Iterator<Item = f64>,
        f: impl Fn(f64) -> f64,
        want: impl Fn(f64) -> f64,
    ) -> (f64, f64) {
        let mut worst = (0.0f64, 0.0);
        for x in xs {
            let (got, want) = (f(x), want(x));
            let w = want.abs();
            let spacing = f64::from_bits(w.to_bits() + 1) - w;
            let e = if got == want {
                0.0
            } else {
                (got - want).abs() / spacing
            };
            assert!(e.is_finite(), "f({x}) = {got}, want {want}");
            if e > worst.0 {
                worst = (e, x);
            }
        }
        worst
    }

    /// Arguments of acos: a dense sweep of [−1, 1], the ends and their last 2¹⁶ f64s, and the
    /// branch points ±1/2 with their neighbours.
    fn acos_args() -> impl Iterator<Item = f64> {
        let n = 1 << 20;
        let sweep = (0..=n).map(move |i| -1.0 + 2.0 * i as f64 / n as f64);
        let ends = (0..1u64 << 16).flat_map(|k| {
            let one = 1.0f64.to_bits();
            [f64::from_bits(one - k), -f64::from_bits(one - k)]
        });
        let halves = (0..1u64 << 10).flat_map(|k| {
            let h = 0.5f64.to_bits();
            [h - k, h + k]
                .map(f64::from_bits)
                .into_iter()
                .flat_map(|x| [x, -x])
        });
        sweep.chain(ends).chain(halves)
    }

    /// Arguments of sin and cos: a dense sweep of [−4π, 4π], each multiple of π/4 up to 64π
    /// and the 64 f64s either side of it (where sin or cos is near 0), and a sweep up to 64π.
    fn sin_cos_args() -> impl Iterator<Item = f64> {
        use std::f64::consts::{FRAC_PI_4, PI};
        let n = 1 << 20;
        let sweep = (0..=n).map(move |i| -4.0 * PI + 8.0 * PI * i as f64 / n as f64);
        let quadrants = (-256..=256i32).flat_map(|k| {
            let b = (k as f64 * FRAC_PI_4).to_bits();
            (0..64u64).flat_map(move |j| [f64::from_bits(b + j), f64::from_bits(b - j)])
        });
        let far = (0..=n).map(move |i| 64.0 * PI * i as f64 / n as f64);
        sweep.chain(quadrants).chain(far).filter(|x| x.is_finite())
    }

    /// acos, sin and cos over lanes are within 1 ulp of the C library's (0.5–1 measured) and
    /// agree with their one-lane (scalar) form bit for bit; errors of 2 ulps (one control)
    /// or a lost quadrant sign (the other) are caught.
    #[test]
    fn f64_trigonometry_is_accurate_and_the_same_over_lanes() {
        let acos1 = |x: f64| acos64::<f64, 1>(x);
        let (worst, at) = worst_ulps(acos_args(), acos1, f64::acos);
        assert!(worst <= 1.0, "acos: {worst} ulps at {at}");
        let sin1 = |x: f64| sin_cos64::<f64, 1>(x).0;
        let cos1 = |x: f64| sin_cos64::<f64, 1>(x).1;
        let (ws, at_s) = worst_ulps(sin_cos_args(), sin1, f64::sin);
        let (wc, at_c) = worst_ulps(sin_cos_args(), cos1, f64::cos);
        assert!(ws <= 1.0, "sin: {ws} ulps at {at_s}");
        assert!(wc <= 1.0, "cos: {wc} ulps at {at_c}");
        eprintln!("acos {worst} ulps at {at}, sin {ws} at {at_s}, cos {wc} at {at_c}");
        // Controls: two ulps off, and cos without its sign in the second and third quadrants.
        let off = |x: f64| acos1(x) * (1.0 + 4.0 * f64::EPSILON);
        assert!(worst_ulps(acos_args(), off, f64::acos).0 > 1.0);
        let unsigned = |x: f64| cos1(x).abs();
        assert!(worst_ulps(sin_cos_args(), unsigned, f64::cos).0 > 1.0);
        // Over lanes, on every ISA: the scalar bits.
        struct Lanes16<'a>(&'a [f64; WIDTH]);
        impl crate::simd::Kernel for Lanes16<'_> {
            type Out = ([f64; WIDTH], [f64; WIDTH], [f64; WIDTH]);
            #[inline(always)]
            fn run<L: crate::simd::Lanes>(self) -> Self::Out {
                let x = L::D::from_f64(self.0);
                let (s, c) = sin_cos64(x);
                let a = acos64(x.max(L::D::splat(-1.0)).min(L::D::splat(1.0)));
                (lanes64(s), lanes64(c), lanes64(a))
            }
        }
        let xs: Vec<f64> = acos_args().chain(sin_cos_args()).step_by(7).collect();
        for isa in crate::simd::Isa::available() {
            for chunk in xs.chunks_exact(WIDTH) {
                let x: [f64; WIDTH] = chunk.try_into().unwrap();
                let (s, c, a) = crate::simd::run(isa, Lanes16(&x));
                for lane in 0..WIDTH {
                    let (s1, c1) = sin_cos64::<f64, 1>(x[lane]);
                    let a1 = acos64::<f64, 1>(x[lane].clamp(-1.0, 1.0));
                    assert_eq!(
                        [s[lane], c[lane], a[lane]].map(f64::to_bits),
                        [s1, c1, a1].map(f64::to_bits),
                        "{isa:?} at {}",
                        x[lane]
                    );
                }
            }
        }
    }

    /// asin is within 1 ulp of the C library's over [−1, 1] (its breakpoints 1/2 and 0.975
    /// among the arguments, and tiny ones), and atan2 of the upper half plane within 3 ulps on
    /// circles of radius 1e−20 to 4, exact at the origin; the same bits over lanes on every ISA.
    /// Controls: asin two ulps off, and atan2 by acos alone (which loses small angles), are
    /// caught.
    #[test]
    fn f64_asin_and_atan2_are_accurate_and_the_same_over_lanes() {
        let asin1 = |x: f64| asin64::<f64, 1>(x);
        let breaks = [0.975f64, 0.5, 1e-10, 1e-300].into_iter().flat_map(|b| {
            (0..1u64 << 10).flat_map(move |k| {
                [b.to_bits() - k, b.to_bits() + k].map(|v| [f64::from_bits(v), -f64::from_bits(v)])
            })
        });
        let args = || acos_args().chain(breaks.clone().flatten());
        let (worst, at) = worst_ulps(args(), asin1, f64::asin);
        assert!(worst <= 1.0, "asin: {worst} ulps at {at}");
        let off = |x: f64| asin1(x) * (1.0 + 4.0 * f64::EPSILON);
        assert!(worst_ulps(args(), off, f64::asin).0 > 1.0);
        // atan2 on circles of several radii, by angle, as (y, x) pairs encoded in one f64 index.
        let n = 1 << 18;
        let points = move || {
            (0..=n).flat_map(move |i| {
                let a = std::f64::consts::PI * i as f64 / n as f64;
                [4.0, 1.0, 1e-3, 1e-20].map(|r| (r * a.sin(), r * a.cos()))
            })
        };
        let worst_atan = |f: &dyn Fn(f64, f64) -> f64| {
            let mut worst = (0.0f64, (0.0, 0.0));
            for (y, x) in points() {
                let (got, want) = (f(y, x), y.atan2(x));
                let spacing = f64::from_bits(want.abs().to_bits() + 1) - want.abs();
                let e = if got == want {
                    0.0
                } else {
                    (got - want).abs() / spacing
                };
                if e > worst.0 {
                    worst = (e, (y, x));
                }
            }
            worst
        };
        let atan1 = |y: f64, x: f64| atan2_64_upper::<f64, 1>(y, x);
        let (wa, at_a) = worst_atan(&atan1);
        // The bound from the steps: r = √(x² + y²) within 1 ulp, y/r within another 0.5, and
        // asin of a small argument keeps that relative error, plus its own 1 ulp: 2.5 ulps,
        // and half an ulp for the result's rounding (acos between, where x/r ∈ [−½, ½],
        // damps its input's error: about 2 ulps).
        assert!(wa <= 3.0, "atan2: {wa} ulps at {at_a:?}");
        assert_eq!(atan1(0.0, 0.0).to_bits(), 0.0f64.to_bits());
        eprintln!("asin {worst} ulps at {at}, atan2 {wa} at {at_a:?}");
        let by_acos = |y: f64, x: f64| acos64::<f64, 1>(x / (x * x + y * y).sqrt());
        assert!(worst_atan(&by_acos).0 > 3.0);
        struct Lanes16<'a>(&'a [f64; WIDTH], &'a [f64; WIDTH]);
        impl crate::simd::Kernel for Lanes16<'_> {
            type Out = ([f64; WIDTH], [f64; WIDTH]);
            #[inline(always)]
            fn run<L: crate::simd::Lanes>(self) -> Self::Out {
                let (y, x) = (L::D::from_f64(self.0), L::D::from_f64(self.1));
                (lanes64(asin64(x)), lanes64(atan2_64_upper(y, x)))
            }
        }
        let xs: Vec<f64> = args().step_by(5).collect();
        let ys: Vec<f64> = xs.iter().map(|x| (1.0 - x * x).max(0.0).sqrt()).collect();
        for isa in crate::simd::Isa::available() {
            for (cx, cy) in xs.chunks_exact(WIDTH).zip(ys.chunks_exact(WIDTH)) {
                let (x, y): ([f64; WIDTH], [f64; WIDTH]) =
                    (cx.try_into().unwrap(), cy.try_into().unwrap());
                let (a, t) = crate::simd::run(isa, Lanes16(&y, &x));
                for lane in 0..WIDTH {
                    assert_eq!(
                        [a[lane], t[lane]].map(f64::to_bits),
                        [asin1(x[lane]), atan1(y[lane], x[lane])].map(f64::to_bits),
                        "{isa:?} at ({}, {})",
                        y[lane],
                        x[lane]
                    );
                }
            }
        }
    }

    fn lanes64<D: Vector64<WIDTH>>(v: D) -> [f64; WIDTH] {
        let mut a = [0.0; WIDTH];
        v.to_f64(&mut a);
        a
    }

    /// atan2 is within 3.5 ulps of f64 everywhere (3.16 measured), exact on the axes and at the
    /// origin; a polynomial one term short (the control) is not.
    #[test]
    fn atan2_is_accurate_in_every_octant() {
        let worst = worst_atan2(atan2::<f32, 1>);
        assert!(worst <= 3.5, "{worst} ulps");
        use std::f32::consts::{FRAC_PI_2, PI};
        for (y, x, want) in [
            (0.0, 1.0, 0.0),
            (1.0, 0.0, FRAC_PI_2),
            (0.0, -1.0, PI),
            (-1.0, 0.0, -FRAC_PI_2),
            (0.0, 0.0, 0.0),
        ] {
            assert_eq!(atan2::<f32, 1>(y, x), want, "atan2({y}, {x})");
        }
        let short = |y: f32, x: f32| {
            // Cephes' polynomial without its highest term, through the same reduction.
            let (ax, ay) = (x.abs(), y.abs());
            let a = ax.min(ay) / if ax.max(ay) == 0.0 { 1.0 } else { ax.max(ay) };
            let above = a > 0.414_213_57;
            let t = if above { (a - 1.0) / (a + 1.0) } else { a };
            let z = t * t;
            let p = ((-1.387_768_6e-1 * z + 1.997_771_1e-1) * z - 3.333_295e-1) * z * t + t;
            let r = if above {
                std::f32::consts::FRAC_PI_4 + p
            } else {
                p
            };
            let r = if ax < ay { FRAC_PI_2 - r } else { r };
            let r = if x < 0.0 { PI - r } else { r };
            if y.is_sign_negative() { -r } else { r }
        };
        let control = worst_atan2(short);
        assert!(control > 3.5, "the control is within {control} ulps");
    }

    struct Atan2Lanes<'a>(&'a [(f32, f32)]);

    impl crate::simd::Kernel for Atan2Lanes<'_> {
        type Out = Vec<u32>;
        fn run<L: crate::simd::Lanes>(self) -> Vec<u32> {
            let mut out = Vec::new();
            for c in self.0.chunks_exact(WIDTH) {
                let y = L::V::load(&std::array::from_fn(|i| c[i].0));
                let x = L::V::load(&std::array::from_fn(|i| c[i].1));
                let mut o = [0.0; WIDTH];
                atan2(y, x).store(&mut o);
                out.extend(o.map(f32::to_bits));
            }
            out
        }
    }

    /// atan2 over lanes is the scalar one bit for bit on every ISA, signed zeros included.
    #[test]
    fn lane_atan2_is_the_scalar_one() {
        let special = [0.0, -0.0, 1.0, -1.0, 0.414_213_57, 1e-38, -3.5, f32::MAX];
        let mut v: Vec<(f32, f32)> = special
            .iter()
            .flat_map(|&y| special.iter().map(move |&x| (y, x)))
            .collect();
        v.extend((0..2048u64).map(|i| {
            let m = mix64(i);
            (
                ((m >> 40) as f32 / (1u64 << 23) as f32) - 1.0,
                ((m >> 8 & 0xff_ffff) as f32 / (1u64 << 23) as f32) - 1.0,
            )
        }));
        v.truncate(v.len() / WIDTH * WIDTH);
        let want: Vec<u32> = v
            .iter()
            .map(|&(y, x)| atan2::<f32, 1>(y, x).to_bits())
            .collect();
        for isa in crate::simd::Isa::available() {
            assert_eq!(crate::simd::run(isa, Atan2Lanes(&v)), want, "{isa:?}");
        }
    }

    #[test]
    fn frame_is_orthonormal_for_all_octants() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.0, -1.0, 1e-7).normalize(),
            Vec3::new(-0.3, 0.5, -0.8).normalize(),
        ] {
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5 && (f.t.length() - 1.0).abs() < 1e-5);
            assert!(
                f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5
            );
            let v = Vec3::new(0.2, -0.7, 0.4);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
    }

    /// The offset origin lies strictly in front of the plane (normal n) through every corner of
    /// the error box, and moves no further than the box's projection plus rounding.
    #[test]
    fn offset_clears_the_error_box_at_every_scale() {
        for scale in [1e-3f32, 1.0, 1e3, 1e5] {
            for n in [
                Vec3::new(0.3, -0.2, 0.9).normalize(),
                Vec3::new(-1.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 1e-4).normalize(),
            ] {
                let p = Vec3::new(scale, -scale, 0.5 * scale);
                let err = gamma(7) * p.abs();
                let q = offset_ray_origin(p, err, n);
                for corner in 0..8 {
                    let s = Vec3::new(
                        if corner & 1 == 0 { -1.0 } else { 1.0 },
                        if corner & 2 == 0 { -1.0 } else { 1.0 },
                        if corner & 4 == 0 { -1.0 } else { 1.0 },
                    );
                    let c = (p.as_dvec3() + (s * err).as_dvec3()).as_vec3().as_dvec3();
                    assert!(
                        (q.as_dvec3() - c).dot(n.as_dvec3()) > 0.0,
                        "scale {scale}, n {n}: origin not in front of corner {corner}"
                    );
                }
                let moved = (q - p).length();
                let bound = n.abs().dot(err) + 4.0 * f32::EPSILON * p.abs().max_element();
                assert!(moved <= bound, "scale {scale}: moved {moved} > {bound}");
            }
        }
    }

    /// Zeros, subnormals, the extremes, infinities, NaNs of both signs and a few neighbours of
    /// them: the values every `next_f32` test (scalar and lanes) starts from.
    pub(crate) const SPECIAL_F32: [f32; 16] = [
        0.0,
        -0.0,
        f32::from_bits(1),
        -f32::from_bits(1),
        f32::MIN_POSITIVE,
        f32::MAX,
        f32::MIN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        -f32::NAN,
        1.0,
        -1.0,
        f32::from_bits(0x7f7f_ffff),
        f32::from_bits(0x8000_0002),
        3.5,
    ];

    /// `next_f32` is std's `next_up`/`next_down` on zeros, subnormals, the extremes,
    /// infinities, NaN and a spread of bit patterns.
    #[test]
    fn next_f32_is_std() {
        let spread = (0..100_000u64).map(|i| f32::from_bits((mix64(i) >> 32) as u32));
        for x in SPECIAL_F32.into_iter().chain(spread) {
            for (up, want) in [(true, x.next_up()), (false, x.next_down())] {
                let got = next_f32(x, up);
                assert!(
                    got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                    "{x:e} ({:#x}) up={up}: {got:e} != {want:e}",
                    x.to_bits()
                );
            }
        }
    }

    #[test]
    fn a_point_without_error_is_not_moved() {
        let p = Vec3::new(0.25, 1.0, -3.0);
        assert_eq!(offset_ray_origin(p, Vec3::ZERO, Vec3::Y), p);
    }
}
