//! Clarberg's equal-area octahedral map ("Fast Equal-Area Mapping of the (Hemi)Sphere using
//! SIMD", JGT 2008), in pbrt-v4's form (`EqualAreaSquareToSphere` / `EqualAreaSphereToSquare`)
//! with its pole axis on our +Y. Equal area: dω/(du dv) = 4π everywhere.

use super::latlong::below_one;
use glam::Vec3;
use std::f32::consts::{FRAC_2_PI, FRAC_PI_4, PI};

/// pbrt's (x, y, z) with z the pole is our (x, z, y): a fixed permutation, so the map stays
/// equal-area and its inverse is the same permutation.
pub fn uv_to_dir(uv: [f32; 2]) -> Vec3 {
    let (u, v) = (2.0 * uv[0] - 1.0, 2.0 * uv[1] - 1.0);
    let (up, vp) = (u.abs(), v.abs());
    let signed_distance = 1.0 - (up + vp);
    let d = signed_distance.abs();
    let r = 1.0 - d;
    let phi = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 } * FRAC_PI_4;
    let z = (1.0 - r * r).copysign(signed_distance);
    let cos_phi = phi.cos().copysign(u);
    let sin_phi = phi.sin().copysign(v);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    Vec3::new(cos_phi * s, z, sin_phi * s).normalize()
}

pub fn dir_to_uv(w: Vec3) -> [f32; 2] {
    let (dx, dy, dz) = (w.x, w.z, w.y);
    let (x, y, z) = (dx.abs(), dy.abs(), dz.abs());
    // 1 - |z| from the other components, exact near the poles: (x² + y²)/(1 + |z|).
    let r = ((x * x + y * y) / (1.0 + z)).sqrt();
    let a = x.max(y);
    let b = if a == 0.0 { 0.0 } else { x.min(y) / a };
    let mut phi = b.atan() * FRAC_2_PI;
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if dz < 0.0 {
        std::mem::swap(&mut u, &mut v);
        u = 1.0 - u;
        v = 1.0 - v;
    }
    u = u.copysign(dx);
    v = v.copysign(dy);
    [below_one(0.5 * (u + 1.0)), below_one(0.5 * (v + 1.0))]
}

pub fn jacobian(_uv: [f32; 2]) -> f32 {
    4.0 * PI
}
