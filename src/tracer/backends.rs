//! Backends by name, for `--backend` and the cross-check: `obvhs` (obvhs's own single-ray
//! traversal) and `packet` (our SIMD packet core) always, `embree` when built with
//! `--features embree`.

use super::Geometry;
use super::Tracer;
use super::bvh::ObvhsTracer;
use super::packet::PacketTracer;
use crate::error::{Error, Result};
use crate::simd::Isa;
use std::sync::Arc;

/// The compiled-in backends; the first is the cross-check's reference.
pub const AVAILABLE: &[&str] = &[
    "obvhs",
    "packet",
    #[cfg(feature = "embree")]
    "embree",
];

/// The fastest backend that needs nothing outside crates.io.
pub const DEFAULT: &str = "packet";

/// Builds the named backend over `geometry` (`packet` at the detected ISA, which
/// `DIBENCH_ISA` can force); an unknown or not-compiled-in name is an error listing the
/// available ones.
pub fn build(name: &str, geometry: Arc<Geometry>) -> Result<Box<dyn Tracer>> {
    build_isa(name, geometry, None)
}

/// As [`build`], with the packet backend's ISA given.
pub fn build_isa(name: &str, geometry: Arc<Geometry>, isa: Option<Isa>) -> Result<Box<dyn Tracer>> {
    match name {
        "obvhs" => Ok(Box::new(ObvhsTracer::build(geometry))),
        "packet" => {
            let isa = match isa {
                Some(i) => i,
                None => Isa::detect()?,
            };
            Ok(Box::new(PacketTracer::build(geometry, isa)?))
        }
        #[cfg(feature = "embree")]
        "embree" => Ok(Box::new(super::embree::EmbreeTracer::build(geometry)?)),
        _ => Err(unknown(name)),
    }
}

/// The error for a backend name that is not compiled in, listing the available ones: a
/// backend error for `embree` built without it, a usage error for any other name.
pub fn unknown(name: &str) -> Error {
    let message = format!(
        "unknown backend `{name}` (available: {}{})",
        AVAILABLE.join(", "),
        if cfg!(feature = "embree") {
            ""
        } else {
            "; `embree` needs scripts/setup-embree.sh and --features embree"
        }
    );
    if name == "embree" {
        Error::Backend(message)
    } else {
        Error::Usage(message)
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
