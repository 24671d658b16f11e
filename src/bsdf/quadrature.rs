//! Deterministic quadrature for reflectance integrals, in f64 and independent of every sampler:
//! adaptive Gauss–Kronrod (G7–K15, QUADPACK's `qk15` rule with global bisection of the interval
//! of largest error), nested for 2D. It gives the closed forms that the energy-conservation,
//! furnace, unbiasedness and stress checks compare estimators against.
//!
//! A directional albedo ∫ f(wo, wi) cos θi dωi is taken over half vectors, wi = reflect(wo, h),
//! h on the upper hemisphere (a bijection onto the sphere of wi), in the lobe's stretched polar
//! coordinates: h ∝ (αx sin θ′ cos φ, αy sin θ′ sin φ, cos θ′). There a GGX lobe of any width is
//! smooth, since D(h) dωh = |(αx sin θ′ cos φ, αy sin θ′ sin φ, cos θ′)| sin θ′/π dθ′ dφ.

use super::{Bsdf, Lobe};
use glam::{DVec3, Vec3};
use std::f64::consts::{FRAC_PI_2, PI};

/// Kronrod abscissae on [-1, 1] (the positive half; index 7 is 0); odd indices are the Gauss
/// nodes.
const XGK: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];
const WGK: [f64; 8] = [
    0.022_935_322_010_529_22,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_2,
    0.140_653_259_715_525_9,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_727_8,
];
/// Gauss weights of the nodes XGK[1], XGK[3], XGK[5], XGK[7].
const WG: [f64; 4] = [
    0.129_484_966_168_869_7,
    0.279_705_391_489_276_7,
    0.381_830_050_505_118_9,
    0.417_959_183_673_469_4,
];

/// A quadrature result: the integral (per channel) and an estimate of its absolute error
/// (the largest channel's).
#[derive(Clone, Copy, Debug)]
pub struct Quadrature {
    pub value: DVec3,
    pub error: f64,
}

/// K15 and |K15 − G7| on [a, b].
fn gk15(f: &mut impl FnMut(f64) -> DVec3, a: f64, b: f64) -> (DVec3, f64) {
    let c = 0.5 * (a + b);
    let h = 0.5 * (b - a);
    let mut k = WGK[7] * f(c);
    let mut g = WG[3] * (k / WGK[7]);
    for i in 0..7 {
        let x = h * XGK[i];
        let s = f(c - x) + f(c + x);
        k += WGK[i] * s;
        if i % 2 == 1 {
            g += WG[i / 2] * s;
        }
    }
    let (k, g) = (k * h, g * h);
    (k, (k - g).abs().max_element())
}

/// ∫ₐᵇ f by adaptive Gauss–Kronrod: `panels` equal intervals first, then the interval of
/// largest error is bisected until the summed error is below `tol` or `max_intervals` is
/// reached (the error estimate then says how far it got).
pub fn integrate(
    f: &mut impl FnMut(f64) -> DVec3,
    a: f64,
    b: f64,
    tol: f64,
    panels: usize,
    max_intervals: usize,
) -> Quadrature {
    let mut parts: Vec<(f64, f64, DVec3, f64)> = (0..panels)
        .map(|i| {
            let lo = a + (b - a) * i as f64 / panels as f64;
            let hi = a + (b - a) * (i + 1) as f64 / panels as f64;
            let (v, e) = gk15(f, lo, hi);
            (lo, hi, v, e)
        })
        .collect();
    loop {
        let error: f64 = parts.iter().map(|p| p.3).sum();
        if error <= tol || parts.len() >= max_intervals {
            return Quadrature {
                value: parts.iter().map(|p| p.2).sum(),
                error,
            };
        }
        let worst = (0..parts.len())
            .max_by(|&i, &j| parts[i].3.total_cmp(&parts[j].3))
            .expect("at least one interval");
        let (lo, hi, _, _) = parts.swap_remove(worst);
        let mid = 0.5 * (lo + hi);
        for (l, h) in [(lo, mid), (mid, hi)] {
            let (v, e) = gk15(f, l, h);
            parts.push((l, h, v, e));
        }
    }
}

