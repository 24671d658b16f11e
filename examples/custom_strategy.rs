//! A strategy dibench lacks, defined outside the crate: one-sample MIS (Veach 1997, §9.2.4).
//! A coin picks light or BSDF sampling; the sample is weighted by ½ p_light + ½ p_bsdf.
//! `cargo run --release --example custom_strategy -- compare cornell`
use dibench::prelude::*;

pub struct OneSampleMis;

impl Strategy for OneSampleMis {
    fn name(&self) -> String {
        "one-sample-mis".into()
    }
    fn describe(&self) -> String {
        "light or BSDF sample by a coin flip, weighted by the mixture pdf (Veach 1997)".into()
    }
    fn bind<'s>(&self, scene: SceneView<'s>) -> Result<Box<dyn Estimator + 's>, String> {
        if scene.lights.has_delta() {
            return Err("a point, spot or directional light: the BSDF half cannot reach it".into());
        }
        let lights = BoundLights::bind(&scene, default_selector(), LightMethods::SOLID_ANGLE)?;
        Ok(Box::new(OneSample(lights)))
    }
}

struct OneSample<'s>(BoundLights<'s>);

impl Estimator for OneSample<'_> {
    fn layout(&self) -> Layout {
        let coin = Layout::of(&[Dimension::one("technique")]);
        coin.then(Layout::of(&LIGHT_DIMS))
            .then(Layout::of(&BSDF_DIMS))
    }
    fn sample(&self, sp: &ShadingPoint, u: &mut Dims) -> Probes {
        let (coin, light, bsdf) = (u.get_1d(), u.get::<4>(), u.get_3d());
        let policy = BsdfSampling::default();
        if coin >= 0.5 {
            let s = sp.bsdf.sample(bsdf, policy); // emission_weight finishes the mixture weight
            return emission_probe_with(sp, s.wi, 2.0 * s.f, s.pdf);
        }
        let Some((mut probe, ls, local, _)) = self.0.probe(sp, &mut Dims::new(&light)) else {
            return Probes::default();
        };
        // f·L·cos/p_light → f·L·cos/(½ p_light + ½ p_bsdf)
        probe.value *= 2.0 * ls.pdf / (ls.pdf + sp.bsdf.pdf_local(local, policy));
        Probes::shadow(probe)
    }
    fn emission_weight(&self, sp: &ShadingPoint, probe: &EmissionProbe, hit: &SurfaceHit) -> f32 {
        let p_light = hit
            .emitter
            .map_or(0.0, |e| self.0.pdf(sp, e.light as usize, hit.p, e.local));
        probe.pdf / (probe.pdf + p_light)
    }
    fn env_weight(&self, sp: &ShadingPoint, probe: &EmissionProbe) -> f32 {
        probe.pdf / (probe.pdf + self.0.env_pdf(sp, probe.ray.dir))
    }
}

fn main() -> std::process::ExitCode {
    dibench::cli::main_with(vec![Box::new(OneSampleMis)])
}
