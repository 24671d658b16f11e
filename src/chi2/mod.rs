//! One χ² goodness-of-fit harness for every direction sampler (after Mitsuba 3's
//! `ChiSquareTest`): histogram the samples on an equal-area grid of a spherical cap, integrate
//! the sampler's pdf over each cell for the expected counts, pool cells expecting < 5, and take
//! p = Q(dof/2, χ²/2). A sample where the pdf is zero, a non-finite sample, or a returned pdf
//! that disagrees with `pdf()` is a hard failure.
//!
//! Each sampler's cases live beside it (`chi2_cases()` in `sampling::warp`, `bsdf`, each
//! light's file, `env`), built through one adapter, [`WarpCase`] (sample(u), pdf(ω), and the
//! cap holding the support); [`registry`] only concatenates them.

pub mod image;
pub mod registry;

use crate::geometry::Ray;
use crate::geometry::triangle::{Triangle, WatertightRay};
use crate::lights::{Light, LightCtx, LightHit, LightMethods};
use crate::math::Frame;
use glam::{DVec3, Vec3};
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// A spherical cap around `axis` with 1 - cos θ ≤ `h`, parameterised by
/// (a, b) = ((1 - cos θ)/h, φ/2π) ∈ [0,1)²: equal-area, so a grid on (a, b) has cells of equal
/// solid angle 2πh/cells. A cap hugging a sampler's support keeps tiny cones and sharp lobes
/// resolvable; h = 2 is the whole sphere.
#[derive(Clone, Copy, Debug)]
pub struct Chart {
    pub frame: Frame,
    pub h: f64,
}

impl Chart {
    pub fn sphere() -> Self {
        Chart {
            frame: Frame::from_normal(Vec3::Z),
            h: 2.0,
        }
    }

    pub fn cap(axis: Vec3, h: f64) -> Self {
        Chart {
            frame: Frame::from_normal(axis.normalize()),
            h: h.min(2.0),
        }
    }

    /// Chart coordinates of a unit direction; a ≥ 1 means outside the cap.
    pub fn coords(&self, w: Vec3) -> (f64, f64) {
        let l = self.frame.to_local(w).as_dvec3();
        let xy2 = l.x * l.x + l.y * l.y;
        // 1 - cos θ without cancellation near the axis.
        let omc = if l.z > 0.0 {
            xy2 / (1.0 + l.z)
        } else {
            1.0 - l.z
        };
        let mut b = l.y.atan2(l.x) / (2.0 * PI);
        if b < 0.0 {
            b += 1.0;
        }
        (omc / self.h, b.min(1.0 - 1e-12))
    }

    pub fn direction(&self, a: f64, b: f64) -> Vec3 {
        let omc = a * self.h;
        let sin = (omc * (2.0 - omc)).max(0.0).sqrt();
        let phi = 2.0 * PI * b;
        self.frame
            .to_world(DVec3::new(sin * phi.cos(), sin * phi.sin(), 1.0 - omc).as_vec3())
            .normalize()
    }

    /// Solid angle per unit area of (a, b).
    pub fn jacobian(&self) -> f64 {
        2.0 * PI * self.h
    }
}

type SampleFn = Box<dyn Fn([f32; 3]) -> Option<(Vec3, f32)>>;
type PdfFn = Box<dyn Fn(Vec3) -> f64>;

/// A sampler under test: `sample(u)` gives a unit direction and the solid-angle pdf it claims
/// (None: no sample, weight 0), `pdf(w)` the density as the sampler's own pdf routine computes
/// it. The chart must contain the sampler's support.
pub struct WarpCase {
    pub label: String,
    pub sample: SampleFn,
    pub pdf: PdfFn,
    /// Fraction of samples allowed to disagree with `pdf()` by rounding (see [`DEFAULT_SLACK`]).
    pub mismatch_slack: f64,
    pub chart: Chart,
}

/// Boundary samples can fall off a shape by f32 rounding when the harness re-finds them; more
/// than 1e-5·N such events is a real disagreement (hypothesis.h's lenient rule).
pub const DEFAULT_SLACK: f64 = 1e-5;

#[derive(Clone, Debug)]
pub struct Histogram {
    pub res_a: usize,
    pub res_b: usize,
    pub observed: Vec<f64>,
    pub expected: Vec<f64>,
    pub outside: u64,
}

#[derive(Clone, Debug)]
pub struct Chi2Result {
    pub label: String,
    pub samples: u64,
    pub p_value: f64,
    pub chi2: f64,
    pub dof: usize,
    /// Why the test failed regardless of its p-value.
    pub hard_failure: Option<String>,
    pub histogram: Histogram,
}