/// ∫∫ f(x, y) dy dx over [x0, x1] × [y0, y1], the inner integrals to a tenth of the share of
/// `tol` their x-interval carries (their errors are added to the outer estimate's).
pub fn integrate_2d(
    f: &mut impl FnMut(f64, f64) -> DVec3,
    x: (f64, f64),
    y: (f64, f64),
    tol: f64,
) -> Quadrature {
    let inner_tol = 0.1 * tol / (x.1 - x.0);
    let mut inner_error = 0.0f64;
    let mut outer = |xv: f64| {
        let q = integrate(&mut |yv| f(xv, yv), y.0, y.1, inner_tol, 8, 400);
        inner_error = inner_error.max(q.error);
        q.value
    };
    let q = integrate(&mut outer, x.0, x.1, tol, 8, 400);
    Quadrature {
        value: q.value,
        error: q.error + inner_error * (x.1 - x.0),
    }
}

/// ∫ f(wo, wi) cos θi dωi for an f given in f64 (a reference model, or a lobe widened from f32),
/// over half vectors in the coordinates stretched by `spread` = (αx, αy).
pub fn albedo_of(f: impl Fn(DVec3) -> DVec3, wo: DVec3, spread: [f64; 2], tol: f64) -> Quadrature {
    albedo_by_half_vector(|wi, _| f(wi), wo, spread, tol)
}

/// As [`albedo_of`], with f also given the node's half vector.
pub fn albedo_by_half_vector(
    f: impl Fn(DVec3, DVec3) -> DVec3,
    wo: DVec3,
    spread: [f64; 2],
    tol: f64,
) -> Quadrature {
    let [ax, ay] = spread;
    let mut g = |phi: f64, t: f64| {
        let (st, ct) = t.sin_cos();
        let m = DVec3::new(ax * st * phi.cos(), ay * st * phi.sin(), ct);
        let len = m.length();
        let h = m / len;
        let c = wo.dot(h);
        let wi = 2.0 * c * h - wo;
        if wi.z <= 0.0 {
            return DVec3::ZERO;
        }
        // dωi = 4|wo·h| dωh, dωh = αx αy sin θ′/|m|³ dθ′ dφ.
        f(wi, h) * (wi.z * 4.0 * c.abs() * ax * ay * st / (len * len * len))
    };
    integrate_2d(&mut g, (0.0, 2.0 * PI), (0.0, FRAC_PI_2), tol)
}

/// A lobe's directional albedo at `wo`, evaluating the lobe itself (f32) at each node, with
/// the node's exact half vector ([`Lobe::eval_with_half_vector`]).
pub fn lobe_albedo(lobe: &dyn Lobe, wo: Vec3, tol: f64) -> Quadrature {
    let [ax, ay] = lobe.half_vector_spread();
    albedo_by_half_vector(
        |wi, h| {
            lobe.eval_with_half_vector(wo, wi.as_vec3().normalize(), h.as_vec3().normalize())
                .as_dvec3()
        },
        wo.as_dvec3(),
        [ax as f64, ay as f64],
        tol,
    )
}

/// A material's directional albedo at `wo`: the sum of its lobes', each in its own coordinates.
pub fn directional_albedo(bsdf: &Bsdf, wo: Vec3, tol: f64) -> Quadrature {
    let share = tol / bsdf.lobes().len() as f64;
    bsdf.lobes()
        .iter()
        .map(|l| lobe_albedo(l.as_ref(), wo, share))
        .fold(
            Quadrature {
                value: DVec3::ZERO,
                error: 0.0,
            },
            |a, q| Quadrature {
                value: a.value + q.value,
                error: a.error + q.error,
            },
        )
}

/// ∫ over the cone of directions within θmax of `axis` (unit) of g(ω) dω, in polar
/// coordinates about the axis with `panels` initial intervals per coordinate.
pub fn over_cone(g: impl Fn(DVec3) -> DVec3, axis: DVec3, cos_max: f64, tol: f64) -> Quadrature {
    let f = crate::math::Frame::from_normal(axis.as_vec3());
    let (s, t) = (f.s.as_dvec3(), f.t.as_dvec3());
    let theta_max = cos_max.clamp(-1.0, 1.0).acos();
    let mut h = |phi: f64, theta: f64| {
        let (st, ct) = theta.sin_cos();
        let w = s * (st * phi.cos()) + t * (st * phi.sin()) + axis * ct;
        g(w) * st
    };
    integrate_2d(&mut h, (0.0, 2.0 * PI), (0.0, theta_max), tol)
}

