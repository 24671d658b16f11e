//! Surface reflectance. Lambertian: f = ρ/π (energy-conserving for ρ ≤ 1).

use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug)]
pub struct Lambertian {
    pub albedo: Vec3,
}

impl Lambertian {
    pub fn eval(&self) -> Vec3 {
        self.albedo * FRAC_1_PI
    }
}
