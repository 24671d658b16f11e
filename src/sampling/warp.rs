//! Warps from [0,1)² to directions and points, each beside its pdf. Directions are in a local
//! frame with the axis of interest along +z.

use crate::simd::Vector;
use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI, TAU};

/// (cos a, sin a) for |a| ≤ π/4, by the minimax polynomials of Cephes' `cosf`/`sinf`
/// (Moshier 1989; within 1 ulp, see the test). Written once over lanes: the scalar warps
/// call it with `f32` as one lane, so scalar and lane samples agree bit for bit on every ISA,
/// and on every platform (C libraries' `sincosf` differ).
#[inline(always)]
pub fn cos_sin_quarter<V: Vector<N>, const N: usize>(a: V) -> (V, V) {
    let z = a.mul(a);
    let c = V::splat(2.443_315_7e-5)
        .mul(z)
        .add(V::splat(-1.388_731_6e-3))
        .mul(z)
        .add(V::splat(4.166_664_6e-2))
        .mul(z)
        .mul(z);
    let c = c.sub(V::splat(0.5).mul(z)).add(V::splat(1.0));
    let s = V::splat(-1.951_529_6e-4)
        .mul(z)
        .add(V::splat(8.332_161e-3))
        .mul(z)
        .add(V::splat(-1.666_665_5e-1))
        .mul(z)
        .mul(a);
    (c, s.add(a))
}

/// (cos 2πu, sin 2πu) for u in [0, 1]: u is reduced exactly to r = u − q/4 with |r| ≤ 1/8
/// (Sterbenz: u and q/4 are within a factor of two), then the quadrant q rotates
/// (cos 2πr, sin 2πr). Exact at the quarter turns (u = 0, ¼, ½, ¾, 1).
#[inline(always)]
pub fn cos_sin_turns<V: Vector<N>, const N: usize>(u: V) -> (V, V) {
    let past = |t: f32| V::splat(t).le(u);
    let (q1, q2, q3, q4) = (past(0.125), past(0.375), past(0.625), past(0.875));
    let quarter = V::select(
        q4,
        V::splat(1.0),
        V::select(
            q3,
            V::splat(0.75),
            V::select(
                q2,
                V::splat(0.5),
                V::select(q1, V::splat(0.25), V::splat(0.0)),
            ),
        ),
    );
    let (c, s) = cos_sin_quarter(u.sub(quarter).mul(V::splat(TAU)));
    // Quadrant 1: (−s, c); 2: (−c, −s); 3: (s, −c); 0 and 4: (c, s).
    let (odd, neg_cos, neg_sin) = ((q1 & !q2) | (q3 & !q4), q1 & !q3, q2 & !q4);
    let (x, y) = (V::select(odd, s, c), V::select(odd, c, s));
    (
        V::select(neg_cos, x.neg(), x),
        V::select(neg_sin, y.neg(), y),
    )
}

/// Concentric map from the square to the unit disk (Shirley & Chiu 1997): low distortion, so
/// stratification survives the warp. Over lanes, and for one lane as `f32`.
#[inline(always)]
pub fn concentric_disk<V: Vector<N>, const N: usize>(u0: V, u1: V) -> (V, V) {
    let (one, two) = (V::splat(1.0), V::splat(2.0));
    let (ox, oy) = (two.mul(u0).sub(one), two.mul(u1).sub(one));
    // About the x axis, θ = π/4·(y/x); about the y axis, θ = π/2 − π/4·(x/y), whose
    // (cos θ, sin θ) is (sin a, cos a) of a = π/4·(x/y).
    let about_x = oy.abs().lt(ox.abs());
    let centre = ox.eq(V::splat(0.0)) & oy.eq(V::splat(0.0));
    let r = V::select(about_x, ox, oy);
    let t = V::select(about_x, oy, ox).div(V::select(centre, one, r));
    let (c, s) = cos_sin_quarter(V::splat(FRAC_PI_4).mul(t));
    let zero = V::splat(0.0);
    (
        V::select(centre, zero, r.mul(V::select(about_x, c, s))),
        V::select(centre, zero, r.mul(V::select(about_x, s, c))),
    )
}

