//! Light selection, apart from the lights (pbrt-v4 `LightSampler`): which light a light
//! sample goes to, with what probability, given the shading point and its normal. A selector
//! is built once per scene from its lights; the strategy that uses it names it.
//!
//! Every selector returns the probability it sampled with, and `pmf` recomputes the same
//! number by the same arithmetic, so the two agree exactly; the pmf over all lights sums to 1
//! wherever some light can be selected, and no light that can light the point gets 0.

use super::{LaneQuery, Light, LightCtx};
use crate::simd::WIDTH as LANES;

/// A distribution over a scene's lights that may depend on where it is asked from.
pub trait LightSelector: Send + Sync {
    /// A light index and the probability of having picked it, for u in [0, 1) (48 random
    /// bits: see [`super::selection_number`]); None when no light can be picked from `ctx`.
    fn sample(&self, ctx: &LightCtx, u: f64) -> Option<(usize, f32)>;

    /// The probability that [`Self::sample`] returns `light` from `ctx`.
    fn pmf(&self, ctx: &LightCtx, light: usize) -> f32;

    /// [`Self::sample`] for the lanes of `mask` of a packet (their points in `q`, their
    /// numbers in `u`): each picked lane's light and probability in `light` and `pmf`, other
    /// lanes left as they are; returns the lanes that picked one. The default asks lane by
    /// lane; a selector that ignores the point overrides it with one loop over the numbers
    /// (no dynamic call and no point gathered per lane). Must give what `sample` gives.
    fn sample_lanes(
        &self,
        q: &LaneQuery,
        u: &[f64; LANES],
        mask: u32,
        light: &mut [usize; LANES],
        pmf: &mut [f32; LANES],
    ) -> u32 {
        let mut picked = 0u32;
        let mut rest = mask;
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            if let Some((i, p)) = self.sample(&q.ctx(lane), u[lane]) {
                (light[lane], pmf[lane]) = (i, p);
                picked |= 1 << lane;
            }
        }
        picked
    }

    /// What [`Self::sample`] returns from every point for every u, where that is one answer
    /// (a selector over one light that can always pick it): callers may skip asking per
    /// sample. None by default, always correct.
    fn constant(&self) -> Option<(usize, f32)> {
        None
    }
}

/// [`LightSelector::sample_lanes`] of a selector that ignores the point (power, uniform):
/// `pick(u)` for each lane of `mask`, every one of which picks a light.
pub(crate) fn point_free_lanes(
    u: &[f64; LANES],
    mask: u32,
    light: &mut [usize; LANES],
    pmf: &mut [f32; LANES],
    pick: impl Fn(f64) -> (usize, f32),
) -> u32 {
    let mut rest = mask;
    while rest != 0 {
        let lane = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        (light[lane], pmf[lane]) = pick(u[lane]);
    }
    mask
}

/// Builds a selector over a scene's lights, or says why it cannot select among them.
pub type BuildSelector = fn(&[Box<dyn Light>]) -> Result<Box<dyn LightSelector>, String>;

/// A kind of selector, as registered: its name (part of a strategy's name when it is not the
/// default) and how it is built over a scene's lights.
pub struct SelectorType {
    pub name: &'static str,
    pub describe: &'static str,
    /// Err when it cannot select among these lights (e.g. no light with positive power).
    pub build: BuildSelector,
}

impl std::fmt::Debug for SelectorType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

impl PartialEq for SelectorType {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self, other)
    }
}

impl Eq for SelectorType {}

crate::plugin::registry! {
    /// Every light selector, in listing order; the first is the default.
    pub static SELECTORS: SelectorType = [
        power::POWER,
        uniform::UNIFORM,
        bvh::BVH,
        bvh_split::BVH_SPLIT,
        exhaustive::EXHAUSTIVE,
    ];
}

/// The selector strategies use unless they name another.
pub fn default_selector() -> &'static SelectorType {
    SELECTORS[0]
}

pub fn by_name(name: &str) -> Option<&'static SelectorType> {
    SELECTORS.iter().copied().find(|s| s.name == name)
}

/// u in [0, 1) rescaled after a choice that took [lo, lo + p): uniform on [0, 1) again,
/// clamped below 1 against rounding.
#[inline]
pub fn remap(u: f64, lo: f64, p: f64) -> f64 {
    ((u - lo) / p).min(1.0 - f64::EPSILON / 2.0)
}
