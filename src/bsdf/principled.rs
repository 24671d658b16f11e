//! The `principled` material type (after Burley 2012's parameters, reflection only): base
//! colour, metallic, roughness, specular and optional anisotropy, as two lobes —
//! a GGX lobe with Schlick Fresnel F0 = lerp(0.08·specular, base, metallic), and for the
//! dielectric share a diffuse lobe attenuated by the specular Fresnel on both directions,
//! f_d = (1 − metallic)·base/π·(1 − F(cos θo))(1 − F(cos θi)) (the Fresnel-weighted diffuse of
//! Shirley et al. 1997 without its normalisation, so ∫ f_d cos ≤ (1 − metallic)·base).
//!
//! Its lobes estimate their directional albedos (Fresnel at the view angle) for the
//! by-albedo selection policy; by coefficient, the GGX lobe weighs its F0 and the diffuse lobe
//! its (1 − metallic)·base.

use super::fresnel::{
    Fresnel, clamp01_lanes, schlick_hemispherical_mean, schlick_weight, schlick_weight_lanes,
};
use super::ggx::{GgxLobe, parse_distribution};
use super::material::{MaterialType, Params};
use super::{Bsdf, EvalLanes, Lobe, MicrofacetSampler, PdfQuery, SampleQuery};
use crate::error::Result;
use crate::sampling::warp::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
use crate::simd::{Isa, Soa3, V3, Vector, WIDTH};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;
use std::sync::Arc;

/// The dielectric reflectance at normal incidence per unit `specular` (0.5 → 4 %, Burley 2012).
pub const SPECULAR_F0_SCALE: f32 = 0.08;

/// kd/π·(1 − F(cos θo))(1 − F(cos θi)) with Schlick's F of scalar F0, cosine-sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FresnelDiffuse {
    pub kd: Vec3,
    pub f0: f32,
}

impl FresnelDiffuse {
    fn transmitted(&self, cos: f32) -> f32 {
        (1.0 - self.f0) * (1.0 - schlick_weight(cos.clamp(0.0, 1.0)))
    }

    /// [`Self::transmitted`] over lanes.
    #[inline(always)]
    fn transmitted_lanes<V: Vector<WIDTH>>(&self, cos: V) -> V {
        let w = schlick_weight_lanes(clamp01_lanes(cos));
        V::splat(1.0 - self.f0).mul(V::splat(1.0).sub(w))
    }
}

impl EvalLanes for FresnelDiffuse {
    #[inline(always)]
    fn eval_v<V: Vector<WIDTH>>(&self, wo: V3<V>, wi: V3<V>) -> V3<V> {
        let zero = V::splat(0.0);
        let above = !wi.z.le(zero) & !wo.z.le(zero);
        let s = V::splat(FRAC_1_PI)
            .mul(self.transmitted_lanes(wo.z))
            .mul(self.transmitted_lanes(wi.z));
        V3::select(above, V3::splat(self.kd).scale(s), V3::splat(Vec3::ZERO))
    }

    /// `cosine_hemisphere_pdf(wi.z)`.
    #[inline(always)]
    fn pdf_v<V: Vector<WIDTH>>(&self, _wo: V3<V>, wi: V3<V>, _: MicrofacetSampler) -> V {
        wi.z.max(V::splat(0.0)).mul(V::splat(FRAC_1_PI))
    }

    #[inline(always)]
    fn sample_v<V: Vector<WIDTH>>(&self, _wo: V3<V>, u: [V; 2], _: MicrofacetSampler) -> V3<V> {
        super::lambert::cosine_lanes(u)
    }
}

impl Lobe for FresnelDiffuse {
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        self.kd * (FRAC_1_PI * self.transmitted(wo.z) * self.transmitted(wi.z))
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

    /// Exact: kd·(1 − F(cos θo))·(1 − F0)(1 − 1/21), the second factor the cosine-weighted
    /// hemispherical mean of 1 − F.
    fn albedo_estimate(&self, wo: Vec3) -> Vec3 {
        self.kd * (self.transmitted(wo.z) * (1.0 - schlick_hemispherical_mean(self.f0)))
    }

    fn estimates_albedo(&self) -> bool {
        true
    }

    fn is_cosine_sampled(&self) -> bool {
        true
    }
}

/// The principled parameters, validated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Principled {
    pub base: Vec3,
    pub metallic: f32,
    pub specular: f32,
    pub dist: super::ggx::Ggx,
}

impl Principled {
    pub fn bsdf(&self) -> Bsdf {
        let f0d = SPECULAR_F0_SCALE * self.specular;
        let kd = (1.0 - self.metallic) * self.base;
        let mut lobes: Vec<Arc<dyn Lobe>> = Vec::new();
        if kd != Vec3::ZERO {
            lobes.push(Arc::new(FresnelDiffuse { kd, f0: f0d }));
        }
        lobes.push(Arc::new(GgxLobe {
            ks: Vec3::ONE,
            dist: self.dist,
            fresnel: Fresnel::Schlick {
                f0: Vec3::splat(f0d).lerp(self.base, self.metallic),
            },
        }));
        Bsdf::new(lobes)
    }
}