/// The line `dibench warp` prints: statistic, degrees of freedom, p-value and sample count.
impl std::fmt::Display for Chi2Result {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}: χ² = {:.1}, dof = {}, p = {:.4e} ({} samples)",
            self.label, self.chi2, self.dof, self.p_value, self.samples
        )
    }
}

impl Chi2Result {
    pub fn passes(&self, alpha: f64) -> bool {
        self.hard_failure.is_none() && self.p_value >= alpha
    }
}

/// Šidák-corrected per-test significance for a suite of `tests` at family-wise level `alpha`.
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / tests as f64)
}

pub type Params = BTreeMap<String, f64>;

/// Builds a case from parameters, or says why the parameters are invalid.
pub type BuildFn = Box<dyn Fn(&Params) -> Result<WarpCase, String>>;

/// A sampler as registered for the χ² suite and `dibench warp`: a name, its parameters with
/// defaults, the parameter sets the test suite runs (extremes included), and a constructor
/// that builds the [`WarpCase`] from parameters.
pub struct WarpEntry {
    pub name: String,
    pub describe: &'static str,
    /// Parameters and their defaults.
    pub params: &'static [(&'static str, f64)],
    /// Overrides the test suite runs, one parameter set each (empty: the defaults).
    pub suite: &'static [&'static [(&'static str, f64)]],
    /// The lecture's inconsistent pair: kept so the harness can show that it fails.
    pub expect_fail: bool,
    pub build: BuildFn,
}

impl WarpEntry {
    pub fn new(
        name: impl Into<String>,
        describe: &'static str,
        params: &'static [(&'static str, f64)],
        suite: &'static [&'static [(&'static str, f64)]],
        build: impl Fn(&Params) -> Result<WarpCase, String> + 'static,
    ) -> Self {
        WarpEntry {
            name: name.into(),
            describe,
            params,
            suite,
            expect_fail: false,
            build: Box::new(build),
        }
    }

    /// Defaults overridden by `overrides`; unknown names are errors.
    pub fn params(&self, overrides: &[(String, f64)]) -> Result<Params, String> {
        let mut p: Params = self
            .params
            .iter()
            .map(|(k, v)| (k.to_string(), *v))
            .collect();
        for (k, v) in overrides {
            if !p.contains_key(k) {
                let known: Vec<_> = self.params.iter().map(|(k, _)| *k).collect();
                return Err(format!(
                    "sampler `{}` has no parameter `{k}` (parameters: {})",
                    self.name,
                    known.join(", ")
                ));
            }
            if !v.is_finite() {
                return Err(format!("parameter `{k}` must be finite, got {v}"));
            }
            p.insert(k.clone(), *v);
        }
        Ok(p)
    }

    /// The parameter sets of the test suite.
    pub fn suite_params(&self) -> Vec<Params> {
        let sets: Vec<&[(&str, f64)]> = if self.suite.is_empty() {
            vec![&[]]
        } else {
            self.suite.to_vec()
        };
        sets.into_iter()
            .map(|s| {
                self.params(
                    &s.iter()
                        .map(|(k, v)| (k.to_string(), *v))
                        .collect::<Vec<_>>(),
                )
                .expect("suite parameters are valid")
            })
            .collect()
    }
}

/// `name(k=v, ...)`: a case's label.
/// No χ² cases: for a registry entry with no density of its own to test (a delta light, or a
/// sampler tested elsewhere).
pub fn no_cases() -> Vec<WarpEntry> {
    Vec::new()
}

pub fn label(name: &str, p: &Params) -> String {
    let args: Vec<String> = p.iter().map(|(k, v)| format!("{k}={v}")).collect();
    format!("{name}({})", args.join(", "))
}

/// Parameter `k` as f32.
pub fn param(p: &Params, k: &str) -> f32 {
    p[k] as f32
}

/// 1 - cos θ about +z from a unit direction, exact near the pole.
pub fn omc_z(w: Vec3) -> f32 {
    if w.z > 0.0 {
        (w.x * w.x + w.y * w.y) / (1.0 + w.z)
    } else {
        1.0 - w.z
    }
}

/// The light adapter: a light seen from the origin, sampled by `methods`, with its pdf found
/// by locating where a direction meets the light (`hit`: the point and the light's part) and
/// asking the light's own pdf routine. The chart must hold the support.
pub fn light_case(
    label: String,
    light: impl Light + 'static,
    methods: LightMethods,
    hit: impl Fn(Vec3) -> Option<(Vec3, u32)> + 'static,
    chart: Chart,
) -> WarpCase {
    let light = std::sync::Arc::new(light);
    let l2 = light.clone();
    let ctx = LightCtx {
        p: Vec3::ZERO,
        n: chart.frame.n,
    };
    WarpCase {
        label,
        sample: Box::new(move |u| light.sample(&ctx, u, &methods).map(|s| (s.wi, s.pdf))),
        pdf: Box::new(move |w| match hit(w) {
            Some((q, local)) => l2.pdf(&ctx, LightHit::Surface { q, local }, &methods) as f64,
            None => 0.0,
        }),
        mismatch_slack: DEFAULT_SLACK,
        chart,
    }
}

/// The smallest cap about the direction to `center` containing every point (a convex shape's
/// solid angle is bounded by its vertices), with a margin for rounding.
pub fn cap_around(center: Vec3, points: &[Vec3]) -> Chart {
    let axis = center.normalize();
    let h = points
        .iter()
        .map(|p| 0.5 * (axis.as_dvec3() - p.normalize().as_dvec3()).length_squared())
        .fold(0.0f64, f64::max);
    Chart::cap(axis, (h * 1.02).max(1e-9))
}

/// The first of `tris` a ray from the origin along `w` hits: the point and the index.
pub fn first_hit(tris: &[Triangle], w: Vec3) -> Option<(Vec3, u32)> {
    let ray = Ray::new(Vec3::ZERO, w, f32::INFINITY);
    let wr = WatertightRay::new(w);
    let mut best: Option<(f32, Vec3, u32)> = None;
    for (i, t) in tris.iter().enumerate() {
        if let Some(h) = t.intersect(&ray, &wr)
            && best.is_none_or(|b| h.t < b.0)
        {
            best = Some((h.t, t.point(h.b1, h.b2), i as u32));
        }
    }
    best.map(|(_, q, i)| (q, i))
}

/// Low-discrepancy-free, reproducible uniforms: a PCG stream per case.
fn uniforms(seed: u64) -> crate::sampling::stream::SampleStream {
    crate::sampling::stream::SampleStream::new(seed, 0x636869, 0, 0)
}

/// Runs the χ² test with `samples` samples on a `res_a` × `res_b` grid.
pub fn run(case: &WarpCase, samples: u64, res_a: usize, res_b: usize, seed: u64) -> Chi2Result {
    let cells = res_a * res_b;
    let mut observed = vec![0.0f64; cells];
    let mut outside = 0u64;
    let mut hard_failure = None;
    let mut rng = uniforms(seed);
    let mut mismatches = 0u64;
    let mut first_mismatch = String::new();
    for _ in 0..samples {
        let u = [rng.next_1d(), rng.next_1d(), rng.next_1d()];
        let Some((w, pdf)) = (case.sample)(u) else {
            continue;
        };
        if !w.is_finite() || !pdf.is_finite() || (w.length() - 1.0).abs() > 1e-4 {
            hard_failure.get_or_insert(format!(
                "non-finite or non-unit sample {w} with pdf {pdf} at u = {u:?}"
            ));
            continue;
        }
        let eval = (case.pdf)(w);
        // Sample/pdf consistency: the pdf a sample reports is the pdf of that direction.
        if ((pdf as f64) - eval).abs() > 1e-3 * eval.max(pdf as f64) {
            mismatches += 1;
            if first_mismatch.is_empty() {
                first_mismatch = format!("sample reports pdf {pdf} but pdf() = {eval} at {w}");
            }
        }
        let (a, b) = case.chart.coords(w);
        if a >= 1.0 {
            outside += 1;
            continue;
        }
        let i = ((a * res_a as f64) as usize).min(res_a - 1);
        let j = ((b * res_b as f64) as usize).min(res_b - 1);
        observed[i * res_b + j] += 1.0;
    }
    let allowed = (DEFAULT_SLACK * samples as f64).max(1.0) as u64;
    if mismatches > (case.mismatch_slack * samples as f64).max(1.0) as u64 {
        hard_failure.get_or_insert(format!(
            "{mismatches} samples disagree with pdf(), e.g. {first_mismatch}"
        ));
    }
    if outside > allowed {
        hard_failure.get_or_insert(format!(
            "{outside} samples outside the chart's cap (where the pdf is taken to be zero)"
        ));
    }
    let expected = expected_counts(case, samples, res_a, res_b);
    let in_zero: f64 = observed
        .iter()
        .zip(&expected)
        .filter(|&(_, &e)| e == 0.0)
        .map(|(&o, _)| o)
        .sum();
    if in_zero > allowed as f64 {
        hard_failure.get_or_insert(format!("{in_zero} samples in cells where the pdf is zero"));
    }
    let total_expected: f64 = expected.iter().sum::<f64>() / samples as f64;
    if total_expected > 1.1 {
        hard_failure.get_or_insert(format!(
            "the pdf integrates to {total_expected:.3} over the cap"
        ));
    }
    let (chi2, dof) = pearson(&observed, &expected);
    let p_value = if dof == 0 {
        1.0
    } else {
        statrs::function::gamma::gamma_ur(dof as f64 / 2.0, chi2 / 2.0)
    };
    Chi2Result {
        label: case.label.clone(),
        samples,
        p_value,
        chi2,
        dof,
        hard_failure,
        histogram: Histogram {
            res_a,
            res_b,
            observed,
            expected,
            outside,
        },
    }
}

/// Expected counts: N ∫cell pdf dω by a midpoint rule, 8×8 per cell, refined to 64×64 in cells
/// where the pdf is not constant (support edges, lobes): boundary cells are where a coarse rule
/// errs. Peaky pdfs are handled by a chart that zooms onto them.
fn expected_counts(case: &WarpCase, samples: u64, res_a: usize, res_b: usize) -> Vec<f64> {
    let jac = case.chart.jacobian();
    let cell_area = 1.0 / (res_a * res_b) as f64;
    let integrate = |i: usize, j: usize, ires: usize| {
        let (mut s, mut lo, mut hi) = (0.0, f64::INFINITY, 0.0f64);
        for si in 0..ires {
            for sj in 0..ires {
                let a = (i as f64 + (si as f64 + 0.5) / ires as f64) / res_a as f64;
                let b = (j as f64 + (sj as f64 + 0.5) / ires as f64) / res_b as f64;
                let v = (case.pdf)(case.chart.direction(a, b));
                s += v;
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        (s / (ires * ires) as f64, lo != hi)
    };
    let coarse: Vec<(f64, bool)> = (0..res_a * res_b)
        .map(|k| integrate(k / res_b, k % res_b, 8))
        .collect();
    // Refine where the pdf varies inside a cell or differs from a neighbour's: a support edge
    // can clip a cell's corner between the coarse points.
    let differs = |i: usize, j: usize| {
        let own = coarse[i * res_b + j].0;
        (-1i64..=1).any(|di| {
            (-1i64..=1).any(|dj| {
                let (ni, nj) = (i as i64 + di, (j as i64 + dj).rem_euclid(res_b as i64));
                ni >= 0
                    && (ni as usize) < res_a
                    && coarse[ni as usize * res_b + nj as usize].0 != own
            })
        })
    };
    let mut out = vec![0.0; res_a * res_b];
    for i in 0..res_a {
        for j in 0..res_b {
            let (mut mean, varies) = coarse[i * res_b + j];
            if varies || differs(i, j) {
                mean = integrate(i, j, 64).0;
            }
            out[i * res_b + j] = samples as f64 * mean * cell_area * jac;
        }
    }
    out
}

/// Pearson's statistic with cells expecting fewer than 5 pooled (Mitsuba's rule): returns
/// (χ², degrees of freedom).
pub fn pearson(observed: &[f64], expected: &[f64]) -> (f64, usize) {
    let mut idx: Vec<usize> = (0..expected.len()).collect();
    idx.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut pool_o, mut pool_e, mut chi2, mut terms) = (0.0, 0.0, 0.0, 0usize);
    for k in idx {
        let (o, e) = (observed[k], expected[k]);
        if e == 0.0 {
            continue; // counted as a hard failure if observed > 0
        }
        if e < 5.0 {
            pool_o += o;
            pool_e += e;
            if pool_e >= 5.0 {
                chi2 += (pool_o - pool_e).powi(2) / pool_e;
                terms += 1;
                pool_o = 0.0;
                pool_e = 0.0;
            }
            continue;
        }
        chi2 += (o - e).powi(2) / e;
        terms += 1;
    }
    if pool_e > 0.0 {
        chi2 += (pool_o - pool_e).powi(2) / pool_e;
        terms += 1;
    }
    (chi2, terms.saturating_sub(1))
}

/// χ² test of a discrete distribution against its pmf.
pub fn run_discrete(pmf: &[f64], sample: impl Fn(f32) -> usize, samples: u64, seed: u64) -> f64 {
    let mut observed = vec![0.0; pmf.len()];
    let mut rng = uniforms(seed);
    for _ in 0..samples {
        observed[sample(rng.next_1d())] += 1.0;
    }
    let expected: Vec<f64> = pmf.iter().map(|p| p * samples as f64).collect();
    let (chi2, dof) = pearson(&observed, &expected);
    if dof == 0 {
        1.0
    } else {
        statrs::function::gamma::gamma_ur(dof as f64 / 2.0, chi2 / 2.0)
    }
}
