//! Strategies that sample a direction and find the emitter it reaches: uniform hemisphere
//! (pdf 1/2π), cosine hemisphere (pdf cos θ/π) and BSDF sampling (the material's lobe
//! mixture). Estimator f·Le·cos θ / pdf. None of them can reach a delta light.

use super::{EmissionProbe, Probes, ShadingPoint, Strategy};
use crate::geometry::Ray;
use crate::math::Frame;
use crate::prepare::PreparedScene;
use crate::sampling::stream::SampleStream;
use crate::sampling::warp::{
    UNIFORM_HEMISPHERE_PDF, cosine_hemisphere_pdf, sample_cosine_hemisphere,
    sample_uniform_hemisphere,
};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DirectionKind {
    UniformHemisphere,
    CosineHemisphere,
    Bsdf,
}

pub struct DirectionSampling(pub DirectionKind);

/// Why no direction-sampling strategy applies, if none does.
pub fn direction_sampling_applies(scene: &PreparedScene) -> Result<(), String> {
    if scene.lights.iter().any(|l| l.is_delta()) {
        return Err(
            "the scene has a point, spot or directional light, which no sampled direction can hit"
                .into(),
        );
    }
    if !scene.scene.has_emitters() && !scene.scene.has_environment() {
        return Err("the scene has no emitting surface and no environment".into());
    }
    Ok(())
}

impl Strategy for DirectionSampling {
    fn name(&self) -> &'static str {
        match self.0 {
            DirectionKind::UniformHemisphere => "uniform",
            DirectionKind::CosineHemisphere => "cosine",
            DirectionKind::Bsdf => "bsdf",
        }
    }

    fn describe(&self) -> &'static str {
        match self.0 {
            DirectionKind::UniformHemisphere => {
                "uniform hemisphere directions, emission of the first hit"
            }
            DirectionKind::CosineHemisphere => {
                "cosine-weighted hemisphere directions, emission of the first hit"
            }
            DirectionKind::Bsdf => {
                "BSDF-sampled directions (lobe chosen by coefficient), emission of the first hit"
            }
        }
    }

    fn applies(&self, scene: &PreparedScene) -> Result<(), String> {
        direction_sampling_applies(scene)?;
        if self.0 == DirectionKind::Bsdf && scene.bsdfs.iter().all(|b| b.is_lambertian()) {
            return Err("identical to `cosine`: every material is Lambertian".into());
        }
        Ok(())
    }

    fn sample(&self, _scene: &PreparedScene, sp: &ShadingPoint, rng: &mut SampleStream) -> Probes {
        let u = [rng.next_1d(), rng.next_1d(), rng.next_1d()];
        let (wi, pdf) = match self.0 {
            DirectionKind::UniformHemisphere => (
                Frame::from_normal(sp.n).to_world(sample_uniform_hemisphere([u[0], u[1]])),
                UNIFORM_HEMISPHERE_PDF,
            ),
            DirectionKind::CosineHemisphere => {
                let local = sample_cosine_hemisphere([u[0], u[1]]);
                (
                    Frame::from_normal(sp.n).to_world(local),
                    cosine_hemisphere_pdf(local.z),
                )
            }
            DirectionKind::Bsdf => {
                let s = sp.bsdf.sample(sp.n, sp.wo, u);
                (s.wi, s.pdf)
            }
        };
        emission_probe(sp, wi, pdf)
    }
}

/// The emission probe for a direction sampled with solid-angle pdf `pdf`; nothing for
/// directions below the surface or of zero pdf (measure-zero or outside the support: no
/// contribution, and no division by zero).
pub fn emission_probe(sp: &ShadingPoint, wi: glam::Vec3, pdf: f32) -> Probes {
    let cos = sp.n.dot(wi);
    if cos <= 0.0 || pdf <= 0.0 {
        return Probes::default();
    }
    let weight = sp.bsdf.eval(sp.n, sp.wo, wi) * (cos / pdf);
    Probes {
        shadow: None,
        emission: Some(EmissionProbe {
            ray: Ray::new(sp.origin, wi, f32::INFINITY),
            weight,
            pdf,
        }),
    }
}
