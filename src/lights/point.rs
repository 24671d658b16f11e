//! Isotropic point light: intensity I = Φ/(4π); irradiance I·cosθ/d² (inverse-square law).

use super::bounds::{Bounds, LightBounds};
use super::{Light, LightCtx, LightHit, LightMethods, LightSample, LightShape, direction_to};
use crate::math::luminance;
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct PointLight {
    pub position: Vec3,
    pub intensity: Vec3,
}

impl PointLight {
    /// The only direction there is. None at the light's own position, where I/d² is undefined
    /// (a measure-zero set of shading points).
    pub fn sample_from(&self, p: Vec3) -> Option<LightSample> {
        let (wi, d2) = direction_to(p, self.position)?;
        Some(LightSample {
            wi,
            point: self.position,
            normal: Vec3::ZERO,
            point_error: Vec3::ZERO,
            radiance: self.intensity / d2,
            pdf: 1.0,
            distant: false,
        })
    }
}

impl Light for PointLight {
    fn shape(&self) -> LightShape {
        LightShape::Point
    }

    fn power(&self) -> f32 {
        4.0 * std::f32::consts::PI * luminance(self.intensity)
    }

    fn bounds(&self) -> Bounds {
        Bounds::Local(LightBounds::point(self.position, luminance(self.intensity)))
    }

    fn sample(&self, ctx: &LightCtx, _u: [f32; 3], _m: &LightMethods) -> Option<LightSample> {
        self.sample_from(ctx.p)
    }

    /// A delta light: no sampled direction reaches it.
    fn pdf(&self, _ctx: &LightCtx, _at: LightHit, _m: &LightMethods) -> f32 {
        0.0
    }
}
