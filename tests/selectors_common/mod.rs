//! Light sets for the selector tests: every light type at random places, sizes, orientations
//! and radiances, each kept beside a description that can decide in f64 whether it can light
//! a given point (the truth "no contributing light gets pmf 0" is checked against).
#![allow(dead_code)]

use dibench::env::Environment;
use dibench::geometry::triangle::Triangle;
use dibench::lights::directional::DirectionalLight;
use dibench::lights::environment::EnvironmentLight;
use dibench::lights::mesh::TriangleLight;
use dibench::lights::point::PointLight;
use dibench::lights::quad::QuadLight;
use dibench::lights::selector::{LightSelector, SELECTORS};
use dibench::lights::sphere::SphereLight;
use dibench::lights::spot::SpotLight;
use dibench::lights::{Light, LightCtx};
use dibench::math::Frame;
use dibench::sampling::stream::SampleStream;
use dibench::sampling::warp::sample_uniform_sphere;
use glam::{DVec3, Vec3};
use std::sync::Arc;

pub struct Rng(SampleStream);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(SampleStream::new(seed, 0x5e1ec7, 0, 0))
    }
    pub fn f(&mut self) -> f32 {
        self.0.next_1d()
    }
    pub fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f()
    }
    /// Log-uniform in [a, b].
    pub fn log(&mut self, a: f32, b: f32) -> f32 {
        (a.ln() + (b.ln() - a.ln()) * self.f()).exp()
    }
    pub fn dir(&mut self) -> Vec3 {
        sample_uniform_sphere(self.0.next_2d())
    }
    pub fn point(&mut self, half: f32) -> Vec3 {
        Vec3::new(
            self.range(-half, half),
            self.range(-half, half),
            self.range(-half, half),
        )
    }
    pub fn u64(&mut self) -> f64 {
        dibench::lights::selection_number(self.f(), self.f())
    }
}

/// A light as generated, with what it takes to decide whether it can light a point.
#[derive(Clone, Debug)]
pub enum Spec {
    Quad(QuadLight),
    Triangle(TriangleLight),
    Sphere(SphereLight),
    Point(PointLight),
    Spot(SpotLight),
    Directional(DirectionalLight),
    /// A constant environment of this radiance, and the scene radius its power is taken over.
    Environment(Vec3, f32),
}

impl Spec {
    pub fn light(&self) -> Box<dyn Light> {
        match self {
            Spec::Quad(l) => Box::new(*l),
            Spec::Triangle(l) => Box::new(*l),
            Spec::Sphere(l) => Box::new(*l),
            Spec::Point(l) => Box::new(*l),
            Spec::Spot(l) => Box::new(*l),
            Spec::Directional(l) => Box::new(*l),
            Spec::Environment(c, scene_radius) => {
                let c = *c;
                Box::new(EnvironmentLight {
                    env: Arc::new(Environment::build_with(&move |_| c, [16, 8, 16, 8])),
                    scene_radius: *scene_radius,
                })
            }
        }
    }

    /// Whether the light sends light into the open hemisphere about `n` at p (n = 0: any
    /// direction), decided in f64 from the f32 description. Directional lights use the f32
    /// dot product the estimator itself tests the horizon with.
    pub fn contributes(&self, p: Vec3, n: Vec3) -> bool {
        let (pd, nd) = (p.as_dvec3(), n.as_dvec3());
        let above = |x: DVec3| n == Vec3::ZERO || (x - pd).dot(nd) > 0.0;
        match self {
            Spec::Quad(q) => {
                let c = q.corner.as_dvec3();
                let (u, v) = (q.edge_u.as_dvec3(), q.edge_v.as_dvec3());
                let front = (pd - c).dot(u.cross(v)) > 0.0;
                front && [c, c + u, c + v, c + u + v].into_iter().any(above)
            }
            Spec::Triangle(t) => {
                let tr = &t.triangle;
                let (a, b, c) = (tr.v0.as_dvec3(), tr.v1.as_dvec3(), tr.v2.as_dvec3());
                let front = (pd - a).dot((b - a).cross(c - a)) > 0.0;
                front && [a, b, c].into_iter().any(above)
            }
            Spec::Sphere(s) => {
                let c = s.center.as_dvec3();
                let r = s.radius as f64;
                if (c - pd).length_squared() <= r * r || n == Vec3::ZERO {
                    return true;
                }
                (c - pd).dot(nd) + r * nd.length() > 0.0
            }
            Spec::Point(l) => {
                let x = l.position.as_dvec3();
                x != pd && above(x)
            }
            Spec::Spot(s) => {
                let x = s.position.as_dvec3();
                if x == pd || !above(x) {
                    return false;
                }
                let cos = (pd - x).normalize().dot(s.axis.as_dvec3());
                cos > s.cos_cone as f64
            }
            Spec::Directional(d) => n == Vec3::ZERO || n.dot(d.to_light) > 0.0,
            Spec::Environment(c, _) => c.max_element() > 0.0,
        }
    }
}

