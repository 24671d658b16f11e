//! Cosine-weighted hemisphere sampling: a direction with pdf cos θ/π, traced to the first
//! surface; its emission counts. For a Lambertian surface the weight f·cos/pdf is the albedo.
//! Cannot reach point lights, so it applies only to scenes without delta lights.

use super::{EmissionProbe, Probes, ShadingPoint, Strategy};
use crate::geometry::Ray;
use crate::math::Frame;
use crate::prepare::PreparedScene;
use crate::sampling::stream::SampleStream;
use crate::sampling::warp::sample_cosine_hemisphere;

pub struct CosineHemisphere;

impl Strategy for CosineHemisphere {
    fn name(&self) -> &'static str {
        "cosine"
    }

    fn describe(&self) -> &'static str {
        "cosine-weighted hemisphere directions, emission of the first hit"
    }

    fn applies(&self, scene: &PreparedScene) -> Result<(), String> {
        if scene.lights.iter().any(|l| l.is_delta()) {
            Err("the scene has a point light, which no direction sample can hit".into())
        } else {
            Ok(())
        }
    }

    fn sample(&self, _scene: &PreparedScene, sp: &ShadingPoint, rng: &mut SampleStream) -> Probes {
        let local = sample_cosine_hemisphere(rng.next_2d());
        // z = 0 has pdf 0: a measure-zero event with no contribution, never a division by 0.
        if local.z <= 0.0 {
            return Probes::default();
        }
        let dir = Frame::from_normal(sp.n).to_world(local).normalize();
        let ray = Ray::new(sp.origin, dir, f32::INFINITY);
        Probes {
            shadow: None,
            emission: Some(EmissionProbe {
                ray,
                weight: sp.albedo,
            }),
        }
    }
}
