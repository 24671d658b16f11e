//! Every light weighed at the point by its own importance bound, no tree (pbrt-v4
//! `ExhaustiveLightSampler`): the light BVH's distribution without clustering, O(n) per
//! sample — the oracle its approximation is measured against, affordable for small counts.
//! Lights at infinity weigh in with the irradiance they deliver, as at the BVH's top level.
//! pbrt-v4 draws by weighted reservoir sampling with a hash of u; here two passes invert the
//! running sum exactly, so `pmf` is the probability `sample` draws with.

use super::bvh::positive;
use super::{LightSelector, SelectorType};
use crate::lights::LightCtx;
use crate::lights::bounds::{Bounds, CompactBounds, DistantBounds, ImportanceModel};

/// Above this many lights `exhaustive` does not apply: at ~20 ns per light and sample, ten
/// thousand lights already cost 0.2 ms per sample.
pub const MAX_LIGHTS: usize = 10_000;

pub static EXHAUSTIVE: SelectorType = SelectorType {
    name: "exhaustive",
    describe: "every light weighed by its own importance bound at the point (O(n) per sample)",
    build: |lights| {
        if lights.len() > MAX_LIGHTS {
            return Err(format!(
                "{} lights: exhaustive selection costs O(n) per sample and stops at {MAX_LIGHTS}",
                lights.len()
            ));
        }
        Exhaustive::build(
            &lights.iter().map(|l| l.bounds()).collect::<Vec<_>>(),
            ImportanceModel::STANDARD,
        )
        .map(|e| Box::new(e) as Box<dyn LightSelector>)
    },
};

enum Entry {
    Local(CompactBounds),
    Distant(DistantBounds),
    /// No intensity: never selected.
    Dark,
}

pub struct Exhaustive {
    entries: Vec<Entry>,
    model: ImportanceModel,
}

impl Exhaustive {
    /// Over lights with these bounds; Err when none has positive intensity or irradiance.
    pub fn build(bounds: &[Bounds], model: ImportanceModel) -> Result<Self, String> {
        let entries: Vec<Entry> = bounds
            .iter()
            .map(|b| match b {
                Bounds::Local(b) if b.intensity > 0.0 => Entry::Local(CompactBounds::new(b)),
                Bounds::Distant(d) if d.irradiance > 0.0 => Entry::Distant(*d),
                _ => Entry::Dark,
            })
            .collect();
        if entries.iter().all(|e| matches!(e, Entry::Dark)) {
            return Err("no light with positive intensity".into());
        }
        Ok(Exhaustive { entries, model })
    }

    #[inline]
    fn weight(&self, e: &Entry, ctx: &LightCtx) -> f64 {
        match e {
            Entry::Local(b) => b.importance_with(ctx.p, ctx.n, &self.model),
            Entry::Distant(d) => d.importance(ctx.n),
            Entry::Dark => 0.0,
        }
    }

    fn total(&self, ctx: &LightCtx) -> f64 {
        self.entries.iter().map(|e| self.weight(e, ctx)).sum()
    }
}

impl LightSelector for Exhaustive {
    fn sample(&self, ctx: &LightCtx, u: f64) -> Option<(usize, f32)> {
        let total = self.total(ctx);
        if total <= 0.0 {
            return None;
        }
        let target = u * total;
        let mut acc = 0.0;
        let mut last = None;
        for (i, e) in self.entries.iter().enumerate() {
            let w = self.weight(e, ctx);
            if w > 0.0 {
                last = Some((i, w));
                acc += w;
                if target < acc {
                    break;
                }
            }
        }
        // Rounding can leave u·total at or past the last running sum: the last light's.
        let (i, w) = last?;
        positive(i, w / total)
    }

    fn pmf(&self, ctx: &LightCtx, light: usize) -> f32 {
        let total = self.total(ctx);
        if total <= 0.0 {
            return 0.0;
        }
        (self.weight(&self.entries[light], ctx) / total) as f32
    }
}
