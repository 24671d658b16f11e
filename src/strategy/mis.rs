//! Multiple importance sampling (Veach & Guibas 1995) of one light sample and one BSDF sample,
//! with the balance or power (β = 2) heuristic. Lights are sampled in solid angle where the
//! scene allows it; the environment by the representation and sampler the strategy pins, and
//! BSDF samples that escape see the environment in that same representation. The light pdf
//! includes the light-selection pmf (redner #56). The BSDF sample, and the BSDF pdf of light
//! samples, follow the strategy's [`BsdfSampling`] part (lobe selection, GGX sampler).

use super::direction::{BSDF_DIMS, bsdf_emission_packet, emission_probe_with};
use super::light_sampling::{
    BoundLights, LIGHT_DIMS, LightProbe, LightWeight, selector_applies, with_selector,
};
use super::{
    EmissionProbe, Estimator, Integrand, ProbePacket, Probes, ShadingPacket, ShadingPoint,
    ShadowProbe, Strategy, env_method_name,
};
use crate::bsdf::{BsdfSampling, LocalBsdf};
use crate::env::EnvMethod;
use crate::lights::selector::{SelectorType, default_selector};
use crate::lights::{LightMethods, LightShape, SurfaceLanes};
use crate::prepare::{SceneView, SurfaceHit};
use crate::sampling::{Dims, Layout, PacketDims};
use crate::simd::{Soa3, Vector, WIDTH};
use crate::tracer::LANES;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Heuristic {
    Balance,
    Power,
}

impl Heuristic {
    pub const ALL: [Heuristic; 2] = [Heuristic::Balance, Heuristic::Power];

    pub fn name(self) -> &'static str {
        match self {
            Heuristic::Balance => "balance",
            Heuristic::Power => "power",
        }
    }

    /// Weight of a sample drawn with pdf `a` when the other strategy has pdf `b` (a > 0).
    /// In ratio form, so huge pdfs (tiny lights) cannot overflow.
    pub fn weight(&self, a: f32, b: f32) -> f32 {
        self.weight_lanes::<f32, 1>(a, b)
    }

    /// [`Self::weight`] over lanes (f32 is its one lane): the same operations.
    #[inline(always)]
    pub fn weight_lanes<V: Vector<N>, const N: usize>(&self, a: V, b: V) -> V {
        let r = b.div(a);
        let one = V::splat(1.0);
        match self {
            Heuristic::Balance => one.div(one.add(r)),
            Heuristic::Power => one.div(one.add(r.mul(r))),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mis {
    pub heuristic: Heuristic,
    /// The environment representation and sampler this variant pins; None: lat/long by CDF.
    pub env: Option<EnvMethod>,
    pub selector: &'static SelectorType,
    pub sampling: BsdfSampling,
    /// How lights are sampled: in solid angle where the scene allows it (the default), or by
    /// area as `light` samples them (and as Mitsuba 3's `direct` does).
    pub light_sampling: MisLights,
}

/// The light-sampling methods of an MIS variant's light sample (and of its light pdf).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MisLights {
    /// [`LightMethods::SOLID_ANGLE`]: spherical rectangles and triangles.
    SolidAngle,
    /// [`LightMethods::BASIC`]: quads and mesh triangles uniform by area.
    Area,
}

impl MisLights {
    fn methods(self) -> LightMethods {
        match self {
            MisLights::SolidAngle => LightMethods::SOLID_ANGLE,
            MisLights::Area => LightMethods::BASIC,
        }
    }

    fn name_suffix(self) -> &'static str {
        match self {
            MisLights::SolidAngle => "",
            MisLights::Area => "-area",
        }
    }
}

impl Mis {
    /// `mis-balance` / `mis-power`.
    pub fn new(heuristic: Heuristic) -> Self {
        Mis {
            heuristic,
            env: None,
            selector: default_selector(),
            sampling: BsdfSampling::default(),
            light_sampling: MisLights::SolidAngle,
        }
    }

