//! Lambertian reflection kd/π, sampled cosine-weighted (Malley's method); the `diffuse`
//! material type.

use super::material::{MaterialType, Params};
use super::{Bsdf, EvalLanes, Lobe, MicrofacetSampler, PdfQuery, SampleQuery};
use crate::error::Result;
use crate::sampling::warp::{cosine_hemisphere, cosine_hemisphere_pdf, sample_cosine_hemisphere};
use crate::simd::{Isa, Soa3, V3, Vector, WIDTH};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambert {
    pub kd: Vec3,
}

impl Lobe for Lambert {
    fn eval(&self, _wo: Vec3, wi: Vec3) -> Vec3 {
        if wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        self.kd * FRAC_1_PI
    }

    fn add_eval_lanes(&self, isa: Isa, wo: &Soa3, wi: &Soa3, mask: u32, acc: &mut Soa3) {
        super::add_eval_lanes(self, isa, wo, wi, mask, acc);
    }

    fn add_pdf_lanes(&self, isa: Isa, q: &PdfQuery, p: f32, acc: &mut [f32; WIDTH]) {
        super::add_pdf_lanes(self, isa, q, p, acc);
    }

    fn sample(&self, _wo: Vec3, u: [f32; 2], _: MicrofacetSampler) -> Vec3 {
        sample_cosine_hemisphere(u)
    }

    fn sample_lanes(&self, isa: Isa, q: &SampleQuery, out: &mut Soa3) {
        super::sample_lanes(self, isa, q, out);
    }

    fn pdf(&self, _wo: Vec3, wi: Vec3, _: MicrofacetSampler) -> f32 {
        cosine_hemisphere_pdf(wi.z)
    }

    fn coefficient(&self) -> Vec3 {
        self.kd
    }

    fn is_cosine_sampled(&self) -> bool {
        true
    }
}

impl EvalLanes for Lambert {
    #[inline(always)]
    fn eval_v<V: Vector<WIDTH>>(&self, _wo: V3<V>, wi: V3<V>) -> V3<V> {
        let f = V3::splat(self.kd).scale(V::splat(FRAC_1_PI));
        V3::select(!wi.z.le(V::splat(0.0)), f, V3::splat(Vec3::ZERO))
    }

    /// `cosine_hemisphere_pdf(wi.z)`.
    #[inline(always)]
    fn pdf_v<V: Vector<WIDTH>>(&self, _wo: V3<V>, wi: V3<V>, _: MicrofacetSampler) -> V {
        wi.z.max(V::splat(0.0)).mul(V::splat(FRAC_1_PI))
    }

    #[inline(always)]
    fn sample_v<V: Vector<WIDTH>>(&self, _wo: V3<V>, u: [V; 2], _: MicrofacetSampler) -> V3<V> {
        cosine_lanes(u)
    }
}

/// [`sample_cosine_hemisphere`] over lanes (the same warp code).
#[inline(always)]
pub(crate) fn cosine_lanes<V: Vector<WIDTH>>(u: [V; 2]) -> V3<V> {
    let (x, y, z) = cosine_hemisphere(u[0], u[1]);
    V3 { x, y, z }
}

/// `Bsdf::eval` and `Bsdf::pdf` of a diffuse material (its one Lambert lobe of `kd`) over
/// lanes, for directions of local z `z`: `0 + kd/π` above the surface, else 0, and
/// `0 + max(z, 0)/π`, the scalar path's operations in their order, so the same bits.
#[inline(always)]
pub fn diffuse_lanes<V: Vector<WIDTH>>(kd: V3<V>, z: V) -> (V3<V>, V) {
    let (zero, inv_pi) = (V::splat(0.0), V::splat(FRAC_1_PI));
    let none = V3::splat(Vec3::ZERO);
    let f = none + V3::select(!z.le(zero), kd.scale(inv_pi), none);
    (f, zero.add(z.max(zero).mul(inv_pi)))
}

/// `type = "diffuse"`: `albedo` (kd per channel in [0, 1], default black).
pub static DIFFUSE: MaterialType = MaterialType {
    name: "diffuse",
    describe: "Lambertian reflection of albedo kd",
    fields: &["albedo"],
    parse: parse_diffuse,
    // Its sampler is the cosine warp, tested with the warps (`sampling::warp`).
    chi2_cases: crate::chi2::no_cases,
};

fn parse_diffuse(p: &mut Params) -> Result<Bsdf> {
    let albedo = p.rgb_in("albedo", 0.0, 1.0)?.unwrap_or(Vec3::ZERO);
    Ok(Bsdf::lambertian(albedo))
}
