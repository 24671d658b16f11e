//! The baseline backend: a BVH2 built by obvhs (PLOC) over triangles and analytic spheres,
//! traversed by obvhs's single-ray kernels with our exact primitive tests in the leaves.
//! Packets go through the trait's per-lane loop.

use super::{Geometry, Tracer};
use crate::geometry::triangle::WatertightRay;
use crate::geometry::{Hit, Ray};
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::ray::{Ray as BvhRay, RayHit};
use obvhs::{Boundable, BvhBuildParams};
use std::sync::Arc;

pub struct ObvhsTracer {
    geometry: Arc<Geometry>,
    bvh: Bvh2,
    /// obvhs leaf slot → our primitive id.
    slot_prim: Vec<u32>,
}

#[derive(Clone, Copy)]
struct PrimBounds(Aabb);

impl Boundable for PrimBounds {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

impl ObvhsTracer {
    pub fn build(geometry: Arc<Geometry>) -> Self {
        let mut bounds: Vec<PrimBounds> = geometry
            .triangles
            .iter()
            .map(|t| {
                let (a, b, c) = (t.v0.into(), t.v1.into(), t.v2.into());
                PrimBounds(Aabb::new(
                    glam::Vec3A::min(a, b).min(c),
                    glam::Vec3A::max(a, b).max(c),
                ))
            })
            .collect();
        bounds.extend(geometry.spheres.iter().map(|s| {
            let r = glam::Vec3A::splat(s.radius);
            PrimBounds(Aabb::new(
                glam::Vec3A::from(s.center) - r,
                glam::Vec3A::from(s.center) + r,
            ))
        }));
        let mut build_time = std::time::Duration::ZERO;
        let bvh = obvhs::bvh2::builder::build_bvh2(
            &bounds,
            BvhBuildParams::medium_build(),
            &mut build_time,
        );
        let slot_prim = bvh.primitive_indices.clone();
        ObvhsTracer {
            geometry,
            bvh,
            slot_prim,
        }
    }

    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    pub fn bvh(&self) -> &Bvh2 {
        &self.bvh
    }

    fn to_bvh_ray(ray: &Ray) -> BvhRay {
        BvhRay::new(ray.origin.into(), ray.dir.into(), 0.0, ray.tmax)
    }

    /// Exact primitive test; `f32::INFINITY` on a miss, as obvhs's callbacks expect.
    fn hit_prim(&self, ray: &Ray, wr: &WatertightRay, prim: u32) -> (f32, f32, f32) {
        match self.geometry.sphere_index(prim) {
            None => match self.geometry.triangles[prim as usize].intersect(ray, wr) {
                Some(h) => (h.t, h.b1, h.b2),
                None => (f32::INFINITY, 0.0, 0.0),
            },
            Some(s) => (
                self.geometry.spheres[s]
                    .intersect(ray)
                    .unwrap_or(f32::INFINITY),
                0.0,
                0.0,
            ),
        }
    }
}

impl Tracer for ObvhsTracer {
    fn name(&self) -> &'static str {
        "obvhs"
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if self.slot_prim.is_empty() {
            return None;
        }
        let wr = WatertightRay::new(ray.dir);
        let mut best = Hit {
            t: ray.tmax,
            prim: u32::MAX,
            u: 0.0,
            v: 0.0,
        };
        let mut hit = RayHit::none();
        self.bvh
            .ray_traverse(Self::to_bvh_ray(ray), &mut hit, |r, slot| {
                let prim = self.slot_prim[slot];
                // Leaves are tested against the shrinking closest distance obvhs keeps in r.tmax.
                let (t, u, v) = self.hit_prim(&Ray::new(ray.origin, ray.dir, r.tmax), &wr, prim);
                if t < best.t {
                    best = Hit { t, prim, u, v };
                }
                t
            });
        (best.prim != u32::MAX).then_some(best)
    }

    fn occluded(&self, ray: &Ray) -> bool {
        if self.slot_prim.is_empty() {
            return false;
        }
        let wr = WatertightRay::new(ray.dir);
        !self
            .bvh
            .ray_traverse_miss(Self::to_bvh_ray(ray), |_, slot| {
                self.hit_prim(ray, &wr, self.slot_prim[slot]).0
            })
    }
}