    /// Heuristic `heuristic` with the BSDF sampled by `sampling`: `mis-power-ggx-ndf`, ...
    pub fn with_sampling(heuristic: Heuristic, sampling: BsdfSampling) -> Self {
        Mis {
            sampling,
            ..Self::new(heuristic)
        }
    }

    /// Power heuristic with the environment in representation and sampler `env`.
    pub fn env(env: EnvMethod) -> Self {
        Mis {
            env: Some(env),
            ..Self::new(Heuristic::Power)
        }
    }

    /// `mis-power-area`: lights sampled by area.
    pub fn by_area(heuristic: Heuristic) -> Self {
        Mis {
            light_sampling: MisLights::Area,
            ..Self::new(heuristic)
        }
    }

    fn methods(&self) -> LightMethods {
        LightMethods {
            env: self.env.unwrap_or(EnvMethod::LATLONG_CDF),
            ..self.light_sampling.methods()
        }
    }
}

impl Strategy for Mis {
    fn name(&self) -> String {
        let base = match (self.env, self.heuristic) {
            (Some(e), Heuristic::Power) => format!("mis-env-{}", env_method_name(e)),
            (Some(e), h) => format!("mis-{}-env-{}", h.name(), env_method_name(e)),
            (None, h) => format!("mis-{}", h.name()),
        };
        with_selector(
            format!(
                "{base}{}{}",
                self.light_sampling.name_suffix(),
                self.sampling.name_suffix()
            ),
            self.selector,
        )
    }

    fn describe(&self) -> String {
        let base = match self.env {
            Some(_) => "as `mis-power`, with the environment looked up and sampled in this representation by this sampler".into(),
            None if self.selector != default_selector() => format!(
                "as `mis-{}`, but the light chosen by the `{}` selector",
                self.heuristic.name(),
                self.selector.name
            ),
            None if self.light_sampling == MisLights::Area => format!(
                "as `mis-{}`, lights sampled by area as `light` samples them (quads and mesh triangles uniform by area)",
                self.heuristic.name()
            ),
            None => format!(
                "one light sample (solid angle) + one BSDF sample, {} heuristic",
                self.heuristic.name()
            ),
        };
        if self.sampling == BsdfSampling::default() {
            base
        } else {
            format!("{base}; BSDF: {}", self.sampling.describe())
        }
    }

    fn integrand(&self) -> Integrand {
        self.env
            .map_or(Integrand::DIRECT, |e| Integrand::Direct(e.repr))
    }

    fn bind<'s>(&self, scene: SceneView<'s>) -> Result<Box<dyn Estimator + 's>, String> {
        let lights = BoundLights::bind(&scene, self.selector, self.methods())?;
        selector_applies(&scene, self.selector)?;
        let has_env = scene.lights.environment().is_some();
        if !scene.has_emitting_surface() && !has_env {
            return Err(
                "no emitting surface and no environment: MIS would reduce to light sampling".into(),
            );
        }
        match self.env {
            Some(_) if !has_env => return Err("the scene has no environment".into()),
            None if self.heuristic == Heuristic::Power
                && self.sampling == BsdfSampling::default()
                && scene.lights.len() == 1
                && scene.lights.has(LightShape::Environment) =>
            {
                return Err(
                    "identical to `mis-env-latlong-cdf`: the environment is the only light".into(),
                );
            }
            _ => {}
        }
        if self.light_sampling != MisLights::SolidAngle {
            let other = Mis {
                light_sampling: MisLights::SolidAngle,
                ..*self
            };
            let (mine, theirs) = (lights.methods, scene.lights.usable_methods(other.methods()));
            // Only the shapes the scene has: their methods are what the two would run.
            let differs = (scene.lights.has(LightShape::Quad) && mine.quad != theirs.quad)
                || (scene.lights.has(LightShape::Mesh) && mine.mesh != theirs.mesh)
                || (scene.lights.has(LightShape::Sphere) && mine.sphere != theirs.sphere);
            if !differs {
                return Err(format!(
                    "identical to `{}`: its lights are sampled the same way by area and in solid angle",
                    other.name()
                ));
            }
        }
        if let Some(why) = self.sampling.same_as_default(&scene.world.materials) {
            let default = Mis {
                sampling: BsdfSampling::default(),
                ..*self
            };
            return Err(format!("identical to `{}`: {why}", default.name()));
        }
        Ok(Box::new(MisEstimator {
            strategy: *self,
            lights,
        }))
    }
}

