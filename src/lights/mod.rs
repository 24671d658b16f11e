//! Light sources with their samplers and pdfs side by side, one file per light type.
//! Every sampler returns its pdf in solid angle at the shading point, the measure of the
//! direct-illumination integral, or reports a delta light.

pub mod directional;
pub mod environment;
pub mod mesh;
pub mod point;
pub mod quad;
pub mod sphere;
pub mod spot;

use crate::env::EnvMethod;
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
    /// Absolute per-axis error bound of `point`, to offset the shadow ray's far end by.
    pub point_error: Vec3,
    /// Incident radiance along -wi; for a delta light, the irradiance at normal incidence I/d².
    pub radiance: Vec3,
    /// Solid-angle pdf; 1 for a delta light.
    pub pdf: f32,
    /// A light at infinity (directional): the shadow ray is unbounded and `point` unused.
    pub distant: bool,
}

/// Unit direction and squared distance from p to a sampled light point q; None when q is p
/// itself (a shading point on the light's own surface can draw its own position: a
/// measure-zero event that carries no light, and would otherwise divide zero by zero).
pub fn direction_to(p: Vec3, q: Vec3) -> Option<(Vec3, f32)> {
    let d = q - p;
    let d2 = d.length_squared();
    (d2 > 0.0).then(|| (d / d2.sqrt(), d2))
}

/// How quads are sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum QuadMethod {
    /// Uniform by area.
    Area,
    /// Uniform in solid angle (spherical rectangle, Ureña et al. 2013).
    SolidAngle,
}

/// How spheres are sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SphereMethod {
    /// Uniform by area over the whole sphere (back-facing samples count as misses).
    Area,
    /// Uniform by area over the cap visible from the shading point.
    Cap,
    /// Uniform in the cone of directions the sphere subtends.
    Cone,
}

/// How emissive meshes are sampled, after a triangle is chosen in proportion to its area.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshMethod {
    /// Uniform by area on the triangle.
    Area,
    /// Uniform in the triangle's solid angle (spherical triangle, Arvo 1995).
    SolidAngle,
}

/// The sampler used for each kind of area light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LightMethods {
    pub quad: QuadMethod,
    pub sphere: SphereMethod,
    pub mesh: MeshMethod,
    pub env: EnvMethod,
}

impl LightMethods {
    /// The lecture's baseline: area sampling for quads and meshes, the cone for spheres.
    pub const BASIC: LightMethods = LightMethods {
        quad: QuadMethod::Area,
        sphere: SphereMethod::Cone,
        mesh: MeshMethod::Area,
        env: EnvMethod::LATLONG_CDF,
    };
    /// The lowest-variance sampler of each kind: solid angle everywhere.
    pub const SOLID_ANGLE: LightMethods = LightMethods {
        quad: QuadMethod::SolidAngle,
        sphere: SphereMethod::Cone,
        mesh: MeshMethod::SolidAngle,
        env: EnvMethod::LATLONG_CDF,
    };
}

impl LightSample {
    /// The unoccluded-test segment from a shading point (already offset) to the sample, with the
    /// light end offset off the light's own surface so the light does not shadow itself.
    pub fn shadow_ray(&self, origin: Vec3) -> Option<Ray> {
        if self.distant {
            // Unbounded, along the light's direction. (Until the stress suite's exact shading
            // points exposed it, this fell through to a segment towards `point` = the world
            // origin: directional shadows were tested against the wrong segment.)
            return Some(Ray::new(origin, self.wi, f32::INFINITY));
        }
        // The far end steps off the light's surface towards the shading point, past its own
        // error box (pbrt-v4 `SpawnRayTo`).
        let towards = if self.normal.dot(origin - self.point) >= 0.0 {
            self.normal
        } else {
            -self.normal
        };
        let target = offset_ray_origin(self.point, self.point_error, towards);
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
    Spot(spot::SpotLight),
    Directional(directional::DirectionalLight),
    Quad(quad::QuadLight),
    Sphere(sphere::SphereLight),
    Mesh(mesh::MeshLight),
    Environment(environment::EnvironmentLight),
}

impl Light {
    /// Radiant power [W], luminance-weighted, for power-proportional light selection.
    pub fn power(&self) -> f32 {
        match self {
            Light::Point(l) => l.power(),
            Light::Spot(l) => l.power(),
            Light::Directional(l) => l.power(),
            Light::Quad(l) => l.power(),
            Light::Sphere(l) => l.power(),
            Light::Mesh(l) => l.power(),
            Light::Environment(l) => l.power(),
        }
    }

    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Light::Point(_) | Light::Spot(_) | Light::Directional(_)
        )
    }

    /// A sample of this light seen from p, by the method `m` selects for its kind.
    pub fn sample(&self, p: Vec3, u: [f32; 3], m: &LightMethods) -> Option<LightSample> {
        let u2 = [u[0], u[1]];
        match self {
            Light::Point(l) => l.sample(p),
            Light::Spot(l) => l.sample(p),
            Light::Directional(l) => Some(l.sample()),
            Light::Quad(l) => match m.quad {
                QuadMethod::Area => l.sample_area(p, u2),
                QuadMethod::SolidAngle => l.sample_solid_angle(p, u2),
            },
            Light::Sphere(l) => match m.sphere {
                SphereMethod::Area => l.sample_area(p, u2),
                SphereMethod::Cap => l.sample_cap(p, u2),
                SphereMethod::Cone => l.sample_cone(p, u2),
            },
            Light::Mesh(l) => match m.mesh {
                MeshMethod::Area => l.sample_area(p, u),
                MeshMethod::SolidAngle => l.sample_solid_angle(p, u),
            },
            Light::Environment(l) => l.sample(u2, m.env),
        }
    }

    /// Solid-angle pdf with which [`Self::sample`] (same method) produces the direction from p
    /// to the point q on this light (triangle `local` for a mesh). 0 for delta lights: no
    /// direction found by another strategy can reach them; 0 for the environment, which has
    /// no points (its pdf is by direction: `EnvironmentLight::pdf`).
    pub fn pdf(&self, p: Vec3, q: Vec3, local: u32, m: &LightMethods) -> f32 {
        match self {
            Light::Point(_) | Light::Spot(_) | Light::Directional(_) | Light::Environment(_) => 0.0,
            Light::Quad(l) => match m.quad {
                QuadMethod::Area => l.pdf_area(p, q),
                QuadMethod::SolidAngle => l.pdf_solid_angle(p, q),
            },
            Light::Sphere(l) => match m.sphere {
                SphereMethod::Area => l.pdf_area(p, q),
                SphereMethod::Cap => l.pdf_cap(p, q),
                SphereMethod::Cone => l.pdf_cone(p, q),
            },
            Light::Mesh(l) => match m.mesh {
                MeshMethod::Area => l.pdf_area(p, q, local as usize),
                MeshMethod::SolidAngle => l.pdf_solid_angle(p, q, local as usize),
            },
        }
    }

    /// Radiance leaving the light at a point with outward geometric normal `n` towards
    /// direction `w` (unit, pointing away from the light): one-sided for quads and meshes,
    /// two-sided for spheres (see docs/conventions.md).
    pub fn emitted(&self, n: Vec3, w: Vec3) -> Vec3 {
        match self {
            Light::Point(_) | Light::Spot(_) | Light::Directional(_) | Light::Environment(_) => {
                Vec3::ZERO
            }
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
