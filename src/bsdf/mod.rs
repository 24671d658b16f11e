//! Surface reflectance as a set of lobes, each evaluated and sampled in the local shading
//! frame (z = shading normal, on the viewer's side), one file per lobe (after tray_rust's
//! `bxdf/`). A BSDF samples by first choosing a lobe — the [`LobeSelection`] policy, a part of
//! the strategy — then a direction from that lobe; its pdf is the mixture of every lobe's
//! pdf (the lecture's multi-lobe recipe), so any lobe's direction is weighted correctly.
//!
//! Reflection only: every lobe is zero for directions below the surface (wi.z ≤ 0).

pub mod lambert;
pub mod phong;

use crate::math::{Frame, luminance};
use glam::Vec3;
use std::sync::Arc;

/// One reflectance lobe in the local shading frame (wo.z > 0 always).
pub trait Lobe: Send + Sync + std::fmt::Debug {
    /// f(wo, wi); zero for wi.z ≤ 0.
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3;

    /// A direction drawn from this lobe's own density [`Self::pdf`]; it may lie below the
    /// surface (f = 0 there), so the pdf stays a density over the whole sphere.
    fn sample(&self, wo: Vec3, u: [f32; 2]) -> Vec3;

    /// Solid-angle density of [`Self::sample`].
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32;

    /// The lobe's reflectance coefficient: the weight the by-coefficient policy gives it.
    fn coefficient(&self) -> Vec3;

    /// Sampling this lobe is cosine-weighted hemisphere sampling (so a strategy can tell when
    /// BSDF sampling would only repeat `cosine`).
    fn is_cosine_sampled(&self) -> bool {
        false
    }
}

/// How a BSDF chooses the lobe it samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum LobeSelection {
    /// In proportion to each lobe's coefficient luminance (the lecture's recipe).
    #[default]
    Coefficient,
}

/// A BSDF sample: the world direction with f and the mixture pdf for it.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub wi: Vec3,
    pub f: Vec3,
    pub pdf: f32,
}

/// A material's lobes. Cheap to clone (the lobes are shared).
#[derive(Clone, Debug)]
pub struct Bsdf {
    lobes: Vec<Arc<dyn Lobe>>,
    /// Selection probabilities by coefficient, in lobe order; the last is 1 − Σ of the others
    /// so that they sum to one exactly.
    by_coefficient: Vec<f32>,
}

impl Bsdf {
    pub fn new(lobes: Vec<Arc<dyn Lobe>>) -> Self {
        let weights: Vec<f32> = lobes.iter().map(|l| luminance(l.coefficient())).collect();
        let total: f32 = weights.iter().sum();
        let mut by_coefficient = Vec::with_capacity(weights.len());
        let mut acc = 0.0;
        for (i, w) in weights.iter().enumerate() {
            let p = if i + 1 == weights.len() {
                1.0 - acc
            } else if total > 0.0 {
                w / total
            } else {
                // No reflectance at all: sample the first lobe (every f is zero anyway).
                if i == 0 { 1.0 } else { 0.0 }
            };
            acc += p;
            by_coefficient.push(p);
        }
        Bsdf {
            lobes,
            by_coefficient,
        }
    }

    /// Diffuse kd plus normalized-Phong ks with exponent n: the lecture's blend (either part
    /// left out when its coefficient is zero; a black material keeps a black Lambert lobe).
    pub fn blend(kd: Vec3, ks: Vec3, exponent: f32) -> Self {
        let mut lobes: Vec<Arc<dyn Lobe>> = Vec::new();
        if kd != Vec3::ZERO || ks == Vec3::ZERO {
            lobes.push(Arc::new(lambert::Lambert { kd }));
        }
        if ks != Vec3::ZERO {
            lobes.push(Arc::new(phong::Phong { ks, exponent }));
        }
        Self::new(lobes)
    }

    pub fn lambertian(albedo: Vec3) -> Self {
        Self::blend(albedo, Vec3::ZERO, 0.0)
    }

    pub fn lobes(&self) -> &[Arc<dyn Lobe>] {
        &self.lobes
    }

    /// BSDF sampling is cosine sampling for this material.
    pub fn is_cosine_sampled(&self) -> bool {
        self.lobes.iter().all(|l| l.is_cosine_sampled())
    }

    fn selection(&self, _policy: LobeSelection) -> &[f32] {
        &self.by_coefficient
    }

    /// Σ f over the lobes, in the local frame.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let mut f = Vec3::ZERO;
        for l in &self.lobes {
            f += l.eval(wo, wi);
        }
        f
    }

    /// Mixture pdf of [`Self::sample`] under `policy`, in the local frame.
    pub fn pdf(&self, wo: Vec3, wi: Vec3, policy: LobeSelection) -> f32 {
        let mut pdf = 0.0;
        for (l, &p) in self.lobes.iter().zip(self.selection(policy)) {
            if p > 0.0 {
                pdf += p * l.pdf(wo, wi);
            }
        }
        pdf
    }

    /// u[2] chooses the lobe, u[0..2] the direction within it; local frame.
    pub fn sample_local(&self, wo: Vec3, u: [f32; 3], policy: LobeSelection) -> Vec3 {
        let probs = self.selection(policy);
        let mut cdf = 0.0;
        let mut chosen = self.lobes.len() - 1;
        for (i, &p) in probs.iter().enumerate() {
            cdf += p;
            if u[2] < cdf {
                chosen = i;
                break;
            }
        }
        self.lobes[chosen].sample(wo, [u[0], u[1]])
    }
}

/// A BSDF at a surface point: the shading frame, the viewer's direction in it and the material.
/// World-space entry points, so strategies need not transform.
#[derive(Clone, Copy, Debug)]
pub struct LocalBsdf<'a> {
    pub frame: Frame,
    pub wo: Vec3,
    pub bsdf: &'a Bsdf,
}