struct MisEstimator<'s> {
    strategy: Mis,
    lights: BoundLights<'s>,
}

impl MisEstimator<'_> {
    /// The light probe with its MIS weight.
    fn weighted(&self, bsdf: &LocalBsdf, light: Option<LightProbe>) -> Option<ShadowProbe> {
        light.map(|(mut probe, ls, local, light)| {
            probe.value *= self.light_weight(bsdf, ls.pdf, local, light);
            probe
        })
    }

    /// The MIS weight of a sample of light `light` with pdf `pdf` (selection included) in
    /// direction `local` (shading frame) from a point of material `bsdf`. A delta light is
    /// reachable by light sampling only: its weight is 1 (`value · 1` is `value`).
    #[inline(always)]
    fn light_weight(&self, bsdf: &LocalBsdf, pdf: f32, local: glam::Vec3, light: usize) -> f32 {
        // A delta light's weight does not read the BSDF pdf: it is not worked out.
        let p_bsdf = if self.lights.lights.get(light).is_delta() {
            0.0
        } else {
            bsdf.pdf_local(local, self.strategy.sampling)
        };
        LightWeight::lane(self, pdf, p_bsdf, light)
    }

    /// The weight of light samples with pdf `pdf` against BSDF pdf `p_bsdf`, 1 in the lanes
    /// of `delta` (delta lights: light sampling alone reaches them). Lane by lane (f32) and
    /// over lanes: one rule.
    #[inline(always)]
    fn delta_rule<V: Vector<N>, const N: usize>(&self, pdf: V, p_bsdf: V, delta: u32) -> V {
        let w = self.strategy.heuristic.weight_lanes::<V, N>(pdf, p_bsdf);
        V::select(delta, V::splat(1.0), w)
    }

    /// The sample after its light probe: the probe's MIS weight, then the BSDF sample.
    fn finish(&self, sp: &ShadingPoint, light: Option<LightProbe>, u: &mut Dims) -> Probes {
        let shadow = self.weighted(&sp.bsdf, light);
        let bs = sp.bsdf.sample(u.get_3d(), self.strategy.sampling);
        let emission = emission_probe_with(sp, bs.wi, bs.f, bs.pdf).emission;
        Probes { shadow, emission }
    }
}

impl LightWeight for MisEstimator<'_> {
    fn sampling(&self) -> Option<BsdfSampling> {
        Some(self.strategy.sampling)
    }

    /// 1 for a delta light (reachable by light sampling only), else the heuristic.
    #[inline(always)]
    fn lane(&self, pdf: f32, p_bsdf: f32, light: usize) -> f32 {
        if self.lights.lights.get(light).is_delta() {
            return self.delta_rule::<f32, 1>(pdf, 0.0, 1);
        }
        self.delta_rule::<f32, 1>(pdf, p_bsdf, 0)
    }

    #[inline(always)]
    fn diffuse_lanes<V: Vector<WIDTH>>(&self, pdf: V, p_bsdf: V, delta: u32) -> V {
        self.delta_rule::<V, WIDTH>(pdf, p_bsdf, delta)
    }
}

