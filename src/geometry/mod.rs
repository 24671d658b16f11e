//! Rays, hits and the exact intersection routines for the primitives the scene holds.

pub mod sphere;
pub mod triangle;

use glam::Vec3;

/// A ray with t in (0, tmax). Origins are offset off surfaces by the caller
/// ([`crate::math::offset_ray_origin`]), so no tmin epsilon is needed.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    pub tmax: f32,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3, tmax: f32) -> Self {
        Ray { origin, dir, tmax }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// Closest hit: distance, the scene primitive id and the primitive's own (u, v) coordinates
/// (barycentrics for triangles, unused for spheres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}
