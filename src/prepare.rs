//! Scene → what the renderer needs, and only that, in two parts: the [`World`] (the triangles
//! and spheres the tracer intersects, per-primitive materials and emitters) and the
//! [`LightSet`] (light structures only for the lights present, selectors built on demand).
//! A strategy sees both through a [`SceneView`], never the tracer.

use crate::bsdf::Bsdf;
use crate::env::texels::PrefetchedTexels;
use crate::env::{Environment, Repr};
use crate::geometry::sphere::Sphere;
use crate::geometry::triangle::Triangle;
use crate::geometry::{Hit, Ray};
use crate::lights::environment::EnvironmentLight;
use crate::lights::mesh::TriangleLight;
use crate::lights::quad::QuadLight;
use crate::lights::sphere::SphereLight;
use crate::lights::{EmitterRef, Light, LightSet};
use crate::scene::Scene;
use crate::simd::{Isa, Soa3, WIDTH};
use crate::strategy::Integrand;
use crate::tracer::bvh::ObvhsTracer;
use crate::tracer::{Geometry, Tracer};
use glam::Vec3;
use std::sync::Arc;

/// What rays hit and what the hit points are made of.
#[derive(Debug)]
pub struct World {
    pub geometry: Arc<Geometry>,
    pub prim_material: Vec<u32>,
    pub prim_emitter: Vec<Option<EmitterRef>>,
    /// Each triangle's unit geometric normal, computed once here rather than per hit (its
    /// square root and division were 8 % of a `light` sample on `cornell`, `perf record`).
    pub triangle_normals: Vec<Vec3>,
    pub materials: Vec<Bsdf>,
    /// Occlusion distance of the ambient-occlusion integrand, when the scene asks for it.
    pub ao_distance: Option<f32>,
    /// Radius of a bounding sphere of the geometry and the camera.
    pub radius: f32,
}

pub struct PreparedScene {
    pub scene: Scene,
    pub world: World,
    pub lights: LightSet,
    pub tracer: Box<dyn Tracer>,
    /// The emitting primitives alone, traced by the same backend; None where nothing emits.
    pub emitters: Option<Emitters>,
}

/// The emitting primitives of a scene in a tracer of their own. An emission probe adds
/// radiance only where its closest hit is an emitter, and a ray whose closest hit is an
/// emitter meets one: the renderer asks this tracer (a tree of a few primitives) which rays
/// meet an emitter at all, and the whole scene for the closest hits of those alone
/// (docs/tracer.md, stop 38).
pub struct Emitters {
    pub tracer: Box<dyn Tracer>,
}

impl Emitters {
    /// The triangles, then spheres, of `g` that emit (`prim_emitter`, by primitive id), as a
    /// geometry of their own; None when none does.
    fn geometry(g: &Geometry, prim_emitter: &[Option<EmitterRef>]) -> Option<Arc<Geometry>> {
        let emits = |prim: usize| prim_emitter[prim].is_some();
        let mut sub = Geometry::default();
        for (i, t) in g.triangles.iter().enumerate() {
            if emits(i) {
                sub.triangles.push(*t);
            }
        }
        for (j, s) in g.spheres.iter().enumerate() {
            if emits(g.triangles.len() + j) {
                sub.spheres.push(*s);
            }
        }
        (sub.prim_count() > 0).then(|| Arc::new(sub))
    }
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

/// The scene as one integrand sees it: the world, the lights, and the representation the
/// environment is looked up in (each integrand has its own: resampling changes the radiance
/// function slightly, so each has its own reference). What a strategy is given.
#[derive(Clone, Copy, Debug)]
pub struct SceneView<'a> {
    pub world: &'a World,
    pub lights: &'a LightSet,
    pub env: Repr,
}

impl SceneView<'_> {
    /// Radiance the environment sends along -`dir` (zero without one).
    pub fn env_radiance(&self, dir: Vec3) -> Vec3 {
        self.lights.env_radiance(self.env, dir)
    }

    /// [`Self::env_radiance`] of the directions `dirs` of lanes `mask`, added to `out` (over
    /// lanes where the representation has a kernel, with the same bits). `prefetched`: what
    /// [`Self::prefetch_env`] returned for these directions.
    pub fn add_env_radiance(
        &self,
        isa: Isa,
        dirs: &Soa3,
        prefetched: Option<&PrefetchedTexels>,
        mask: u32,
        out: &mut [Vec3; WIDTH],
    ) {
        if let Some(env) = self.lights.environment() {
            env.map(self.env)
                .add_lookups(isa, dirs, prefetched, mask, out);
        }
    }

    /// Starts the reads [`Self::add_env_radiance`] of the same directions will make, and
    /// returns their texels for it (see
    /// [`crate::env::texels::ImportanceMap::prefetch_lookups`]); None without an environment.
    pub fn prefetch_env(&self, isa: Isa, dirs: &Soa3, mask: u32) -> Option<PrefetchedTexels> {
        self.lights
            .environment()
            .and_then(|env| env.map(self.env).prefetch_lookups(isa, dirs, mask))
    }

    /// Radiance an emitter primitive sends back along a ray that hit it.
    pub fn emitted(&self, surface: &SurfaceHit, ray_dir: Vec3) -> Vec3 {
        match surface.emitter {
            Some(e) => self.lights.emitted(e, surface.ng, -ray_dir),
            None => Vec3::ZERO,
        }
    }

    /// Some primitive emits (a direction can hit a light).
    pub fn has_emitting_surface(&self) -> bool {
        self.world.prim_emitter.iter().any(Option::is_some)
    }
}

