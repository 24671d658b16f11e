//! Sample warps (pure `sample_x(u)` / `x_pdf(..)` pairs, side by side, as in pbrt-v4's
//! `util/sampling.h`), discrete distributions and the per-pixel random streams.

pub mod discrete;
pub mod spherical;
pub mod stream;
pub mod warp;