impl LocalBsdf<'_> {
    /// World direction `wi` in the shading frame.
    pub fn to_local(&self, wi: Vec3) -> Vec3 {
        self.frame.to_local(wi)
    }

    /// f for world direction `wi`.
    pub fn eval(&self, wi: Vec3) -> Vec3 {
        self.bsdf.eval(self.wo, self.frame.to_local(wi))
    }

    /// f for a direction already in the shading frame.
    pub fn eval_local(&self, wi: Vec3) -> Vec3 {
        self.bsdf.eval(self.wo, wi)
    }

    pub fn pdf(&self, wi: Vec3, policy: LobeSelection) -> f32 {
        self.bsdf.pdf(self.wo, self.frame.to_local(wi), policy)
    }

    /// The pdf of a direction already in the shading frame.
    pub fn pdf_local(&self, wi: Vec3, policy: LobeSelection) -> f32 {
        self.bsdf.pdf(self.wo, wi, policy)
    }

    /// A world direction with f and pdf evaluated for the direction as rounded to world space,
    /// so value and density describe the same direction.
    pub fn sample(&self, u: [f32; 3], policy: LobeSelection) -> BsdfSample {
        let wi = self
            .frame
            .to_world(self.bsdf.sample_local(self.wo, u, policy));
        let local = self.frame.to_local(wi);
        BsdfSample {
            wi,
            f: self.bsdf.eval(self.wo, local),
            pdf: self.bsdf.pdf(self.wo, local, policy),
        }
    }
}

/// The χ² case of BSDF sampling: the diffuse + Phong blend, lobe chosen by coefficient, with
/// the mixture pdf, seen from `theta_o` off the normal.
pub fn chi2_cases() -> Vec<crate::chi2::WarpEntry> {
    use crate::chi2::{Chart, DEFAULT_SLACK, WarpCase, WarpEntry, label, param};
    vec![WarpEntry::new(
        "bsdf-blend",
        "diffuse + normalized Phong blend, lobe chosen by coefficient; wo at theta_o from the normal",
        &[("kd", 0.5), ("ks", 0.4), ("n", 10.0), ("theta_o", 30.0)],
        &[
            &[],
            &[("kd", 0.0), ("ks", 1.0), ("n", 5.0), ("theta_o", 70.0)],
            &[("kd", 0.9), ("ks", 0.1), ("n", 50.0), ("theta_o", 0.0)],
        ],
        |p| {
            let (kd, ks, n, theta) = (
                param(p, "kd"),
                param(p, "ks"),
                param(p, "n"),
                param(p, "theta_o").to_radians(),
            );
            if kd < 0.0 || ks < 0.0 || kd + ks > 1.0 || kd + ks == 0.0 || n < 0.0 {
                return Err("need kd, ks ≥ 0 with 0 < kd + ks ≤ 1, and n ≥ 0".into());
            }
            let bsdf = Bsdf::blend(Vec3::splat(kd), Vec3::splat(ks), n);
            let b2 = bsdf.clone();
            let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
            let policy = LobeSelection::Coefficient;
            Ok(WarpCase {
                label: label("bsdf-blend", p),
                sample: Box::new(move |u| {
                    let wi = bsdf.sample_local(wo, u, policy);
                    Some((wi, bsdf.pdf(wo, wi, policy)))
                }),
                pdf: Box::new(move |w| b2.pdf(wo, w, policy) as f64),
                mismatch_slack: DEFAULT_SLACK,
                chart: Chart::sphere(),
            })
        },
    )]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Directional albedo ∫ f cos dω ≤ kd + ks, with equality for the Phong lobe at normal
    /// incidence (the normalization); by Riemann sum over a fine (φ, cos θ) grid.
    #[test]
    fn energy_conservation_and_normalization() {
        let albedo = |b: &Bsdf, wo: Vec3| {
            let (nt, np) = (4000, 64);
            let mut s = 0.0f64;
            for i in 0..nt {
                let c = (i as f64 + 0.5) / nt as f64;
                for j in 0..np {
                    let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / np as f64;
                    let st = (1.0 - c * c).sqrt();
                    let wi = Vec3::new((st * phi.cos()) as f32, (st * phi.sin()) as f32, c as f32);
                    s += b.eval(wo, wi).x as f64 * c;
                }
            }
            s * 2.0 * std::f64::consts::PI / (nt * np) as f64
        };
        let phong = Bsdf::blend(Vec3::ZERO, Vec3::ONE, 20.0);
        assert!((albedo(&phong, Vec3::Z) - 1.0).abs() < 2e-3);
        let grazing = Vec3::new(0.8, 0.0, 0.6);
        assert!(albedo(&phong, grazing) < 1.0);
        let blend = Bsdf::blend(Vec3::splat(0.5), Vec3::splat(0.5), 5.0);
        assert!((albedo(&blend, Vec3::Z) - 1.0).abs() < 2e-3);
    }

    /// Selection by coefficient luminance: probabilities sum to one and follow the weights.
    #[test]
    fn selection_by_coefficient() {
        let b = Bsdf::blend(Vec3::splat(0.3), Vec3::splat(0.6), 10.0);
        let p = b.selection(LobeSelection::Coefficient);
        assert_eq!(p.len(), 2);
        assert!((p[0] - 1.0 / 3.0).abs() < 1e-6 && (p[0] + p[1] - 1.0).abs() < 1e-7);
        assert_eq!(
            Bsdf::lambertian(Vec3::ONE).selection(LobeSelection::Coefficient),
            [1.0]
        );
        assert_eq!(Bsdf::lambertian(Vec3::ZERO).lobes().len(), 1);
    }
}
