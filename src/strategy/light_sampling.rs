//! Light sampling: a light chosen in proportion to its power, a point on it by the method
//! this strategy uses for its kind, and one shadow ray. Estimator f·L·cos θ / (pmf·pdf_ω).
//! `light` uses the lecture's basic samplers; each variant swaps one kind's sampler.

use super::Integrand;
use super::{Probes, ShadingPoint, ShadowProbe, Strategy};
use crate::env::Repr;
use crate::lights::{Light, LightMethods, LightSample};
use crate::prepare::PreparedScene;
use crate::sampling::stream::SampleStream;

pub struct LightSampling {
    name: &'static str,
    describe: &'static str,
    pub methods: LightMethods,
}

impl LightSampling {
    pub fn basic() -> Self {
        LightSampling {
            name: "light",
            describe: "power-proportional light choice; quad/mesh: uniform area, sphere: uniform cone, point/spot/directional: exact",
            methods: LightMethods::BASIC,
        }
    }

    pub fn variant(name: &'static str, describe: &'static str, methods: LightMethods) -> Self {
        LightSampling {
            name,
            describe,
            methods,
        }
    }
}

/// The light-sampled part of an estimate, shared with MIS: the sample's unweighted value
/// f·L·cos/pdf with its shadow ray, the light sample and the light's index; or None.
pub fn light_probe(
    scene: &PreparedScene,
    sp: &ShadingPoint,
    rng: &mut SampleStream,
    methods: &LightMethods,
) -> Option<(ShadowProbe, LightSample, usize)> {
    let u_select = rng.next_1d();
    let u = [rng.next_1d(), rng.next_1d(), rng.next_1d()];
    let (light, ls) = scene.sample_light(sp.p, u_select, u, methods)?;
    let cos = sp.n.dot(ls.wi);
    if cos <= 0.0 {
        return None;
    }
    let ray = ls.shadow_ray(sp.origin)?;
    let value = sp.bsdf.eval(sp.n, sp.wo, ls.wi) * ls.radiance * (cos / ls.pdf);
    Some((ShadowProbe { ray, value }, ls, light))
}

impl Strategy for LightSampling {
    fn name(&self) -> &'static str {
        self.name
    }

    fn describe(&self) -> &'static str {
        self.describe
    }

    fn applies(&self, scene: &PreparedScene) -> Result<(), String> {
        if scene.light_selection.is_none() {
            return Err("no light with positive power".into());
        }
        let b = LightMethods::BASIC;
        let m = self.methods;
        if m.quad != b.quad {
            if !scene.has_light(|l| matches!(l, Light::Quad(_))) {
                return Err("no quad light".into());
            }
            if scene.usable_methods(m).quad != m.quad {
                return Err(
                    "a quad light is not a rectangle (spherical-rectangle sampling needs one)"
                        .into(),
                );
            }
        }
        if m.sphere != b.sphere && !scene.has_light(|l| matches!(l, Light::Sphere(_))) {
            return Err("no sphere light".into());
        }
        if m.mesh != b.mesh && !scene.has_light(|l| matches!(l, Light::Mesh(_))) {
            return Err("no mesh light".into());
        }
        if m.env != b.env || self.name.starts_with("env-") {
            if scene.environment.is_none() {
                return Err("the scene has no environment".into());
            }
        } else if scene.env_light.is_some() && scene.lights.len() == 1 && m == b {
            return Err("identical to `env-latlong-cdf`: the environment is the only light".into());
        }
        Ok(())
    }

    fn integrand(&self) -> Integrand {
        Integrand::direct_with(self.methods.env.repr)
    }

    fn env_repr(&self) -> Repr {
        self.methods.env.repr
    }

    fn sample(&self, scene: &PreparedScene, sp: &ShadingPoint, rng: &mut SampleStream) -> Probes {
        Probes {
            shadow: light_probe(scene, sp, rng, &self.methods).map(|(p, _, _)| p),
            emission: None,
        }
    }
}