/// [`concentric_disk`] of one point.
pub fn sample_concentric_disk(u: [f32; 2]) -> Vec2 {
    let (x, y) = concentric_disk(u[0], u[1]);
    Vec2::new(x, y)
}

/// Cosine-weighted hemisphere by Malley's method, over lanes: (x, y, z) with z =
/// sqrt(max(1 − x² − y², 0)), which can be 0 at the disk rim, where the pdf is 0.
#[inline(always)]
pub fn cosine_hemisphere<V: Vector<N>, const N: usize>(u0: V, u1: V) -> (V, V, V) {
    let (x, y) = concentric_disk(u0, u1);
    let z = V::splat(1.0)
        .sub(x.mul(x).add(y.mul(y)))
        .max(V::splat(0.0))
        .sqrt();
    (x, y, z)
}

/// Cosine-weighted hemisphere by Malley's method. z can be 0 at the disk rim, where the pdf is
/// 0; callers skip such samples (a measure-zero event), they never divide by it.
pub fn sample_cosine_hemisphere(u: [f32; 2]) -> Vec3 {
    let (x, y, z) = cosine_hemisphere(u[0], u[1]);
    Vec3::new(x, y, z)
}

pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Uniform direction on the unit sphere.
pub fn sample_uniform_sphere(u: [f32; 2]) -> Vec3 {
    let z = 1.0 - 2.0 * u[0];
    // 1 - z² = 4u(1-u): no cancellation near the poles.
    let r = (4.0 * u[0] * (1.0 - u[0])).sqrt();
    let (c, s) = cos_sin_turns(u[1]);
    Vec3::new(r * c, r * s, z)
}

pub const UNIFORM_SPHERE_PDF: f32 = 1.0 / (4.0 * PI);

/// 1 - cos θmax of a cone whose half-angle has sin²θmax = `sin2_max`, exact in f32 even for
/// tiny cones: 1 - sqrt(1 - s²) = s² / (1 + sqrt(1 - s²)). The naive form is 0 below s ≈ 3e-4.
pub fn one_minus_cos_from_sin2(sin2_max: f32) -> f32 {
    sin2_max / (1.0 + (1.0 - sin2_max).max(0.0).sqrt())
}

/// Uniform direction in the cone about +z with 1 - cos θmax = `one_minus_cos_max`.
/// Uses t = u·(1 - cos θmax), cos θ = 1 - t, sin²θ = t(2 - t): no 1 - cos² cancellation.
pub fn sample_uniform_cone(u: [f32; 2], one_minus_cos_max: f32) -> Vec3 {
    let (x, y, z) = uniform_cone(u[0], u[1], one_minus_cos_max);
    Vec3::new(x, y, z)
}

/// [`sample_uniform_cone`] over lanes, (x, y, z), each lane with its own cone.
#[inline(always)]
pub fn uniform_cone<V: Vector<N>, const N: usize>(u0: V, u1: V, one_minus_cos_max: V) -> (V, V, V) {
    let t = u0.mul(one_minus_cos_max);
    let cos_theta = V::splat(1.0).sub(t);
    let sin_theta = t.mul(V::splat(2.0).sub(t)).max(V::splat(0.0)).sqrt();
    let (c, s) = cos_sin_turns(u1);
    (sin_theta.mul(c), sin_theta.mul(s), cos_theta)
}

/// Solid-angle pdf of [`sample_uniform_cone`] inside the cone (0 outside, which the caller
/// decides from its geometry).
pub fn uniform_cone_pdf(one_minus_cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * one_minus_cos_max)
}

/// Uniform barycentrics (b1, b2) over a triangle (pbrt-v4 `SampleUniformTriangle`, after
/// Heitz 2019's low-distortion map): area pdf 1/A.
pub fn sample_uniform_triangle(u: [f32; 2]) -> (f32, f32) {
    uniform_triangle(u[0], u[1])
}

