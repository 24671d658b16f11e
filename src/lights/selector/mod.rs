//! Light selection, apart from the lights (pbrt-v4 `LightSampler`): which light a light
//! sample goes to, with what probability, given the shading point and its normal. A selector
//! is built once per scene from its lights; the strategy that uses it names it.
//!
//! Every selector returns the probability it sampled with, and `pmf` recomputes the same
//! number by the same arithmetic, so the two agree exactly; the pmf over all lights sums to 1
//! wherever some light can be selected, and no light that can light the point gets 0.

use super::{Light, LightCtx};

/// A distribution over a scene's lights that may depend on where it is asked from.
pub trait LightSelector: Send + Sync {
    /// A light index and the probability of having picked it, for u in [0, 1) (48 random
    /// bits: see [`super::selection_number`]); None when no light can be picked from `ctx`.
    fn sample(&self, ctx: &LightCtx, u: f64) -> Option<(usize, f32)>;

    /// The probability that [`Self::sample`] returns `light` from `ctx`.
    fn pmf(&self, ctx: &LightCtx, light: usize) -> f32;

    /// What [`Self::sample`] returns from every point for every u, where that is one answer
    /// (a selector over one light that can always pick it): callers may skip asking per
    /// sample. None by default, always correct.
    fn constant(&self) -> Option<(usize, f32)> {
        None
    }
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
