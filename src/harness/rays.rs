//! Ray-throughput harness: the fixed ray sets of [`raysets`], traced by each backend (and each
//! ISA of the packet backend), interleaved round by round so machine noise hits all alike.

use super::raysets;
pub use super::raysets::{Packing, Query, RaySet};
use crate::error::{Error, Result};
use crate::prepare::PreparedScene;
use crate::simd::Isa;
use crate::tracer::backends;
use crate::tracer::bvh::ObvhsTracer;
use crate::tracer::packet::{PacketTracer, TraceStats};
use crate::tracer::{HitPacket, LaneMask, RayPacket, Tracer};
use rayon::prelude::*;
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// Backends the `rays`, `compare` and `reference` commands know: the one registry,
/// [`backends::AVAILABLE`].
pub const BACKENDS: &[&str] = backends::AVAILABLE;

/// The ray sets of `dibench rays`: [`raysets::generate`] for a `size`² image.
pub fn generate(scene: &PreparedScene, size: u32, seed: u64) -> Vec<RaySet> {
    raysets::generate(scene, size, size, seed)
}

/// [`generate`] with the camera rays packed as `packing` says ([`raysets::generate_packed`]).
pub fn generate_packed(
    scene: &PreparedScene,
    size: u32,
    seed: u64,
    packing: Packing,
) -> Vec<RaySet> {
    raysets::generate_packed(scene, size, size, seed, packing)
}

/// A backend under test: the obvhs baseline or the packet tracer at one ISA.
pub enum Subject {
    Obvhs(ObvhsTracer),
    Packet(PacketTracer),
    /// The packet backend's single-ray kernel on every ray alone (benches; not a backend).
    Single(PacketTracer),
    /// Embree with `rtcIntersect1/rtcOccluded1` per ray (`packet: false`) or its 16-wide
    /// kernels (`packet: true`), for the side-by-side with our packet core.
    #[cfg(feature = "embree")]
    Embree {
        tracer: crate::tracer::embree::EmbreeTracer,
        packet: bool,
    },
}

impl Subject {
    pub fn label(&self) -> (&'static str, &'static str) {
        match self {
            Subject::Obvhs(_) => ("obvhs", "scalar"),
            Subject::Packet(p) => ("packet", p.isa().name()),
            Subject::Single(p) => ("packet-1ray", p.isa().name()),
            #[cfg(feature = "embree")]
            Subject::Embree { packet, .. } => ("embree", if *packet { "16-wide" } else { "1-ray" }),
        }
    }

    /// How long its tree took to build: obvhs's binary tree; our wide tree (the binary build
    /// and its collapse); Embree's scene, whose builder runs on Embree's own threads.
    pub fn build_seconds(&self) -> f64 {
        match self {
            Subject::Obvhs(t) => t.build_time(),
            Subject::Packet(t) | Subject::Single(t) => t.wide().build_time,
            #[cfg(feature = "embree")]
            Subject::Embree { tracer, .. } => tracer.build_time(),
        }
        .as_secs_f64()
    }

    fn tracer(&self) -> &dyn Tracer {
        match self {
            Subject::Obvhs(t) => t,
            Subject::Packet(t) | Subject::Single(t) => t,
            #[cfg(feature = "embree")]
            Subject::Embree { tracer, .. } => tracer,
        }
    }

    /// Traces a set; the obvhs baseline goes one ray at a time (the trait's lane loop).
    /// Returns a checksum so the work cannot be optimised away.
    pub fn trace(&self, set: &RaySet, threads: usize) -> u64 {
        let one = |(p, &m): (&RayPacket, &LaneMask)| -> u64 {
            #[cfg(feature = "embree")]
            if let Subject::Embree { tracer, packet } = self {
                return trace_embree(tracer, *packet, set, p, m);
            }
            if let Subject::Single(t) = self {
                return trace_single(t, set.query, p, m);
            }
            match set.query {
                Query::Closest => {
                    let mut h = HitPacket::default();
                    self.tracer().intersect_packet(p, m, &mut h);
                    h.prim.iter().map(|&x| x as u64).sum()
                }
                Query::Occluded => self.tracer().occluded_packet(p, m) as u64,
            }
        };
        if threads <= 1 {
            set.packets.iter().zip(&set.masks).map(one).sum()
        } else {
            set.packets.par_iter().zip(&set.masks).map(one).sum()
        }
    }

    fn stats(&self, set: &RaySet) -> Option<TraceStats> {
        let Subject::Packet(t) = self else {
            return None;
        };
        let mut s = TraceStats::default();
        let mut h = HitPacket::default();
        for (p, &m) in set.packets.iter().zip(&set.masks) {
            match set.query {
                Query::Closest => t.intersect_packet_stats(p, m, &mut h, &mut s),
                Query::Occluded => {
                    t.occluded_packet_stats(p, m, &mut s);
                }
            }
        }
        Some(s)
    }
}