impl Estimator for MisEstimator<'_> {
    fn layout(&self) -> Layout {
        Layout::of(&LIGHT_DIMS).then(Layout::of(&BSDF_DIMS))
    }

    fn sample(&self, sp: &ShadingPoint, u: &mut Dims) -> Probes {
        let light = self.lights.probe(sp, u);
        self.finish(sp, light, u)
    }

    fn sample_packet(&self, packet: &ShadingPacket, u: &mut PacketDims, out: &mut ProbePacket) {
        // Each light probe weighted as its value is made.
        self.lights.probe_packet_rows(packet, u, out, self);
        bsdf_emission_packet(self.lights.isa, packet, u, self.strategy.sampling, out);
    }

    fn emission_weight(&self, sp: &ShadingPoint, probe: &EmissionProbe, hit: &SurfaceHit) -> f32 {
        let Some(e) = hit.emitter else { return 1.0 };
        let p_light = self.lights.pdf(sp, e.light as usize, hit.p, e.local);
        self.strategy.heuristic.weight(probe.pdf, p_light)
    }

    fn emission_weight_packet(
        &self,
        packet: &ShadingPacket,
        probes: &ProbePacket,
        hits: &[Option<SurfaceHit>; LANES],
    ) -> [f32; LANES] {
        let mut at = SurfaceLanes::default();
        let mut light = [0u32; LANES];
        let mut mask = 0u32;
        for lane in 0..LANES {
            if (packet.mask & probes.emission_mask) >> lane & 1 != 0
                && let Some(hit) = &hits[lane]
                && let Some(e) = hit.emitter
            {
                at.set(lane, &packet.light_ctx(lane), hit.p, e.local);
                light[lane] = e.light;
                mask |= 1 << lane;
            }
        }
        let p_light = self.lights.pdf_packet(&light, &at, mask);
        let mut out = [1.0f32; LANES];
        for (lane, o) in out.iter_mut().enumerate() {
            if mask >> lane & 1 != 0 {
                let pdf = probes.emission_pdf[lane];
                *o = self.strategy.heuristic.weight(pdf, p_light[lane]);
            }
        }
        out
    }

    fn env_weight(&self, sp: &ShadingPoint, probe: &EmissionProbe) -> f32 {
        let p_light = self.lights.env_pdf(sp, probe.ray.dir);
        self.strategy.heuristic.weight(probe.pdf, p_light)
    }

    fn env_weight_packet(
        &self,
        packet: &ShadingPacket,
        probes: &ProbePacket,
        dirs: &Soa3,
        mask: u32,
    ) -> [f32; LANES] {
        let p_light = self.lights.env_pdf_packet(packet, dirs, mask);
        let mut out = [1.0f32; LANES];
        for (lane, o) in out.iter_mut().enumerate() {
            if (mask & probes.emission_mask) >> lane & 1 != 0 {
                let pdf = probes.emission_pdf[lane];
                *o = self.strategy.heuristic.weight(pdf, p_light[lane]);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The heuristics' weights for fixed pdfs (Veach 1997, eqs. 9.12–9.13) and the property
    /// that makes MIS unbiased: the two techniques' weights for one direction sum to one.
    #[test]
    fn weights_for_fixed_pdfs_sum_to_one() {
        for (a, b) in [(2.0f32, 0.5f32), (0.3, 7.0), (1.0, 1.0), (1e-6, 3e4)] {
            let balance = a / (a + b);
            let power = a * a / (a * a + b * b);
            let bw = Heuristic::Balance.weight(a, b);
            let pw = Heuristic::Power.weight(a, b);
            assert!(
                (bw - balance).abs() <= 1e-6 * balance,
                "balance({a}, {b}) = {bw}"
            );
            assert!(
                (pw - power).abs() <= 1e-6 * power.max(1e-30),
                "power({a}, {b}) = {pw}"
            );
            for h in Heuristic::ALL {
                let sum = h.weight(a, b) + h.weight(b, a);
                assert!(
                    (sum - 1.0).abs() < 1e-6,
                    "{h:?}({a}, {b}): weights sum to {sum}"
                );
            }
        }
        // The two heuristics differ where they should: power favours the larger pdf more.
        assert!(Heuristic::Power.weight(3.0, 1.0) > Heuristic::Balance.weight(3.0, 1.0));
    }
}
