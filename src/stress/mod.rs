//! The stability suite behind `dibench stress`: every applicable strategy on every stiff case
//! (`cases`), one shading point each. A sample that is NaN, infinite or negative fails the
//! case outright; where the case has a closed form, the mean must match it in a two-sided
//! z-test whose standard error comes from the estimator's own sample variance, at a
//! family-wise significance `FAMILY_ALPHA` split over all checks (Šidák).

pub mod cases;

use crate::bsdf::Bsdf;
use crate::closed_form::mean_test;
use crate::error::{Error, Result};
use crate::prepare::PreparedScene;
use crate::scene::Scene;
use crate::stats::{Welford, z_critical};
use crate::strategy::estimate::for_each_sample;
use crate::strategy::{Integrand, ShadingPoint, Strategy, applicable};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Chance that a correct suite run reports any false unbiasedness failure.
pub const FAMILY_ALPHA: f64 = 1e-3;
/// Below this effective sample size (Kish: (Σx)²/Σx² = n/(1 + σ²/μ²)) the mean rests on a
/// handful of samples, the sample variance says too little, and the z-test is not trusted:
/// e.g. area sampling a unit quad from 1e-6 below it, where all the light arrives from a
/// 1e-6-wide spot that 1e5 uniform points never hit.
pub const MIN_EFFECTIVE_SAMPLES: f64 = 100.0;

/// The shading point of a case, in f64 so the closed form sees the exact geometry.
#[derive(Clone, Copy, Debug)]
pub struct ViewPoint {
    pub p: DVec3,
    pub n: DVec3,
    /// Unit direction the point is seen along (towards the surface).
    pub view_dir: DVec3,
    pub kd: f64,
    pub ks: f64,
    pub exponent: f64,
    /// Shade with the scene's material of this name instead of the kd/ks/exponent blend.
    pub material: Option<&'static str>,
    /// Find the point by tracing a ray from here towards `p`, and shade the hit exactly as the
    /// renderer does (its computed position and error bound): the self-intersection test.
    pub trace_from: Option<DVec3>,
}

impl ViewPoint {
    /// A grey Lambertian point seen straight along its normal.
    pub fn lambert(p: DVec3, n: DVec3, albedo: f64) -> Self {
        ViewPoint {
            p,
            n,
            view_dir: -n,
            kd: albedo,
            ks: 0.0,
            exponent: 0.0,
            material: None,
            trace_from: None,
        }
    }

    /// The point's material: the named scene material, else the kd/ks/exponent blend.
    pub fn bsdf(&self, scene: &PreparedScene) -> Bsdf {
        if let Some(name) = self.material {
            let m = scene.scene.materials.iter().find(|m| m.name == name);
            return m
                .expect("a stress case names a material of its scene")
                .bsdf
                .clone();
        }
        Bsdf::blend(
            Vec3::splat(self.kd as f32),
            Vec3::splat(self.ks as f32),
            self.exponent as f32,
        )
    }

    /// The shading point with material `bsdf`, exact or found by tracing (None if the traced
    /// ray misses).
    pub fn shading_point<'a>(
        &self,
        scene: &PreparedScene,
        bsdf: &'a Bsdf,
    ) -> Option<ShadingPoint<'a>> {
        let Some(from) = self.trace_from else {
            return Some(ShadingPoint::new(
                self.p.as_vec3(),
                self.n.as_vec3(),
                self.view_dir.as_vec3(),
                bsdf,
            ));
        };
        let o = from.as_vec3();
        let dir = (self.p - from).normalize().as_vec3();
        let ray = crate::geometry::Ray::new(o, dir, f32::INFINITY);
        let hit = scene.tracer.intersect(&ray)?;
        let surf = scene.surface(&ray, &hit);
        Some(ShadingPoint::with_error(
            surf.p,
            surf.p_error,
            surf.ng,
            dir,
            bsdf,
        ))
    }
}

/// Closed-form reflected radiance as a function of the shading point actually used.
pub type ClosedForm = std::sync::Arc<dyn Fn(DVec3) -> f64 + Send + Sync>;

