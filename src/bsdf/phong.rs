//! Normalized Phong lobe ks·(n+2)/(2π)·cos^n α, α the angle between wi and the mirror direction
//! of wo (the modified Phong BRDF of Lafortune & Willems 1994, whose directional albedo is at
//! most ks, so kd + ks ≤ 1 conserves energy), sampled by the Phong lobe warp about the mirror
//! direction, pdf (n+1)/(2π)·cos^n α (see docs/lecture-errata.md for the lecture's pair).
//! The `phong` material type is the lecture's blend of a Lambert kd and this lobe.

use super::material::{MaterialType, Params};
use super::{Bsdf, Lobe, MicrofacetSampler};
use crate::error::Result;
use crate::math::Frame;
use crate::sampling::warp::{phong_lobe_pdf, sample_phong_lobe};
use glam::Vec3;
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phong {
    pub ks: Vec3,
    pub exponent: f32,
}

/// Mirror direction of wo about the local normal +z (exact: two sign flips).
fn reflect(wo: Vec3) -> Vec3 {
    Vec3::new(-wo.x, -wo.y, wo.z)
}

/// 1 - cos α between two unit vectors, by the chord: exact near α = 0, where 1 - dot
/// loses everything in f32 (a Phong lobe of exponent 1e6 lives at α ~ 1e-3).
fn one_minus_cos(a: Vec3, b: Vec3) -> f32 {
    0.5 * (a - b).length_squared()
}

impl Lobe for Phong {
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        let omc = one_minus_cos(reflect(wo), wi);
        if omc >= 1.0 {
            return Vec3::ZERO;
        }
        let n = self.exponent;
        self.ks * ((n + 2.0) / (2.0 * PI) * (n * (-omc).ln_1p()).exp())
    }

    fn sample(&self, wo: Vec3, u: [f32; 2], _: MicrofacetSampler) -> Vec3 {
        Frame::from_normal(reflect(wo)).to_world(sample_phong_lobe(u, self.exponent))
    }

    fn pdf(&self, wo: Vec3, wi: Vec3, _: MicrofacetSampler) -> f32 {
        phong_lobe_pdf(one_minus_cos(reflect(wo), wi), self.exponent)
    }

    fn coefficient(&self) -> Vec3 {
        self.ks
    }

    /// The lobe's cos^n α about the mirror direction is, in half vectors, a lobe of angular
    /// width ~(n + 2)^-1/2 (half the angle in reflected directions).
    fn half_vector_spread(&self) -> [f32; 2] {
        let a = (2.0 / (self.exponent + 2.0)).sqrt().min(1.0);
        [a, a]
    }
}

/// `type = "phong"` (and any material without a type that has `specular` or `exponent`):
/// `albedo` kd, `specular` ks, kd + ks ≤ 1 per channel, and `exponent` n ≥ 0 (required when
/// ks is non-zero).
pub static PHONG: MaterialType = MaterialType {
    name: "phong",
    describe: "Lambert kd + normalized Phong ks with exponent n (the lecture's blend)",
    fields: &["albedo", "specular", "exponent"],
    parse: parse_phong,
    chi2_cases,
};

fn parse_phong(p: &mut Params) -> Result<Bsdf> {
    let albedo = p.rgb("albedo")?.unwrap_or(Vec3::ZERO);
    let specular = p.rgb("specular")?.unwrap_or(Vec3::ZERO);
    if albedo.min_element() < 0.0
        || specular.min_element() < 0.0
        || (albedo + specular).max_element() > 1.0
    {
        return Err(p.error(
            "",
            "albedo and specular must be non-negative with albedo + specular ≤ 1 per channel (energy conservation)",
        ));
    }
    let exponent = match p.number("exponent")? {
        Some(e) if e < 0.0 => return Err(p.error("exponent", "must be ≥ 0")),
        Some(e) => e,
        None if specular != Vec3::ZERO => {
            return Err(p.error("exponent", "required when `specular` is non-zero"));
        }
        None => 0.0,
    };
    Ok(Bsdf::blend(albedo, specular, exponent))
}

/// The χ² cases of the blend's sampling: diffuse + Phong, lobe chosen by coefficient, with the
/// mixture pdf, seen from `theta_o` off the normal.
pub fn chi2_cases() -> Vec<crate::chi2::WarpEntry> {
    use super::BsdfSampling;
    use crate::chi2::{Chart, DEFAULT_SLACK, WarpCase, WarpEntry, label, param};
    let v = vec![WarpEntry::new(
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
            let policy = BsdfSampling::default();
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
    )];
    v
}

