//! Latitude/longitude (equirectangular) parameterization, the layout of the input EXR.
//! +Y up; θ from +Y, φ = atan2(z, x) from +X towards +Z; u = φ/2π, v = θ/π (row 0 at the top,
//! +Y). Jacobian dω/(du dv) = 2π·π·sin θ.

use glam::Vec3;
use std::f32::consts::PI;

/// (u, v) ∈ [0, 1)² of a unit direction.
pub fn dir_to_uv(w: Vec3) -> [f32; 2] {
    let mut phi = w.z.atan2(w.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    // atan2 of (sin θ, cos θ): accurate at the poles, where acos is not.
    let theta = (w.x * w.x + w.z * w.z).sqrt().atan2(w.y);
    [below_one(phi / (2.0 * PI)), below_one(theta / PI)]
}

pub fn uv_to_dir(uv: [f32; 2]) -> Vec3 {
    let (phi, theta) = (2.0 * PI * uv[0], PI * uv[1]);
    let s = theta.sin();
    Vec3::new(s * phi.cos(), theta.cos(), s * phi.sin())
}

pub fn jacobian(uv: [f32; 2]) -> f32 {
    2.0 * PI * PI * (PI * uv[1]).sin()
}

/// x rounded into [0, 1): 2π/2π can round to 1.
pub(crate) fn below_one(x: f32) -> f32 {
    x.clamp(0.0, crate::sampling::stream::ONE_MINUS_EPSILON)
}
