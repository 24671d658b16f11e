//! Spot light with a falloff linear in angle, as Mitsuba 3's `spot` emitter has it:
//! I(θ) = I₀ for θ ≤ θs (the beam), I₀ (θe − θ)/(θe − θs) for θs < θ < θe, zero beyond the
//! cutoff θe. dibench's `spot_light` falls off by a smoothstep in cos θ (pbrt-v4); this type
//! lets a scene match Mitsuba's convention exactly. It is also the worked example of a light
//! type added in one file (docs/extending.md (e)): it reuses the point shape's delta sampling.

use super::bounds::{Bounds, LightBounds};
use super::point::PointLight;
use super::{Light, LightCtx, LightHit, LightMethods, LightSample, LightShape, LightSpec, LightType};
use crate::math::luminance;
use glam::Vec3;
use std::sync::Arc;

/// `[[linear_spot_light]]`: the fields of `spot_light` (`falloff_start_deg` is Mitsuba's
/// `beam_width`, `cone_angle_deg` its `cutoff_angle`).
pub static LINEAR_SPOT: LightType = LightType {
    name: "linear_spot_light",
    describe: "point light in a cone, falloff linear in angle (Mitsuba 3's spot)",
    fields: super::spot::SPOT.fields,
    parse: |p| {
        let (cone, start) = super::spot::parse_cone(p)?;
        let (theta_cone, theta_start) = (cone.to_radians(), start.to_radians());
        let solid = solid_angle(theta_start, theta_cone) as f32;
        let intensity = super::point::power_or_intensity(p, solid)?;
        Ok(Arc::new(LinearSpotLight {
            position: p.required_rgb("position")?,
            axis: p.direction("direction")?,
            intensity,
            theta_cone,
            theta_start,
        }))
    },
    chi2_cases: crate::chi2::no_cases,
};

/// Φ/I₀ = 2π [∫₀^θs sin θ dθ + ∫_θs^θe (θe − θ)/(θe − θs) sin θ dθ], in f64, each part
/// in a form without cancellation: 1 − cos θs = 2 sin²(θs/2), and with Δ = θe − θs the
/// band's integral is [cos θs (Δ − sin Δ) + sin θs (1 − cos Δ)] / Δ (zero for Δ = 0).
pub fn solid_angle(theta_start: f32, theta_cone: f32) -> f64 {
    let (s, e) = (theta_start as f64, theta_cone as f64);
    let core = 2.0 * (0.5 * s).sin().powi(2);
    let delta = e - s;
    let band = if delta > 0.0 {
        // Δ − sin Δ by its series where the difference would cancel.
        let d_minus_sin = if delta < 1e-2 {
            let d2 = delta * delta;
            delta * d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0))
        } else {
            delta - delta.sin()
        };
        (s.cos() * d_minus_sin + s.sin() * 2.0 * (0.5 * delta).sin().powi(2)) / delta
    } else {
        0.0
    };
    2.0 * std::f64::consts::PI * (core + band)
}


#[derive(Clone, Copy, Debug)]
pub struct LinearSpotLight {
    pub position: Vec3,
    /// Unit axis.
    pub axis: Vec3,
    /// On-axis intensity I₀ [W/sr].
    pub intensity: Vec3,
    /// The cutoff θe and the beam θs ≤ θe, radians.
    pub theta_cone: f32,
    pub theta_start: f32,
}

impl LinearSpotLight {
    /// The falloff at angle θ from the axis.
    pub fn falloff(&self, theta: f32) -> f32 {
        if theta <= self.theta_start {
            // θs = θe: a hard edge (only the axis when both are zero).
            return if theta <= self.theta_cone { 1.0 } else { 0.0 };
        }
        if theta >= self.theta_cone {
            return 0.0;
        }
        (self.theta_cone - theta) / (self.theta_cone - self.theta_start)
    }

    /// The angle between unit vectors a and b by atan2 of sine and cosine, accurate near 0
    /// where acos(cos θ) loses half its digits.
    fn angle(a: Vec3, b: Vec3) -> f32 {
        a.cross(b).length().atan2(a.dot(b))
    }

    /// Φ/I₀ of this light ([`solid_angle`]).
    pub fn solid_angle(&self) -> f64 {
        solid_angle(self.theta_start, self.theta_cone)
    }

    /// The point light's sample, scaled by the falloff at its direction.
    pub fn sample_from(&self, p: Vec3) -> Option<LightSample> {
        let point = PointLight {
            position: self.position,
            intensity: self.intensity,
        };
        let mut s = point.sample_from(p)?;
        let falloff = self.falloff(Self::angle(-s.wi, self.axis));
        if falloff == 0.0 {
            return None;
        }
        s.radiance *= falloff;
        Some(s)
    }
}

