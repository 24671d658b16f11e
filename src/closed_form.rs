//! Closed-form irradiance for configurations the unbiasedness tests and the stress suite check
//! estimators against. E is irradiance; a Lambertian surface of albedo ρ reflects ρE/π.

use glam::DVec3;
use std::f64::consts::PI;

/// Irradiance at a point with unit normal `n` from a uniformly emitting sphere of radiance L
/// (Snyder 1996; Lagarde & de Rousiers 2014, `illuminanceSphereOrDisk`), including the case of
/// a sphere partly below the horizon. The point must be outside the sphere.
pub fn sphere_irradiance(p: DVec3, n: DVec3, center: DVec3, radius: f64, radiance: f64) -> f64 {
    let d = center - p;
    let dist2 = d.length_squared();
    let sin2_s = radius * radius / dist2;
    let cos_b = n.dot(d) / dist2.sqrt();
    if cos_b * cos_b > sin2_s {
        return radiance * PI * sin2_s * cos_b.max(0.0);
    }
    let sin_b = (1.0 - cos_b * cos_b).sqrt();
    let x = (1.0 / sin2_s - 1.0).sqrt();
    let y = -x * cos_b / sin_b;
    let s = sin_b * (1.0 - y * y).sqrt();
    radiance * ((cos_b * y.acos() - x * s) * sin2_s + (s / x).atan())
}

/// Irradiance from a planar polygon of radiance L lying entirely above the point's horizon:
/// Lambert's formula E = L/2 Σ Θ_i (n · Γ_i) (Lambert 1760; Arvo 1995, eq. 2), with Θ_i the
/// angle subtended by edge i and Γ_i the unit normal of the plane through p and that edge.
/// The sign of the sum depends on the winding; the magnitude is the irradiance.
pub fn polygon_irradiance(p: DVec3, n: DVec3, vertices: &[DVec3], radiance: f64) -> f64 {
    let mut sum = 0.0;
    for i in 0..vertices.len() {
        let a = (vertices[i] - p).normalize();
        let b = (vertices[(i + 1) % vertices.len()] - p).normalize();
        let c = a.cross(b);
        let theta = c.length().atan2(a.dot(b));
        sum += theta * n.dot(c.normalize());
    }
    radiance * 0.5 * sum.abs()
}

/// Irradiance from an isotropic point light of intensity I at distance d: I max(cos θ, 0)/d².
pub fn point_irradiance(p: DVec3, n: DVec3, light: DVec3, intensity: f64) -> f64 {
    let d = light - p;
    intensity * n.dot(d.normalize()).max(0.0) / d.length_squared()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small, distant quad behaves like a point source: E ≈ L·A·cos θ_l·cos θ/d².
    #[test]
    fn polygon_formula_matches_the_small_source_limit() {
        let h = 1e-3;
        let c = DVec3::new(0.0, 10.0, 0.0);
        let quad = [
            c + DVec3::new(-h, 0.0, -h),
            c + DVec3::new(h, 0.0, -h),
            c + DVec3::new(h, 0.0, h),
            c + DVec3::new(-h, 0.0, h),
        ];
        let e = polygon_irradiance(DVec3::ZERO, DVec3::Y, &quad, 1.0);
        let approx = 4.0 * h * h / 100.0;
        assert!((e / approx - 1.0).abs() < 1e-6, "{e} vs {approx}");
    }

    /// The partial-horizon sphere formula is continuous with the fully-above case.
    #[test]
    fn sphere_formula_is_continuous_at_the_horizon_switch() {
        let (r, dist) = (0.5f64, 2.0f64);
        let sin_s: f64 = r / dist;
        let beta = sin_s.acos(); // cos²β = sin²σ: the switch point
        let at = |b: f64| {
            sphere_irradiance(
                DVec3::ZERO,
                DVec3::Y,
                DVec3::new(b.sin(), b.cos(), 0.0) * dist,
                r,
                1.0,
            )
        };
        let (lo, hi) = (at(beta - 1e-7), at(beta + 1e-7));
        assert!((lo - hi).abs() < 1e-5 * lo.max(1e-12), "{lo} vs {hi}");
        // Below the horizon entirely: nothing.
        assert_eq!(at(std::f64::consts::PI * 0.9), 0.0);
    }
}
