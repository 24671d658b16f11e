//! A strategy evaluated at one given shading point, with single rays: the estimator behind the
//! unbiasedness tests and the stress suite, where a closed form is known for one point.

use super::{Probes, ShadingPoint, Strategy};
use crate::prepare::PreparedScene;
use crate::render::{emission_contribution, escape_contribution};
use crate::sampling::stream::{SampleStream, name_id};
use crate::stats::Welford;
use glam::Vec3;

/// The radiance one sample's probes contribute, traced one ray at a time.
pub fn probe_radiance(
    scene: &PreparedScene,
    strategy: &dyn Strategy,
    sp: &ShadingPoint,
    probes: &Probes,
) -> Vec3 {
    let mut l = Vec3::ZERO;
    if let Some(s) = probes.shadow
        && !scene.tracer.occluded(&s.ray)
    {
        l += s.value;
    }
    if let Some(e) = probes.emission {
        l += match scene.tracer.intersect(&e.ray) {
            Some(hit) => emission_contribution(scene, strategy, sp, &e, &hit),
            None => escape_contribution(scene, strategy, sp, &e),
        };
    }
    l
}

/// `samples` independent estimates of the reflected direct radiance at `sp`, as per-channel
/// running statistics.
pub fn estimate_at(
    scene: &PreparedScene,
    strategy: &dyn Strategy,
    sp: &ShadingPoint,
    samples: u64,
    seed: u64,
) -> [Welford; 3] {
    let mut stats = [Welford::default(); 3];
    let id = name_id(strategy.name());
    for i in 0..samples {
        let mut rng = SampleStream::new(seed, id, u64::MAX, i);
        let l = probe_radiance(scene, strategy, sp, &strategy.sample(scene, sp, &mut rng));
        for (c, s) in stats.iter_mut().enumerate() {
            s.add(l[c] as f64);
        }
    }
    stats
}