/// Single-scattering white furnace of GGX (F = 1) at `wo`, from the textbook f64 forms
/// (D with tan θ, Λ = (−1 + sqrt(1 + α² tan² θ))/2, G2 = 1/(1 + Λo + Λi); Heitz 2014, eqs. 71,
/// 72, 99): an implementation apart from the f32 lobe, for reference values.
pub fn ggx_white_furnace(ax: f64, ay: f64, wo: DVec3, tol: f64) -> Quadrature {
    let lambda = |w: DVec3| {
        let tan2 = (w.x * w.x + w.y * w.y) / (w.z * w.z);
        let cos2phi_over = if w.x == 0.0 && w.y == 0.0 {
            0.0
        } else {
            (ax * ax * w.x * w.x + ay * ay * w.y * w.y) / (w.x * w.x + w.y * w.y)
        };
        0.5 * (-1.0 + (1.0 + cos2phi_over * tan2).sqrt())
    };
    let d = |h: DVec3| {
        let cos2 = h.z * h.z;
        let tan2 = (h.x * h.x + h.y * h.y) / cos2;
        let e = if tan2 == 0.0 {
            0.0
        } else {
            tan2 * (h.x * h.x / (ax * ax) + h.y * h.y / (ay * ay)) / (h.x * h.x + h.y * h.y)
        };
        1.0 / (PI * ax * ay * cos2 * cos2 * (1.0 + e) * (1.0 + e))
    };
    let f = |wi: DVec3| {
        let h = (wo + wi).normalize();
        let g2 = 1.0 / (1.0 + lambda(wo) + lambda(wi));
        DVec3::splat(d(h) * g2 / (4.0 * wo.z * wi.z))
    };
    albedo_of(f, wo, [ax, ay], tol)
}

/// The closed form of the white furnace at α = 1 (isotropic): D = 1/π and
/// G2 = 2μoμi/(μo + μi), so f = 1/(2π(μo + μi)) and E(μo) = 1 − μo ln(1 + 1/μo).
pub fn ggx_white_furnace_alpha_one(mu_o: f64) -> f64 {
    1.0 - mu_o * (1.0 + 1.0 / mu_o).ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule integrates polynomials of degree 22 exactly, a kinked and an endpoint-
    /// singular function to the tolerance; a wrong weight is caught.
    #[test]
    fn gauss_kronrod_is_exact_and_adaptive() {
        let q = integrate(&mut |x| DVec3::splat(x.powi(22)), 0.0, 1.0, 1e-14, 1, 1);
        assert!((q.value.x - 1.0 / 23.0).abs() < 1e-15, "{}", q.value.x);
        let q = integrate(
            &mut |x| DVec3::splat((x - 0.3).abs()),
            0.0,
            1.0,
            1e-12,
            1,
            500,
        );
        assert!((q.value.x - 0.29).abs() < 1e-11 && q.error < 1e-12, "{q:?}");
        let q = integrate(&mut |x| DVec3::splat(x.sqrt()), 0.0, 1.0, 1e-10, 4, 500);
        assert!((q.value.x - 2.0 / 3.0).abs() < 1e-10, "{q:?}");
        let q = integrate_2d(
            &mut |x, y| DVec3::splat(x * y.exp()),
            (0.0, 2.0),
            (0.0, 1.0),
            1e-11,
        );
        assert!(
            (q.value.x - 2.0 * (1f64.exp() - 1.0)).abs() < 1e-10,
            "{q:?}"
        );
        // The error estimate is honest: a Gauss rule alone would miss x^22 by more.
        let g7: f64 = (0..4)
            .map(|i| {
                let x = XGK[2 * i + 1];
                let w = WG[i] * if i == 3 { 1.0 } else { 2.0 };
                let y = 0.5 * (1.0 + x);
                w * 0.5 * y.powi(22)
            })
            .sum();
        assert!((g7 - 1.0 / 23.0).abs() > 1e-6);
    }

    /// The α = 1 closed form against the reference quadrature, and the reference against the
    /// lobe's own f32 evaluation: one physical number three ways.
    #[test]
    fn white_furnace_at_alpha_one() {
        for mu in [1.0f64, 0.5, 0.2, 0.017_452_4] {
            let wo = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            let closed = ggx_white_furnace_alpha_one(mu);
            let q = ggx_white_furnace(1.0, 1.0, wo, 1e-9);
            assert!(
                (q.value.x - closed).abs() < 1e-8,
                "μ = {mu}: {q:?} vs {closed}"
            );
        }
        assert!((ggx_white_furnace_alpha_one(1.0) - (1.0 - 2f64.ln())).abs() < 1e-15);
    }

    #[test]
    fn over_cone_is_the_solid_angle() {
        let axis = DVec3::new(0.3, 0.4, 0.5).normalize();
        let c = 0.9f64;
        let q = over_cone(|_| DVec3::ONE, axis, c, 1e-12);
        assert!((q.value.x - 2.0 * PI * (1.0 - c)).abs() < 1e-11);
    }
}
