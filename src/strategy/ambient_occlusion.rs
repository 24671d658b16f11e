//! Ambient occlusion (1/π)∫ V(ω) cos θ dω, V = 1 when nothing lies within the scene's AO
//! distance, under uniform (estimator 2V cos θ) and cosine-weighted (estimator V) hemisphere
//! sampling — the lecture's example of importance sampling the cosine term.

use super::{Integrand, Probes, ShadingPoint, ShadowProbe, Strategy};
use crate::geometry::Ray;
use crate::math::Frame;
use crate::prepare::PreparedScene;
use crate::sampling::stream::SampleStream;
use crate::sampling::warp::{sample_cosine_hemisphere, sample_uniform_hemisphere};
use glam::Vec3;

pub struct AmbientOcclusion {
    pub cosine: bool,
}

impl Strategy for AmbientOcclusion {
    fn name(&self) -> &'static str {
        if self.cosine {
            "ao-cosine"
        } else {
            "ao-uniform"
        }
    }

    fn describe(&self) -> &'static str {
        if self.cosine {
            "ambient occlusion, cosine-weighted hemisphere (estimator V)"
        } else {
            "ambient occlusion, uniform hemisphere (estimator 2V cos θ)"
        }
    }

    fn integrand(&self) -> Integrand {
        Integrand::AmbientOcclusion
    }

    fn applies(&self, scene: &PreparedScene) -> Result<(), String> {
        match scene.scene.ao_distance {
            Some(_) => Ok(()),
            None => Err("the scene has no [ambient_occlusion] section".into()),
        }
    }

    fn sample(&self, scene: &PreparedScene, sp: &ShadingPoint, rng: &mut SampleStream) -> Probes {
        let Some(distance) = scene.scene.ao_distance else {
            return Probes::default();
        };
        let u = rng.next_2d();
        let (local, value) = if self.cosine {
            (sample_cosine_hemisphere(u), 1.0)
        } else {
            let w = sample_uniform_hemisphere(u);
            (w, 2.0 * w.z)
        };
        if local.z <= 0.0 {
            return Probes::default();
        }
        let dir = Frame::from_normal(sp.n).to_world(local);
        Probes {
            shadow: Some(ShadowProbe {
                ray: Ray::new(sp.origin, dir, distance),
                value: Vec3::splat(value),
            }),
            emission: None,
        }
    }
}
