//! Environment light: radiance from infinitely far away, looked up and importance-sampled in
//! the representation and by the sampler a strategy's `LightMethods::env` names
//! (`crate::env`). Like a directional light it is distant: its shadow rays are unbounded.

use super::bounds::{Bounds, DistantBounds};
use super::{Light, LightCtx, LightHit, LightMethods, LightSample, LightShape};
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
    pub fn sample_env(&self, u: [f32; 2], m: EnvMethod) -> Option<LightSample> {
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

    pub fn pdf_env(&self, wi: Vec3, m: EnvMethod) -> f32 {
        self.env.pdf(m, wi)
    }
}

impl Light for EnvironmentLight {
    fn shape(&self) -> LightShape {
        LightShape::Environment
    }

    /// Luminance-weighted power for light selection (pbrt-v4 `ImageInfiniteLight::Phi`).
    fn power(&self) -> f32 {
        let r = self.scene_radius as f64;
        (std::f64::consts::PI * r * r * self.env.map(Repr::LatLong).luminance_integral) as f32
    }

    fn bounds(&self) -> Bounds {
        Bounds::Distant(DistantBounds {
            to_light: None,
            irradiance: self.env.map(Repr::LatLong).luminance_integral as f32,
        })
    }

    fn sample(&self, _ctx: &LightCtx, u: [f32; 3], m: &LightMethods) -> Option<LightSample> {
        self.sample_env([u[0], u[1]], m.env)
    }

    /// By direction: the environment has no points.
    fn pdf(&self, _ctx: &LightCtx, at: LightHit, m: &LightMethods) -> f32 {
        match at {
            LightHit::Direction(w) => self.pdf_env(w, m.env),
            LightHit::Surface { .. } => 0.0,
        }
    }
}
