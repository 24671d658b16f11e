//! Directional (distant) light: irradiance E⊥ arriving along one direction, E = E⊥·cos θ.
//! Its shadow ray is unbounded.

use super::bounds::{Bounds, DistantBounds};
use super::{Light, LightCtx, LightHit, LightMethods, LightSample, LightShape};
use crate::math::luminance;
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct DirectionalLight {
    /// Unit direction towards the light (minus the direction the light travels in).
    pub to_light: Vec3,
    pub irradiance: Vec3,
    /// Radius of the scene's bounding sphere: the power that reaches the scene is π r² E⊥.
    pub scene_radius: f32,
}

impl DirectionalLight {
    pub fn sample_direction(&self) -> LightSample {
        LightSample {
            wi: self.to_light,
            point: Vec3::ZERO,
            normal: Vec3::ZERO,
            point_error: Vec3::ZERO,
            radiance: self.irradiance,
            pdf: 1.0,
            distant: true,
        }
    }
}

impl Light for DirectionalLight {
    fn shape(&self) -> LightShape {
        LightShape::Direction
    }

    fn power(&self) -> f32 {
        std::f32::consts::PI * self.scene_radius * self.scene_radius * luminance(self.irradiance)
    }

    fn bounds(&self) -> Bounds {
        Bounds::Distant(DistantBounds {
            to_light: Some(self.to_light),
            irradiance: luminance(self.irradiance),
        })
    }

    fn sample(&self, _ctx: &LightCtx, _u: [f32; 3], _m: &LightMethods) -> Option<LightSample> {
        Some(self.sample_direction())
    }

    /// A delta light: no sampled direction reaches it.
    fn pdf(&self, _ctx: &LightCtx, _at: LightHit, _m: &LightMethods) -> f32 {
        0.0
    }
}
