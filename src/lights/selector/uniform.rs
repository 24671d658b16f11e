//! Every light equally likely (pbrt-v4 `UniformLightSampler`; Mitsuba 3's only choice before
//! per-emitter weights): the baseline that knows nothing.

use super::{LightSelector, SelectorType, point_free_lanes};
use crate::lights::{LaneQuery, LightCtx};
use crate::simd::WIDTH as LANES;

pub static UNIFORM: SelectorType = SelectorType {
    name: "uniform",
    describe: "every light equally likely",
    build: |lights| {
        if lights.is_empty() {
            return Err("no light".into());
        }
        Ok(Box::new(UniformSelector {
            n: lights.len(),
        }))
    },
};

pub struct UniformSelector {
    n: usize,
}

impl LightSelector for UniformSelector {
    fn sample(&self, _ctx: &LightCtx, u: f64) -> Option<(usize, f32)> {
        Some((self.index(u), self.p()))
    }

    fn pmf(&self, _ctx: &LightCtx, _light: usize) -> f32 {
        self.p()
    }

    /// The point plays no part: one loop over the lanes' numbers.
    fn sample_lanes(
        &self,
        _q: &LaneQuery,
        u: &[f64; LANES],
        mask: u32,
        light: &mut [usize; LANES],
        pmf: &mut [f32; LANES],
    ) -> u32 {
        point_free_lanes(u, mask, light, pmf, |u| (self.index(u), self.p()))
    }

    fn constant(&self) -> Option<(usize, f32)> {
        (self.n == 1).then(|| (0, self.p()))
    }
}

impl UniformSelector {
    /// The light that number u picks: what `sample` and `sample_lanes` return.
    fn index(&self, u: f64) -> usize {
        ((u * self.n as f64) as usize).min(self.n - 1)
    }

    /// Every light's probability, the one number `sample`, `pmf` and `constant` report.
    fn p(&self) -> f32 {
        (1.0 / self.n as f64) as f32
    }
}
