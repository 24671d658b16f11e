//! Warps from [0,1)² to directions and points, each beside its pdf. Directions are in a local
//! frame with the axis of interest along +z.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI};

/// Concentric map from the square to the unit disk (Shirley & Chiu 1997): low distortion, so
/// stratification survives the warp.
pub fn sample_concentric_disk(u: [f32; 2]) -> Vec2 {
    let o = Vec2::new(2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    if o == Vec2::ZERO {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Cosine-weighted hemisphere by Malley's method. z can be 0 at the disk rim, where the pdf is
/// 0; callers skip such samples (a measure-zero event), they never divide by it.
pub fn sample_cosine_hemisphere(u: [f32; 2]) -> Vec3 {
    let d = sample_concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Uniform direction on the unit sphere.
pub fn sample_uniform_sphere(u: [f32; 2]) -> Vec3 {
    let z = 1.0 - 2.0 * u[0];
    // 1 - z² = 4u(1-u): no cancellation near the poles.
    let r = (4.0 * u[0] * (1.0 - u[0])).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
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
    let t = u[0] * one_minus_cos_max;
    let cos_theta = 1.0 - t;
    let sin_theta = (t * (2.0 - t)).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

/// Solid-angle pdf of [`sample_uniform_cone`] inside the cone (0 outside, which the caller
/// decides from its geometry).
pub fn uniform_cone_pdf(one_minus_cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * one_minus_cos_max)
}

/// Uniform barycentrics (b1, b2) over a triangle (pbrt-v4 `SampleUniformTriangle`, after
/// Heitz 2019's low-distortion map): area pdf 1/A.
pub fn sample_uniform_triangle(u: [f32; 2]) -> (f32, f32) {
    let (b0, b1);
    if u[0] < u[1] {
        b0 = u[0] / 2.0;
        b1 = u[1] - b0;
    } else {
        b1 = u[1] / 2.0;
        b0 = u[0] - b1;
    }
    (b1, 1.0 - b0 - b1)
}

/// Uniform direction on the hemisphere about +z.
pub fn sample_uniform_hemisphere(u: [f32; 2]) -> Vec3 {
    let z = 1.0 - u[0];
    // 1 - z² = u(2 - u): no cancellation near the pole.
    let r = (u[0] * (2.0 - u[0])).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
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
    let phi = 2.0 * PI * u[1];
    Vec3::new(sin * phi.cos(), sin * phi.sin(), 1.0 - one_minus_cos)
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
