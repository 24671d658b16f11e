//! Backends by name, for `--backend` and the cross-check: `obvhs` always, `embree` when built
//! with `--features embree`.

use super::Geometry;
use super::Tracer;
use super::bvh::ObvhsTracer;
use crate::error::{Error, Result};
use std::sync::Arc;

/// The compiled-in backends; the first is the default and the cross-check's reference.
pub const AVAILABLE: &[&str] = &[
    "obvhs",
    #[cfg(feature = "embree")]
    "embree",
];

pub const DEFAULT: &str = "obvhs";

/// Builds the named backend over `geometry`; an unknown or not-compiled-in name is an error
/// listing the available ones.
pub fn build(name: &str, geometry: Arc<Geometry>) -> Result<Box<dyn Tracer>> {
    match name {
        "obvhs" => Ok(Box::new(ObvhsTracer::build(geometry))),
        #[cfg(feature = "embree")]
        "embree" => Ok(Box::new(super::embree::EmbreeTracer::build(geometry)?)),
        _ => Err(Error::Usage(format!(
            "unknown backend `{name}` (available: {}{})",
            AVAILABLE.join(", "),
            if cfg!(feature = "embree") {
                ""
            } else {
                "; `embree` needs scripts/setup-embree.sh and --features embree"
            }
        ))),
    }
}

/// Checks a backend name without building anything.
pub fn check(name: &str) -> Result<()> {
    if AVAILABLE.contains(&name) {
        Ok(())
    } else {
        build(name, Arc::default()).map(|_| ())
    }
}