impl LightSpec for LinearSpotLight {
    fn place(&self, _scene_radius: f32) -> Box<dyn Light> {
        Box::new(*self)
    }
}

impl Light for LinearSpotLight {
    fn shape(&self) -> LightShape {
        LightShape::Point
    }

    fn power(&self) -> f32 {
        (self.solid_angle() * luminance(self.intensity) as f64) as f32
    }

    /// Full intensity within θs of the axis, falling off over θe − θs beyond it (as
    /// `spot_light`'s bounds); the angles widened by a few ulps of the f32 angle `falloff` is
    /// called with.
    fn bounds(&self) -> Bounds {
        let widen = |x: f32| (x + 4.0 * f32::EPSILON).min(std::f32::consts::PI);
        Bounds::Local(LightBounds {
            axis: self.axis,
            theta_o: widen(self.theta_start),
            theta_e: widen((self.theta_cone - self.theta_start).max(0.0)),
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

#[cfg(test)]
mod tests {
    use super::*;

    fn spot(start_deg: f32, cone_deg: f32) -> LinearSpotLight {
        LinearSpotLight {
            position: Vec3::ZERO,
            axis: Vec3::Z,
            intensity: Vec3::ONE,
            theta_cone: cone_deg.to_radians(),
            theta_start: start_deg.to_radians(),
        }
    }

    /// Φ/I₀ against a midpoint-rule integral of 2π ∫ falloff(θ) sin θ dθ, from a hard edge
    /// to a wide band, down to cones of a few arc seconds (where 1 − cos θ in f32 would lose
    /// every digit).
    #[test]
    fn solid_angle_matches_quadrature() {
        for (s, e) in [
            (20.0, 20.0),
            (15.0, 20.0),
            (0.0, 90.0),
            (30.0, 180.0),
            (0.0, 0.001),
            (0.0005, 0.001),
            (179.0, 180.0),
        ] {
            let l = spot(s, e);
            let (ts, te) = (l.theta_start as f64, l.theta_cone as f64);
            let n = 200_000;
            // 1 − cos θs as the identity 2 sin²(θs/2): f64's 1 − cos has no digits left at
            // arc seconds, and the core is not what this test is for.
            let core = 2.0 * std::f64::consts::PI * 2.0 * (0.5 * ts).sin().powi(2);
            let mut band = 0.0;
            for i in 0..n * (te > ts) as usize {
                let t = ts + (te - ts) * (i as f64 + 0.5) / n as f64;
                band += (te - t) / (te - ts) * t.sin();
            }
            if te > ts {
                band *= 2.0 * std::f64::consts::PI * (te - ts) / n as f64;
            }
            let expected = core + band;
            let got = l.solid_angle();
            assert!(
                (got - expected).abs() <= 1e-7 * expected,
                "θs {s}°, θe {e}°: {got} vs {expected}"
            );
        }
    }

    /// The falloff is 1 in the beam, linear in angle across the band (½ at its middle), zero
    /// beyond the cutoff; and the angle is right to f32 precision for directions a few arc
    /// seconds off the axis.
    #[test]
    fn falloff_is_linear_in_angle() {
        let l = spot(10.0, 30.0);
        let at = |deg: f32| {
            let t = deg.to_radians();
            let to_p = Vec3::new(t.sin(), 0.0, t.cos());
            l.sample_from(to_p * 2.0).map_or(0.0, |s| s.radiance.x * 4.0)
        };
        assert_eq!(at(5.0), 1.0);
        assert!((at(20.0) - 0.5).abs() < 1e-5, "{}", at(20.0));
        assert!((at(25.0) - 0.25).abs() < 1e-5, "{}", at(25.0));
        assert_eq!(at(31.0), 0.0);
        let narrow = spot(0.0, 0.002);
        let t = 0.001f32.to_radians();
        let w = Vec3::new(t.sin(), 0.0, t.cos());
        let f = narrow.falloff(LinearSpotLight::angle(w, Vec3::Z));
        assert!((f - 0.5).abs() < 1e-3, "{f}");
    }

    /// The bounds hold every direction that receives light: along the whole band, the angle
    /// to the axis is within θo + θe.
    #[test]
    fn bounds_cover_the_lit_cone() {
        for (s, e) in [(10.0, 30.0), (0.0, 0.01), (45.0, 45.0)] {
            let l = spot(s, e);
            let Bounds::Local(b) = l.bounds() else {
                panic!("a spot is local")
            };
            for k in 0..=1000 {
                let t = l.theta_cone * k as f32 / 1000.0;
                let w = Vec3::new(t.sin(), 0.0, t.cos());
                let theta = LinearSpotLight::angle(w, Vec3::Z);
                if l.falloff(theta) > 0.0 {
                    assert!(theta <= b.theta_o + b.theta_e, "θ {theta} beyond the bounds");
                }
            }
        }
    }
}