/// [`sample_uniform_triangle`] over lanes (and for one lane as `f32`).
#[inline(always)]
pub fn uniform_triangle<V: Vector<N>, const N: usize>(u0: V, u1: V) -> (V, V) {
    let two = V::splat(2.0);
    let first = u0.lt(u1);
    let (h0, h1) = (u0.div(two), u1.div(two));
    let b0 = V::select(first, h0, u0.sub(h1));
    let b1 = V::select(first, u1.sub(h0), h1);
    (b1, V::splat(1.0).sub(b0).sub(b1))
}

/// Uniform direction on the hemisphere about +z.
pub fn sample_uniform_hemisphere(u: [f32; 2]) -> Vec3 {
    let z = 1.0 - u[0];
    // 1 - z² = u(2 - u): no cancellation near the pole.
    let r = (u[0] * (2.0 - u[0])).sqrt();
    let (c, s) = cos_sin_turns(u[1]);
    Vec3::new(r * c, r * s, z)
}

pub const UNIFORM_HEMISPHERE_PDF: f32 = 1.0 / (2.0 * PI);

/// Phong lobe about +z, pdf (n+1)/(2π)·cos^n α, by cos α = u^(1/(n+1)) (Lafortune & Willems
/// 1994). Written with expm1 so that huge exponents neither collapse the lobe to the axis nor
/// produce NaN: 1 - cos α = -expm1(ln u/(n+1)), sin²α = -expm1(2 ln u/(n+1)).
/// The lecture's pair — pdf (n+2)/(2π) cos^n with cos α = u^(1/(n+2)) — is inconsistent:
/// see docs/lecture-errata.md.
pub fn sample_phong_lobe(u: [f32; 2], exponent: f32) -> Vec3 {
    let l = (1.0 - u[0]).ln() / (exponent + 1.0); // 1 - u keeps u = 0 at the pole, not ln 0
    let one_minus_cos = -l.exp_m1();
    let sin2 = -(2.0 * l).exp_m1();
    let sin = sin2.max(0.0).sqrt();
    let (c, s) = cos_sin_turns(u[1]);
    Vec3::new(sin * c, sin * s, 1.0 - one_minus_cos)
}

/// Solid-angle pdf of [`sample_phong_lobe`] for a direction whose angle to the lobe axis has
/// 1 - cos α = `one_minus_cos` (pass the chordal form |a - b|²/2 for precision near the axis).
pub fn phong_lobe_pdf(one_minus_cos: f32, exponent: f32) -> f32 {
    if one_minus_cos >= 1.0 {
        return 0.0; // the lobe's back hemisphere
    }
    (exponent + 1.0) * (0.5 * FRAC_1_PI) * (exponent * (-one_minus_cos).ln_1p()).exp()
}

/// Inverse of [`sample_uniform_cone`] for a direction inside the cone.
pub fn invert_uniform_cone(w: Vec3, one_minus_cos_max: f32) -> [f32; 2] {
    let one_minus_cos = (w.x * w.x + w.y * w.y) / (1.0 + w.z);
    [one_minus_cos / one_minus_cos_max, wrap_phi(w.y.atan2(w.x))]
}

/// Inverse of [`sample_cosine_hemisphere`] (the inverse concentric map of Shirley & Chiu).
pub fn invert_cosine_hemisphere(w: Vec3) -> [f32; 2] {
    let (x, y) = (w.x, w.y);
    let r = (x * x + y * y).sqrt();
    let phi = y.atan2(x);
    // Back to the square by the quadrant the concentric map sent it to.
    let (a, b) = if (-FRAC_PI_4..=FRAC_PI_4).contains(&phi)
        || phi >= 3.0 * FRAC_PI_4
        || phi <= -3.0 * FRAC_PI_4
    {
        let sign = if x >= 0.0 { 1.0 } else { -1.0 };
        let a = sign * r;
        let t = if x >= 0.0 {
            phi
        } else if phi > 0.0 {
            phi - PI
        } else {
            phi + PI
        };
        (a, a * t / FRAC_PI_4)
    } else {
        let sign = if y >= 0.0 { 1.0 } else { -1.0 };
        let b = sign * r;
        let t = if y >= 0.0 {
            FRAC_PI_2 - phi
        } else {
            -FRAC_PI_2 - phi
        };
        (b * t / FRAC_PI_4, b)
    };
    [0.5 * (a + 1.0), 0.5 * (b + 1.0)]
}