/// One ray at a time through a tracer's single-ray entry points.
fn trace_single(t: &dyn Tracer, query: Query, p: &RayPacket, m: LaneMask) -> u64 {
    let lanes = (0..crate::tracer::LANES).filter(|l| m & (1 << l) != 0);
    match query {
        Query::Closest => lanes
            .map(|l| t.intersect(&p.get(l)).map_or(0, |h| h.prim as u64))
            .sum(),
        Query::Occluded => lanes.filter(|&l| t.occluded(&p.get(l))).count() as u64,
    }
}

/// Builds the subjects for `--backend` names: `packet` expands to every ISA in `isas`.
pub fn subjects(scene: &PreparedScene, backends: &[String], isas: &[Isa]) -> Result<Vec<Subject>> {
    let geometry: Arc<_> = scene.world.geometry.clone();
    let mut out = vec![];
    for b in backends {
        match b.as_str() {
            "obvhs" => out.push(Subject::Obvhs(ObvhsTracer::build(geometry.clone()))),
            "packet" => {
                for &isa in isas {
                    out.push(Subject::Packet(PacketTracer::build(geometry.clone(), isa)?));
                }
            }
            #[cfg(feature = "embree")]
            "embree" => {
                for packet in [false, true] {
                    out.push(Subject::Embree {
                        tracer: crate::tracer::embree::EmbreeTracer::build(geometry.clone())?,
                        packet,
                    });
                }
            }
            other => return Err(unknown_backend(other)),
        }
    }
    Ok(out)
}

/// One packet through Embree: per-ray calls, or the 16-wide kernels with the coherent hint
/// for camera tiles.
#[cfg(feature = "embree")]
fn trace_embree(
    t: &crate::tracer::embree::EmbreeTracer,
    packet: bool,
    set: &RaySet,
    p: &RayPacket,
    m: LaneMask,
) -> u64 {
    match (set.query, packet) {
        (query, false) => trace_single(t, query, p, m),
        (Query::Closest, true) => {
            let mut h = HitPacket::default();
            if set.coherent {
                t.intersect_packet_coherent(p, m, &mut h);
            } else {
                t.intersect_packet(p, m, &mut h);
            }
            h.prim.iter().map(|&x| x as u64).sum()
        }
        (Query::Occluded, true) => t.occluded_packet(p, m) as u64,
    }
}

pub fn unknown_backend(name: &str) -> Error {
    backends::unknown(name)
}

/// What `dibench rays` measured: its setting, a row per (backend, ISA, ray class), and where
/// the CSV is.
pub struct RaysReport {
    pub scene: String,
    pub threads: usize,
    pub size: u32,
    pub rounds: usize,
    pub packing: Packing,
    pub rows: Vec<RaysRow>,
    pub csv: PathBuf,
    /// The machine, as [`super::cpu_model`] describes it: figures name it.
    pub cpu: String,
}

