//! Analytic sphere intersection. A sphere light is traced as the exact sphere its sampler
//! samples, never a tessellation, or light and geometry would disagree.

use super::Ray;
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
}

impl Sphere {
    /// Nearest t in (0, ray.tmax) of a unit-direction ray. The discriminant is computed as
    /// r² - |f - (f·d)d|² and the roots as q/a, c/q (Haines et al., "Precision Improvements for
    /// Ray/Sphere Intersection", Ray Tracing Gems, ch. 7), in f64: for a near-tangent chord,
    /// such as a shadow ray from a point 1e-6 above a unit sphere to a sampled point 1e-3 away,
    /// the discriminant is ~1e-7 and f32 would bury it under the rounding of |perp|² (≈ 1.2e-7),
    /// reporting the light's own surface as an occluder. The inputs are f32, exact in f64.
    pub fn intersect(&self, ray: &Ray) -> Option<f32> {
        let f = ray.origin.as_dvec3() - self.center.as_dvec3();
        let dir = ray.dir.as_dvec3();
        let b = -f.dot(dir);
        let perp = f + dir * b;
        let r = self.radius as f64;
        let r2 = r * r;
        let disc = r2 - perp.length_squared();
        if disc < 0.0 {
            return None;
        }
        let c = f.length_squared() - r2;
        let q = b + b.signum() * disc.sqrt();
        if q == 0.0 {
            return None; // ray origin at the centre of a zero-radius sphere
        }
        let (t0, t1) = {
            let x = c / q;
            if x < q { (x, q) } else { (q, x) }
        };
        let tmax = ray.tmax as f64;
        let t = if t0 > 0.0 && t0 < tmax {
            t0
        } else if t1 > 0.0 && t1 < tmax {
            t1
        } else {
            return None;
        };
        // Rounding to f32 must not carry a hit past tmax or down to 0.
        let t32 = t as f32;
        (t32 > 0.0 && t32 < ray.tmax).then_some(t32)
    }

    /// Outward unit normal at a point on (or near) the surface.
    pub fn normal_at(&self, p: Vec3) -> Vec3 {
        (p - self.center) / self.radius
    }

    /// Projects a point computed from a ray back onto the surface, removing the error in t.
    pub fn project(&self, p: Vec3) -> Vec3 {
        self.center + (p - self.center).normalize() * self.radius
    }

    /// Absolute error bound of a point on the surface computed as centre + r·n̂ (by
    /// [`Self::project`] or a sampler): γ₅ on the reprojected offset (pbrt-v4 §6.8.5), one more
    /// rounding for adding the centre.
    pub fn point_error(&self, p: Vec3) -> Vec3 {
        use crate::math::gamma;
        let local = (p - self.center).abs();
        gamma(6) * local + gamma(1) * self.center.abs()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outside_inside_and_far_small_spheres() {
        let s = Sphere {
            center: Vec3::new(0.0, 0.0, -5.0),
            radius: 1.0,
        };
        let ray = Ray::new(Vec3::ZERO, -Vec3::Z, f32::INFINITY);
        assert!((s.intersect(&ray).unwrap() - 4.0).abs() < 1e-5);
        let inside = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::X, f32::INFINITY);
        assert!((s.intersect(&inside).unwrap() - 1.0).abs() < 1e-6);
        let behind = Ray::new(Vec3::ZERO, Vec3::Z, f32::INFINITY);
        assert!(s.intersect(&behind).is_none());
        // A 1e-3 sphere at distance 1e4: the textbook quadratic loses it entirely in f32.
        let tiny = Sphere {
            center: Vec3::new(0.0, 0.0, -1e4),
            radius: 1e-3,
        };
        let t = tiny.intersect(&ray).expect("tiny far sphere must be hit");
        assert!((t - (1e4 - 1e-3)).abs() / 1e4 < 1e-6);
    }
}
