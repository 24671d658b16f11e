//! Ray-throughput harness: fixed ray sets generated from a scene, traced by each backend
//! (and each ISA of the packet backend), interleaved round by round so machine noise hits
//! all alike.

use crate::error::{Error, Result};
use crate::geometry::Ray;
use crate::math::{mix64, offset_ray_origin};
use crate::prepare::PreparedScene;
use crate::render::camera_ray;
use crate::sampling::warp::sample_uniform_sphere;
use crate::simd::Isa;
use crate::tracer::bvh::ObvhsTracer;
use crate::tracer::packet::{PacketTracer, TraceStats};
use crate::tracer::{HitPacket, LANES, LaneMask, RayPacket, Tracer};
use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;
use std::sync::Arc;
use std::time::Instant;

/// Backends the `rays`, `compare` and `reference` commands know.
pub const BACKENDS: &[&str] = &[
    "obvhs",
    "packet",
    #[cfg(feature = "embree")]
    "embree",
];

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    Closest,
    Occluded,
}

/// One ray class as 16-ray packets (4×4 pixel tiles) with their active masks.
pub struct RaySet {
    pub class: &'static str,
    pub query: Query,
    pub packets: Vec<RayPacket>,
    pub masks: Vec<LaneMask>,
}

impl RaySet {
    pub fn rays(&self) -> u64 {
        self.masks.iter().map(|m| m.count_ones() as u64).sum()
    }
}

/// Uniform [0, 1) from a hashed key: fixed ray sets without RNG state.
fn u01(key: u64) -> f32 {
    (mix64(key) >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// Generates `primary`, `shadow_area`, `shadow_distant` and `incoherent` rays for a `size`²
/// image of the scene's camera. Secondary rays start at the primary hits (offset off the
/// surface) and stay in the primary's packet lane, as the renderer groups them.
pub fn generate(scene: &PreparedScene, size: u32, seed: u64) -> Vec<RaySet> {
    let cam = &scene.scene.camera;
    let tiles = size.div_ceil(4);
    let distant = Vec3::new(0.35, 1.0, 0.25).normalize();
    let mut sets: Vec<RaySet> = [
        ("primary", Query::Closest),
        ("shadow_area", Query::Occluded),
        ("shadow_distant", Query::Occluded),
        ("incoherent", Query::Closest),
    ]
    .into_iter()
    .map(|(class, query)| RaySet {
        class,
        query,
        packets: vec![],
        masks: vec![],
    })
    .collect();
    let mut hits = HitPacket::default();
    for ty in 0..tiles {
        for tx in 0..tiles {
            let mut p = [RayPacket::default(); 4];
            let mut m = [0 as LaneMask; 4];
            for lane in 0..LANES {
                let (x, y) = (tx * 4 + lane as u32 % 4, ty * 4 + lane as u32 / 4);
                if x < size && y < size {
                    p[0].set(lane, &camera_ray(cam, size, size, x, y, [0.5, 0.5]));
                    m[0] |= 1 << lane;
                }
            }
            scene.tracer.intersect_packet(&p[0], m[0], &mut hits);
            for lane in 0..LANES {
                let Some(hit) = hits.get(lane) else { continue };
                let ray = p[0].get(lane);
                let surf = scene.surface(&ray, &hit);
                let n = if surf.ng.dot(ray.dir) < 0.0 {
                    surf.ng
                } else {
                    -surf.ng
                };
                let o = offset_ray_origin(surf.p, surf.p_error, n);
                let key = seed ^ ((ty as u64 * tiles as u64 + tx as u64) << 4 | lane as u64) << 8;
                let u = |i: u64| u01(key.wrapping_add(i));
                if let Some((_, ls)) = scene.sample_light(
                    o,
                    u(1),
                    [u(2), u(3), u(4)],
                    &crate::lights::LightMethods::BASIC,
                ) && let Some(r) = ls.shadow_ray(o)
                {
                    p[1].set(lane, &r);
                    m[1] |= 1 << lane;
                }
                p[2].set(lane, &Ray::new(o, distant, f32::INFINITY));
                m[2] |= 1 << lane;
                let d = sample_uniform_sphere([u(5), u(6)]);
                let d = if d.dot(n) < 0.0 { -d } else { d };
                p[3].set(lane, &Ray::new(o, d, f32::INFINITY));
                m[3] |= 1 << lane;
            }
            for k in 0..4 {
                if m[k] != 0 {
                    sets[k].packets.push(p[k]);
                    sets[k].masks.push(m[k]);
                }
            }
        }
    }
    sets
}

/// A backend under test: the obvhs baseline or the packet tracer at one ISA.
pub enum Subject {
    Obvhs(ObvhsTracer),
    Packet(PacketTracer),
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
            #[cfg(feature = "embree")]
            Subject::Embree { packet, .. } => ("embree", if *packet { "16-wide" } else { "1-ray" }),
        }
    }

    fn tracer(&self) -> &dyn Tracer {
        match self {
            Subject::Obvhs(t) => t,
            Subject::Packet(t) => t,
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
    let lanes = (0..crate::tracer::LANES).filter(|l| m & (1 << l) != 0);
    match (set.query, packet) {
        (Query::Closest, false) => lanes
            .map(|l| t.intersect(&p.get(l)).map_or(0, |h| h.prim as u64))
            .sum(),
        (Query::Occluded, false) => lanes.filter(|&l| t.occluded(&p.get(l))).count() as u64,
        (Query::Closest, true) => {
            let mut h = HitPacket::default();
            if set.class == "primary" {
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
    Error::Usage(format!(
        "unknown backend `{name}` (known: {})",
        BACKENDS.join(", ")
    ))
}

#[derive(Clone, Debug, Serialize)]
pub struct RaysRow {
    pub scene: String,
    pub backend: String,
    pub isa: String,
    pub ray_class: String,
    pub rays: u64,
    pub threads: usize,
    pub rounds: usize,
    /// Fastest round (least disturbed by other load).
    pub seconds: f64,
    pub mrays_per_s: f64,
    pub ratio_to_obvhs: Option<f64>,
    /// Mean active lanes per 16-wide box test (packet backend only).
    pub active_lane_fraction: Option<f64>,
    /// Node visits per ray, counting each active lane of a packet test (packet backend only).
    pub nodes_per_ray: Option<f64>,
    /// Box-test instructions issued per ray: packet tests plus single-ray tests.
    pub tests_per_ray: Option<f64>,
}

/// Times every subject on every set: `rounds` rounds, the subject order reversed on odd
/// rounds; best round per (subject, set).
pub fn measure(
    scene: &str,
    sets: &[RaySet],
    subjects: &[Subject],
    rounds: usize,
    threads: usize,
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
            });
        }
    }
    rows
}
