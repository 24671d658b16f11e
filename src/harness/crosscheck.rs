//! `dibench crosscheck`: traces fixed ray sets through every compiled-in backend and compares
//! each with `obvhs` (the reference), times them single-threaded, and renders a few passes on
//! each backend to compare the images.

use super::raysets::{self, Query, RaySet};
use crate::error::{Error, Result};
use crate::film::{Film, Image};
use crate::geometry::triangle::WatertightRay;
use crate::geometry::{Hit, Ray};
use crate::prepare::PreparedScene;
use crate::render::Renderer;
use crate::strategy;
use crate::tracer::{HitPacket, LANES, Tracer, backends};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Pass/fail thresholds (also in `--help` and the README). Mismatch fractions are of the rays in
/// a set; prim mismatches exclude ties (both primitives hit at the same t by our exact tests).
pub const MAX_HIT_MISMATCH: f64 = 1e-4;
pub const MAX_PRIM_MISMATCH: f64 = 1e-4;
pub const MAX_OCCLUSION_MISMATCH: f64 = 1e-4;
pub const MAX_T_REL_DIFF: f64 = 1e-3;
pub const MAX_IMAGE_REL_RMSE: f64 = 1e-2;
/// Relative t difference under which two different primitives count as a tie.
const TIE_T_REL: f32 = 1e-4;
pub const RENDER_PASSES: u64 = 4;
const TIMING_ROUNDS: usize = 5;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Single,
    Packet16,
}

impl Mode {
    pub fn name(self) -> &'static str {
        match self {
            Mode::Single => "single",
            Mode::Packet16 => "packet16",
        }
    }
}

/// One row of crosscheck.csv: a (ray set, backend, mode), or a render comparison (set `render`).
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub scene: String,
    pub set: String,
    pub backend: String,
    pub mode: String,
    pub rays: usize,
    pub hit_mismatch: usize,
    pub prim_mismatch: usize,
    pub ties: usize,
    pub t_rel_max: f64,
    pub occlusion_mismatch: usize,
    /// The set's natural query: occlusion for shadow rays, closest hit otherwise.
    pub timed_query: String,
    pub seconds: f64,
    pub mrays_per_s: f64,
    pub image_rel_rmse: Option<f64>,
    pub pass: bool,
}

pub struct Report {
    pub rows: Vec<Row>,
    pub csv: PathBuf,
    pub failures: Vec<String>,
}

/// The table `dibench crosscheck` prints: a line per (set, backend, mode) or render
/// comparison, then where the CSV is.
impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{:<12} {:<8} {:<9} {:>7} {:>6} {:>6} {:>5} {:>9} {:>6} {:>9} {:>8}",
            "set",
            "backend",
            "mode",
            "rays",
            "hitMM",
            "primMM",
            "ties",
            "t_rel",
            "occMM",
            "seconds",
            "Mrays/s"
        )?;
        for r in &self.rows {
            if let Some(d) = r.image_rel_rmse {
                writeln!(
                    f,
                    "{:<12} {:<8} {:<9} image relative RMSE vs obvhs {d:.3e} {}",
                    r.set,
                    r.backend,
                    r.mode,
                    if r.pass { "ok" } else { "FAIL" }
                )?;
                continue;
            }
            writeln!(
                f,
                "{:<12} {:<8} {:<9} {:>7} {:>6} {:>6} {:>5} {:>9.2e} {:>6} {:>9.4} {:>8.2}{}",
                r.set,
                r.backend,
                r.mode,
                r.rays,
                r.hit_mismatch,
                r.prim_mismatch,
                r.ties,
                r.t_rel_max,
                r.occlusion_mismatch,
                r.seconds,
                r.mrays_per_s,
                if r.pass { "" } else { "  FAIL" }
            )?;
        }
        writeln!(f, "results: {}", self.csv.display())
    }
}

/// Closest hits and occlusion of every ray of a set, single-ray or as 16-packets.
pub struct Traced {
    pub hits: Vec<Option<Hit>>,
    pub occluded: Vec<bool>,
}

pub fn trace_closest(tracer: &dyn Tracer, set: &RaySet, mode: Mode) -> Vec<Option<Hit>> {
    let mut out = Vec::with_capacity(set.rays() as usize);
    let mut hits = HitPacket::default();
    for (p, &m) in set.packets.iter().zip(&set.masks) {
        let lanes = (0..LANES).filter(|l| m & (1 << l) != 0);
        match mode {
            Mode::Single => out.extend(lanes.map(|l| tracer.intersect(&p.get(l)))),
            Mode::Packet16 => {
                if set.coherent {
                    tracer.intersect_packet_coherent(p, m, &mut hits);
                } else {
                    tracer.intersect_packet(p, m, &mut hits);
                }
                out.extend(lanes.map(|l| hits.get(l)));
            }
        }
    }
    out
}

