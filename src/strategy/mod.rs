//! Direct-illumination strategies: each a named, self-contained estimator that turns a
//! shading point into at most one shadow probe and one emission probe. The renderer traces
//! the probes as packets; a strategy never sees the tracer.

pub mod cosine_hemisphere;
pub mod estimate;
pub mod light_sampling;

use crate::geometry::Ray;
use crate::math::offset_ray_origin;
use crate::prepare::PreparedScene;
use crate::sampling::stream::SampleStream;
use glam::Vec3;

/// A surface point about to be shaded, with the normal flipped to the viewer's side (surfaces
/// are two-sided reflectors) and the origin already offset for rays leaving on that side.
#[derive(Clone, Copy, Debug)]
pub struct ShadingPoint {
    pub p: Vec3,
    pub origin: Vec3,
    pub n: Vec3,
    pub albedo: Vec3,
}

impl ShadingPoint {
    /// A point seen along `view_dir` (pointing at the surface): the normal is flipped to the
    /// viewer's side and the ray origin offset along it.
    pub fn new(p: Vec3, ng: Vec3, view_dir: Vec3, albedo: Vec3) -> Self {
        let n = if ng.dot(view_dir) < 0.0 { ng } else { -ng };
        ShadingPoint {
            p,
            origin: offset_ray_origin(p, n),
            n,
            albedo,
        }
    }
}

/// What one sample asks the tracer. The contribution is
/// `shadow.value` if the shadow segment is clear, plus `emission.weight · Le` of the emitter the
/// emission ray hits first.
#[derive(Clone, Copy, Debug, Default)]
pub struct Probes {
    pub shadow: Option<ShadowProbe>,
    pub emission: Option<EmissionProbe>,
}

#[derive(Clone, Copy, Debug)]
pub struct ShadowProbe {
    pub ray: Ray,
    pub value: Vec3,
}

#[derive(Clone, Copy, Debug)]
pub struct EmissionProbe {
    pub ray: Ray,
    pub weight: Vec3,
}

pub trait Strategy: Send + Sync {
    fn name(&self) -> &'static str;

    /// One-line description for `--help`-style listings.
    fn describe(&self) -> &'static str;

    /// Ok if the strategy is unbiased for this scene, otherwise why it does not apply.
    fn applies(&self, scene: &PreparedScene) -> Result<(), String>;

    fn sample(&self, scene: &PreparedScene, sp: &ShadingPoint, rng: &mut SampleStream) -> Probes;
}

/// Every strategy dibench knows, in listing order.
pub fn registry() -> Vec<Box<dyn Strategy>> {
    vec![
        Box::new(light_sampling::LightSampling),
        Box::new(cosine_hemisphere::CosineHemisphere),
    ]
}

/// The strategy references are rendered with: unbiased for every scene with a light.
pub fn reference_strategy() -> Box<dyn Strategy> {
    Box::new(light_sampling::LightSampling)
}

pub fn by_name(name: &str) -> Option<Box<dyn Strategy>> {
    registry().into_iter().find(|s| s.name() == name)
}

/// A strategy left out of a run, and why.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Skipped {
    pub name: String,
    pub reason: String,
}

/// Splits the registry into the strategies that apply to the scene and the ones that do not.
pub fn applicable(scene: &PreparedScene) -> (Vec<Box<dyn Strategy>>, Vec<Skipped>) {
    let mut run = Vec::new();
    let mut skipped = Vec::new();
    for s in registry() {
        match s.applies(scene) {
            Ok(()) => run.push(s),
            Err(reason) => skipped.push(Skipped {
                name: s.name().to_string(),
                reason,
            }),
        }
    }
    (run, skipped)
}