/// `type = "principled"`: `base_color` (default 0.8 grey), `metallic` ∈ [0, 1] (default 0),
/// `specular` ∈ [0, 1] (default 0.5), `roughness` (default 0.5) and `anisotropy` or `alpha` as
/// for `ggx`.
pub static PRINCIPLED: MaterialType = MaterialType {
    name: "principled",
    describe: "base colour, metallic, roughness, specular, anisotropy: GGX + Fresnel-weighted diffuse",
    fields: &[
        "base_color",
        "metallic",
        "specular",
        "roughness",
        "anisotropy",
        "alpha",
    ],
    parse: parse_principled,
    chi2_cases,
};

fn parse_principled(p: &mut Params) -> Result<Bsdf> {
    let base = p.rgb_in("base_color", 0.0, 1.0)?.unwrap_or(Vec3::splat(0.8));
    let metallic = p.number_in("metallic", 0.0, 1.0)?.unwrap_or(0.0);
    let specular = p.number_in("specular", 0.0, 1.0)?.unwrap_or(0.5);
    let dist = parse_distribution(p, Some(0.5))?;
    Ok(Principled {
        base,
        metallic,
        specular,
        dist,
    }
    .bsdf())
}

/// χ² of the principled mixture (diffuse + GGX) under both lobe-selection policies and every
/// GGX sampler, on the sphere of reflected directions.
pub fn chi2_cases() -> Vec<crate::chi2::WarpEntry> {
    use super::{BsdfSampling, LobeSelection};
    use crate::chi2::{Chart, DEFAULT_SLACK, WarpCase, WarpEntry, label, param};
    vec![WarpEntry::new(
        "bsdf-principled",
        "principled mixture (Fresnel diffuse + GGX); policy 0 by coefficient, 1 by albedo; sampler 0-3 = ndf, vndf, cap, bounded",
        &[
            ("metallic", 0.0),
            ("roughness", 0.5),
            ("anisotropy", 0.0),
            ("policy", 1.0),
            ("sampler", 1.0),
            ("theta_o", 60.0),
        ],
        &[
            &[],
            &[("policy", 0.0)],
            &[("sampler", 0.0), ("theta_o", 80.0)],
            &[("sampler", 2.0), ("metallic", 0.5), ("anisotropy", 1.0)],
            // The bounded sampler's support ends in a sliver just below the horizon, under
            // 1e-3 thick at θo = 85°, which this sphere chart's cells cannot resolve (22 of
            // 1e6 samples fell in cells integrated to zero); its grazing cases run in the
            // half-vector chart of `ggx-vndf-bounded`.
            &[("sampler", 3.0), ("roughness", 0.8), ("theta_o", 70.0)],
            &[("sampler", 3.0), ("policy", 0.0), ("theta_o", 0.0)],
        ],
        |p| {
            let policy = match param(p, "policy") {
                0.0 => LobeSelection::Coefficient,
                1.0 => LobeSelection::Albedo,
                _ => return Err("policy must be 0 or 1".into()),
            };
            let s = param(p, "sampler");
            if !((0.0..=3.0).contains(&s) && s.fract() == 0.0) {
                return Err("sampler must be 0, 1, 2 or 3".into());
            }
            let (m, r, a) = (
                param(p, "metallic"),
                param(p, "roughness"),
                param(p, "anisotropy"),
            );
            if !((0.0..=1.0).contains(&m) && (0.3..=1.0).contains(&r) && (0.0..=1.0).contains(&a))
            {
                // Narrower lobes need the half-vector chart of the GGX cases.
                return Err("need metallic, anisotropy in [0, 1] and roughness in [0.3, 1]".into());
            }
            let alpha = r * r;
            let bsdf = Principled {
                base: Vec3::new(0.9, 0.6, 0.3),
                metallic: m,
                specular: 0.5,
                dist: super::ggx::Ggx {
                    ax: alpha,
                    ay: alpha * (1.0 - 0.9 * a),
                },
            }
            .bsdf();
            let b2 = bsdf.clone();
            let sampling = BsdfSampling {
                lobes: policy,
                microfacet: MicrofacetSampler::ALL[s as usize],
            };
            let wo = super::ggx::chi2_view(param(p, "theta_o"));
            Ok(WarpCase {
                label: label("bsdf-principled", p),
                sample: Box::new(move |u| {
                    let wi = bsdf.sample_local(wo, u, sampling);
                    Some((wi, bsdf.pdf(wo, wi, sampling)))
                }),
                pdf: Box::new(move |w| b2.pdf(wo, w, sampling) as f64),
                mismatch_slack: DEFAULT_SLACK,
                chart: Chart::sphere(),
            })
        },
    )]
}
