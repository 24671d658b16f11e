//! Ambient occlusion (1/π)∫ V(ω) cos θ dω, V = 1 when nothing lies within the scene's AO
//! distance, under uniform (estimator 2V cos θ) and cosine-weighted (estimator V) hemisphere
//! sampling — the lecture's example of importance sampling the cosine term.

use super::{Estimator, Integrand, Probes, ShadingPoint, ShadowProbe, Strategy};
use crate::geometry::Ray;
use crate::prepare::SceneView;
use crate::sampling::warp::{sample_cosine_hemisphere, sample_uniform_hemisphere};
use crate::sampling::{Dimension, Dims, Layout};
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AmbientOcclusion {
    pub cosine: bool,
}

impl Strategy for AmbientOcclusion {
    fn name(&self) -> String {
        if self.cosine {
            "ao-cosine"
        } else {
            "ao-uniform"
        }
        .into()
    }

    fn describe(&self) -> String {
        if self.cosine {
            "ambient occlusion, cosine-weighted hemisphere (estimator V)"
        } else {
            "ambient occlusion, uniform hemisphere (estimator 2V cos θ)"
        }
        .into()
    }

    fn integrand(&self) -> Integrand {
        Integrand::AmbientOcclusion
    }

    fn bind<'s>(&self, scene: SceneView<'s>) -> Result<Box<dyn Estimator + 's>, String> {
        match scene.world.ao_distance {
            Some(distance) => Ok(Box::new(AoEstimator {
                cosine: self.cosine,
                distance,
            })),
            None => Err("the scene has no [ambient_occlusion] section".into()),
        }
    }
}

struct AoEstimator {
    cosine: bool,
    distance: f32,
}

impl Estimator for AoEstimator {
    fn layout(&self) -> Layout {
        Layout::of(&[Dimension::pair("direction")])
    }

    fn sample(&self, sp: &ShadingPoint, u: &mut Dims) -> Probes {
        let u = u.get_2d();
        let (local, value) = if self.cosine {
            (sample_cosine_hemisphere(u), 1.0)
        } else {
            let w = sample_uniform_hemisphere(u);
            (w, 2.0 * w.z)
        };
        if local.z <= 0.0 {
            return Probes::default();
        }
        let dir = sp.bsdf.frame.to_world(local);
        Probes {
            shadow: Some(ShadowProbe {
                ray: Ray::new(sp.origin, dir, self.distance),
                value: Vec3::splat(value),
            }),
            emission: None,
        }
    }
}
