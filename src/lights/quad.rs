//! Parallelogram area light, emitting on the side of edge_u × edge_v.
//! Area sampling: a uniform point q, pdf_A = 1/A, converted to solid angle at p by
//! pdf_ω = pdf_A · d² / |cos θ_l| (Veach 1997, eq. 8.10).

use super::LightSample;
use crate::math::luminance;
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct QuadLight {
    pub corner: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
    /// Unit normal of the emitting side.
    pub normal: Vec3,
    pub area: f32,
    pub radiance: Vec3,
}

impl QuadLight {
    pub fn new(corner: Vec3, edge_u: Vec3, edge_v: Vec3, radiance: Vec3) -> Self {
        let c = edge_u.cross(edge_v);
        let area = c.length();
        QuadLight {
            corner,
            edge_u,
            edge_v,
            normal: c / area,
            area,
            radiance,
        }
    }

    pub fn power(&self) -> f32 {
        std::f32::consts::PI * self.area * luminance(self.radiance)
    }

    /// Uniform area sampling. None when p sees the back (non-emitting) side, or lies in the
    /// light's plane: those directions carry no radiance, so no sample is the unbiased answer.
    pub fn sample_area(&self, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        let q = self.corner + self.edge_u * u[0] + self.edge_v * u[1];
        let d = q - p;
        let d2 = d.length_squared();
        let wi = d / d2.sqrt();
        let cos_l = -self.normal.dot(wi);
        if cos_l <= 0.0 {
            return None;
        }
        Some(LightSample {
            wi,
            point: q,
            normal: self.normal,
            radiance: self.radiance,
            pdf: d2 / (self.area * cos_l),
        })
    }

    /// Solid-angle pdf of [`Self::sample_area`] for the direction that reaches light point q.
    pub fn pdf_area(&self, p: Vec3, q: Vec3) -> f32 {
        let d = q - p;
        let d2 = d.length_squared();
        let cos_l = -self.normal.dot(d) / d2.sqrt();
        if cos_l > 0.0 {
            d2 / (self.area * cos_l)
        } else {
            0.0
        }
    }
}
