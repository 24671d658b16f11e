//! Light sampling: a light chosen by the strategy's selector, a point on it by the method the
//! strategy uses for its shape, and one shadow ray. Estimator f·L·cos θ / (pmf·pdf_ω).
//! `light` uses the lecture's basic samplers; each variant overrides one shape's sampler or
//! pins the environment's representation and sampler.

use super::{Estimator, Integrand, Probes, ShadingPoint, ShadowProbe, Strategy, env_method_name};
use crate::env::EnvMethod;
use crate::lights::selector::{LightSelector, SelectorType, default_selector};
use crate::lights::{LightHit, LightMethods, LightSample, LightSet, LightShape, MethodOverride};
use crate::prepare::SceneView;
use crate::sampling::{Dimension, Dims, Layout};
use glam::Vec3;

/// The light-sampling part of a layout: which light, where on it, and a third number for
/// lights with parts (a mesh's triangle).
pub const LIGHT_DIMS: [Dimension; 3] = [
    Dimension::one("light selection"),
    Dimension::pair("light point"),
    Dimension::one("light part"),
];

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightSampling {
    /// The one shape whose basic sampler this variant replaces.
    pub method: Option<MethodOverride>,
    /// The environment representation and sampler this variant pins (its integrand is that
    /// representation's); None: the integrand's default, lat/long by CDF.
    pub env: Option<EnvMethod>,
    pub selector: &'static SelectorType,
}

impl LightSampling {
    pub fn basic() -> Self {
        LightSampling {
            method: None,
            env: None,
            selector: default_selector(),
        }
    }

    pub fn with_override(o: MethodOverride) -> Self {
        LightSampling {
            method: Some(o),
            ..Self::basic()
        }
    }

    pub fn with_selector(selector: &'static SelectorType) -> Self {
        LightSampling {
            selector,
            ..Self::basic()
        }
    }

    pub fn env(m: EnvMethod) -> Self {
        LightSampling {
            env: Some(m),
            ..Self::basic()
        }
    }

    pub fn methods(&self) -> LightMethods {
        let mut m = LightMethods::BASIC;
        if let Some(o) = self.method {
            m = o.apply(m);
        }
        if let Some(e) = self.env {
            m.env = e;
        }
        m
    }
}

/// Light sampling as bound to a scene: the lights, the selector built over them, and the
/// methods resolved once for this scene and integrand.
pub struct BoundLights<'s> {
    pub lights: &'s LightSet,
    pub selector: &'s dyn LightSelector,
    pub methods: LightMethods,
}

impl<'s> BoundLights<'s> {
    /// `methods` as the scene can use them, in the view's environment representation; Err
    /// when the selector cannot select (no light with positive power, too many lights).
    pub fn bind(
        scene: &SceneView<'s>,
        selector: &'static SelectorType,
        methods: LightMethods,
    ) -> Result<Self, String> {
        let selector = scene.lights.selector(selector)?;
        Ok(BoundLights {
            lights: scene.lights,
            selector,
            methods: scene
                .lights
                .usable_methods(methods)
                .with_env_repr(scene.env),
        })
    }

    /// The light-sampled part of an estimate (shared with MIS): the unweighted value
    /// f·L·cos/pdf with its shadow ray, the light sample (its direction also in the shading
    /// frame) and the light's index; or None.
    pub fn probe(
        &self,
        sp: &ShadingPoint,
        u: &mut Dims,
    ) -> Option<(ShadowProbe, LightSample, Vec3, usize)> {
        let u_select = u.get_1d();
        let ul = u.get_3d();
        let (light, ls) =
            self.lights
                .sample(self.selector, &sp.light_ctx(), u_select, ul, &self.methods)?;
        let cos = sp.n.dot(ls.wi);
        if cos <= 0.0 {
            return None;
        }
        let ray = ls.shadow_ray(sp.origin)?;
        let local = sp.bsdf.to_local(ls.wi);
        let value = sp.bsdf.eval_local(local) * ls.radiance * (cos / ls.pdf);
        Some((ShadowProbe { ray, value }, ls, local, light))
    }

