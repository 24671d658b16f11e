//! Selection in proportion to each light's (luminance) power, independent of the shading
//! point: the classic choice (pbrt-v4 `PowerLightSampler`), exact for a point that sees every
//! light equally and poor for many lights of which few are near. An alias table (Walker 1977,
//! Vose 1991) makes it O(1) per sample.

use super::{LightSelector, SelectorType, point_free_lanes};
use crate::lights::{LaneQuery, LightCtx};
use crate::simd::WIDTH as LANES;
use crate::sampling::discrete::AliasTable;

pub static POWER: SelectorType = SelectorType {
    name: "power",
    describe: "lights chosen in proportion to their power (alias table)",
    build: |lights| {
        let powers: Vec<f32> = lights.iter().map(|l| l.power()).collect();
        AliasTable::new(&powers)
            .map(|t| Box::new(PowerSelector(t)) as Box<dyn LightSelector>)
            .ok_or_else(|| "no light with positive power".to_string())
    },
};

pub struct PowerSelector(pub AliasTable);

impl PowerSelector {
    /// The light number u picks and its probability: what `sample` and `sample_lanes` return.
    fn pick(&self, u: f64) -> (usize, f32) {
        let i = self.0.sample(u);
        (i, self.0.pmf(i))
    }
}

impl LightSelector for PowerSelector {
    fn sample(&self, _ctx: &LightCtx, u: f64) -> Option<(usize, f32)> {
        Some(self.pick(u))
    }

    fn pmf(&self, _ctx: &LightCtx, light: usize) -> f32 {
        self.0.pmf(light)
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
        point_free_lanes(u, mask, light, pmf, |u| self.pick(u))
    }

    /// One light: the table's only bin, kept whole (q = 1), whatever u is.
    fn constant(&self) -> Option<(usize, f32)> {
        (self.0.len() == 1).then(|| (0, self.0.pmf(0)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lights::Light;
    use crate::lights::point::PointLight;
    use glam::Vec3;

    /// pmf ∝ power, sums to one, and `sample` reports the pmf of what it returns.
    #[test]
    fn proportional_to_power() {
        let lights: Vec<Box<dyn Light>> = [1.0f32, 3.0, 0.0, 4.0]
            .iter()
            .map(|&i| {
                Box::new(PointLight {
                    position: Vec3::ZERO,
                    intensity: Vec3::splat(i),
                }) as Box<dyn Light>
            })
            .collect();
        let s = (POWER.build)(&lights).unwrap();
        let ctx = LightCtx {
            p: Vec3::ONE,
            n: Vec3::Y,
        };
        let pmfs: Vec<f32> = (0..4).map(|i| s.pmf(&ctx, i)).collect();
        assert!((pmfs.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        assert!((pmfs[1] - 0.375).abs() < 1e-6 && pmfs[2] == 0.0);
        for k in 0..100 {
            let (i, p) = s.sample(&ctx, k as f64 / 100.0).unwrap();
            assert_eq!(p, pmfs[i]);
            assert_ne!(i, 2, "a light without power was picked");
        }
    }
}
