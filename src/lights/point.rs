//! Isotropic point light: intensity I = Φ/(4π); irradiance I·cosθ/d² (inverse-square law).

use super::bounds::{Bounds, LightBounds};
use super::{
    Light, LightCtx, LightHit, LightMethods, LightSample, LightShape, LightSpec, LightType,
    direction_to,
};
use crate::error::Result;
use crate::math::luminance;
use crate::scene::params::Params;
use glam::Vec3;
use std::sync::Arc;

/// `[[point_light]]`: `position`, and `power` Φ [W] or `intensity` I [W/sr] per channel.
pub static POINT: LightType = LightType {
    name: "point_light",
    describe: "isotropic point light",
    fields: &["position", "power", "intensity"],
    parse: |p| {
        let position = p.required_rgb("position")?;
        // Isotropic: Φ = 4π I.
        let intensity = power_or_intensity(p, 4.0 * std::f32::consts::PI)?;
        Ok(Arc::new(PointLight {
            position,
            intensity,
        }))
    },
    chi2_cases: crate::chi2::no_cases,
};

/// The intensity of a point-shaped light from exactly one of `power` (divided by `solid_angle`,
/// Φ/I for the light's emission profile) and `intensity`, each non-negative.
pub fn power_or_intensity(p: &mut Params, solid_angle: f32) -> Result<Vec3> {
    let (key, value) = match (p.has("power"), p.has("intensity")) {
        (true, false) => ("power", p.required_rgb("power")?),
        (false, true) => ("intensity", p.required_rgb("intensity")?),
        _ => return Err(p.error("", "give exactly one of `power` and `intensity`")),
    };
    if value.min_element() < 0.0 {
        return Err(p.error(key, "must be non-negative"));
    }
    if key == "intensity" {
        return Ok(value);
    }
    if solid_angle <= 0.0 {
        return Err(p.error(
            key,
            "a light with an empty cone has no power to distribute: give `intensity`",
        ));
    }
    Ok(value / solid_angle)
}

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

impl LightSpec for PointLight {
    fn place(&self, _scene_radius: f32) -> Box<dyn Light> {
        Box::new(*self)
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
