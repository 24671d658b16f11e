//! Scene → what the renderer needs, and only that: the triangles and spheres the tracer
//! intersects, per-primitive materials, and light structures only for the lights present.

use crate::bsdf::Bsdf;
use crate::env::{Environment, Repr};
use crate::geometry::sphere::Sphere;
use crate::geometry::triangle::Triangle;
use crate::geometry::{Hit, Ray};
use crate::lights::directional::DirectionalLight;
use crate::lights::environment::EnvironmentLight;
use crate::lights::mesh::MeshLight;
use crate::lights::point::PointLight;
use crate::lights::quad::QuadLight;
use crate::lights::sphere::SphereLight;
use crate::lights::spot::SpotLight;
use crate::lights::{Light, LightMethods, LightSample, QuadMethod};
use crate::sampling::discrete::DiscreteDistribution;
use crate::scene::Scene;
use crate::tracer::bvh::ObvhsTracer;
use crate::tracer::{Geometry, Tracer};
use glam::Vec3;
use std::sync::Arc;

/// Which light (and, for a mesh light, which of its triangles) a primitive emits as.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmitterRef {
    pub light: u32,
    pub local: u32,
}

pub struct PreparedScene {
    pub scene: Scene,
    pub geometry: Arc<Geometry>,
    pub tracer: Box<dyn Tracer>,
    pub prim_material: Vec<u32>,
    pub prim_emitter: Vec<Option<EmitterRef>>,
    pub bsdfs: Vec<Bsdf>,
    pub lights: Vec<Light>,
    /// Power-proportional light selection; None when no light has positive power.
    pub light_selection: Option<DiscreteDistribution>,
    /// The environment in every representation, built only when the scene has one.
    pub environment: Option<Arc<Environment>>,
    /// Index of the environment in `lights`.
    pub env_light: Option<usize>,
}

/// A surface point hit by a ray.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub p: Vec3,
    /// Absolute per-axis error bound of `p`, for offsetting rays that leave it.
    pub p_error: Vec3,
    /// Unit geometric normal: the winding's side for triangles, outward for spheres.
    pub ng: Vec3,
    pub material: u32,
    pub emitter: Option<EmitterRef>,
}

impl PreparedScene {
    pub fn new(scene: Scene) -> Self {
        Self::with_tracer(scene, |g| Box::new(ObvhsTracer::build(g)))
    }

    /// Prepares with a tracer of the caller's choice (a backend built over the same geometry).
    pub fn with_tracer(
        scene: Scene,
        make_tracer: impl FnOnce(Arc<Geometry>) -> Box<dyn Tracer>,
    ) -> Self {
        let mut g = Geometry::default();
        let mut prim_material = Vec::new();
        let mut prim_emitter = Vec::new();
        let mut lights = Vec::new();

        for mesh in &scene.meshes {
            let tris: Vec<Triangle> = mesh
                .triangles
                .iter()
                .map(|t| {
                    Triangle::new(
                        mesh.positions[t[0] as usize],
                        mesh.positions[t[1] as usize],
                        mesh.positions[t[2] as usize],
                    )
                })
                .collect();
            let light = mesh
                .emission
                .and_then(|l| MeshLight::new(tris.clone(), l))
                .map(|m| {
                    lights.push(Light::Mesh(m));
                    lights.len() as u32 - 1
                });
            for (k, t) in tris.into_iter().enumerate() {
                g.triangles.push(t);
                prim_material.push(mesh.material);
                prim_emitter.push(light.map(|light| EmitterRef {
                    light,
                    local: k as u32,
                }));
            }
        }
        for q in &scene.quads {
            let light = q.emission.map(|l| {
                lights.push(Light::Quad(QuadLight::new(q.corner, q.edge_u, q.edge_v, l)));
                lights.len() as u32 - 1
            });
            let (c, u, v) = (q.corner, q.edge_u, q.edge_v);
            // Both triangles keep the winding of edge_u × edge_v.
            for t in [
                Triangle::new(c, c + u, c + u + v),
                Triangle::new(c, c + u + v, c + v),
            ] {
                g.triangles.push(t);
                prim_material.push(q.material);
                prim_emitter.push(light.map(|light| EmitterRef { light, local: 0 }));
            }
        }
        for s in &scene.spheres {
            let light = s.emission.map(|l| {
                lights.push(Light::Sphere(SphereLight {
                    center: s.center,
                    radius: s.radius,
                    radiance: l,
                }));
                lights.len() as u32 - 1
            });
            g.spheres.push(Sphere {
                center: s.center,
                radius: s.radius,
            });
            prim_material.push(s.material);
            prim_emitter.push(light.map(|light| EmitterRef { light, local: 0 }));
        }
        for p in &scene.point_lights {
            lights.push(Light::Point(PointLight {
                position: p.position,
                intensity: p.intensity,
            }));
        }
        for s in &scene.spot_lights {
            lights.push(Light::Spot(SpotLight {
                position: s.position,
                axis: s.direction,
                intensity: s.intensity,
                cos_cone: s.cos_cone,
                cos_falloff_start: s.cos_falloff_start,
            }));
        }
        let scene_radius = bounding_radius(&g, &scene.camera);
        if !scene.directional_lights.is_empty() {
            for d in &scene.directional_lights {
                lights.push(Light::Directional(DirectionalLight {
                    to_light: -d.direction,
                    irradiance: d.irradiance,
                    scene_radius,
                }));
            }
        }
        let environment = scene
            .environment
            .as_ref()
            .map(|spec| Arc::new(Environment::build(&|w| spec.radiance(w))));
        let env_light = environment.as_ref().map(|env| {
            lights.push(Light::Environment(EnvironmentLight {
                env: env.clone(),
                scene_radius,
            }));
            lights.len() - 1
        });
        let bsdfs = scene
            .materials
            .iter()
            .map(|m| Bsdf::new(m.albedo, m.specular, m.exponent))
            .collect();

        let light_selection = if lights.is_empty() {
            None
        } else {
            DiscreteDistribution::new(&lights.iter().map(Light::power).collect::<Vec<_>>())
        };
        let geometry = Arc::new(g);
        let tracer = make_tracer(geometry.clone());
        PreparedScene {
            scene,
            geometry,
            tracer,
            prim_material,
            prim_emitter,
            bsdfs,
            lights,
            light_selection,
            environment,
            env_light,
        }
    }

