//! Sample warps (pure `sample_x(u)` / `x_pdf(..)` pairs, side by side, as in pbrt-v4's
//! `util/sampling.h`), discrete distributions, and the sample generators that feed them.

pub mod discrete;
pub mod generator;
pub mod microfacet;
pub mod qmc;
pub mod spherical;
pub mod stream;
pub mod warp;

pub use generator::{
    Dimension, Dims, LaneValues, Layout, PacketDims, SampleGenerator, SampleKey, SampleKeys, Setup,
};

crate::plugin::registry! {
    /// Every sample generator, in listing order; the first is the default.
    pub static GENERATORS: dyn SampleGenerator = [
        independent::INDEPENDENT,
        stratified::STRATIFIED,
        sobol::SOBOL,
        zsobol::ZSOBOL,
    ];
}

/// The generator named `name`.
pub fn generator(name: &str) -> Option<&'static dyn SampleGenerator> {
    GENERATORS.iter().copied().find(|g| g.name() == name)
}

/// Every generator's name, comma-separated, for usage errors.
pub fn generator_names() -> String {
    GENERATORS
        .iter()
        .map(|g| g.name())
        .collect::<Vec<_>>()
        .join(", ")
}
