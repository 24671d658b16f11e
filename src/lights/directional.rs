//! Directional (distant) light: irradiance E⊥ arriving along one direction, E = E⊥·cos θ.
//! Its shadow ray is unbounded.

use super::bounds::{Bounds, DistantBounds};
use super::{Light, LightCtx, LightHit, LightMethods, LightSample, LightShape, LightSpec, LightType};
use crate::math::luminance;
use glam::Vec3;
use std::sync::Arc;

/// `[[directional_light]]`: `direction` (the way the light travels, towards the scene) and
/// `irradiance` E⊥ [W/m²] on a surface facing it.
pub static DIRECTIONAL: LightType = LightType {
    name: "directional_light",
    describe: "distant light from one direction",
    fields: &["direction", "irradiance"],
    parse: |p| {
        let direction = p.direction("direction")?;
        let irradiance = p.required_rgb("irradiance")?;
        if irradiance.min_element() < 0.0 {
            return Err(p.error("irradiance", "must be non-negative"));
        }
        Ok(Arc::new(Placed {
            to_light: -direction,
            irradiance,
        }))
    },
    chi2_cases: crate::chi2::no_cases,
};

/// A directional light before the scene is known: its power is π r² E⊥ for a scene of
/// radius r.
#[derive(Clone, Copy, Debug)]
struct Placed {
    to_light: Vec3,
    irradiance: Vec3,
}

impl LightSpec for Placed {
    fn place(&self, scene_radius: f32) -> Box<dyn Light> {
        Box::new(DirectionalLight {
            to_light: self.to_light,
            irradiance: self.irradiance,
            scene_radius,
        })
    }
}

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