    /// Radiance the environment sends along -`dir` in representation `repr` (zero without one).
    pub fn env_radiance(&self, repr: Repr, dir: Vec3) -> Vec3 {
        match &self.environment {
            Some(env) => env.radiance(repr, dir),
            None => Vec3::ZERO,
        }
    }

    /// The pdf with which [`Self::sample_light`] produces direction `wi` towards the
    /// environment (selection probability included); 0 without one.
    pub fn env_light_pdf(&self, wi: Vec3, methods: &LightMethods) -> f32 {
        match (self.env_light, &self.light_selection, &self.environment) {
            (Some(i), Some(sel), Some(env)) => sel.pmf(i) * env.pdf(methods.env, wi),
            _ => 0.0,
        }
    }

    pub fn surface(&self, ray: &Ray, hit: &Hit) -> SurfaceHit {
        let (p, p_error, ng) = match self.geometry.sphere_index(hit.prim) {
            None => {
                let t = &self.geometry.triangles[hit.prim as usize];
                // Barycentric position: more accurate than o + t·d, which matters for offsets.
                let (u, v) = (hit.u, hit.v);
                (t.point(u, v), t.point_error(u, v), t.cross().normalize())
            }
            Some(s) => {
                let s = &self.geometry.spheres[s];
                let p = s.project(ray.at(hit.t));
                (p, s.point_error(p), s.normal_at(p))
            }
        };
        SurfaceHit {
            p,
            p_error,
            ng,
            material: self.prim_material[hit.prim as usize],
            emitter: self.prim_emitter[hit.prim as usize],
        }
    }

    /// Radiance an emitter primitive sends back along a ray that hit it.
    pub fn emitted(&self, surface: &SurfaceHit, ray_dir: Vec3) -> Vec3 {
        match surface.emitter {
            Some(e) => self.lights[e.light as usize].emitted(surface.ng, -ray_dir),
            None => Vec3::ZERO,
        }
    }

    /// Picks a light by power and samples it by `methods`; the returned pdf includes the
    /// selection probability.
    pub fn sample_light(
        &self,
        p: Vec3,
        u_select: f32,
        u: [f32; 3],
        methods: &LightMethods,
    ) -> Option<(usize, LightSample)> {
        let sel = self.light_selection.as_ref()?;
        let i = sel.sample(u_select);
        let mut s = self.lights[i].sample(p, u, methods)?;
        s.pdf *= sel.pmf(i);
        Some((i, s))
    }

    /// The pdf with which [`Self::sample_light`] produces the direction from p to point q of
    /// the emitter `e` (selection probability included).
    pub fn light_pdf(&self, p: Vec3, q: Vec3, e: EmitterRef, methods: &LightMethods) -> f32 {
        let Some(sel) = self.light_selection.as_ref() else {
            return 0.0;
        };
        sel.pmf(e.light as usize) * self.lights[e.light as usize].pdf(p, q, e.local, methods)
    }

    /// True if the scene has a light `kind` accepts.
    pub fn has_light(&self, kind: impl Fn(&Light) -> bool) -> bool {
        self.lights.iter().any(kind)
    }

    /// `methods` with what this scene cannot use replaced: spherical-rectangle sampling needs
    /// rectangles, not general parallelograms.
    pub fn usable_methods(&self, mut methods: LightMethods) -> LightMethods {
        if self
            .lights
            .iter()
            .any(|l| matches!(l, Light::Quad(q) if !q.is_rectangle()))
        {
            methods.quad = QuadMethod::Area;
        }
        methods
    }
}

/// Radius of a bounding sphere (about the box centre) of the geometry, the camera and the
/// point it looks at, so it is positive even for a scene with no geometry.
fn bounding_radius(g: &Geometry, camera: &crate::scene::Camera) -> f32 {
    let look_at = camera.eye + camera.forward;
    let mut lo = camera.eye.min(look_at);
    let mut hi = camera.eye.max(look_at);
    for t in &g.triangles {
        for v in [t.v0, t.v1, t.v2] {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    for s in &g.spheres {
        lo = lo.min(s.center - s.radius);
        hi = hi.max(s.center + s.radius);
    }
    0.5 * (hi - lo).length()
}