impl World {
    pub fn surface(&self, ray: &Ray, hit: &Hit) -> SurfaceHit {
        let (p, p_error, ng) = match self.geometry.sphere_index(hit.prim) {
            None => {
                let t = &self.geometry.triangles[hit.prim as usize];
                // Barycentric position: more accurate than o + t·d, which matters for offsets.
                let (u, v) = (hit.u, hit.v);
                let ng = self.triangle_normals[hit.prim as usize];
                (t.point(u, v), t.point_error(u, v), ng)
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
}

impl PreparedScene {
    pub fn new(scene: Scene) -> Self {
        Self::with_tracer(scene, |g| Box::new(ObvhsTracer::build(g)))
    }

    /// Prepares with a tracer of the caller's choice (a backend built over the same geometry).
    pub fn with_tracer(
        scene: Scene,
        mut make_tracer: impl FnMut(Arc<Geometry>) -> Box<dyn Tracer>,
    ) -> Self {
        let mut g = Geometry::default();
        let mut prim_material = Vec::new();
        let mut prim_emitter = Vec::new();
        let mut lights: Vec<Box<dyn Light>> = Vec::new();
        let add = |lights: &mut Vec<Box<dyn Light>>, l: Box<dyn Light>| {
            lights.push(l);
            lights.len() as u32 - 1
        };

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
            // One light per emitting triangle, so that a selector can weigh each on its own
            // (triangles without area cannot emit and get none).
            for t in tris {
                let light = mesh
                    .emission
                    .and_then(|l| TriangleLight::new(t, l))
                    .map(|l| add(&mut lights, Box::new(l)));
                g.triangles.push(t);
                prim_material.push(mesh.material);
                prim_emitter.push(light.map(|light| EmitterRef { light, local: 0 }));
            }
        }
        for q in &scene.quads {
            let light = q.emission.map(|l| {
                add(
                    &mut lights,
                    Box::new(QuadLight::new(q.corner, q.edge_u, q.edge_v, l)),
                )
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
                add(
                    &mut lights,
                    Box::new(SphereLight {
                        center: s.center,
                        radius: s.radius,
                        radiance: l,
                    }),
                )
            });
            g.spheres.push(Sphere {
                center: s.center,
                radius: s.radius,
            });
            prim_material.push(s.material);
            prim_emitter.push(light.map(|light| EmitterRef { light, local: 0 }));
        }
        let radius = bounding_radius(&g, &scene.camera);
        for l in &scene.lights {
            lights.push(l.spec.place(radius));
        }
        let environment = scene.environment.as_ref().map(|spec| {
            let env = Arc::new(Environment::build(&|w| spec.radiance(w)));
            lights.push(Box::new(EnvironmentLight {
                env: env.clone(),
                scene_radius: radius,
            }));
            (lights.len() - 1, env)
        });
        let materials = scene.materials.iter().map(|m| m.bsdf.clone()).collect();
        let triangle_normals = g.triangles.iter().map(|t| t.cross().normalize()).collect();
        let geometry = Arc::new(g);
        let tracer = make_tracer(geometry.clone());
        let emitters = Emitters::geometry(&geometry, &prim_emitter).map(|g| Emitters {
            tracer: make_tracer(g),
        });
        PreparedScene {
            world: World {
                geometry,
                prim_material,
                prim_emitter,
                triangle_normals,
                materials,
                ao_distance: scene.ao_distance,
                radius,
            },
            lights: LightSet::new(lights, environment),
            tracer,
            emitters,
            scene,
        }
    }

    /// Traces with the tracers `make_tracer` builds (the scene's and its emitters'), handing
    /// back the ones it replaces; on an error nothing is replaced.
    pub fn replace_tracers(
        &mut self,
        mut make_tracer: impl FnMut(Arc<Geometry>) -> crate::error::Result<Box<dyn Tracer>>,
    ) -> crate::error::Result<(Box<dyn Tracer>, Option<Emitters>)> {
        let tracer = make_tracer(self.world.geometry.clone())?;
        let emitters = match Emitters::geometry(&self.world.geometry, &self.world.prim_emitter) {
            Some(g) => Some(Emitters {
                tracer: make_tracer(g)?,
            }),
            None => None,
        };
        Ok((
            std::mem::replace(&mut self.tracer, tracer),
            std::mem::replace(&mut self.emitters, emitters),
        ))
    }

    /// The scene as `integrand` sees it.
    pub fn view(&self, integrand: Integrand) -> SceneView<'_> {
        SceneView {
            world: &self.world,
            lights: &self.lights,
            env: integrand.env_repr(),
        }
    }

    pub fn surface(&self, ray: &Ray, hit: &Hit) -> SurfaceHit {
        self.world.surface(ray, hit)
    }

    /// A light sample from `p` with the default selector and `methods` (for ray-set
    /// generation, which needs realistic shadow rays, not a strategy).
    pub fn sample_light(
        &self,
        p: Vec3,
        u_select: f32,
        u: [f32; 3],
        methods: &crate::lights::LightMethods,
    ) -> Option<(usize, crate::lights::LightSample)> {
        let sel = self
            .lights
            .selector(crate::lights::selector::default_selector())
            .ok()?;
        let ctx = crate::lights::LightCtx { p, n: Vec3::ZERO };
        self.lights.sample(sel, &ctx, u_select, u, methods)
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