    /// The pdf with which [`Self::probe`] samples the direction to point `q` of part `local`
    /// of light `light` (selection included).
    pub fn pdf(&self, sp: &ShadingPoint, light: usize, q: Vec3, local: u32) -> f32 {
        self.lights.pdf(
            self.selector,
            &sp.light_ctx(),
            light,
            LightHit::Surface { q, local },
            &self.methods,
        )
    }

    /// The pdf with which [`Self::probe`] samples direction `wi` towards the environment.
    pub fn env_pdf(&self, sp: &ShadingPoint, wi: Vec3) -> f32 {
        self.lights
            .env_pdf(self.selector, &sp.light_ctx(), wi, &self.methods)
    }
}

/// A strategy's name with its light selector appended when it is not the default one:
/// `light@bvh`, `mis-power@uniform`.
pub fn with_selector(base: String, selector: &'static SelectorType) -> String {
    if selector == default_selector() {
        base
    } else {
        format!("{base}@{}", selector.name)
    }
}

/// Why a strategy with a non-default selector adds nothing on this scene, if it does not.
pub fn selector_applies(scene: &SceneView, selector: &'static SelectorType) -> Result<(), String> {
    if selector != default_selector() && scene.lights.len() < 2 {
        return Err(format!(
            "identical to the `{}` selector: the scene has one light",
            default_selector().name
        ));
    }
    Ok(())
}

impl Strategy for LightSampling {
    fn name(&self) -> String {
        let base = match (self.env, self.method) {
            (Some(e), _) => format!("env-{}", env_method_name(e)),
            (None, Some(o)) => format!("light-{}", o.name()),
            (None, None) => "light".into(),
        };
        with_selector(base, self.selector)
    }

    fn describe(&self) -> String {
        match (self.env, self.method) {
            (Some(_), _) => "as `light`, but the environment looked up and sampled in this representation by this sampler (cdf: marginal/conditional, hier: hierarchical warping)".into(),
            (None, Some(o)) => format!("as `light`, but {}", o.describe()),
            (None, None) if self.selector != default_selector() => format!(
                "as `light`, but the light chosen by the `{}` selector: {}",
                self.selector.name, self.selector.describe
            ),
            (None, None) => "power-proportional light choice; quad/mesh: uniform area, sphere: uniform cone, point/spot/directional: exact".into(),
        }
    }

    fn integrand(&self) -> Integrand {
        self.env
            .map_or(Integrand::DIRECT, |e| Integrand::Direct(e.repr))
    }

    fn bind<'s>(&self, scene: SceneView<'s>) -> Result<Box<dyn Estimator + 's>, String> {
        let bound = BoundLights::bind(&scene, self.selector, self.methods())?;
        selector_applies(&scene, self.selector)?;
        if let Some(o) = self.method {
            if !scene.lights.has(o.shape()) {
                return Err(format!("no {} light", o.shape().name()));
            }
            if o.apply(bound.methods) != bound.methods {
                return Err(format!(
                    "a {} light cannot be sampled this way (spherical-rectangle sampling needs a rectangle)",
                    o.shape().name()
                ));
            }
        }
        match self.env {
            Some(_) if scene.lights.environment().is_none() => {
                return Err("the scene has no environment".into());
            }
            None if self.method.is_none()
                && scene.lights.len() == 1
                && scene.lights.has(LightShape::Environment) =>
            {
                return Err(
                    "identical to `env-latlong-cdf`: the environment is the only light".into(),
                );
            }
            _ => {}
        }
        Ok(Box::new(LightEstimator(bound)))
    }
}

struct LightEstimator<'s>(BoundLights<'s>);

impl Estimator for LightEstimator<'_> {
    fn layout(&self) -> Layout {
        Layout::of(&LIGHT_DIMS)
    }

    fn sample(&self, sp: &ShadingPoint, u: &mut Dims) -> Probes {
        match self.0.probe(sp, u) {
            Some((p, ..)) => Probes::shadow(p),
            None => Probes::default(),
        }
    }
}
