//! Fresnel reflectance of a microfacet, per RGB channel, as a function of the cosine between
//! the view and the microfacet normal. The outside medium is vacuum (index 1) on the viewer's
//! side (docs/conventions.md).

use crate::simd::{V3, Vector, WIDTH};
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fresnel {
    /// F = 1: the lobe's coefficient alone sets its colour (the lecture's k_s blend).
    One,
    /// Schlick's approximation F0 + (1 − F0)(1 − cos)^5 (Schlick 1994, eq. 24).
    Schlick { f0: Vec3 },
    /// The exact unpolarised Fresnel reflectance of a conductor of complex index η + iκ per
    /// channel (Born & Wolf §14.2; the complex form of pbrt-v4's `FrComplex`).
    Conductor { eta: Vec3, k: Vec3 },
}

impl Fresnel {
    /// F at cosine `cos` ∈ [0, 1] between the view and the microfacet normal.
    pub fn eval(&self, cos: f32) -> Vec3 {
        let c = cos.clamp(0.0, 1.0);
        match *self {
            Fresnel::One => Vec3::ONE,
            Fresnel::Schlick { f0 } => f0 + (Vec3::ONE - f0) * schlick_weight(c),
            Fresnel::Conductor { eta, k } => Vec3::new(
                conductor(c, eta.x, k.x),
                conductor(c, eta.y, k.y),
                conductor(c, eta.z, k.z),
            ),
        }
    }

    /// [`Self::eval`] over lanes, the same operations in the same order per lane.
    #[inline(always)]
    pub fn eval_lanes<V: Vector<WIDTH>>(&self, cos: V) -> V3<V> {
        let c = clamp01_lanes(cos);
        match *self {
            Fresnel::One => V3::splat(Vec3::ONE),
            Fresnel::Schlick { f0 } => {
                V3::splat(f0) + V3::splat(Vec3::ONE - f0).scale(schlick_weight_lanes(c))
            }
            Fresnel::Conductor { eta, k } => V3 {
                x: conductor_lanes(c, eta.x, k.x),
                y: conductor_lanes(c, eta.y, k.y),
                z: conductor_lanes(c, eta.z, k.z),
            },
        }
    }

    /// F is 1 for every angle (no colour or angle dependence to estimate).
    pub fn is_one(&self) -> bool {
        match *self {
            Fresnel::One => true,
            Fresnel::Schlick { f0 } => f0 == Vec3::ONE,
            Fresnel::Conductor { .. } => false,
        }
    }
}

/// (1 − c)^5, Schlick's angular weight.
pub fn schlick_weight(c: f32) -> f32 {
    let m = 1.0 - c;
    let m2 = m * m;
    m2 * m2 * m
}

/// `c.clamp(0.0, 1.0)` over lanes: f32::clamp's two comparisons (a −0 stays −0, as there).
#[inline(always)]
pub fn clamp01_lanes<V: Vector<N>, const N: usize>(c: V) -> V {
    let (zero, one) = (V::splat(0.0), V::splat(1.0));
    let c = c.lt_select(zero, zero, c);
    one.lt_select(c, one, c)
}

/// [`schlick_weight`] over lanes.
#[inline(always)]
pub fn schlick_weight_lanes<V: Vector<N>, const N: usize>(c: V) -> V {
    let m = V::splat(1.0).sub(c);
    let m2 = m.mul(m);
    m2.mul(m2).mul(m)
}

/// ∫ over the hemisphere of Schlick's F(cos θ)·cos θ dω / π = F0 + (1 − F0)/21: the cosine-
/// weighted mean reflectance (2∫₀¹ (1 − μ)^5 μ dμ = 1/21).
pub fn schlick_hemispherical_mean(f0: f32) -> f32 {
    f0 + (1.0 - f0) / 21.0
}

/// A tiny complex number, only what the conductor formula needs.
#[derive(Clone, Copy, Debug)]
struct C {
    re: f32,
    im: f32,
}