/// The table `dibench rays` prints, with our best packet path against Embree's best kernel
/// per ray class where both ran (the bar to steer by).
impl std::fmt::Display for RaysReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let rows = &self.rows;
        writeln!(
            f,
            "scene {} · {} threads · {}x{} rays per class, packets of {} · best of {} rounds\ncpu {}",
            self.scene,
            self.threads,
            self.size,
            self.size,
            match self.packing {
                Packing::Tile => "4x4 pixels",
                Packing::Pixel => "one pixel's 16 samples",
            },
            self.rounds,
            self.cpu
        )?;
        writeln!(
            f,
            "{:<8} {:<9} {:<15} {:>8} {:>9} {:>10} {:>8} {:>8} {:>8}",
            "backend",
            "isa",
            "ray_class",
            "rays",
            "Mrays/s",
            "x obvhs",
            "lanes",
            "nodes/r",
            "tests/r"
        )?;
        let opt = |x: Option<f64>, p: usize| x.map_or("-".to_string(), |v| format!("{v:.p$}"));
        for r in rows {
            writeln!(
                f,
                "{:<8} {:<9} {:<15} {:>8} {:>9.2} {:>10} {:>8} {:>8} {:>8}",
                r.backend,
                r.isa,
                r.ray_class,
                r.rays,
                r.mrays_per_s,
                opt(r.ratio_to_obvhs, 2),
                opt(r.active_lane_fraction, 2),
                opt(r.nodes_per_ray, 1),
                opt(r.tests_per_ray, 1)
            )?;
        }
        // Each subject's build, once (its rows of every class carry it).
        let mut builds: Vec<(&str, &str, f64)> = vec![];
        for r in rows {
            if !builds.iter().any(|b| (b.0, b.1) == (&r.backend, &r.isa)) {
                builds.push((&r.backend, &r.isa, r.build_s));
            }
        }
        let builds: Vec<String> = builds
            .iter()
            .map(|(backend, isa, s)| format!("{backend} {isa} {:.1} ms", s * 1e3))
            .collect();
        writeln!(f, "build: {}", builds.join(" · "))?;
        for class in rows
            .iter()
            .map(|r| r.ray_class.clone())
            .collect::<std::collections::BTreeSet<_>>()
        {
            let best = |b: &str| {
                rows.iter()
                    .filter(|r| r.ray_class == class && r.backend == b)
                    .map(|r| r.mrays_per_s)
                    .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))))
            };
            if let (Some(ours), Some(embree)) = (best("packet"), best("embree")) {
                writeln!(f, "packet/embree {class:<15} {:.2}", ours / embree)?;
            }
        }
        writeln!(f, "results: {}", self.csv.display())
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct RaysRow {
    pub scene: String,
    pub backend: String,
    pub isa: String,
    pub ray_class: String,
    /// What a packet's camera rays are: `tile` or `pixel` ([`Packing`]).
    pub packets: Packing,
    pub rays: u64,
    pub threads: usize,
    pub rounds: usize,
    /// Fastest round (least disturbed by other load).
    pub seconds: f64,
    pub mrays_per_s: f64,
    pub ratio_to_obvhs: Option<f64>,
    /// Mean active lanes per 16-lane visit of a wide node (packet backend only).
    pub active_lane_fraction: Option<f64>,
    /// Wide-node visits per ray, counting each active lane of a packet visit (packet backend
    /// only; each visit tests all of a node's up to 8 children).
    pub nodes_per_ray: Option<f64>,
    /// Wide-node visits issued per ray: packet visits plus single-ray visits.
    pub tests_per_ray: Option<f64>,
    /// Fraction of node visits made by single rays (the hybrid tail).
    pub single_fraction: Option<f64>,
    /// Leaf tests (a block of up to 8 triangles, or a sphere) per ray, by packets or single
    /// rays.
    pub leaves_per_ray: Option<f64>,
    /// How long the subject's tree took to build ([`Subject::build_seconds`]).
    pub build_s: f64,
}

/// Times every subject on every set: `rounds` rounds, the subject order reversed on odd
/// rounds; best round per (subject, set).
pub fn measure(
    scene: &str,
    sets: &[RaySet],
    subjects: &[Subject],
    rounds: usize,
    threads: usize,
    packing: Packing,
) -> Vec<RaysRow> {
    let mut best = vec![vec![f64::INFINITY; subjects.len()]; sets.len()];
    for round in 0..rounds {
        for (si, set) in sets.iter().enumerate() {
            let order: Vec<usize> = if round % 2 == 0 {
                (0..subjects.len()).collect()
            } else {
                (0..subjects.len()).rev().collect()
            };
            for b in order {
                let start = Instant::now();
                std::hint::black_box(subjects[b].trace(set, threads));
                let s = start.elapsed().as_secs_f64();
                best[si][b] = best[si][b].min(s);
            }
        }
    }
    let mut rows = vec![];
    for (si, set) in sets.iter().enumerate() {
        let rays = set.rays();
        let base = subjects
            .iter()
            .position(|s| matches!(s, Subject::Obvhs(_)))
            .map(|b| best[si][b]);
        for (b, subj) in subjects.iter().enumerate() {
            let (backend, isa) = subj.label();
            let seconds = best[si][b];
            let st = subj.stats(set);
            let per_ray = |x: u64| x as f64 / rays.max(1) as f64;
            rows.push(RaysRow {
                scene: scene.to_string(),
                backend: backend.into(),
                isa: isa.into(),
                ray_class: set.class.into(),
                packets: packing,
                rays,
                threads,
                rounds,
                seconds,
                mrays_per_s: rays as f64 / seconds / 1e6,
                ratio_to_obvhs: base.map(|t| t / seconds),
                active_lane_fraction: st
                    .map(|s| s.packet_lanes as f64 / (16 * s.packet_nodes.max(1)) as f64),
                nodes_per_ray: st.map(|s| per_ray(s.packet_lanes + s.single_nodes)),
                tests_per_ray: st.map(|s| per_ray(s.packet_nodes + s.single_nodes)),
                single_fraction: st.map(|s| {
                    s.single_nodes as f64 / (s.packet_nodes + s.single_nodes).max(1) as f64
                }),
                leaves_per_ray: st.map(|s| per_ray(s.leaves)),
                build_s: subj.build_seconds(),
            });
        }
    }
    rows
}
