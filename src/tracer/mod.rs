//! The tracer interface, shaped for packets: closest-hit and occlusion for single rays and for
//! 16-ray SoA packets with an active-lane mask. Strategies and the renderer see only this
//! trait, so the SIMD packet core and Embree drop in behind it.

pub mod backends;
pub mod bvh;
#[cfg(feature = "embree")]
pub mod embree;
pub mod packet;

use crate::geometry::sphere::Sphere;
use crate::geometry::triangle::Triangle;
use crate::geometry::{Hit, Ray};
use crate::simd::{V3, Vector};
use glam::Vec3;

/// Rays per packet: one 4×4 pixel tile, one 16-lane vector of the SIMD layer.
pub const LANES: usize = crate::simd::WIDTH;

const _: () = assert!(
    LANES == (crate::film::TILE * crate::film::TILE) as usize,
    "a packet is one film tile"
);

/// Bit i set = lane i active.
pub type LaneMask = u16;

pub const ALL_LANES: LaneMask = u16::MAX;

/// 16 rays, structure-of-arrays, 64-byte aligned so a lane array is one AVX-512 register or
/// two AVX2 registers.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct RayPacket {
    pub ox: [f32; LANES],
    pub oy: [f32; LANES],
    pub oz: [f32; LANES],
    pub dx: [f32; LANES],
    pub dy: [f32; LANES],
    pub dz: [f32; LANES],
    pub tmax: [f32; LANES],
}

impl RayPacket {
    /// The origins over lanes (for kernels).
    #[inline(always)]
    pub fn origin_lanes<V: Vector<LANES>>(&self) -> V3<V> {
        V3 {
            x: V::load(&self.ox),
            y: V::load(&self.oy),
            z: V::load(&self.oz),
        }
    }

    /// The directions over lanes (for kernels).
    #[inline(always)]
    pub fn dir_lanes<V: Vector<LANES>>(&self) -> V3<V> {
        V3 {
            x: V::load(&self.dx),
            y: V::load(&self.dy),
            z: V::load(&self.dz),
        }
    }
}

impl Default for RayPacket {
    fn default() -> Self {
        RayPacket {
            ox: [0.0; LANES],
            oy: [0.0; LANES],
            oz: [0.0; LANES],
            dx: [0.0; LANES],
            dy: [0.0; LANES],
            dz: [1.0; LANES],
            tmax: [0.0; LANES],
        }
    }
}

impl RayPacket {
    pub fn set(&mut self, lane: usize, ray: &Ray) {
        self.ox[lane] = ray.origin.x;
        self.oy[lane] = ray.origin.y;
        self.oz[lane] = ray.origin.z;
        self.dx[lane] = ray.dir.x;
        self.dy[lane] = ray.dir.y;
        self.dz[lane] = ray.dir.z;
        self.tmax[lane] = ray.tmax;
    }

    pub fn get(&self, lane: usize) -> Ray {
        Ray::new(
            Vec3::new(self.ox[lane], self.oy[lane], self.oz[lane]),
            Vec3::new(self.dx[lane], self.dy[lane], self.dz[lane]),
            self.tmax[lane],
        )
    }
}

/// Closest hits of a packet; `prim[lane] == NO_HIT` where the lane missed or was inactive.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct HitPacket {
    pub t: [f32; LANES],
    pub u: [f32; LANES],
    pub v: [f32; LANES],
    pub prim: [u32; LANES],
}

pub const NO_HIT: u32 = u32::MAX;

impl Default for HitPacket {
    fn default() -> Self {
        HitPacket {
            t: [f32::INFINITY; LANES],
            u: [0.0; LANES],
            v: [0.0; LANES],
            prim: [NO_HIT; LANES],
        }
    }
}

impl HitPacket {
    pub fn get(&self, lane: usize) -> Option<Hit> {
        (self.prim[lane] != NO_HIT).then(|| Hit {
            t: self.t[lane],
            prim: self.prim[lane],
            u: self.u[lane],
            v: self.v[lane],
        })
    }

    pub fn set(&mut self, lane: usize, hit: Option<Hit>) {
        match hit {
            Some(h) => {
                self.t[lane] = h.t;
                self.u[lane] = h.u;
                self.v[lane] = h.v;
                self.prim[lane] = h.prim;
            }
            None => {
                self.t[lane] = f32::INFINITY;
                self.prim[lane] = NO_HIT;
            }
        }
    }
}

/// What every backend traces: triangles get primitive ids `0..triangles.len()`, spheres the
/// ids after them.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    pub triangles: Vec<Triangle>,
    pub spheres: Vec<Sphere>,
}

impl Geometry {
    pub fn prim_count(&self) -> usize {
        self.triangles.len() + self.spheres.len()
    }

    /// Sphere index of a primitive id, if it is a sphere.
    pub fn sphere_index(&self, prim: u32) -> Option<usize> {
        (prim as usize).checked_sub(self.triangles.len())
    }
}

/// The closest-hit rule every backend we own follows: among the primitives our exact tests hit
/// on (0, tmax), the smallest t, and on equal t the smallest primitive id. It makes the answer
/// independent of the tree and of the order a traversal meets the primitives in, so the
/// `obvhs` and `packet` backends (every ISA, single rays and packets) agree bit for bit, ties
/// on shared edges included.
#[inline(always)]
pub fn closer(t: f32, prim: u32, best_t: f32, best_prim: u32) -> bool {
    t < best_t || (t == best_t && prim < best_prim)
}

/// Relative slack of [`cull_t`]: 2⁻²⁰, far above the few roundings between a box's entry
/// distance and a triangle's computed t, far below anything a traversal would notice.
pub const CULL_SCALE: f32 = 1.0 + 1.0 / (1u32 << 20) as f32;

/// The distance beyond which a closest-hit traversal may skip boxes and reject triangles, given
/// the closest hit so far: a little past it, so that a hit at the same t (a tie the rule above
/// may still prefer) or one rounding away is never culled.
#[inline(always)]
pub fn cull_t(best_t: f32) -> f32 {
    best_t * CULL_SCALE
}

pub trait Tracer: Send + Sync {
    /// Short backend name for CSV columns (`obvhs`, `packet`, `embree`).
    fn name(&self) -> &'static str;

    fn intersect(&self, ray: &Ray) -> Option<Hit>;

    /// True if anything lies on the open segment (0, ray.tmax).
    fn occluded(&self, ray: &Ray) -> bool;

    /// Closest hits of the active lanes; inactive lanes come back as misses.
    fn intersect_packet(&self, rays: &RayPacket, active: LaneMask, hits: &mut HitPacket) {
        for lane in 0..LANES {
            let hit = if active & (1 << lane) != 0 {
                self.intersect(&rays.get(lane))
            } else {
                None
            };
            hits.set(lane, hit);
        }
    }

    /// The mask of active lanes that are occluded.
    fn occluded_packet(&self, rays: &RayPacket, active: LaneMask) -> LaneMask {
        let mut out = 0;
        for lane in 0..LANES {
            if active & (1 << lane) != 0 && self.occluded(&rays.get(lane)) {
                out |= 1 << lane;
            }
        }
        out
    }

    /// Closest hits of a packet the caller knows is coherent (a camera tile), so a backend
    /// can pick a coherent kernel; the same results as [`Tracer::intersect_packet`].
    fn intersect_packet_coherent(&self, rays: &RayPacket, active: LaneMask, hits: &mut HitPacket) {
        self.intersect_packet(rays, active, hits)
    }
}
