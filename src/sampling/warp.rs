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
