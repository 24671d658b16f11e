//! Light sampling: a light chosen in proportion to its power, then a point on it by that
//! light's sampler (area form for quads and mesh lights, the uniform cone for spheres, the
//! position of a point light), and one shadow ray. Estimator f·L·cos θ / (pmf · pdf_ω).

use super::{Probes, ShadingPoint, ShadowProbe, Strategy};
use crate::bsdf::Lambertian;
use crate::prepare::PreparedScene;
use crate::sampling::stream::SampleStream;

pub struct LightSampling;

impl Strategy for LightSampling {
    fn name(&self) -> &'static str {
        "light"
    }

    fn describe(&self) -> &'static str {
        "power-proportional light choice; quad/mesh: uniform area, sphere: uniform cone, point: exact"
    }

    fn applies(&self, scene: &PreparedScene) -> Result<(), String> {
        match scene.light_selection {
            Some(_) => Ok(()),
            None => Err("no light with positive power".into()),
        }
    }

    fn sample(&self, scene: &PreparedScene, sp: &ShadingPoint, rng: &mut SampleStream) -> Probes {
        let u_select = rng.next_1d();
        let u = [rng.next_1d(), rng.next_1d(), rng.next_1d()];
        let Some((_, ls)) = scene.sample_light(sp.p, u_select, u) else {
            return Probes::default();
        };
        let cos = sp.n.dot(ls.wi);
        if cos <= 0.0 {
            return Probes::default();
        }
        let Some(ray) = ls.shadow_ray(sp.origin) else {
            return Probes::default();
        };
        let value = Lambertian { albedo: sp.albedo }.eval() * ls.radiance * (cos / ls.pdf);
        Probes {
            shadow: Some(ShadowProbe { ray, value }),
            emission: None,
        }
    }
}
