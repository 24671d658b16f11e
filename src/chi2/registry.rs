//! Every sampler dibench has, for the χ² suite and `dibench warp`: the concatenation of the
//! cases each module exports beside its samplers (material and light types through their
//! registries, so a new type's cases need no line here).

use super::WarpEntry;

pub fn registry() -> Vec<WarpEntry> {
    let mut v = crate::sampling::warp::chi2_cases();
    v.extend(crate::bsdf::chi2_cases());
    v.extend(crate::lights::quad::chi2_cases());
    v.extend(crate::lights::sphere::chi2_cases());
    v.extend(crate::lights::mesh::chi2_cases());
    v.extend(
        crate::lights::LIGHT_TYPES
            .iter()
            .flat_map(|t| (t.chi2_cases)()),
    );
    v.extend(crate::env::chi2_cases());
    v
}

pub fn by_name(name: &str) -> Option<WarpEntry> {
    registry().into_iter().find(|e| e.name == name)
}