pub fn trace_occluded(tracer: &dyn Tracer, set: &RaySet, mode: Mode) -> Vec<bool> {
    let mut out = Vec::with_capacity(set.rays() as usize);
    for (p, &m) in set.packets.iter().zip(&set.masks) {
        let lanes = (0..LANES).filter(|l| m & (1 << l) != 0);
        match mode {
            Mode::Single => out.extend(lanes.map(|l| tracer.occluded(&p.get(l)))),
            Mode::Packet16 => {
                let o = tracer.occluded_packet(p, m);
                out.extend(lanes.map(|l| o & (1 << l) != 0));
            }
        }
    }
    out
}

/// Distance at which our exact test hits primitive `prim`, if it does.
pub fn exact_t(scene: &PreparedScene, ray: &Ray, prim: u32) -> Option<f32> {
    let g = &scene.world.geometry;
    match g.sphere_index(prim) {
        None => g
            .triangles
            .get(prim as usize)?
            .intersect(ray, &WatertightRay::new(ray.dir))
            .map(|h| h.t),
        Some(s) => g.spheres.get(s)?.intersect(ray),
    }
}

/// |t_a - t_b| relative to max(t_a, largest |origin coordinate|): f32 resolves a hit point only
/// to the precision of the coordinates involved, so for a ray starting a hair above a surface far
/// from the world origin, t itself is the wrong scale.
pub fn t_rel_diff(ray: &Ray, ta: f32, tb: f32) -> f64 {
    let scale = ta
        .abs()
        .max(ray.origin.abs().max_element())
        .max(f32::MIN_POSITIVE);
    ((ta - tb).abs() / scale) as f64
}

/// Counts of disagreement between a reference and a candidate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Agreement {
    pub hit_mismatch: usize,
    pub prim_mismatch: usize,
    pub ties: usize,
    pub t_rel_max: f64,
    pub occlusion_mismatch: usize,
}

impl Agreement {
    pub fn failures(&self, rays: usize) -> Vec<String> {
        let n = rays.max(1) as f64;
        let mut f = Vec::new();
        let mut frac = |what: &str, count: usize, max: f64| {
            if count as f64 / n > max {
                f.push(format!("{what} {count}/{rays} > {max:e}"));
            }
        };
        frac("hit/miss mismatch", self.hit_mismatch, MAX_HIT_MISMATCH);
        frac("primitive mismatch", self.prim_mismatch, MAX_PRIM_MISMATCH);
        frac(
            "occlusion mismatch",
            self.occlusion_mismatch,
            MAX_OCCLUSION_MISMATCH,
        );
        // NaN (a broken backend) fails too.
        if self.t_rel_max.is_nan() || self.t_rel_max > MAX_T_REL_DIFF {
            f.push(format!(
                "t relative difference {:.2e} > {MAX_T_REL_DIFF:e}",
                self.t_rel_max
            ));
        }
        f
    }
}

pub fn agreement(
    scene: &PreparedScene,
    rays: &[Ray],
    reference: &Traced,
    other: &Traced,
) -> Agreement {
    let mut a = Agreement::default();
    for (i, ray) in rays.iter().enumerate() {
        match (reference.hits[i], other.hits[i]) {
            (None, None) => {}
            (Some(_), None) | (None, Some(_)) => a.hit_mismatch += 1,
            (Some(r), Some(o)) => {
                let rel = t_rel_diff(ray, r.t, o.t);
                if r.prim == o.prim {
                    a.t_rel_max = a.t_rel_max.max(rel);
                } else {
                    // A tie: our exact tests hit both primitives at (nearly) the same t.
                    match (exact_t(scene, ray, r.prim), exact_t(scene, ray, o.prim)) {
                        (Some(ta), Some(tb)) if (ta - tb).abs() <= TIE_T_REL * ta.max(tb) => {
                            a.ties += 1
                        }
                        _ => a.prim_mismatch += 1,
                    }
                }
            }
        }
        if reference.occluded[i] != other.occluded[i] {
            a.occlusion_mismatch += 1;
        }
    }
    a
}

/// Relative RMSE of `b` against `a`: sqrt(mean (a-b)²) / mean(a), over pixels and channels.
pub fn image_rel_rmse(a: &Image, b: &Image) -> f64 {
    let (mut se, mut sum, mut n) = (0.0f64, 0.0f64, 0usize);
    for (pa, pb) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..3 {
            se += (pa[c] - pb[c]).powi(2);
            sum += pa[c];
            n += 1;
        }
    }
    let n = n.max(1) as f64;
    (se / n).sqrt() / (sum / n).max(f64::MIN_POSITIVE)
}

/// Renders `passes` passes of `strategy` with `seed` using the scene's current tracer.
pub fn render(
    scene: &PreparedScene,
    strategy: &dyn strategy::Strategy,
    seed: u64,
    passes: u64,
) -> Result<Image> {
    let mut r = Renderer::new(scene, strategy, seed)?;
    let mut film = Film::new(scene.scene.width, scene.scene.height);
    while film.spp < passes {
        let count = (passes - film.spp).min(crate::render::MAX_GROUP);
        r.add_passes(&mut film, count);
    }
    Ok(film.mean())
}

fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let start = Instant::now();
    let out = f();
    (out, start.elapsed().as_secs_f64())
}