/// A rectangle of sides a, b about `center` whose emitting side faces `normal`.
pub fn quad(center: Vec3, normal: Vec3, a: f32, b: f32, radiance: Vec3) -> QuadLight {
    let f = Frame::from_normal(normal);
    let (eu, ev) = (f.to_world(Vec3::X) * a, f.to_world(Vec3::Y) * b);
    let (eu, ev) = if eu.cross(ev).dot(normal) > 0.0 {
        (eu, ev)
    } else {
        (ev, eu)
    };
    QuadLight::new(center - 0.5 * (eu + ev), eu, ev, radiance)
}

/// `n` lights of every local kind (and with `distant`, two directional lights and a constant
/// environment) in a cube of half-side 5, with sizes and radiances over two decades, spots
/// with hard, narrow, ordinary and wider-than-hemisphere cones.
pub fn mixed(seed: u64, n: usize, distant: bool) -> Vec<Spec> {
    let mut r = Rng::new(seed);
    let mut v = Vec::new();
    for k in 0..n {
        let c = r.point(5.0);
        let radiance = Vec3::new(r.log(0.1, 10.0), r.log(0.1, 10.0), r.log(0.1, 10.0));
        let size = r.log(0.05, 2.0);
        v.push(match k % 6 {
            0 => Spec::Quad(quad(c, r.dir(), size, size * r.range(0.2, 1.0), radiance)),
            1 => {
                let t = Triangle::new(c + r.dir() * size, c + r.dir() * size, c + r.dir() * size);
                match TriangleLight::new(t, radiance) {
                    Some(t) => Spec::Triangle(t),
                    None => continue,
                }
            }
            2 => Spec::Sphere(SphereLight {
                center: c,
                radius: 0.3 * size,
                radiance,
            }),
            3 => Spec::Point(PointLight {
                position: c,
                intensity: radiance,
            }),
            4 => {
                let (cone, start): (f32, f32) = match (k / 6) % 4 {
                    0 => (20.0, 20.0),
                    1 => (0.5, 0.2),
                    2 => (40.0, 10.0),
                    _ => (170.0, 90.0),
                };
                Spec::Spot(SpotLight {
                    position: c,
                    axis: r.dir(),
                    intensity: radiance,
                    cos_cone: cone.to_radians().cos(),
                    cos_falloff_start: start.to_radians().cos(),
                })
            }
            _ => Spec::Quad(quad(c, r.dir(), 0.01 * size, 0.01 * size, radiance * 100.0)),
        });
    }
    if distant {
        for d in [Vec3::new(0.3, 1.0, 0.2), Vec3::new(-0.5, 0.4, -0.7)] {
            v.push(Spec::Directional(DirectionalLight {
                to_light: d.normalize(),
                irradiance: Vec3::new(0.5, 0.4, 0.3),
                scene_radius: 10.0,
            }));
        }
        v.push(Spec::Environment(Vec3::new(0.02, 0.03, 0.05), 10.0));
    }
    v
}

pub fn lights(specs: &[Spec]) -> Vec<Box<dyn Light>> {
    specs.iter().map(Spec::light).collect()
}

/// Every registered selector over `lights`, by name.
pub fn selectors(lights: &[Box<dyn Light>]) -> Vec<(&'static str, Box<dyn LightSelector>)> {
    SELECTORS
        .iter()
        .map(|s| (s.name, (s.build)(lights).unwrap()))
        .collect()
}

/// Shading points in the cube, a tenth of them without orientation.
pub fn contexts(seed: u64, count: usize) -> Vec<LightCtx> {
    let mut r = Rng::new(seed);
    (0..count)
        .map(|k| LightCtx {
            p: r.point(6.0),
            n: if k % 10 == 0 { Vec3::ZERO } else { r.dir() },
        })
        .collect()
}
