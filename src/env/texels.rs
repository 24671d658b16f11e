//! A representation's texels (piecewise-constant radiance over its atlas) and the importance
//! map over them: texel weights luminance · J(centre), both samplers, and the shared pdf.

use super::cdf::MarginalConditional;
use super::hierarchical::HierarchicalWarp;
use super::latlong::below_one;
use super::{EnvSampler, Repr};
use crate::math::luminance;
use glam::Vec3;
use rayon::prelude::*;

/// Supersamples per texel side when resampling from the source.
const SUPERSAMPLE: usize = 4;

#[derive(Clone, Debug)]
pub struct TexelMap {
    pub repr: Repr,
    /// Atlas size: `repr.tiles()` square tiles of side `height`.
    pub width: usize,
    pub height: usize,
    /// Row-major radiance.
    pub texels: Vec<Vec3>,
}

impl TexelMap {
    /// Each texel is the solid-angle-weighted mean of `radiance` over it (a J-weighted
    /// 4×4 midpoint rule), so the map's integral over the sphere matches the source's.
    pub fn resample(repr: Repr, tile: usize, radiance: &(dyn Fn(Vec3) -> Vec3 + Sync)) -> Self {
        let (width, height) = (repr.tiles() * tile, tile);
        let texels = (0..width * height)
            .into_par_iter()
            .map(|k| {
                let (x, y) = (k % width, k / width);
                let (mut sum, mut jsum) = (Vec3::ZERO, 0.0f32);
                for i in 0..SUPERSAMPLE {
                    for j in 0..SUPERSAMPLE {
                        let s = SUPERSAMPLE as f32;
                        let uv = [
                            (x as f32 + (i as f32 + 0.5) / s) / width as f32,
                            (y as f32 + (j as f32 + 0.5) / s) / height as f32,
                        ];
                        let jac = repr.jacobian(uv);
                        sum += jac * radiance(repr.uv_to_dir(uv));
                        jsum += jac;
                    }
                }
                sum / jsum
            })
            .collect();
        TexelMap {
            repr,
            width,
            height,
            texels,
        }
    }

    /// Texel index of an atlas point.
    pub fn index(&self, uv: [f32; 2]) -> usize {
        let x = ((uv[0] * self.width as f32) as usize).min(self.width - 1);
        let y = ((uv[1] * self.height as f32) as usize).min(self.height - 1);
        y * self.width + x
    }

    pub fn lookup(&self, w: Vec3) -> Vec3 {
        self.texels[self.index(self.repr.dir_to_uv(w))]
    }

    /// Atlas centre of texel k.
    fn centre(&self, k: usize) -> [f32; 2] {
        [
            ((k % self.width) as f32 + 0.5) / self.width as f32,
            ((k / self.width) as f32 + 0.5) / self.height as f32,
        ]
    }
}

/// A sampled direction with the radiance arriving along it and its solid-angle pdf.
#[derive(Clone, Copy, Debug)]
pub struct EnvSample {
    pub wi: Vec3,
    pub radiance: Vec3,
    pub pdf: f32,
}

#[derive(Clone, Debug)]
pub struct ImportanceMap {
    pub texels: TexelMap,
    weights: Vec<f64>,
    total: f64,
    /// ∫ luminance(L) dω over the sphere (≈ Σ weights / texel count).
    pub luminance_integral: f64,
    /// None for a black map: nothing to sample.
    cdf: Option<MarginalConditional>,
    hier: Option<HierarchicalWarp>,
}

impl ImportanceMap {
    pub fn new(texels: TexelMap) -> Self {
        let weights: Vec<f64> = (0..texels.texels.len())
            .map(|k| {
                luminance(texels.texels[k]) as f64 * texels.repr.jacobian(texels.centre(k)) as f64
            })
            .collect();
        let total: f64 = weights.iter().sum();
        let cdf = MarginalConditional::new(&weights, texels.width);
        let hier = HierarchicalWarp::new(&weights, texels.repr.tiles(), texels.height);
        ImportanceMap {
            luminance_integral: total / weights.len() as f64,
            weights,
            total,
            cdf,
            hier,
            texels,
        }
    }

    /// Density over the atlas of texel k: (w_k / Σw) · texel count.
    fn pdf_uv(&self, k: usize) -> f64 {
        self.weights[k] / self.total * self.weights.len() as f64
    }

    /// None for a black map, and for the measure-zero atlas points where J = 0 (lat/long poles).
    pub fn sample(&self, sampler: EnvSampler, u: [f32; 2]) -> Option<EnvSample> {
        let ((col, row), [du, dv]) = match sampler {
            EnvSampler::Cdf => self.cdf.as_ref()?.sample(u),
            EnvSampler::Hierarchical => self.hier.as_ref()?.sample(u),
        };
        let t = &self.texels;
        let uv = [
            below_one(((col as f64 + du) / t.width as f64) as f32),
            below_one(((row as f64 + dv) / t.height as f64) as f32),
        ];
        // The texel of the f32 point (rounding can move a point on an edge next door), so
        // radiance and pdf are those a lookup of the same point gives.
        let k = t.index(uv);
        let jac = t.repr.jacobian(uv);
        if self.weights[k] <= 0.0 || jac <= 0.0 {
            return None;
        }
        Some(EnvSample {
            wi: t.repr.uv_to_dir(uv),
            radiance: t.texels[k],
            pdf: (self.pdf_uv(k) / jac as f64) as f32,
        })
    }

    /// Solid-angle pdf of direction `w`: 0 for a black map, in black texels and at J = 0.
    pub fn pdf(&self, w: Vec3) -> f32 {
        if self.total <= 0.0 {
            return 0.0;
        }
        let uv = self.texels.repr.dir_to_uv(w);
        let jac = self.texels.repr.jacobian(uv);
        if jac <= 0.0 {
            return 0.0;
        }
        (self.pdf_uv(self.texels.index(uv)) / jac as f64) as f32
    }
}