#[derive(Clone)]
pub struct StressCase {
    pub name: String,
    pub about: String,
    /// The scene file's text.
    pub scene: String,
    /// Files the scene refers to (name relative to the scene, content: OBJ text, EXR bytes).
    pub files: Vec<(String, Vec<u8>)>,
    pub point: ViewPoint,
    /// Closed-form reflected radiance at the point, where one is known.
    pub expected: Option<ClosedForm>,
    /// The strategies that must resolve the case (reach `MIN_EFFECTIVE_SAMPLES`); the others
    /// may legitimately never find the light (a direction sampler aiming at a 1e-6 sphere) and
    /// are reported unresolved, not failed.
    pub must_resolve: &'static [&'static str],
    /// Strategies known to miss part of the integral at any practical sample count, and why:
    /// a z-test failure is reported as unresolved with that reason instead of as a failure.
    /// (Their NaN/Inf/negative counts still fail.)
    pub known_unresolvable: &'static [&'static str],
    pub why_unresolvable: &'static str,
    /// The closed form holds in every environment representation (a constant or black map),
    /// so the cube, octahedral and HEALPix strategies run too, not only lat/long.
    pub every_env_representation: bool,
}

impl StressCase {
    /// Writes the scene and its files into `dir` as `<name>.toml`, so the case can be rendered
    /// with `compare` like any scene.
    pub fn write_to(&self, dir: &Path) -> Result<std::path::PathBuf> {
        let sub = dir.join(&self.name);
        std::fs::create_dir_all(&sub).map_err(|e| Error::Io {
            path: sub.clone(),
            source: e,
        })?;
        for (name, bytes) in &self.files {
            crate::output::write_bytes(&sub.join(name), bytes)?;
        }
        let path = sub.join("scene.toml");
        crate::output::write_bytes(&path, self.scene.as_bytes())?;
        Ok(path)
    }

