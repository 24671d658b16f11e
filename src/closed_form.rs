//! Closed-form irradiance for configurations the unbiasedness tests and the stress suite check
//! estimators against (E is irradiance; a Lambertian surface of albedo ρ reflects ρE/π), and
//! the one test every such check makes: [`PointCase`] and [`mean_test`].

use crate::prepare::PreparedScene;
use crate::sampling::SampleGenerator;
use crate::stats::{Welford, t_critical, z_critical};
use crate::strategy::estimate::{estimate_at, estimate_at_with};
use crate::strategy::{ShadingPoint, Strategy};
use glam::DVec3;
use std::f64::consts::PI;

/// A two-sided z-test of a sample mean against a closed form, with the standard error from the
/// estimator's own sample variance.
#[derive(Clone, Copy, Debug)]
pub struct MeanTest {
    pub mean: f64,
    pub expected: f64,
    pub std_error: f64,
    /// None for an estimator without variance (a delta light), which has no z.
    pub z: Option<f64>,
    pub passed: bool,
}

/// |mean − expected| < z_crit · standard error + the f32 rounding of the estimator's own
/// arithmetic (16 ulps of the expected value: all that is left when an estimator has no
/// variance, e.g. a delta light or cosine sampling inside a uniform sphere).
pub fn mean_test(st: &Welford, expected: f64, z_crit: f64) -> MeanTest {
    let se = st.std_error();
    let rounding = 16.0 * f32::EPSILON as f64 * expected.abs();
    MeanTest {
        mean: st.mean,
        expected,
        std_error: se,
        z: (se > 0.0).then(|| st.z_score(expected)),
        passed: (st.mean - expected).abs() < z_crit * se + rounding,
    }
}

/// A shading point of a scene where the reflected radiance is known per channel.
pub struct PointCase<'a> {
    pub scene: &'a PreparedScene,
    pub point: ShadingPoint<'a>,
    pub expected: [f64; 3],
}

/// Independent replicates (seeds) the checks of a non-independent generator average over.
pub const REPLICATES: u64 = 32;

impl PointCase<'_> {
    /// [`Self::check`] with samples from `generator`. An independent generator is checked as
    /// there; any other by [`REPLICATES`] independently randomized replicates (seeds seed,
    /// seed + 1, …) of `samples / REPLICATES` samples each (rounded down to a power of two, so
    /// a replicate is a whole net), t-testing the mean of the replicate means with the
    /// standard error across replicates — the only honest one for correlated samples.
    pub fn check_with(
        &self,
        generator: &dyn SampleGenerator,
        strategy: &dyn Strategy,
        samples: u64,
        seed: u64,
        alpha: f64,
        detectable: f64,
    ) -> Result<(), String> {
        let name = format!("{} ({})", strategy.name(), generator.name());
        if generator.independent_samples() {
            return self.check_stats(
                &name,
                estimate_at_with(generator, self.scene, strategy, &self.point, samples, seed),
                z_critical(alpha),
                detectable,
            );
        }
        let per = 1u64 << (63 - (samples / REPLICATES).max(1).leading_zeros());
        let mut means = [Welford::default(); 3];
        for r in 0..REPLICATES {
            let st = estimate_at_with(
                generator,
                self.scene,
                strategy,
                &self.point,
                per,
                seed.wrapping_add(r),
            );
            for c in 0..3 {
                means[c].add(st[c].mean);
            }
        }
        // The replicates' Welford: its std_error is that of the mean of REPLICATES means.
        self.check_stats(
            &name,
            means,
            t_critical(alpha, (REPLICATES - 1) as f64),
            detectable,
        )
    }

    /// Each channel's mean against the closed form at critical value `z_crit`, and the test's
    /// power against a relative bias of `detectable`; errors are labelled `name`.
    fn check_stats(
        &self,
        name: &str,
        stats: [Welford; 3],
        z_crit: f64,
        detectable: f64,
    ) -> Result<(), String> {
        for (c, st) in stats.iter().enumerate() {
            let t = mean_test(st, self.expected[c], z_crit);
            if !t.passed {
                return Err(format!(
                    "{name}, channel {c}: mean {:.6e} vs closed form {:.6e} (se {:.2e}, z = {:.2}, critical {z_crit:.2})",
                    t.mean,
                    t.expected,
                    t.std_error,
                    t.z.unwrap_or(f64::INFINITY)
                ));
            }
            if t.std_error * z_crit >= detectable * t.expected.abs() {
                return Err(format!(
                    "{name}: standard error {:.2e} too large to detect a {}% bias of {:.3e}",
                    t.std_error,
                    detectable * 100.0,
                    t.expected
                ));
            }
        }
        Ok(())
    }

    /// `samples` of `strategy` at the point, each channel z-tested at significance `alpha`;
    /// also an error when the test is too blunt to see a relative bias of `detectable` (its
    /// standard error is too large for the closed form), so a pass means something.
    pub fn check(
        &self,
        strategy: &dyn Strategy,
        samples: u64,
        seed: u64,
        alpha: f64,
        detectable: f64,
    ) -> Result<(), String> {
        let stats = estimate_at(self.scene, strategy, &self.point, samples, seed);
        self.check_stats(&strategy.name(), stats, z_critical(alpha), detectable)
    }
}

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

    /// The z-test rejects a mean off by more than its bound and accepts one within it.
    #[test]
    fn mean_test_has_teeth() {
        let mut st = Welford::default();
        for k in 0..1000 {
            st.add(1.0 + if k % 2 == 0 { 0.1 } else { -0.1 });
        }
        let crit = 3.0;
        assert!(mean_test(&st, 1.0, crit).passed);
        let se = st.std_error();
        assert!(!mean_test(&st, 1.0 + 4.0 * se, crit).passed);
        assert!(mean_test(&st, 1.0 + 2.0 * se, crit).passed);
    }

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
