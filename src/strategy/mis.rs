//! Multiple importance sampling (Veach & Guibas 1995) of one light sample and one BSDF sample,
//! with the balance or power (β = 2) heuristic. Lights are sampled in solid angle where the
//! scene allows it; the environment by the representation and sampler the strategy names,
//! and BSDF samples that escape see the environment in that same representation. The light
//! pdf includes the light-selection pmf (redner #56).

use super::direction::emission_probe;
use super::light_sampling::light_probe;
use super::{EmissionProbe, Integrand, Probes, ShadingPoint, Strategy};
use crate::env::{EnvMethod, Repr};
use crate::lights::LightMethods;
use crate::prepare::{PreparedScene, SurfaceHit};
use crate::sampling::stream::SampleStream;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Heuristic {
    Balance,
    Power,
}

impl Heuristic {
    /// Weight of a sample drawn with pdf `a` when the other strategy has pdf `b` (a > 0).
    /// In ratio form, so huge pdfs (tiny lights) cannot overflow.
    pub fn weight(&self, a: f32, b: f32) -> f32 {
        let r = b / a;
        match self {
            Heuristic::Balance => 1.0 / (1.0 + r),
            Heuristic::Power => 1.0 / (1.0 + r * r),
        }
    }
}

pub struct Mis {
    name: &'static str,
    describe: &'static str,
    pub heuristic: Heuristic,
    pub env: EnvMethod,
    /// An environment variant: applies only to scenes with an environment.
    env_variant: bool,
}

impl Mis {
    /// `mis-balance` / `mis-power`: the environment, if any, by lat/long CDF.
    pub fn new(heuristic: Heuristic) -> Self {
        let (name, describe) = match heuristic {
            Heuristic::Balance => (
                "mis-balance",
                "one light sample (solid angle) + one BSDF sample, balance heuristic",
            ),
            Heuristic::Power => (
                "mis-power",
                "one light sample (solid angle) + one BSDF sample, power heuristic",
            ),
        };
        Mis {
            name,
            describe,
            heuristic,
            env: EnvMethod::LATLONG_CDF,
            env_variant: false,
        }
    }

    /// Power heuristic with the environment in representation and sampler `env`.
    pub fn env(name: &'static str, env: EnvMethod) -> Self {
        Mis {
            name,
            describe: "as `mis-power`, with the environment looked up and sampled in this representation by this sampler",
            heuristic: Heuristic::Power,
            env,
            env_variant: true,
        }
    }

    fn methods(&self, scene: &PreparedScene) -> LightMethods {
        LightMethods {
            env: self.env,
            ..scene.usable_methods(LightMethods::SOLID_ANGLE)
        }
    }
}

impl Strategy for Mis {
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
        if !scene.scene.has_emitters() && !scene.scene.has_environment() {
            return Err(
                "no emitting surface and no environment: MIS would reduce to light sampling".into(),
            );
        }
        if self.env_variant {
            if scene.environment.is_none() {
                return Err("the scene has no environment".into());
            }
        } else if self.heuristic == Heuristic::Power
            && scene.env_light.is_some()
            && scene.lights.len() == 1
        {
            return Err(
                "identical to `mis-env-latlong-cdf`: the environment is the only light".into(),
            );
        }
        Ok(())
    }

    fn integrand(&self) -> Integrand {
        Integrand::direct_with(self.env.repr)
    }

    fn env_repr(&self) -> Repr {
        self.env.repr
    }

    fn sample(&self, scene: &PreparedScene, sp: &ShadingPoint, rng: &mut SampleStream) -> Probes {
        let methods = self.methods(scene);
        let shadow = light_probe(scene, sp, rng, &methods).map(|(mut probe, ls, light)| {
            // A delta light is reachable by light sampling only: its weight is 1.
            if !scene.lights[light].is_delta() {
                probe.value *= self
                    .heuristic
                    .weight(ls.pdf, sp.bsdf.pdf(sp.n, sp.wo, ls.wi));
            }
            probe
        });
        let u = [rng.next_1d(), rng.next_1d(), rng.next_1d()];
        let bs = sp.bsdf.sample(sp.n, sp.wo, u);
        let emission = emission_probe(sp, bs.wi, bs.pdf).emission;
        Probes { shadow, emission }
    }

    fn emission_weight(
        &self,
        scene: &PreparedScene,
        sp: &ShadingPoint,
        probe: &EmissionProbe,
        hit: &SurfaceHit,
    ) -> f32 {
        let Some(e) = hit.emitter else { return 1.0 };
        let p_light = scene.light_pdf(sp.p, hit.p, e, &self.methods(scene));
        self.heuristic.weight(probe.pdf, p_light)
    }

    fn env_weight(&self, scene: &PreparedScene, _sp: &ShadingPoint, probe: &EmissionProbe) -> f32 {
        let p_light = scene.env_light_pdf(probe.ray.dir, &self.methods(scene));
        self.heuristic.weight(probe.pdf, p_light)
    }
}
