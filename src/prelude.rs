//! What a strategy written outside the crate needs, in one import:
//! `use dibench::prelude::*;` (see `examples/custom_strategy.rs` and `docs/extending.md`).

pub use crate::bsdf::{Bsdf, BsdfSample, BsdfSampling, LobeSelection};
pub use crate::lights::selector::default_selector;
pub use crate::lights::{LightMethods, LightSample};
pub use crate::prepare::{SceneView, SurfaceHit};
pub use crate::sampling::{Dimension, Dims, Layout};
pub use crate::strategy::direction::{BSDF_DIMS, emission_probe, emission_probe_with};
pub use crate::strategy::light_sampling::{BoundLights, LIGHT_DIMS};
pub use crate::strategy::{
    EmissionProbe, Estimator, Integrand, Probes, ShadingPoint, ShadowProbe, Strategy,
};
pub use glam::Vec3;
