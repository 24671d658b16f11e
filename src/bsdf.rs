//! Surface reflectance: a blend of a Lambertian lobe (kd/π) and a normalized Phong lobe
//! ks·(n+2)/(2π)·cos^n α, α the angle between wi and the mirror direction of wo (the modified
//! Phong BRDF of Lafortune & Willems 1994, whose directional albedo is at most ks, so
//! kd + ks ≤ 1 conserves energy). Pure Lambertian: ks = 0; pure Phong: kd = 0.
//!
//! Sampling picks a lobe with probability proportional to its coefficient's luminance and
//! samples it; the pdf is the mixture of both lobes' pdfs (the lecture's multi-lobe recipe).

use crate::math::{Frame, luminance};
use crate::sampling::warp::{
    cosine_hemisphere_pdf, phong_lobe_pdf, sample_cosine_hemisphere, sample_phong_lobe,
};
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bsdf {
    pub kd: Vec3,
    pub ks: Vec3,
    pub exponent: f32,
    /// Probability of sampling the diffuse lobe.
    p_diffuse: f32,
}

/// A sampled direction with the BSDF value and the mixture pdf for it. Directions below the
/// surface are returned too (with f = 0) so that the pdf stays a density over the sphere.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub wi: Vec3,
    pub f: Vec3,
    pub pdf: f32,
}

impl Bsdf {
    pub fn new(kd: Vec3, ks: Vec3, exponent: f32) -> Self {
        let (d, s) = (luminance(kd), luminance(ks));
        let p_diffuse = if d + s > 0.0 { d / (d + s) } else { 1.0 };
        Bsdf {
            kd,
            ks,
            exponent,
            p_diffuse,
        }
    }

    pub fn lambertian(albedo: Vec3) -> Self {
        Self::new(albedo, Vec3::ZERO, 0.0)
    }

    pub fn is_lambertian(&self) -> bool {
        self.ks == Vec3::ZERO
    }

    /// Mirror direction of wo about n.
    fn reflect(n: Vec3, wo: Vec3) -> Vec3 {
        2.0 * n.dot(wo) * n - wo
    }

    /// 1 - cos α between two unit vectors, by the chord: exact near α = 0, where 1 - dot
    /// loses everything in f32 (a Phong lobe of exponent 1e6 lives at α ~ 1e-3).
    fn one_minus_cos(a: Vec3, b: Vec3) -> f32 {
        0.5 * (a - b).length_squared()
    }

    /// f(wo, wi) for unit wo, wi with wo on the side of n; zero for wi below the surface.
    pub fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        if n.dot(wi) <= 0.0 {
            return Vec3::ZERO;
        }
        let mut f = self.kd * FRAC_1_PI;
        if self.ks != Vec3::ZERO {
            let omc = Self::one_minus_cos(Self::reflect(n, wo), wi);
            if omc < 1.0 {
                f += self.ks
                    * ((self.exponent + 2.0) / (2.0 * PI) * (self.exponent * (-omc).ln_1p()).exp());
            }
        }
        f
    }

    /// Mixture pdf (solid angle) of [`Self::sample`] over the whole sphere of directions.
    pub fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        let mut pdf = self.p_diffuse * cosine_hemisphere_pdf(n.dot(wi));
        if self.p_diffuse < 1.0 {
            pdf += (1.0 - self.p_diffuse)
                * phong_lobe_pdf(Self::one_minus_cos(Self::reflect(n, wo), wi), self.exponent);
        }
        pdf
    }

    /// u[2] chooses the lobe, u[0..2] the direction within it.
    pub fn sample(&self, n: Vec3, wo: Vec3, u: [f32; 3]) -> BsdfSample {
        let wi = if u[2] < self.p_diffuse {
            Frame::from_normal(n).to_world(sample_cosine_hemisphere([u[0], u[1]]))
        } else {
            Frame::from_normal(Self::reflect(n, wo))
                .to_world(sample_phong_lobe([u[0], u[1]], self.exponent))
        };
        BsdfSample {
            wi,
            f: self.eval(n, wo, wi),
            pdf: self.pdf(n, wo, wi),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Directional albedo ∫ f cos dω ≤ kd + ks, with equality for the Phong lobe at normal
    /// incidence (the normalization); by Riemann sum over a fine (φ, cos θ) grid.
    #[test]
    fn energy_conservation_and_normalization() {
        let n = Vec3::Z;
        let albedo = |b: &Bsdf, wo: Vec3| {
            let (nt, np) = (4000, 64);
            let mut s = 0.0f64;
            for i in 0..nt {
                let c = (i as f64 + 0.5) / nt as f64;
                for j in 0..np {
                    let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / np as f64;
                    let st = (1.0 - c * c).sqrt();
                    let wi = Vec3::new((st * phi.cos()) as f32, (st * phi.sin()) as f32, c as f32);
                    s += b.eval(n, wo, wi).x as f64 * c;
                }
            }
            s * 2.0 * std::f64::consts::PI / (nt * np) as f64
        };
        let phong = Bsdf::new(Vec3::ZERO, Vec3::ONE, 20.0);
        assert!((albedo(&phong, Vec3::Z) - 1.0).abs() < 2e-3);
        let grazing = Vec3::new(0.8, 0.0, 0.6);
        assert!(albedo(&phong, grazing) < 1.0);
        let blend = Bsdf::new(Vec3::splat(0.5), Vec3::splat(0.5), 5.0);
        assert!((albedo(&blend, Vec3::Z) - 1.0).abs() < 2e-3);
    }
}
