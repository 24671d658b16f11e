//! Spherical area light emitting radiance L on both faces.
//! Cone sampling: uniform over the solid angle the sphere subtends (pbrt-v4 `Sphere::Sample`;
//! point placed analytically after Akalin 2015, no ray cast), pdf 1/(2π(1 - cos θmax)) with
//! 1 - cos θmax computed stably. From inside the sphere the cone is undefined and the
//! sampler switches to uniform area sampling over the whole sphere, converted to solid angle.

use super::{LightSample, direction_to};
use crate::math::{Frame, luminance};
use crate::sampling::warp::{
    UNIFORM_SPHERE_PDF, one_minus_cos_from_sin2, sample_uniform_cone, sample_uniform_sphere,
    uniform_cone_pdf,
};
use glam::Vec3;
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug)]
pub struct SphereLight {
    pub center: Vec3,
    pub radius: f32,
    pub radiance: Vec3,
}

impl SphereLight {
    pub fn power(&self) -> f32 {
        // Outward power; the inward face only matters to points inside.
        PI * 4.0 * PI * self.radius * self.radius * luminance(self.radiance)
    }

    pub fn sample_cone(&self, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        let to_c = self.center - p;
        let d2 = to_c.length_squared();
        let r2 = self.radius * self.radius;
        if d2 <= r2 {
            return self.sample_area_inside(p, u);
        }
        let dc = d2.sqrt();
        let sin2_max = r2 / d2;
        let omc_max = one_minus_cos_from_sin2(sin2_max);
        let frame = Frame::from_normal(to_c / dc);
        let local = sample_uniform_cone(u, omc_max);
        // The point on the sphere from the sampled cone angle θ, without a ray cast (Akalin
        // 2015, as in pbrt-v4): α, the angle at the centre between -axis and the point, has
        // cos α = sin²θ/sin θmax + cos θ·sqrt(1 - sin²θ/sin²θmax). A ray cast would lose tiny
        // spheres to f32 error.
        let (cos_t, sin2_t) = (local.z, local.x * local.x + local.y * local.y);
        let sin_max = sin2_max.sqrt();
        let cos_a = sin2_t / sin_max + cos_t * (1.0 - sin2_t / sin2_max).max(0.0).sqrt();
        let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
        let sin_t = sin2_t.sqrt();
        let (cos_phi, sin_phi) = if sin_t > 0.0 {
            (local.x / sin_t, local.y / sin_t)
        } else {
            (1.0, 0.0)
        };
        let normal = frame.to_world(Vec3::new(sin_a * cos_phi, sin_a * sin_phi, -cos_a));
        let point = self.center + normal * self.radius;
        let (wi, _) = direction_to(p, point)?;
        Some(LightSample {
            wi,
            point,
            normal,
            radiance: self.radiance,
            pdf: uniform_cone_pdf(omc_max),
            distant: false,
        })
    }

    /// Solid-angle pdf of [`Self::sample_cone`] for the direction from p to the light point q.
    pub fn pdf_cone(&self, p: Vec3, q: Vec3) -> f32 {
        let to_c = self.center - p;
        let d2 = to_c.length_squared();
        let r2 = self.radius * self.radius;
        if d2 <= r2 {
            return self.pdf_area_inside(p, q);
        }
        let sin2_max = r2 / d2;
        // Cone membership by sin² of the angle to the axis (a cross product), which keeps its
        // precision for tiny cones where 1 - cos would round to 0.
        let wi = (q - p).normalize();
        let axis = to_c / d2.sqrt();
        let inside = wi.dot(axis) > 0.0 && wi.cross(axis).length_squared() <= sin2_max;
        if inside {
            uniform_cone_pdf(one_minus_cos_from_sin2(sin2_max))
        } else {
            0.0
        }
    }

    fn pdf_area_inside(&self, p: Vec3, q: Vec3) -> f32 {
        let d = q - p;
        let dist2 = d.length_squared();
        let cos_l = ((q - self.center) / self.radius).dot(d).abs() / dist2.sqrt();
        if cos_l > 0.0 {
            UNIFORM_SPHERE_PDF / (self.radius * self.radius) * dist2 / cos_l
        } else {
            0.0
        }
    }

