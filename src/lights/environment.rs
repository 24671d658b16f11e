//! Environment light: radiance from infinitely far away, looked up and importance-sampled in
//! the representation and by the sampler a strategy's `LightMethods::env` names
//! (`crate::env`). Like a directional light it is distant: its shadow rays are unbounded.

use super::LightSample;
use crate::env::{EnvMethod, Environment, Repr};
use glam::Vec3;
use std::sync::Arc;

#[derive(Clone, Debug)]
pub struct EnvironmentLight {
    pub env: Arc<Environment>,
    /// Radius of the scene's bounding sphere: the power reaching the scene is π r² ∫L dω.
    pub scene_radius: f32,
}

impl EnvironmentLight {
    /// Luminance-weighted power for light selection (pbrt-v4 `ImageInfiniteLight::Phi`).
    pub fn power(&self) -> f32 {
        let r = self.scene_radius as f64;
        (std::f64::consts::PI * r * r * self.env.map(Repr::LatLong).luminance_integral) as f32
    }

    pub fn sample(&self, u: [f32; 2], m: EnvMethod) -> Option<LightSample> {
        let s = self.env.sample(m, u)?;
        Some(LightSample {
            wi: s.wi,
            point: Vec3::ZERO,
            point_error: Vec3::ZERO,
            normal: Vec3::ZERO,
            radiance: s.radiance,
            pdf: s.pdf,
            distant: true,
        })
    }

    pub fn pdf(&self, wi: Vec3, m: EnvMethod) -> f32 {
        self.env.pdf(m, wi)
    }
}
