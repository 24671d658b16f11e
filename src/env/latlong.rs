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
    let (u, v) = dir_to_uv_lanes(w.x, w.y, w.z);
    [u, v]
}

/// [`dir_to_uv`] of N lanes' directions (x, y, z).
#[inline(always)]
pub fn dir_to_uv_lanes<V: Vector<N>, const N: usize>(x: V, y: V, z: V) -> (V, V) {
    let phi = atan2(z, x);
    let phi = phi.lt_select(V::splat(0.0), phi.add(V::splat(2.0 * PI)), phi);
    // atan2 of (sin θ, cos θ): accurate at the poles, where acos is not.
    let theta = atan2(x.mul(x).add(z.mul(z)).sqrt(), y);
    (
        below_one_lanes(phi.div(V::splat(2.0 * PI))),
        below_one_lanes(theta.div(V::splat(PI))),
    )
}

/// [`below_one`] of N lanes, the same comparisons.
#[inline(always)]
fn below_one_lanes<V: Vector<N>, const N: usize>(x: V) -> V {
    let top = V::splat(crate::sampling::stream::ONE_MINUS_EPSILON);
    V::select(
        x.lt(V::splat(0.0)),
        V::splat(0.0),
        V::select(top.lt(x), top, x),
    )
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