/// Runs the cross-check on a prepared scene (its tracer must be `obvhs`) and writes
/// `<out>/<scene>/crosscheck.csv`. Tracing and timing run on the calling thread; the renders
/// use the current rayon pool.
pub fn run(scene: &mut PreparedScene, out: &Path, seed: u64) -> Result<Report> {
    let sets = raysets::generate(scene, scene.scene.width, scene.scene.height, seed);
    let names = backends::AVAILABLE;
    let tracers: Vec<Box<dyn Tracer>> = names
        .iter()
        .map(|n| backends::build(n, scene.world.geometry.clone()))
        .collect::<Result<_>>()?;
    let modes = [Mode::Single, Mode::Packet16];
    let scene_name = scene.scene.name.clone();
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    for set in &sets {
        let shadow = set.query == Query::Occluded;
        let rays = set.flat();
        // traced[b][m], best time[b][m]; backends interleaved round by round so load changes
        // on the shared machine hit all of them alike.
        let mut best = vec![[f64::INFINITY; 2]; tracers.len()];
        let mut traced: Vec<Vec<Traced>> = Vec::new();
        for round in 0..TIMING_ROUNDS {
            for (b, t) in tracers.iter().enumerate() {
                let mut per_mode = Vec::new();
                for (m, &mode) in modes.iter().enumerate() {
                    let (hits, t_closest) = timed(|| trace_closest(t.as_ref(), set, mode));
                    let (occluded, t_occl) = timed(|| trace_occluded(t.as_ref(), set, mode));
                    let secs = if shadow { t_occl } else { t_closest };
                    best[b][m] = best[b][m].min(secs);
                    per_mode.push(Traced { hits, occluded });
                }
                if round + 1 == TIMING_ROUNDS {
                    traced.push(per_mode);
                }
            }
        }
        for (b, name) in names.iter().enumerate() {
            for (m, mode) in modes.iter().enumerate() {
                let a = agreement(scene, &rays, &traced[0][0], &traced[b][m]);
                let why = a.failures(rays.len());
                for w in &why {
                    failures.push(format!(
                        "{scene_name}/{}/{name}/{}: {w}",
                        set.class,
                        mode.name()
                    ));
                }
                let secs = best[b][m];
                rows.push(Row {
                    scene: scene_name.clone(),
                    set: set.class.into(),
                    backend: (*name).into(),
                    mode: mode.name().into(),
                    rays: rays.len(),
                    hit_mismatch: a.hit_mismatch,
                    prim_mismatch: a.prim_mismatch,
                    ties: a.ties,
                    t_rel_max: a.t_rel_max,
                    occlusion_mismatch: a.occlusion_mismatch,
                    timed_query: if shadow { "occluded" } else { "closest" }.into(),
                    seconds: secs,
                    mrays_per_s: if secs > 0.0 {
                        rays.len() as f64 / secs / 1e6
                    } else {
                        0.0
                    },
                    image_rel_rmse: None,
                    pass: why.is_empty(),
                });
            }
        }
    }
    // The same strategy and seed on each backend: images should agree to float noise (plus the
    // rare tie resolved differently, which changes a sample path).
    let (applicable, _) = strategy::applicable(scene);
    if let Some(strategy) = applicable.first() {
        let reference = render(scene, strategy.as_ref(), seed, RENDER_PASSES)?;
        for name in names.iter().skip(1) {
            let (tracer, emitters) = scene.replace_tracers(|g| backends::build(name, g))?;
            let img = render(scene, strategy.as_ref(), seed, RENDER_PASSES);
            (scene.tracer, scene.emitters) = (tracer, emitters);
            let img = img?;
            let d = image_rel_rmse(&reference, &img);
            let pass = d <= MAX_IMAGE_REL_RMSE;
            if !pass {
                failures.push(format!(
                    "{scene_name}/render/{name}: image relative RMSE {d:.2e} > {MAX_IMAGE_REL_RMSE:e}"
                ));
            }
            rows.push(Row {
                scene: scene_name.clone(),
                set: "render".into(),
                backend: (*name).into(),
                mode: format!("{}x{}spp", strategy.name(), RENDER_PASSES),
                rays: 0,
                hit_mismatch: 0,
                prim_mismatch: 0,
                ties: 0,
                t_rel_max: 0.0,
                occlusion_mismatch: 0,
                timed_query: String::new(),
                seconds: 0.0,
                mrays_per_s: 0.0,
                image_rel_rmse: Some(d),
                pass,
            });
        }
    }
    let csv = out.join(&scene_name).join("crosscheck.csv");
    crate::output::write_csv(&csv, &rows)?;
    Ok(Report {
        rows,
        csv,
        failures,
    })
}

/// The failure summary as one error, for a non-zero exit.
pub fn into_result(report: &Report) -> Result<()> {
    if report.failures.is_empty() {
        Ok(())
    } else {
        Err(Error::Check(format!(
            "crosscheck failed ({} checks below threshold):\n  {}",
            report.failures.len(),
            report.failures.join("\n  ")
        )))
    }
}