    /// Uniform over the whole sphere's area, for points inside it, where every surface point
    /// is visible. pdf_ω = d² / (A |cos θ_l|).
    fn sample_area_inside(&self, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        let n = sample_uniform_sphere(u);
        let point = self.center + n * self.radius;
        let d = point - p;
        let dist2 = d.length_squared();
        if dist2 == 0.0 {
            return None;
        }
        let wi = d / dist2.sqrt();
        let cos_l = n.dot(wi).abs();
        if cos_l == 0.0 {
            return None;
        }
        let area_pdf = UNIFORM_SPHERE_PDF / (self.radius * self.radius);
        // Oriented towards p: from inside, that is the inward normal.
        Some(LightSample {
            wi,
            point,
            normal: -n,
            radiance: self.radiance,
            pdf: area_pdf * dist2 / cos_l,
            distant: false,
        })
    }
}

impl SphereLight {
    fn area(&self) -> f32 {
        4.0 * PI * self.radius * self.radius
    }

    /// Uniform over the whole sphere by area: pdf_ω = d²/(A |cos θ_l|). From outside, a sample
    /// on the far side is hidden by the sphere itself: None (it carries no radiance), so about
    /// half the samples are wasted — the lecture's point about this method.
    pub fn sample_area(&self, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        let outside = (p - self.center).length_squared() > self.radius * self.radius;
        if !outside {
            return self.sample_area_inside(p, u);
        }
        let n = sample_uniform_sphere(u);
        let point = self.center + n * self.radius;
        let (wi, dist2) = direction_to(p, point)?;
        let cos_l = -n.dot(wi);
        if cos_l <= 0.0 {
            return None;
        }
        Some(LightSample {
            wi,
            point,
            normal: n,
            radiance: self.radiance,
            pdf: dist2 / (self.area() * cos_l),
            distant: false,
        })
    }

    /// pdf of [`Self::sample_area`] for light point q (visible from p).
    /// From outside, a point on the far side has pdf 0: the sampler never returns it.
    pub fn pdf_area(&self, p: Vec3, q: Vec3) -> f32 {
        if (p - self.center).length_squared() <= self.radius * self.radius {
            return self.pdf_area_inside(p, q);
        }
        let d = q - p;
        let dist2 = d.length_squared();
        let cos_l = -((q - self.center) / self.radius).dot(d) / dist2.sqrt();
        if cos_l > 0.0 {
            dist2 / (self.area() * cos_l)
        } else {
            0.0
        }
    }

    /// Uniform by area over the cap visible from p: the points whose angle α from the axis
    /// centre→p has cos α ≥ r/d, of area 2πr²(1 - r/d); uniform in cos α by Archimedes'
    /// hat-box theorem. From inside the sphere, uniform over the whole sphere.
    pub fn sample_cap(&self, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        let to_p = p - self.center;
        let dc = to_p.length();
        if dc <= self.radius {
            return self.sample_area_inside(p, u);
        }
        let cap = 1.0 - self.radius / dc; // 1 - cos α_max
        let n = Frame::from_normal(to_p / dc).to_world(sample_uniform_cone(u, cap));
        let point = self.center + n * self.radius;
        let (wi, dist2) = direction_to(p, point)?;
        let cos_l = -n.dot(wi);
        if cos_l <= 0.0 {
            return None; // the cap's rim, tangent to the line of sight (measure zero)
        }
        let cap_area = 2.0 * PI * self.radius * self.radius * cap;
        Some(LightSample {
            wi,
            point,
            normal: n,
            radiance: self.radiance,
            pdf: dist2 / (cap_area * cos_l),
            distant: false,
        })
    }

    /// pdf of [`Self::sample_cap`] for light point q visible from p.
    pub fn pdf_cap(&self, p: Vec3, q: Vec3) -> f32 {
        let to_p = p - self.center;
        let dc = to_p.length();
        if dc <= self.radius {
            return self.pdf_area_inside(p, q);
        }
        let n = (q - self.center) / self.radius;
        let d = q - p;
        let dist2 = d.length_squared();
        let cos_l = -n.dot(d) / dist2.sqrt();
        if cos_l <= 0.0 {
            return 0.0;
        }
        let cap_area = 2.0 * PI * self.radius * self.radius * (1.0 - self.radius / dc);
        dist2 / (cap_area * cos_l)
    }
}
