//! Every light equally likely (pbrt-v4 `UniformLightSampler`; Mitsuba 3's only choice before
//! per-emitter weights): the baseline that knows nothing.

use super::{LightSelector, SelectorType};
use crate::lights::LightCtx;

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
        let i = ((u * self.n as f64) as usize).min(self.n - 1);
        Some((i, self.p()))
    }

    fn pmf(&self, _ctx: &LightCtx, _light: usize) -> f32 {
        self.p()
    }

    fn constant(&self) -> Option<(usize, f32)> {
        (self.n == 1).then(|| (0, self.p()))
    }
}

impl UniformSelector {
    /// Every light's probability, the one number `sample`, `pmf` and `constant` report.
    fn p(&self) -> f32 {
        (1.0 / self.n as f64) as f32
    }
}