/// Inverse of [`sample_phong_lobe`].
pub fn invert_phong_lobe(w: Vec3, exponent: f32) -> [f32; 2] {
    let one_minus_cos = (w.x * w.x + w.y * w.y) / (1.0 + w.z);
    // 1 - u = cos^(n+1) α
    [
        -((exponent + 1.0) * (-one_minus_cos).ln_1p()).exp_m1(),
        wrap_phi(w.y.atan2(w.x)),
    ]
}

fn wrap_phi(phi: f32) -> f32 {
    let t = phi / (2.0 * PI);
    if t < 0.0 { t + 1.0 } else { t }
}

/// The χ² cases of the warps above (and the lecture's inconsistent Phong pair, which must fail).
pub fn chi2_cases() -> Vec<crate::chi2::WarpEntry> {
    use crate::chi2::{Chart, DEFAULT_SLACK, WarpCase, WarpEntry, label, omc_z, param};
    let hemisphere = Chart::cap(Vec3::Z, 1.0 + 1e-6);
    let mut lecture = WarpEntry::new(
        "phong-lecture",
        "the lecture's pair: cos α = u^(1/(n+2)) with pdf (n+2)/2π cos^n α — inconsistent, fails",
        &[("n", 20.0)],
        &[&[("n", 1.0)], &[("n", 20.0)]],
        move |p| {
            let n = param(p, "n");
            let pdf = move |w: Vec3| {
                if w.z > 0.0 {
                    (n + 2.0) / (2.0 * PI) * w.z.powf(n)
                } else {
                    0.0
                }
            };
            Ok(WarpCase {
                label: label("phong-lecture", p),
                sample: Box::new(move |u| {
                    let cos = (1.0 - u[0]).powf(1.0 / (n + 2.0));
                    let sin = (1.0 - cos * cos).max(0.0).sqrt();
                    let phi = 2.0 * PI * u[1];
                    let w = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
                    Some((w, pdf(w)))
                }),
                pdf: Box::new(move |w| pdf(w) as f64),
                mismatch_slack: DEFAULT_SLACK,
                chart: hemisphere,
            })
        },
    );
    lecture.expect_fail = true;
    vec![
        WarpEntry::new(
            "uniform-hemisphere",
            "uniform hemisphere about +z, pdf 1/2π",
            &[],
            &[],
            move |p| {
                Ok(WarpCase {
                    label: label("uniform-hemisphere", p),
                    sample: Box::new(|u| {
                        Some((
                            sample_uniform_hemisphere([u[0], u[1]]),
                            UNIFORM_HEMISPHERE_PDF,
                        ))
                    }),
                    pdf: Box::new(|w| {
                        if w.z > 0.0 {
                            UNIFORM_HEMISPHERE_PDF as f64
                        } else {
                            0.0
                        }
                    }),
                    mismatch_slack: DEFAULT_SLACK,
                    chart: hemisphere,
                })
            },
        ),
        WarpEntry::new(
            "cosine-hemisphere",
            "cosine-weighted hemisphere (Malley, concentric disk), pdf cos θ/π",
            &[],
            &[],
            move |p| {
                Ok(WarpCase {
                    label: label("cosine-hemisphere", p),
                    sample: Box::new(|u| {
                        let w = sample_cosine_hemisphere([u[0], u[1]]);
                        (w.z > 0.0).then(|| (w, cosine_hemisphere_pdf(w.z)))
                    }),
                    pdf: Box::new(|w| cosine_hemisphere_pdf(w.z) as f64),
                    mismatch_slack: DEFAULT_SLACK,
                    chart: hemisphere,
                })
            },
        ),
        WarpEntry::new(
            "uniform-sphere",
            "uniform sphere, pdf 1/4π",
            &[],
            &[],
            |p| {
                Ok(WarpCase {
                    label: label("uniform-sphere", p),
                    sample: Box::new(|u| {
                        Some((sample_uniform_sphere([u[0], u[1]]), UNIFORM_SPHERE_PDF))
                    }),
                    pdf: Box::new(|_| UNIFORM_SPHERE_PDF as f64),
                    mismatch_slack: DEFAULT_SLACK,
                    chart: Chart::sphere(),
                })
            },
        ),
        WarpEntry::new(
            "uniform-cone",
            "uniform cone about +z with half-angle sin θmax = s, stable 1 - cos θmax",
            &[("s", 0.5)],
            &[
                &[("s", 0.5)],
                &[("s", 0.999)],
                &[("s", 1e-2)],
                &[("s", 1e-3)],
            ],
            |p| {
                let s = param(p, "s");
                if !(s > 0.0 && s <= 1.0) {
                    return Err("s must be in (0, 1]".into());
                }
                let omc = one_minus_cos_from_sin2(s * s);
                Ok(WarpCase {
                    label: label("uniform-cone", p),
                    sample: Box::new(move |u| {
                        Some((
                            sample_uniform_cone([u[0], u[1]], omc),
                            uniform_cone_pdf(omc),
                        ))
                    }),
                    pdf: Box::new(move |w| {
                        if omc_z(w) <= omc {
                            uniform_cone_pdf(omc) as f64
                        } else {
                            0.0
                        }
                    }),
                    mismatch_slack: DEFAULT_SLACK,
                    chart: Chart::cap(Vec3::Z, omc as f64 * 1.01),
                })
            },
        ),
        WarpEntry::new(
            "phong-lobe",
            "Phong lobe about +z, pdf (n+1)/2π cos^n α, cos α = u^(1/(n+1)) via expm1",
            &[("n", 20.0)],
            &[
                &[("n", 0.0)],
                &[("n", 1.0)],
                &[("n", 20.0)],
                &[("n", 1e3)],
                &[("n", 1e4)],
                &[("n", 1e5)],
            ],
            |p| {
                let n = param(p, "n");
                if n < 0.0 {
                    return Err("n must be ≥ 0".into());
                }
                Ok(WarpCase {
                    label: label("phong-lobe", p),
                    sample: Box::new(move |u| {
                        let w = sample_phong_lobe([u[0], u[1]], n);
                        Some((w, phong_lobe_pdf(omc_z(w), n)))
                    }),
                    pdf: Box::new(move |w| phong_lobe_pdf(omc_z(w), n) as f64),
                    mismatch_slack: DEFAULT_SLACK,
                    // The lobe holds all but e^-40 of its mass within 1 - cos α ≤ 40/(n+1).
                    chart: Chart::cap(Vec3::Z, (40.0 / (n as f64 + 1.0)).min(1.0 + 1e-6)),
                })
            },
        ),
        lecture,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd::{Isa, Kernel, Lanes, WIDTH};

    /// |x − want| in units of the f32 spacing at `want` (the ulp of the correctly rounded
    /// value), so 0.5 is a correctly rounded result.
    fn ulps(x: f32, want: f64) -> f64 {
        let w = (want as f32).abs();
        let spacing = if w == 0.0 {
            f32::from_bits(1) as f64
        } else {
            (f32::from_bits(w.to_bits() + 1) - w) as f64
        };
        (x as f64 - want).abs() / spacing
    }

    /// The worst error in ulps of `f` against f64 cos and sin, over 2²⁰ + 1 arguments spread
    /// over [−π/4, π/4] and the tiny ones.
    fn worst_quarter(f: impl Fn(f32) -> (f32, f32)) -> f64 {
        let n = 1 << 20;
        let args = (0..=n)
            .map(|i| FRAC_PI_4 * (2.0 * i as f32 / n as f32 - 1.0))
            .chain([0.0, -0.0, 1e-30, -3e-8, 1e-4, FRAC_PI_4.next_down_f32()]);
        args.map(|a| {
            let (c, s) = f(a);
            ulps(c, (a as f64).cos()).max(ulps(s, (a as f64).sin()))
        })
        .fold(0.0, f64::max)
    }

    trait NextDown {
        fn next_down_f32(self) -> f32;
    }
    impl NextDown for f32 {
        fn next_down_f32(self) -> f32 {
            f32::from_bits(self.to_bits() - 1)
        }
    }

    /// The quarter-range polynomials are within 1 ulp of cos and sin (0.97 measured); a
    /// polynomial one term short (the control) is not.
    #[test]
    fn cos_sin_quarter_is_within_two_ulps() {
        let worst = worst_quarter(cos_sin_quarter::<f32, 1>);
        assert!(worst <= 1.0, "{worst} ulps");
        let short = |a: f32| {
            let (c, _) = cos_sin_quarter::<f32, 1>(a);
            let z = a * a;
            (c, (8.332_161e-3 * z - 1.666_665_5e-1) * z * a + a)
        };
        let worst = worst_quarter(short);
        assert!(worst > 1.0, "the control is within {worst} ulps");
    }

    /// cos 2πu and sin 2πu over [0, 1] within 2 ulps, or, for values under ½, within 2⁻²⁴
    /// absolute (near a zero 2πu itself carries that error): 1.77 measured; exact at quarter
    /// turns.
    /// A quadrant rotated the wrong way (the control) is caught.
    #[test]
    fn cos_sin_turns_is_accurate_in_every_quadrant() {
        let check = |f: &dyn Fn(f32) -> (f32, f32)| {
            let n = 1 << 20;
            let mut worst: f64 = 0.0;
            for i in 0..=n {
                let u = i as f32 / n as f32;
                let (c, s) = f(u);
                let a = std::f64::consts::TAU * u as f64;
                for (x, want) in [(c, a.cos()), (s, a.sin())] {
                    let e = if want.abs() < 0.5 {
                        (x as f64 - want).abs() / 2f64.powi(-25)
                    } else {
                        ulps(x, want)
                    };
                    worst = worst.max(e.min(ulps(x, want)));
                }
            }
            worst
        };
        let worst = check(&|u| cos_sin_turns::<f32, 1>(u));
        assert!(worst <= 2.0, "{worst}");
        for (u, c, s) in [
            (0.0, 1.0, 0.0),
            (0.25, 0.0, 1.0),
            (0.5, -1.0, 0.0),
            (0.75, 0.0, -1.0),
            (1.0, 1.0, 0.0),
        ] {
            assert_eq!(cos_sin_turns::<f32, 1>(u), (c, s), "u = {u}");
        }
        let wrong = |u: f32| {
            let (c, s) = cos_sin_turns::<f32, 1>(u);
            if (0.375..0.625).contains(&u) {
                (c, -s)
            } else {
                (c, s)
            }
        };
        assert!(check(&wrong) > 2.0);
    }

    struct Warps<'a>(&'a [[f32; 2]]);

    impl Kernel for Warps<'_> {
        type Out = Vec<[u32; 7]>;
        fn run<L: Lanes>(self) -> Self::Out {
            let mut out = Vec::new();
            for c in self.0.chunks_exact(WIDTH) {
                let u0 = L::V::load(&std::array::from_fn(|i| c[i][0]));
                let u1 = L::V::load(&std::array::from_fn(|i| c[i][1]));
                let (x, y, z) = cosine_hemisphere(u0, u1);
                let (cc, ss) = cos_sin_turns(u1);
                let (b1, b2) = uniform_triangle(u0, u1);
                let mut o = [[0.0; WIDTH]; 7];
                for (o, v) in o.iter_mut().zip([x, y, z, cc, ss, b1, b2]) {
                    v.store(o);
                }
                out.extend((0..WIDTH).map(|i| o.map(|o| o[i].to_bits())));
            }
            out
        }
    }

    /// The cosine-hemisphere and triangle warps and the turn's cosine and sine over lanes are
    /// the scalar functions bit for bit on every ISA: the disk's centre and diagonals, the square's edges
    /// and corners, the quadrant boundaries, and a spread of points.
    #[test]
    fn lane_warps_are_the_scalar_ones_on_every_isa() {
        let edge = [
            0.0,
            0.125,
            0.25,
            0.375,
            0.5,
            0.625,
            0.75,
            0.875,
            super::super::stream::ONE_MINUS_EPSILON,
            1.0,
        ];
        let mut us: Vec<[f32; 2]> = edge
            .iter()
            .flat_map(|&a| edge.iter().map(move |&b| [a, b]))
            .collect();
        us.extend((0..4000u64).map(|i| {
            let m = crate::math::mix64(i);
            [
                (m >> 40) as f32 / (1u64 << 24) as f32,
                (m >> 8 & 0xff_ffff) as f32 / (1u64 << 24) as f32,
            ]
        }));
        us.truncate(us.len() / WIDTH * WIDTH);
        let want: Vec<[u32; 7]> = us
            .iter()
            .map(|&u| {
                let w = sample_cosine_hemisphere(u);
                let (c, s) = cos_sin_turns::<f32, 1>(u[1]);
                let (b1, b2) = sample_uniform_triangle(u);
                [w.x, w.y, w.z, c, s, b1, b2].map(f32::to_bits)
            })
            .collect();
        for isa in Isa::available() {
            assert_eq!(crate::simd::run(isa, Warps(&us)), want, "{isa:?}");
        }
    }

    fn grid() -> impl Iterator<Item = [f32; 2]> {
        (0..10).flat_map(|i| {
            (0..10).map(move |j| {
                [
                    1e-4 + (1.0 - 2e-4) * i as f32 / 9.0,
                    1e-4 + (1.0 - 2e-4) * j as f32 / 9.0,
                ]
            })
        })
    }

    #[test]
    fn inverses_round_trip() {
        for u in grid() {
            let c = invert_cosine_hemisphere(sample_cosine_hemisphere(u));
            assert!(
                (c[0] - u[0]).abs() < 1e-4 && (c[1] - u[1]).abs() < 1e-4,
                "cosine {u:?} -> {c:?}"
            );
            for omc in [1.0, 0.3, 1e-6] {
                let c = invert_uniform_cone(sample_uniform_cone(u, omc), omc);
                assert!(
                    (c[0] - u[0]).abs() < 1e-3 && (c[1] - u[1]).abs() < 1e-4,
                    "cone {omc}: {u:?} -> {c:?}"
                );
            }
            for n in [0.0, 1.0, 100.0, 1e4] {
                let c = invert_phong_lobe(sample_phong_lobe(u, n), n);
                assert!(
                    (c[0] - u[0]).abs() < 2e-3 && (c[1] - u[1]).abs() < 1e-4,
                    "phong {n}: {u:?} -> {c:?}"
                );
            }
        }
    }

    #[test]
    fn extreme_inputs_stay_finite_and_unit() {
        for u in [
            [0.0, 0.0],
            [super::super::stream::ONE_MINUS_EPSILON; 2],
            [0.5, 0.0],
        ] {
            for w in [
                sample_cosine_hemisphere(u),
                sample_uniform_hemisphere(u),
                sample_uniform_sphere(u),
                sample_uniform_cone(u, 1e-12),
                sample_phong_lobe(u, 0.0),
                sample_phong_lobe(u, 1e6),
            ] {
                assert!(
                    w.is_finite() && (w.length() - 1.0).abs() < 1e-5,
                    "{u:?} -> {w}"
                );
            }
        }
        assert!(phong_lobe_pdf(0.0, 1e6).is_finite());
        assert_eq!(phong_lobe_pdf(1.0, 3.0), 0.0);
    }
}