    /// Parses and prepares the case's scene (its files live in a temporary directory).
    pub fn prepare(&self) -> Result<PreparedScene> {
        let dir = tempfile::tempdir().map_err(|e| Error::Io {
            path: std::env::temp_dir(),
            source: e,
        })?;
        let path = self.write_to(dir.path())?;
        Ok(PreparedScene::new(Scene::load(&path)?))
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct StressRow {
    pub case: String,
    pub strategy: String,
    pub samples: u64,
    pub nan: u64,
    pub inf: u64,
    pub negative: u64,
    pub nonzero: u64,
    pub effective_samples: f64,
    pub mean: f64,
    pub std_error: f64,
    /// Closed form, empty where none is known.
    pub expected: Option<f64>,
    pub z: Option<f64>,
    /// Per-sample variance over the squared mean (a run of n samples has relMSE ≈ this / n).
    pub rel_variance: Option<f64>,
    pub status: Status,
    pub detail: String,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    Pass,
    /// Too few non-zero samples to test, and the strategy is not expected to resolve the case.
    Unresolved,
    Fail,
}

/// Per-sample counts and moments of one (case, strategy) pair.
struct Tally {
    nan: u64,
    inf: u64,
    negative: u64,
    nonzero: u64,
    stats: Welford,
}

fn tally(
    scene: &PreparedScene,
    strategy: &dyn Strategy,
    sp: &ShadingPoint,
    n: u64,
    seed: u64,
) -> std::result::Result<Tally, String> {
    let mut t = Tally {
        nan: 0,
        inf: 0,
        negative: 0,
        nonzero: 0,
        stats: Welford::default(),
    };
    let tallied = for_each_sample(scene, strategy, sp, n, seed, |l| {
        let c = l.to_array();
        if c.iter().any(|x| x.is_nan()) {
            t.nan += 1;
            return;
        }
        if c.iter().any(|x| x.is_infinite()) {
            t.inf += 1;
            return;
        }
        if c.iter().any(|&x| x < 0.0) {
            t.negative += 1;
        }
        let x = c.iter().map(|&x| x as f64).sum::<f64>() / 3.0;
        if x != 0.0 {
            t.nonzero += 1;
        }
        t.stats.add(x);
    });
    tallied.map(|()| t)
}

/// Judges one tally. `z_crit` is the per-check critical value.
fn judge(
    case: &StressCase,
    strategy: &str,
    t: &Tally,
    expected: Option<f64>,
    z_crit: f64,
    n: u64,
) -> StressRow {
    let s = &t.stats;
    let mut row = StressRow {
        case: case.name.clone(),
        strategy: strategy.to_string(),
        samples: n,
        nan: t.nan,
        inf: t.inf,
        negative: t.negative,
        nonzero: t.nonzero,
        effective_samples: if s.mean == 0.0 {
            0.0
        } else {
            n as f64 / (1.0 + s.variance() / (s.mean * s.mean))
        },
        mean: s.mean,
        std_error: s.std_error(),
        expected,
        z: None,
        rel_variance: (s.mean != 0.0).then(|| s.variance() / (s.mean * s.mean)),
        status: Status::Pass,
        detail: String::new(),
    };
    let fail = |row: &mut StressRow, why: String| {
        row.status = Status::Fail;
        row.detail = why;
    };
    if t.nan + t.inf + t.negative > 0 {
        fail(
            &mut row,
            format!(
                "{} NaN, {} Inf, {} negative samples",
                t.nan, t.inf, t.negative
            ),
        );
        return row;
    }
    let Some(expected) = expected else {
        row.detail = "no closed form: finiteness only".into();
        return row;
    };
    if expected == 0.0 {
        // Every contribution is non-negative, so a zero integral admits only zero samples.
        if t.nonzero > 0 {
            fail(
                &mut row,
                format!("{} non-zero samples where no light arrives", t.nonzero),
            );
        }
        return row;
    }
    if row.effective_samples < MIN_EFFECTIVE_SAMPLES {
        let why = format!(
            "effective sample size {:.1} of {n} ({} non-zero)",
            row.effective_samples, t.nonzero
        );
        if case.must_resolve.contains(&strategy) {
            fail(
                &mut row,
                format!("{why}: this strategy should resolve the case"),
            );
        } else {
            row.status = Status::Unresolved;
            row.detail = why;
        }
        return row;
    }
    let test = mean_test(s, expected, z_crit);
    row.z = test.z;
    let z = test.z.unwrap_or(f64::INFINITY);
    if !test.passed {
        if case.known_unresolvable.contains(&strategy) {
            row.status = Status::Unresolved;
            row.detail = format!(
                "known: {} (mean {:.4e} vs {expected:.4e}, z = {z:.1})",
                case.why_unresolvable, s.mean
            );
            return row;
        }
        fail(
            &mut row,
            format!(
                "mean {:.6e} vs closed form {expected:.6e}: z = {z:.2}, critical {z_crit:.2}",
                s.mean
            ),
        );
    }
    row
}

/// What `dibench stress` ran and found: its setting, a row per (case, strategy), and where
/// the CSV is.
pub struct Report {
    /// The cases run, in order (names).
    pub cases: Vec<String>,
    pub samples: u64,
    pub seed: u64,
    pub threads: usize,
    pub rows: Vec<StressRow>,
    pub csv: PathBuf,
}

impl Report {
    /// The checks with status `s`.
    pub fn count(&self, s: Status) -> usize {
        self.rows.iter().filter(|r| r.status == s).count()
    }
}

/// The tables `dibench stress` prints: every row, a line per case, the totals.
impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let rows = &self.rows;
        writeln!(
            f,
            "{} cases · {} samples per strategy · seed {} · {} threads",
            self.cases.len(),
            self.samples,
            self.seed,
            self.threads
        )?;
        writeln!(
            f,
            "{:<24} {:<20} {:>5} {:>9} {:>12} {:>12} {:>7} {:>10}  status",
            "case", "strategy", "bad", "ess", "mean", "expected", "z", "rel.var"
        )?;
        let opt = |x: Option<f64>, g: &dyn Fn(f64) -> String| x.map_or("-".to_string(), g);
        for r in rows {
            writeln!(
                f,
                "{:<24} {:<20} {:>5} {:>9.0} {:>12.5e} {:>12} {:>7} {:>10}  {:?}{}{}",
                r.case,
                r.strategy,
                r.nan + r.inf + r.negative,
                r.effective_samples,
                r.mean,
                opt(r.expected, &|v| format!("{v:.5e}")),
                opt(r.z, &|v| format!("{v:.2}")),
                opt(r.rel_variance, &|v| format!("{v:.3e}")),
                r.status,
                if r.detail.is_empty() { "" } else { ": " },
                r.detail
            )?;
        }
        writeln!(f)?;
        writeln!(
            f,
            "{:<24} {:>4} {:>4} {:>10} {:>4} {:>9}  lowest relative variance",
            "case", "runs", "pass", "unresolved", "fail", "nonfinite"
        )?;
        for name in &self.cases {
            let of: Vec<_> = rows.iter().filter(|r| &r.case == name).collect();
            let n = |s: Status| of.iter().filter(|r| r.status == s).count();
            let best = of
                .iter()
                .filter(|r| r.status == Status::Pass)
                .filter_map(|r| r.rel_variance.map(|v| (v, &r.strategy)))
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map_or("-".to_string(), |(v, s)| format!("{s} {v:.2e}"));
            writeln!(
                f,
                "{:<24} {:>4} {:>4} {:>10} {:>4} {:>9}  {best}",
                name,
                of.iter().filter(|r| r.samples > 0).count(),
                n(Status::Pass),
                n(Status::Unresolved),
                n(Status::Fail),
                of.iter().map(|r| r.nan + r.inf + r.negative).sum::<u64>(),
            )?;
        }
        let bad: u64 = rows.iter().map(|r| r.nan + r.inf + r.negative).sum();
        writeln!(
            f,
            "{} checks: {} pass, {} unresolved, {} fail; {bad} non-finite or negative samples",
            rows.len(),
            self.count(Status::Pass),
            self.count(Status::Unresolved),
            self.count(Status::Fail)
        )?;
        writeln!(f, "results: {}", self.csv.display())
    }
}

