//! Latitude/longitude (equirectangular) parameterization, the layout of the input EXR.
//! +Y up; θ from +Y, φ = atan2(z, x) from +X towards +Z; u = φ/2π, v = θ/π (row 0 at the top,
//! +Y). Jacobian dω/(du dv) = 2π·π·sin θ.

use crate::math::atan2;
use crate::sampling::warp::cos_sin_turns;
use crate::simd::Vector;
use glam::Vec3;
use std::f32::consts::PI;

/// (u, v) ∈ [0, 1)² of a unit direction. atan2 and cos/sin are dibench's own
/// ([`crate::math::atan2`], [`cos_sin_turns`]): the same bits over lanes and alone, on every C
/// library.
pub fn dir_to_uv(w: Vec3) -> [f32; 2] {
    let mut phi = atan2(w.z, w.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    // atan2 of (sin θ, cos θ): accurate at the poles, where acos is not.
    let theta = atan2((w.x * w.x + w.z * w.z).sqrt(), w.y);
    [below_one(phi / (2.0 * PI)), below_one(theta / PI)]
}

pub fn uv_to_dir(uv: [f32; 2]) -> Vec3 {
    let (x, y, z) = uv_to_dir_lanes(uv[0], uv[1]);
    Vec3::new(x, y, z)
}

/// [`uv_to_dir`] of N lanes, (x, y, z).
#[inline(always)]
pub fn uv_to_dir_lanes<V: Vector<N>, const N: usize>(u: V, v: V) -> (V, V, V) {
    let (cos_phi, sin_phi) = cos_sin_turns(u);
    // θ = πv is half a turn times v.
    let (cos_theta, sin_theta) = cos_sin_turns(V::splat(0.5).mul(v));
    (sin_theta.mul(cos_phi), cos_theta, sin_theta.mul(sin_phi))
}

pub fn jacobian(uv: [f32; 2]) -> f32 {
    jacobian_lanes(uv[1])
}

/// [`jacobian`] of N lanes (it depends on v only).
#[inline(always)]
pub fn jacobian_lanes<V: Vector<N>, const N: usize>(v: V) -> V {
    V::splat(2.0 * PI * PI).mul(cos_sin_turns(V::splat(0.5).mul(v)).1)
}

/// x rounded into [0, 1): 2π/2π can round to 1.
pub(crate) fn below_one(x: f32) -> f32 {
    x.clamp(0.0, crate::sampling::stream::ONE_MINUS_EPSILON)
}
