//! Spot light: a point light whose intensity falls off with the angle θ to its axis,
//! I(θ) = I₀ · smoothstep(cos θe, cos θs, cos θ) — full inside the falloff-start cone θs, zero
//! outside the cone θe, Hermite smoothstep in cos θ between (pbrt-v4 `SpotLight::I`). With
//! θs = θe the edge is hard.

use super::bounds::{Bounds, LightBounds};
use super::{Light, LightCtx, LightHit, LightMethods, LightSample, LightShape, direction_to};
use crate::math::luminance;
use glam::Vec3;

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

impl Light for SpotLight {
    fn shape(&self) -> LightShape {
        LightShape::Point
    }

    /// Φ = 2π I₀ [(1 - cos θs) + (cos θs - cos θe)/2]: the smoothstep integrates to half its
    /// interval.
    fn power(&self) -> f32 {
        2.0 * std::f32::consts::PI
            * ((1.0 - self.cos_falloff_start) + 0.5 * (self.cos_falloff_start - self.cos_cone))
            * luminance(self.intensity)
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
