//! Direct-illumination strategies: each a named, self-contained estimator that turns a
//! shading point into at most one shadow probe and one emission probe. The renderer traces
//! the probes as packets; a strategy never sees the tracer.

pub mod ambient_occlusion;
pub mod direction;
pub mod estimate;
pub mod light_sampling;
pub mod mis;

use crate::bsdf::Bsdf;
use crate::env::{EnvMethod, EnvSampler, Repr};
use crate::geometry::Ray;
use crate::lights::{LightMethods, MeshMethod, QuadMethod, SphereMethod};
use crate::math::offset_ray_origin;
use crate::prepare::{PreparedScene, SurfaceHit};
use crate::sampling::stream::SampleStream;
use glam::Vec3;

/// A surface point about to be shaded, with the normal flipped to the viewer's side (surfaces
/// are two-sided reflectors) and the origin already offset for rays leaving on that side.
#[derive(Clone, Copy, Debug)]
pub struct ShadingPoint {
    pub p: Vec3,
    pub origin: Vec3,
    pub n: Vec3,
    /// Unit direction towards the viewer.
    pub wo: Vec3,
    pub bsdf: Bsdf,
}

impl ShadingPoint {
    /// An exact point (no error to step over: rays start at `p` itself) seen along
    /// `view_dir` (unit, pointing at the surface): a point given by a test or stress case.
    pub fn new(p: Vec3, ng: Vec3, view_dir: Vec3, bsdf: Bsdf) -> Self {
        Self::with_error(p, Vec3::ZERO, ng, view_dir, bsdf)
    }

    /// A computed surface point whose coordinates are known to within `p_error` per axis.
    pub fn with_error(p: Vec3, p_error: Vec3, ng: Vec3, view_dir: Vec3, bsdf: Bsdf) -> Self {
        let n = if ng.dot(view_dir) < 0.0 { ng } else { -ng };
        ShadingPoint {
            p,
            origin: offset_ray_origin(p, p_error, n),
            n,
            wo: -view_dir,
            bsdf,
        }
    }
}

/// What one sample asks the tracer. The contribution is `shadow.value` if the shadow segment
/// is clear, plus `emission.weight · Le · w` for the emitter the emission ray hits first, with
/// w the strategy's [`Strategy::emission_weight`].
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
    /// Solid-angle pdf the direction was sampled with (for MIS).
    pub pdf: f32,
}

/// The quantity a strategy estimates: each has its own reference image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Integrand {
    /// Emission seen by the camera plus reflected direct illumination (an environment, if
    /// any, in its lat/long representation).
    Direct,
    /// As `Direct`, with the environment resampled into another representation: a slightly
    /// different radiance function (resampling), so it has its own reference.
    DirectEnv(Repr),
    /// (1/π)∫ V(ω) cos θ dω with occluders within the scene's AO distance.
    AmbientOcclusion,
}

impl Integrand {
    pub fn name(&self) -> &'static str {
        match self {
            Integrand::Direct | Integrand::DirectEnv(Repr::LatLong) => "direct",
            Integrand::DirectEnv(Repr::Cube) => "direct-cube",
            Integrand::DirectEnv(Repr::Octahedral) => "direct-octa",
            Integrand::DirectEnv(Repr::Healpix) => "direct-healpix",
            Integrand::AmbientOcclusion => "ao",
        }
    }

    /// Direct illumination with the environment in representation `r`.
    pub fn direct_with(r: Repr) -> Self {
        match r {
            Repr::LatLong => Integrand::Direct,
            r => Integrand::DirectEnv(r),
        }
    }

    /// Emission seen by the camera counts (every integrand but AO).
    pub fn is_direct(&self) -> bool {
        !matches!(self, Integrand::AmbientOcclusion)
    }
}

pub trait Strategy: Send + Sync {
    fn name(&self) -> &'static str;

    /// One-line description for listings.
    fn describe(&self) -> &'static str;

    /// Ok if the strategy is unbiased for this scene and adds something, otherwise why not.
    fn applies(&self, scene: &PreparedScene) -> Result<(), String>;

    fn sample(&self, scene: &PreparedScene, sp: &ShadingPoint, rng: &mut SampleStream) -> Probes;

    fn integrand(&self) -> Integrand {
        Integrand::Direct
    }

    /// Weight of the emission an emission probe found at `hit` (MIS strategies override).
    fn emission_weight(
        &self,
        _scene: &PreparedScene,
        _sp: &ShadingPoint,
        _probe: &EmissionProbe,
        _hit: &SurfaceHit,
    ) -> f32 {
        1.0
    }

    /// The representation this strategy looks the environment up in (escaped rays, camera
    /// rays that miss), so that its lookups and its samplers agree.
    fn env_repr(&self) -> Repr {
        Repr::LatLong
    }

    /// Weight of environment radiance found by an emission probe that escaped (MIS overrides).
    fn env_weight(
        &self,
        _scene: &PreparedScene,
        _sp: &ShadingPoint,
        _probe: &EmissionProbe,
    ) -> f32 {
        1.0
    }
}

