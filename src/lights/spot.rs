//! Spot light: a point light whose intensity falls off with the angle θ to its axis,
//! I(θ) = I₀ · smoothstep(cos θe, cos θs, cos θ) — full inside the falloff-start cone θs, zero
//! outside the cone θe, Hermite smoothstep in cos θ between (pbrt-v4 `SpotLight::I`). With
//! θs = θe the edge is hard.

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

/// `[[spot_light]]`: `position`, `direction` (the axis), `cone_angle_deg` θe in [0, 180],
/// `falloff_start_deg` θs in [0, θe] (default θe: a hard edge), and `power` or on-axis
/// `intensity`.
pub static SPOT: LightType = LightType {
    name: "spot_light",
    describe: "point light in a cone, smoothstep falloff in cos θ (pbrt-v4)",
    fields: &[
        "position",
        "direction",
        "cone_angle_deg",
        "falloff_start_deg",
        "power",
        "intensity",
    ],
    parse: |p| {
        let (cone, start) = parse_cone(p)?;
        let (cos_cone, cos_falloff_start) = (cone.to_radians().cos(), start.to_radians().cos());
        let intensity =
            super::point::power_or_intensity(p, solid_angle(cos_cone, cos_falloff_start))?;
        Ok(Arc::new(SpotLight {
            position: p.required_rgb("position")?,
            axis: p.direction("direction")?,
            intensity,
            cos_cone,
            cos_falloff_start,
        }))
    },
    chi2_cases: crate::chi2::no_cases,
};

/// `cone_angle_deg` in [0, 180] and `falloff_start_deg` in [0, cone] (default: the cone), in
/// degrees; shared by the spot types.
pub fn parse_cone(p: &mut Params) -> Result<(f32, f32)> {
    let cone = p.required_number("cone_angle_deg")?;
    if !(0.0..=180.0).contains(&cone) {
        return Err(p.error(
            "cone_angle_deg",
            format!("must be in [0, 180], got {cone}"),
        ));
    }
    let start = p.number("falloff_start_deg")?.unwrap_or(cone);
    if !(0.0..=cone).contains(&start) {
        return Err(p.error(
            "falloff_start_deg",
            format!("must be in [0, cone_angle_deg = {cone}], got {start}"),
        ));
    }
    Ok((cone, start))
}

/// Φ/I₀ of a smoothstep spot (pbrt-v4 `SpotLight::Phi`): 2π [(1 − cos θs) + (cos θs − cos θe)/2],
/// the smoothstep integrating to half its interval.
fn solid_angle(cos_cone: f32, cos_falloff_start: f32) -> f32 {
    2.0 * std::f32::consts::PI * ((1.0 - cos_falloff_start) + 0.5 * (cos_falloff_start - cos_cone))
}

#[derive(Clone, Copy, Debug)]
pub struct SpotLight {
    pub position: Vec3,
    pub axis: Vec3,
    pub intensity: Vec3,
    pub cos_cone: f32,
    pub cos_falloff_start: f32,
}

impl SpotLight {
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        if cos_theta >= self.cos_falloff_start {
            return if cos_theta >= self.cos_cone { 1.0 } else { 0.0 }; // θs = θe = 0: only the axis
        }
        if cos_theta <= self.cos_cone {
            return 0.0;
        }
        let t = (cos_theta - self.cos_cone) / (self.cos_falloff_start - self.cos_cone);
        t * t * (3.0 - 2.0 * t)
    }

    pub fn sample_from(&self, p: Vec3) -> Option<LightSample> {
        let (wi, d2) = direction_to(p, self.position)?;
        let falloff = self.falloff(-wi.dot(self.axis));
        if falloff == 0.0 {
            return None;
        }
        Some(LightSample {
            wi,
            point: self.position,
            normal: Vec3::ZERO,
            point_error: Vec3::ZERO,
            radiance: self.intensity * (falloff / d2),
            pdf: 1.0,
            distant: false,
        })
    }
}

impl LightSpec for SpotLight {
    fn place(&self, _scene_radius: f32) -> Box<dyn Light> {
        Box::new(*self)
    }
}

impl Light for SpotLight {
    fn shape(&self) -> LightShape {
        LightShape::Point
    }

    /// Φ = 2π I₀ [(1 - cos θs) + (cos θs - cos θe)/2]: the smoothstep integrates to half its
    /// interval.
    fn power(&self) -> f32 {
        solid_angle(self.cos_cone, self.cos_falloff_start) * luminance(self.intensity)
    }

    /// Full intensity within θs of the axis (the normal cone), falling off over θc − θs
    /// beyond it (pbrt-v4 `SpotLight::Bounds`). The angles are those of the stored f32
    /// cosines widened by the rounding of the f32 cosine `falloff` is called with (a few ulps
    /// near 1, up to 5e-4 rad for a cone of a few arc seconds), and rounded up.
    fn bounds(&self) -> Bounds {
        let widen = |c: f32| ((c as f64 - 4.0 * f32::EPSILON as f64).max(-1.0)).acos();
        let (theta_s, theta_c) = (widen(self.cos_falloff_start), widen(self.cos_cone));
        let up = |x: f64| (x as f32).next_up().min(std::f32::consts::PI);
        Bounds::Local(LightBounds {
            axis: self.axis,
            theta_o: up(theta_s),
            theta_e: up((theta_c - theta_s).max(0.0)),
            ..LightBounds::point(self.position, luminance(self.intensity))
        })
    }

    fn sample(&self, ctx: &LightCtx, _u: [f32; 3], _m: &LightMethods) -> Option<LightSample> {
        self.sample_from(ctx.p)
    }

    /// A delta light: no sampled direction reaches it.
    fn pdf(&self, _ctx: &LightCtx, _at: LightHit, _m: &LightMethods) -> f32 {
        0.0
    }
}
