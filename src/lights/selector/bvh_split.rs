//! The light BVH with splitting where its importance bound is loose (Conty Estevez & Kulla
//! 2018, §5): a node that the shading point is inside of, or that subtends more than 30°
//! (sin θb ≥ 1/2, where 1/d² varies ninefold across it), counts as the sum of its children's
//! importances, two levels down at most. Conty Estevez & Kulla draw one light from each part
//! of a split and add them, several shadow rays per shading point; dibench traces one, so the
//! parts compete for it in proportion to their own importances instead.

use super::bvh::{LightBvh, Split};
use super::{LightSelector, SelectorType};
use crate::lights::bounds::ImportanceModel;

/// The split criterion and depth `bvh-split` uses.
pub const SPLIT: Split = Split {
    min_sin: 0.5,
    depth: 2,
};

pub static BVH_SPLIT: SelectorType = SelectorType {
    name: "bvh-split",
    describe: "light BVH, a node's bound replaced by its children's where the point is inside it or it subtends > 30° (2 levels)",
    build: |lights| {
        LightBvh::build(lights, ImportanceModel::STANDARD, Some(SPLIT))
            .map(|b| Box::new(b) as Box<dyn LightSelector>)
    },
};