/// Names of the environment strategies per (representation, sampler), in `Repr::ALL` and
/// `EnvSampler::ALL` order: light sampling alone, and MIS with BSDF sampling.
const ENV_LIGHT_NAMES: [[&str; 2]; 4] = [
    ["env-latlong-cdf", "env-latlong-hier"],
    ["env-cube-cdf", "env-cube-hier"],
    ["env-octa-cdf", "env-octa-hier"],
    ["env-healpix-cdf", "env-healpix-hier"],
];
const ENV_MIS_NAMES: [[&str; 2]; 4] = [
    ["mis-env-latlong-cdf", "mis-env-latlong-hier"],
    ["mis-env-cube-cdf", "mis-env-cube-hier"],
    ["mis-env-octa-cdf", "mis-env-octa-hier"],
    ["mis-env-healpix-cdf", "mis-env-healpix-hier"],
];

fn env_methods() -> impl Iterator<Item = EnvMethod> {
    Repr::ALL.into_iter().flat_map(|repr| {
        EnvSampler::ALL
            .into_iter()
            .map(move |sampler| EnvMethod { repr, sampler })
    })
}

/// Name of the environment light-sampling strategy for `m`.
pub fn env_light_name(m: EnvMethod) -> &'static str {
    ENV_LIGHT_NAMES[m.repr.index()][m.sampler as usize]
}

/// Name of the environment MIS strategy for `m`.
pub fn env_mis_name(m: EnvMethod) -> &'static str {
    ENV_MIS_NAMES[m.repr.index()][m.sampler as usize]
}

/// Every strategy dibench knows, in listing order.
pub fn registry() -> Vec<Box<dyn Strategy>> {
    use direction::{DirectionKind, DirectionSampling};
    use light_sampling::LightSampling;
    let basic = LightMethods::BASIC;
    let mut v: Vec<Box<dyn Strategy>> = vec![
        Box::new(DirectionSampling(DirectionKind::UniformHemisphere)),
        Box::new(DirectionSampling(DirectionKind::CosineHemisphere)),
        Box::new(DirectionSampling(DirectionKind::Bsdf)),
        Box::new(LightSampling::basic()),
        Box::new(LightSampling::variant(
            "light-quad-sa",
            "as `light`, but quads uniform in solid angle (spherical rectangle, Ureña et al. 2013)",
            LightMethods {
                quad: QuadMethod::SolidAngle,
                ..basic
            },
        )),
        Box::new(LightSampling::variant(
            "light-sphere-area",
            "as `light`, but spheres uniform by area over the whole sphere",
            LightMethods {
                sphere: SphereMethod::Area,
                ..basic
            },
        )),
        Box::new(LightSampling::variant(
            "light-sphere-cap",
            "as `light`, but spheres uniform by area over the visible cap",
            LightMethods {
                sphere: SphereMethod::Cap,
                ..basic
            },
        )),
        Box::new(LightSampling::variant(
            "light-mesh-sa",
            "as `light`, but mesh triangles uniform in solid angle (spherical triangle, Arvo 1995)",
            LightMethods {
                mesh: MeshMethod::SolidAngle,
                ..basic
            },
        )),
        Box::new(mis::Mis::new(mis::Heuristic::Balance)),
        Box::new(mis::Mis::new(mis::Heuristic::Power)),
        Box::new(ambient_occlusion::AmbientOcclusion { cosine: false }),
        Box::new(ambient_occlusion::AmbientOcclusion { cosine: true }),
    ];
    for m in env_methods() {
        v.push(Box::new(LightSampling::variant(
            env_light_name(m),
            "as `light`, but the environment looked up and sampled in this representation by this sampler (cdf: marginal/conditional, hier: hierarchical warping)",
            LightMethods { env: m, ..basic },
        )));
    }
    for m in env_methods() {
        v.push(Box::new(mis::Mis::env(env_mis_name(m), m)));
    }
    v
}

pub fn by_name(name: &str) -> Option<Box<dyn Strategy>> {
    registry().into_iter().find(|s| s.name() == name)
}

/// The strategy a reference for `integrand` is rendered with: the lowest-variance unbiased
/// one that applies.
pub fn reference_strategy(
    scene: &PreparedScene,
    integrand: Integrand,
) -> Option<Box<dyn Strategy>> {
    let env_mis = |repr| {
        env_mis_name(EnvMethod {
            repr,
            sampler: EnvSampler::Cdf,
        })
    };
    let order: Vec<&str> = match integrand {
        Integrand::Direct => vec!["mis-power", env_mis(Repr::LatLong), "light"],
        Integrand::DirectEnv(r) => vec![env_mis(r)],
        Integrand::AmbientOcclusion => vec!["ao-cosine"],
    };
    order
        .iter()
        .filter_map(|n| by_name(n))
        .find(|s| s.applies(scene).is_ok())
}

/// The integrands a scene has (the set its references are made for).
pub fn integrands(scene: &PreparedScene) -> Vec<Integrand> {
    [
        Integrand::Direct,
        Integrand::DirectEnv(Repr::Cube),
        Integrand::DirectEnv(Repr::Octahedral),
        Integrand::DirectEnv(Repr::Healpix),
        Integrand::AmbientOcclusion,
    ]
    .into_iter()
    .filter(|&i| reference_strategy(scene, i).is_some())
    .collect()
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
