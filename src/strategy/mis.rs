//! Multiple importance sampling (Veach & Guibas 1995) of one light sample and one BSDF sample,
//! with the balance or power (β = 2) heuristic. Lights are sampled in solid angle where the
//! scene allows it. The light pdf includes the light-selection pmf (redner #56).

use super::direction::emission_probe;
use super::light_sampling::light_probe;
use super::{EmissionProbe, Probes, ShadingPoint, Strategy};
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

pub struct Mis(pub Heuristic);

impl Mis {
    fn methods(scene: &PreparedScene) -> LightMethods {
        scene.usable_methods(LightMethods::SOLID_ANGLE)
    }
}

impl Strategy for Mis {
    fn name(&self) -> &'static str {
        match self.0 {
            Heuristic::Balance => "mis-balance",
            Heuristic::Power => "mis-power",
        }
    }

    fn describe(&self) -> &'static str {
        match self.0 {
            Heuristic::Balance => {
                "one light sample (solid angle) + one BSDF sample, balance heuristic"
            }
            Heuristic::Power => "one light sample (solid angle) + one BSDF sample, power heuristic",
        }
    }

    fn applies(&self, scene: &PreparedScene) -> Result<(), String> {
        if scene.light_selection.is_none() {
            return Err("no light with positive power".into());
        }
        if !scene.scene.has_emitters() {
            return Err("no emitting surface: MIS would reduce to light sampling".into());
        }
        Ok(())
    }

    fn sample(&self, scene: &PreparedScene, sp: &ShadingPoint, rng: &mut SampleStream) -> Probes {
        let methods = Self::methods(scene);
        let shadow = light_probe(scene, sp, rng, &methods).map(|(mut probe, ls, light)| {
            // A delta light is reachable by light sampling only: its weight is 1.
            if !scene.lights[light].is_delta() {
                probe.value *= self.0.weight(ls.pdf, sp.bsdf.pdf(sp.n, sp.wo, ls.wi));
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
        let p_light = scene.light_pdf(sp.p, hit.p, e, &Self::methods(scene));
        self.0.weight(probe.pdf, p_light)
    }
}
