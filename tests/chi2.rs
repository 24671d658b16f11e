//! The χ² suite: every registered sampler, at every parameter set of its suite (extremes
//! included), passes at a family-wise significance of 1 % (Šidák-corrected) with no hard
//! failure; the lecture's inconsistent Phong pair fails, which shows the test has teeth.

use dibench::chi2::registry::registry;
use dibench::chi2::{run, run_discrete, sidak};
use dibench::sampling::discrete::DiscreteDistribution;

const SAMPLES: u64 = 1_000_000;
const FAMILY_ALPHA: f64 = 0.01;

#[test]
fn every_sampler_passes_chi2() {
    use rayon::prelude::*;
    let entries = registry();
    let cases: Vec<_> = entries
        .iter()
        .enumerate()
        .filter(|(_, e)| !e.expect_fail)
        .flat_map(|(i, e)| e.suite_params().into_iter().map(move |p| (i, p)))
        .collect();
    let alpha = sidak(FAMILY_ALPHA, cases.len() + 1);
    let mut failures = Vec::new();
    // Cases run in parallel (a case's closures are not Send, so each worker builds its own
    // from a fresh registry); the seeds stay per case, so the results do not change.
    let results: Vec<_> = cases
        .par_iter()
        .enumerate()
        .map(|(k, (i, params))| {
            let case = (registry()[*i].build)(params).unwrap();
            run(&case, SAMPLES, 40, 80, 1000 + k as u64)
        })
        .collect();
    for r in results {
        eprintln!(
            "{:<60} p = {:.4} (χ² {:.1}, dof {})",
            r.label, r.p_value, r.chi2, r.dof
        );
        if !r.passes(alpha) {
            failures.push(format!(
                "{}: p = {:.3e} < {alpha:.2e} {}",
                r.label,
                r.p_value,
                r.hard_failure.unwrap_or_default()
            ));
        }
        assert!(
            r.dof >= 10,
            "{}: only {} degrees of freedom: the test has no resolution",
            r.label,
            r.dof
        );
    }
    assert!(failures.is_empty(), "χ² failures:\n{}", failures.join("\n"));
}

#[test]
fn the_lectures_phong_pair_fails() {
    let entry = registry()
        .into_iter()
        .find(|e| e.name == "phong-lecture")
        .unwrap();
    for params in entry.suite_params() {
        let r = run(&(entry.build)(&params).unwrap(), SAMPLES, 40, 80, 7);
        assert!(
            r.p_value < 1e-6,
            "{}: the inconsistent pair passed (p = {})",
            r.label,
            r.p_value
        );
    }
}

/// Area-proportional triangle choice and power-proportional light choice, with a 1e8 weight
/// ratio and zero weights.
#[test]
fn discrete_distribution_chi2() {
    let weights = [1e-8f32, 0.3, 0.0, 1.0, 0.25, 2.5, 0.0, 0.7];
    let d = DiscreteDistribution::new(&weights).unwrap();
    let pmf: Vec<f64> = (0..weights.len()).map(|i| d.pmf(i) as f64).collect();
    let p = run_discrete(&pmf, |u| d.sample(u), SAMPLES, 3);
    assert!(p > sidak(FAMILY_ALPHA, 2), "p = {p}");
    // A wrong pmf must be rejected: swap two entries.
    let mut wrong = pmf.clone();
    wrong.swap(1, 4);
    assert!(run_discrete(&wrong, |u| d.sample(u), SAMPLES, 3) < 1e-6);
}

/// The environment χ² cases have teeth: a cube-map pdf that forgets the gnomonic Jacobian
/// (texel probability spread uniformly over the face's (a, b) square, normalised over the
/// sphere) is rejected.
#[test]
fn an_environment_pdf_without_its_jacobian_fails() {
    use dibench::chi2::{Chart, WarpCase};
    use dibench::env::synthetic_environment;
    use dibench::env::{EnvMethod, EnvSampler, Environment, Repr};
    use std::sync::Arc;
    let m = EnvMethod {
        repr: Repr::Cube,
        sampler: EnvSampler::Cdf,
    };
    let env = Arc::new(Environment::build_with(
        &synthetic_environment(50.0),
        [16; 4],
    ));
    let (e1, e2) = (env.clone(), env);
    // Wrong: pdf × J / mean J, i.e. as if dω/(du dv) were constant (4π).
    let wrong = move |w: glam::Vec3| {
        let uv = Repr::Cube.dir_to_uv(w);
        e2.pdf(m, w) as f64 * Repr::Cube.jacobian(uv) as f64 / (4.0 * std::f64::consts::PI)
    };
    let case = WarpCase {
        label: "cube pdf without Jacobian".into(),
        sample: Box::new(move |u| e1.sample(m, [u[0], u[1]]).map(|s| (s.wi, s.pdf))),
        pdf: Box::new(wrong),
        // The sample's own pdf is right; only the pdf() under test is wrong.
        mismatch_slack: 1.0,
        chart: Chart::sphere(),
    };
    let r = run(&case, SAMPLES, 40, 80, 11);
    assert!(
        r.p_value < 1e-6 || r.hard_failure.is_some(),
        "the Jacobian-free pdf passed (p = {})",
        r.p_value
    );
}

/// The GGX χ² cases have teeth: a visible-normal pdf that forgets its G1(wo) term,
/// D(h)/(4 cos θo) for the reflected direction, is rejected at views where G1 < 1.
#[test]
fn a_vndf_pdf_without_g1_fails() {
    use dibench::bsdf::MicrofacetSampler;
    use dibench::bsdf::ggx::{Ggx, chi2_view, ggx_warp_case};
    for (alpha, theta) in [(0.3f32, 60.0f32), (1.0, 89.0), (0.05, 89.0)] {
        let g = Ggx {
            ax: alpha,
            ay: alpha,
        };
        let wo = chi2_view(theta);
        let case = ggx_warp_case(
            format!("vndf without G1 (alpha {alpha}, theta_o {theta})"),
            g,
            wo,
            move |u| MicrofacetSampler::Vndf.sample_half_vector(&g, wo, u),
            move |h| {
                if wo.dot(h) > 0.0 {
                    g.d(h) / (4.0 * wo.z)
                } else {
                    0.0
                }
            },
        );
        let r = run(&case, SAMPLES, 40, 80, 13);
        assert!(
            r.p_value < 1e-6 || r.hard_failure.is_some(),
            "{}: passed (p = {})",
            r.label,
            r.p_value
        );
        // And the right pdf passes the same configuration.
        let right = ggx_warp_case(
            "vndf".into(),
            g,
            wo,
            move |u| MicrofacetSampler::Vndf.sample_half_vector(&g, wo, u),
            move |h| MicrofacetSampler::Vndf.pdf_half(&g, wo, h),
        );
        let r = run(&right, SAMPLES, 40, 80, 13);
        assert!(
            r.passes(1e-3),
            "{}: p = {} {:?}",
            r.label,
            r.p_value,
            r.hard_failure
        );
    }
}