/// Runs the suite on `cases` with `samples` per (case, strategy); pairs run in parallel, each
/// on its own random streams, so the result does not depend on the thread count.
pub fn run(cases: &[StressCase], samples: u64, seed: u64) -> Result<Vec<StressRow>> {
    if samples < 2 {
        return Err(Error::Usage(format!(
            "--samples must be at least 2 (a variance needs two), got {samples}"
        )));
    }
    let mut jobs = Vec::new();
    let mut points = Vec::new();
    let mut empty = Vec::new();
    let scenes = cases
        .iter()
        .map(StressCase::prepare)
        .collect::<Result<Vec<_>>>()?;
    let bsdfs: Vec<Bsdf> = cases
        .iter()
        .zip(&scenes)
        .map(|(c, s)| c.point.bsdf(s))
        .collect();
    for (k, (case, scene)) in cases.iter().zip(&scenes).enumerate() {
        let sp = case.point.shading_point(scene, &bsdfs[k]).ok_or_else(|| {
            Error::Usage(format!("stress case {}: the traced ray misses", case.name))
        })?;
        let (run, skipped) = applicable(scene);
        let run: Vec<_> = run
            .into_iter()
            .filter(|s| match s.integrand() {
                Integrand::DIRECT => true,
                Integrand::Direct(_) => case.every_env_representation,
                _ => false,
            })
            .collect();
        if run.is_empty() {
            empty.push((k, skipped));
        }
        for s in run {
            jobs.push((k, s));
        }
        points.push(sp);
    }
    let checks = jobs.len().max(1) as f64;
    let per_check_alpha = 1.0 - (1.0 - FAMILY_ALPHA).powf(1.0 / checks);
    let z_crit = z_critical(per_check_alpha);
    let mut rows: Vec<StressRow> = jobs
        .par_iter()
        .map(|(k, s)| {
            let case = &cases[*k];
            let sp = &points[*k];
            let expected = case.expected.as_ref().map(|f| f(sp.p.as_dvec3()));
            let t = tally(&scenes[*k], s.as_ref(), sp, samples, seed).map_err(|why| {
                Error::Usage(format!("stress case {}: {}: {why}", case.name, s.name()))
            })?;
            Ok(judge(case, &s.name(), &t, expected, z_crit, samples))
        })
        .collect::<Result<_>>()?;
    // A case no strategy applies to tests nothing: say so, with the reasons.
    for (k, skipped) in empty {
        let case = &cases[k];
        rows.push(StressRow {
            case: case.name.clone(),
            strategy: "-".into(),
            samples: 0,
            nan: 0,
            inf: 0,
            negative: 0,
            nonzero: 0,
            effective_samples: 0.0,
            mean: 0.0,
            std_error: 0.0,
            expected: case.expected.as_ref().map(|f| f(points[k].p.as_dvec3())),
            z: None,
            rel_variance: None,
            status: Status::Unresolved,
            detail: skipped
                .iter()
                .map(|s| format!("{}: {}", s.name, s.reason))
                .collect::<Vec<_>>()
                .join("; "),
        });
    }
    rows.sort_by_key(|r| cases.iter().position(|c| c.name == r.case));
    Ok(rows)
}
