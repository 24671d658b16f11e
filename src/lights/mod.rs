//! Light sources with their samplers and pdfs side by side, one file per light type.
//! Every sampler returns its pdf in solid angle at the shading point, the measure of the
//! direct-illumination integral, or reports a delta light.

pub mod mesh;
pub mod point;
pub mod quad;
pub mod sphere;

use crate::geometry::Ray;
use crate::math::offset_ray_origin;
use glam::Vec3;

/// One sample of incident light at a shading point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the shading point to the light point.
    pub wi: Vec3,
    /// The sampled point on the light and the light's normal there, oriented towards the
    /// shading point (zero for a point light).
    pub point: Vec3,
    pub normal: Vec3,
    /// Incident radiance along -wi; for a delta light, the irradiance at normal incidence I/d².
    pub radiance: Vec3,
    /// Solid-angle pdf; 1 for a delta light.
    pub pdf: f32,
}

impl LightSample {
    /// The unoccluded-test segment from a shading point (already offset) to the sample, with the
    /// light end offset off the light's own surface so the light does not shadow itself.
    pub fn shadow_ray(&self, origin: Vec3) -> Option<Ray> {
        let target = if self.normal == Vec3::ZERO {
            self.point
        } else {
            offset_ray_origin(self.point, self.normal)
        };
        let d = target - origin;
        let dist = d.length();
        if dist == 0.0 {
            return None;
        }
        // pbrt-v4's ShadowEpsilon: stop just short of the (offset) light point.
        Some(Ray::new(origin, d / dist, dist * (1.0 - 1e-4)))
    }
}

#[derive(Clone, Debug)]
pub enum Light {
    Point(point::PointLight),
    Quad(quad::QuadLight),
    Sphere(sphere::SphereLight),
    Mesh(mesh::MeshLight),
}

impl Light {
    /// Radiant power [W], luminance-weighted, for power-proportional light selection.
    pub fn power(&self) -> f32 {
        match self {
            Light::Point(l) => l.power(),
            Light::Quad(l) => l.power(),
            Light::Sphere(l) => l.power(),
            Light::Mesh(l) => l.power(),
        }
    }

    pub fn is_delta(&self) -> bool {
        matches!(self, Light::Point(_))
    }

    /// Each light's default sampler: area form for quads and meshes, the uniform cone for
    /// spheres.
    pub fn sample(&self, p: Vec3, u: [f32; 3]) -> Option<LightSample> {
        match self {
            Light::Point(l) => l.sample(p),
            Light::Quad(l) => l.sample_area(p, [u[0], u[1]]),
            Light::Sphere(l) => l.sample_cone(p, [u[0], u[1]]),
            Light::Mesh(l) => l.sample_area(p, u),
        }
    }

    /// Radiance leaving the light at a point with outward geometric normal `n` towards
    /// direction `w` (unit, pointing away from the light): one-sided for quads and meshes,
    /// two-sided for spheres (see docs/conventions.md).
    pub fn emitted(&self, n: Vec3, w: Vec3) -> Vec3 {
        match self {
            Light::Point(_) => Vec3::ZERO,
            Light::Quad(l) => {
                if n.dot(w) > 0.0 {
                    l.radiance
                } else {
                    Vec3::ZERO
                }
            }
            Light::Mesh(l) => {
                if n.dot(w) > 0.0 {
                    l.radiance
                } else {
                    Vec3::ZERO
                }
            }
            Light::Sphere(l) => l.radiance,
        }
    }
}
