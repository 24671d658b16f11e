//! The baseline backend: a BVH2 built by obvhs (PLOC) over triangles and analytic spheres,
//! traversed by obvhs's single-ray kernels with our exact primitive tests in the leaves and the
//! contract's closest-hit rule ([`super::closer`]). Packets go through the trait's per-lane loop.

use super::{Geometry, Tracer, closer, cull_t};
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
    build_time: std::time::Duration,
}

#[derive(Clone, Copy)]
struct PrimBounds(Aabb);

impl Boundable for PrimBounds {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// Primitive boxes in id order: triangles, then spheres (the ids of [`Geometry`]).
pub fn prim_bounds(geometry: &Geometry) -> Vec<Aabb> {
    let mut bounds: Vec<Aabb> = geometry
        .triangles
        .iter()
        .map(|t| {
            let (a, b, c) = (t.v0.into(), t.v1.into(), t.v2.into());
            Aabb::new(glam::Vec3A::min(a, b).min(c), glam::Vec3A::max(a, b).max(c))
        })
        .collect();
    bounds.extend(geometry.spheres.iter().map(|s| {
        let r = glam::Vec3A::splat(s.radius);
        Aabb::new(
            glam::Vec3A::from(s.center) - r,
            glam::Vec3A::from(s.center) + r,
        )
    }));
    bounds
}

/// obvhs's binary tree (PLOC) over the primitive boxes, with a build preset.
pub fn build_bvh2(geometry: &Geometry, preset: BvhBuildParams) -> Bvh2 {
    let bounds: Vec<PrimBounds> = prim_bounds(geometry).into_iter().map(PrimBounds).collect();
    let mut core = std::time::Duration::ZERO;
    obvhs::bvh2::builder::build_bvh2(&bounds, preset, &mut core)
}

impl ObvhsTracer {
    pub fn build(geometry: Arc<Geometry>) -> Self {
        let start = std::time::Instant::now();
        let bvh = build_bvh2(&geometry, BvhBuildParams::medium_build());
        let slot_prim = bvh.primitive_indices.clone();
        ObvhsTracer {
            geometry,
            bvh,
            slot_prim,
            build_time: start.elapsed(),
        }
    }

    /// How long [`Self::build`] took.
    pub fn build_time(&self) -> std::time::Duration {
        self.build_time
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
            .ray_traverse(Self::to_bvh_ray(ray), &mut hit, |_, slot| {
                let prim = self.slot_prim[slot];
                // The contract's rule (`tracer::closer`): leaves are tested a little past the
                // closest hit so far, so a tie is seen, and the smallest (t, prim) is kept.
                let tm = cull_t(best.t).min(ray.tmax);
                let (t, u, v) = self.hit_prim(&Ray::new(ray.origin, ray.dir, tm), &wr, prim);
                if t < ray.tmax && closer(t, prim, best.t, best.prim) {
                    best = Hit { t, prim, u, v };
                }
                // obvhs culls boxes entered at or beyond the value returned here.
                cull_t(best.t)
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
