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
    /// Ray/Sphere Intersection", Ray Tracing Gems, ch. 7), which stays accurate for small
    /// spheres far from the ray origin, where the textbook b² - 4ac cancels.
    pub fn intersect(&self, ray: &Ray) -> Option<f32> {
        let f = ray.origin - self.center;
        let b = -f.dot(ray.dir);
        let perp = f + ray.dir * b;
        let r2 = self.radius * self.radius;
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
        if t0 > 0.0 && t0 < ray.tmax {
            Some(t0)
        } else if t1 > 0.0 && t1 < ray.tmax {
            Some(t1)
        } else {
            None
        }
    }

    /// Outward unit normal at a point on (or near) the surface.
    pub fn normal_at(&self, p: Vec3) -> Vec3 {
        (p - self.center) / self.radius
    }

    /// Projects a point computed from a ray back onto the surface, removing the error in t.
    pub fn project(&self, p: Vec3) -> Vec3 {
        self.center + (p - self.center).normalize() * self.radius
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
