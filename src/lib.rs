//! dibench: a research harness for Monte Carlo direct illumination.
//!
//! Data flows one way: [`scene`] (plain data from TOML) → [`prepare`] (only what the scene
//! needs) → [`tracer`] → [`strategy`] → [`film`] → [`metrics`] → [`output`] (CSV/EXR), driven
//! by [`harness`].

pub mod bounded;
pub mod bsdf;
pub mod chi2;
pub mod cli;
pub mod closed_form;
pub mod env;
pub mod error;
pub mod film;
pub mod flip;
pub mod geometry;
pub mod harness;
pub mod interrupt;
pub mod lights;
pub mod math;
pub mod metrics;
pub mod output;
pub mod plot;
pub mod plugin;
pub mod prelude;
pub mod prepare;
pub mod render;
pub mod report;
pub mod sampling;
pub mod scene;
pub mod simd;
pub mod stats;
pub mod strategy;
pub mod stress;
pub mod tracer;
