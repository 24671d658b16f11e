//! Directional (distant) light: irradiance E⊥ arriving along one direction, E = E⊥·cos θ.
//! Its shadow ray is unbounded.

use super::LightSample;
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
    pub fn power(&self) -> f32 {
        std::f32::consts::PI * self.scene_radius * self.scene_radius * luminance(self.irradiance)
    }

    pub fn sample(&self) -> LightSample {
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
