//! A strategy evaluated at one given shading point, with single rays: the estimator behind the
//! unbiasedness tests and the stress suite, where a closed form is known for one point.

use super::{Estimator, Probes, ShadingPoint, Strategy};
use crate::prepare::{PreparedScene, SceneView};
use crate::render::{emission_contribution, escape_contribution};
use crate::sampling::generator::MAX_DIMENSIONS;
use crate::sampling::stream::name_id;
use crate::sampling::{Dims, GENERATORS, SampleGenerator, SampleKey, Setup};
use crate::stats::Welford;
use glam::Vec3;

/// The radiance one sample's probes contribute, traced one ray at a time.
pub fn probe_radiance(
    scene: &PreparedScene,
    view: &SceneView,
    estimator: &dyn Estimator,
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
            Some(hit) => emission_contribution(view, estimator, sp, &e, &hit),
            None => escape_contribution(view, estimator, sp, &e),
        };
    }
    l
}

/// Calls `each` with sample i's radiance at `sp` for i in 0..samples, each sample keyed by
/// (seed, strategy, no pixel, i) on the default generator; Err when the strategy does not
/// apply to the scene.
pub fn for_each_sample(
    scene: &PreparedScene,
    strategy: &dyn Strategy,
    sp: &ShadingPoint,
    samples: u64,
    seed: u64,
    each: impl FnMut(Vec3),
) -> Result<(), String> {
    for_each_sample_with(GENERATORS[0], scene, strategy, sp, samples, seed, each)
}

/// [`for_each_sample`] drawing from `generator`, told that `samples` samples will be taken
/// (so a stratified generator stratifies them).
pub fn for_each_sample_with(
    generator: &dyn SampleGenerator,
    scene: &PreparedScene,
    strategy: &dyn Strategy,
    sp: &ShadingPoint,
    samples: u64,
    seed: u64,
    mut each: impl FnMut(Vec3),
) -> Result<(), String> {
    let view = scene.view(strategy.integrand());
    let estimator = strategy.bind(view)?;
    let setup = Setup::point(estimator.layout(), Some(samples));
    generator.check(&setup)?;
    let dims = setup.layout.len();
    if dims > MAX_DIMENSIONS {
        return Err(format!("{dims} dimensions; at most {MAX_DIMENSIONS}"));
    }
    let id = name_id(&strategy.name());
    let mut values = [0.0f32; MAX_DIMENSIONS];
    for i in 0..samples {
        let key = SampleKey {
            seed,
            strategy: id,
            pixel: u64::MAX,
            index: i,
        };
        generator.fill(&setup, key, &mut values[..dims]);
        let probes = estimator.sample(sp, &mut Dims::new(&values[..dims]));
        each(probe_radiance(
            scene,
            &view,
            estimator.as_ref(),
            sp,
            &probes,
        ));
    }
    Ok(())
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
    estimate_at_with(GENERATORS[0], scene, strategy, sp, samples, seed)
}

/// [`estimate_at`] drawing from `generator`. For a generator whose samples are not
/// independent the Welford variance is not the variance of the mean: use replicates with
/// different seeds (`closed_form::PointCase::check_with` does).
pub fn estimate_at_with(
    generator: &dyn SampleGenerator,
    scene: &PreparedScene,
    strategy: &dyn Strategy,
    sp: &ShadingPoint,
    samples: u64,
    seed: u64,
) -> [Welford; 3] {
    let mut stats = [Welford::default(); 3];
    for_each_sample_with(generator, scene, strategy, sp, samples, seed, |l| {
        for (c, s) in stats.iter_mut().enumerate() {
            s.add(l[c] as f64);
        }
    })
    .unwrap_or_else(|why| panic!("strategy `{}` does not apply: {why}", strategy.name()));
    stats
}