impl C {
    fn new(re: f32, im: f32) -> Self {
        C { re, im }
    }
    fn add(self, o: C) -> C {
        C::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: C) -> C {
        C::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: C) -> C {
        C::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    fn scale(self, s: f32) -> C {
        C::new(self.re * s, self.im * s)
    }
    fn norm2(self) -> f32 {
        self.re * self.re + self.im * self.im
    }
    fn div(self, o: C) -> C {
        let d = o.norm2();
        C::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
    /// Principal square root, without cancellation in either component.
    fn sqrt(self) -> C {
        let m = self.norm2().sqrt();
        if m == 0.0 {
            return C::new(0.0, 0.0);
        }
        let t = (0.5 * (m + self.re.abs())).sqrt();
        if self.re >= 0.0 {
            C::new(t, 0.5 * self.im / t)
        } else {
            C::new(0.5 * self.im.abs() / t, t.copysign(self.im))
        }
    }
}

/// Unpolarised reflectance of a conductor η + iκ seen from vacuum at cos θ = c:
/// cos θt = sqrt(1 − sin²θ/η²), r⊥ = (c − η cos θt)/(c + η cos θt),
/// r∥ = (η c − cos θt)/(η c + cos θt), F = (|r⊥|² + |r∥|²)/2. At c = 0 both are −1: F = 1.
pub fn conductor(c: f32, eta: f32, k: f32) -> f32 {
    // A matched index is no interface: nothing is reflected (and at c = 0 both ratios are 0/0).
    if eta == 1.0 && k == 0.0 {
        return 0.0;
    }
    let n = C::new(eta, k);
    let sin2 = C::new((1.0 - c * c).max(0.0), 0.0);
    let cos_t = C::new(1.0, 0.0).sub(sin2.div(n.mul(n))).sqrt();
    let cc = C::new(c, 0.0);
    let perp = cc.sub(n.mul(cos_t)).div(cc.add(n.mul(cos_t)));
    let parl = n.scale(c).sub(cos_t).div(n.scale(c).add(cos_t));
    0.5 * (perp.norm2() + parl.norm2())
}

/// [`C`] over lanes: the same operations in the same order, branches as selects.
#[derive(Clone, Copy)]
struct CLanes<V> {
    re: V,
    im: V,
}

impl<V: Vector<WIDTH>> CLanes<V> {
    #[inline(always)]
    fn new(re: V, im: V) -> Self {
        CLanes { re, im }
    }
    #[inline(always)]
    fn splat(c: C) -> Self {
        CLanes::new(V::splat(c.re), V::splat(c.im))
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        CLanes::new(self.re.add(o.re), self.im.add(o.im))
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        CLanes::new(self.re.sub(o.re), self.im.sub(o.im))
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        CLanes::new(
            self.re.mul(o.re).sub(self.im.mul(o.im)),
            self.re.mul(o.im).add(self.im.mul(o.re)),
        )
    }
    #[inline(always)]
    fn scale(self, s: V) -> Self {
        CLanes::new(self.re.mul(s), self.im.mul(s))
    }
    #[inline(always)]
    fn norm2(self) -> V {
        self.re.mul(self.re).add(self.im.mul(self.im))
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        let d = o.norm2();
        CLanes::new(
            self.re.mul(o.re).add(self.im.mul(o.im)).div(d),
            self.im.mul(o.re).sub(self.re.mul(o.im)).div(d),
        )
    }
    /// [`C::sqrt`]: lanes of modulus 0 give 0 (their t is replaced by 1 so that no lane
    /// divides by zero); t > 0 elsewhere, so copysign is a negation where im's sign bit is set.
    #[inline(always)]
    fn sqrt(self) -> Self {
        let (zero, half) = (V::splat(0.0), V::splat(0.5));
        let m = self.norm2().sqrt();
        let null = m.eq(zero);
        let t = half.mul(m.add(self.re.abs())).sqrt();
        let t = V::select(null, V::splat(1.0), t);
        let right = !self.re.lt(zero);
        let re = V::select(right, t, half.mul(self.im.abs()).div(t));
        let im = V::select(
            right,
            half.mul(self.im).div(t),
            self.im.sign_select(t.neg(), t),
        );
        CLanes::new(V::select(null, zero, re), V::select(null, zero, im))
    }
}

/// [`conductor`] over lanes of c, for one channel's η and κ.
#[inline(always)]
fn conductor_lanes<V: Vector<WIDTH>>(c: V, eta: f32, k: f32) -> V {
    if eta == 1.0 && k == 0.0 {
        return V::splat(0.0);
    }
    let zero = V::splat(0.0);
    let n = CLanes::<V>::splat(C::new(eta, k));
    let sin2 = CLanes::new(V::splat(1.0).sub(c.mul(c)).max(zero), zero);
    let cos_t = CLanes::splat(C::new(1.0, 0.0))
        .sub(sin2.div(n.mul(n)))
        .sqrt();
    let cc = CLanes::new(c, zero);
    let perp = cc.sub(n.mul(cos_t)).div(cc.add(n.mul(cos_t)));
    let parl = n.scale(c).sub(cos_t).div(n.scale(c).add(cos_t));
    V::splat(0.5).mul(perp.norm2().add(parl.norm2()))
}

/// Named conductors: complex index (η, κ) per channel at 650, 550 and 450 nm (R, G, B),
/// linearly interpolated between the tabulated wavelengths of the refractiveindex.info
/// database (CC0; polyanskiy/refractiveindex.info-database, `data-nk/main/<metal>/<set>.yml`):
/// gold, silver and copper from Johnson & Christy, Phys. Rev. B 6, 4370 (1972); aluminium
/// from Rakić, Appl. Opt. 34, 4755 (1995).
pub const CONDUCTORS: &[(&str, [f32; 3], [f32; 3])] = &[
    ("gold", [0.1556, 0.4241, 1.3831], [3.6024, 2.4721, 1.9155]),
    ("silver", [0.0522, 0.0596, 0.0400], [4.4094, 3.5974, 2.6484]),
    ("copper", [0.2378, 1.0066, 1.2404], [3.6264, 2.5823, 2.3929]),
    (
        "aluminium",
        [1.5580, 1.0152, 0.6332],
        [7.7124, 6.6273, 5.4544],
    ),
];

/// The conductor named `name`, or None.
pub fn conductor_preset(name: &str) -> Option<Fresnel> {
    CONDUCTORS
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|&(_, eta, k)| Fresnel::Conductor {
            eta: Vec3::from(eta),
            k: Vec3::from(k),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dielectric Fresnel equations (real index, f64), an independent formula for κ = 0.
    fn dielectric(c: f64, eta: f64) -> f64 {
        let s2 = 1.0 - c * c;
        let ct = (1.0 - s2 / (eta * eta)).sqrt();
        let rs = (c - eta * ct) / (c + eta * ct);
        let rp = (eta * c - ct) / (eta * c + ct);
        0.5 * (rs * rs + rp * rp)
    }

    /// At normal incidence F = ((η−1)² + κ²)/((η+1)² + κ²); at grazing F = 1; with κ = 0 the
    /// dielectric equations; F ∈ [0, 1] everywhere. Negative control: Schlick's approximation
    /// with the same F0 differs from the exact dielectric by more than the tolerance at 80°,
    /// so the comparison resolves a wrong formula.
    #[test]
    fn conductor_matches_closed_forms() {
        for &(name, eta, k) in CONDUCTORS {
            for c in 0..3 {
                let (n, kk) = (eta[c] as f64, k[c] as f64);
                let f0 = ((n - 1.0).powi(2) + kk * kk) / ((n + 1.0).powi(2) + kk * kk);
                let got = conductor(1.0, eta[c], k[c]) as f64;
                assert!((got - f0).abs() < 1e-5, "{name}[{c}]: F(1) = {got} vs {f0}");
                assert!((conductor(0.0, eta[c], k[c]) - 1.0).abs() < 1e-6);
                for i in 0..=100 {
                    let f = conductor(i as f32 / 100.0, eta[c], k[c]);
                    assert!((0.0..=1.0 + 1e-6).contains(&f), "{name}: F = {f}");
                }
            }
        }
        for eta in [1.2f32, 1.5, 2.4] {
            let mut worst = 0.0f64;
            let mut schlick_worst = 0.0f64;
            for i in 0..=200 {
                let c = i as f64 / 200.0;
                let exact = dielectric(c, eta as f64);
                worst = worst.max((conductor(c as f32, eta, 0.0) as f64 - exact).abs());
                let f0 = dielectric(1.0, eta as f64) as f32;
                let s = Fresnel::Schlick {
                    f0: Vec3::splat(f0),
                }
                .eval(c as f32)
                .x as f64;
                schlick_worst = schlick_worst.max((s - exact).abs());
            }
            assert!(worst < 2e-6, "η = {eta}: κ = 0 differs by {worst}");
            assert!(
                schlick_worst > 1e-3,
                "η = {eta}: the test cannot tell Schlick apart"
            );
        }
    }

    #[test]
    fn schlick_endpoints_and_mean() {
        let f = Fresnel::Schlick {
            f0: Vec3::new(0.04, 0.5, 1.0),
        };
        assert_eq!(f.eval(1.0), Vec3::new(0.04, 0.5, 1.0));
        assert_eq!(f.eval(0.0), Vec3::ONE);
        // The hemispherical mean by a midpoint rule.
        let n = 100_000;
        let mean: f64 = (0..n)
            .map(|i| {
                let mu = (i as f64 + 0.5) / n as f64;
                2.0 * mu * (0.04 + 0.96 * (1.0 - mu).powi(5))
            })
            .sum::<f64>()
            / n as f64;
        assert!((mean - schlick_hemispherical_mean(0.04) as f64).abs() < 1e-7);
        assert!(conductor_preset("gold").is_some() && conductor_preset("brass").is_none());
    }
}
