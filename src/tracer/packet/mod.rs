//! The `packet` backend: our own traversal of the obvhs-built BVH2 (the same tree the `obvhs`
//! backend walks), 16 rays at a time through the [`crate::simd`] lane layer, with per-lane
//! masks (Wald et al. 2001, 2007), front-to-back child order, per-lane retirement for
//! occlusion, and a switch to single-ray traversal once few lanes remain (Benthin et al. 2012).

mod kernel;
mod single;

use super::bvh::ObvhsTracer;
use super::{Geometry, HitPacket, LaneMask, RayPacket, Tracer};
use crate::error::{Error, Result};
use crate::geometry::{Hit, Ray};
use crate::simd::{self, Isa};
use std::sync::Arc;

/// Traversal stack depth; the build fails clearly (no panic) on deeper trees.
pub const STACK: usize = 128;

/// Below this many active lanes a packet finishes its lanes one ray at a time. Tuned on
/// bunny (`dibench rays`): 1 loses 30 % on area-light shadows, 3–9 were within noise of
/// each other, with 6–9 best for shadow rays.
pub const HYBRID_LANES: u32 = 8;

/// A BVH2 node as plain data: `count == 0` ⇒ inner node with children `first`, `first + 1`;
/// else a leaf over slots `first..first + count`.
#[derive(Clone, Copy, Debug)]
pub struct Node {
    pub min: [f32; 3],
    pub max: [f32; 3],
    pub first: u32,
    pub count: u32,
}

/// Work counters, for the `rays` harness.
#[derive(Clone, Copy, Debug, Default)]
pub struct TraceStats {
    /// 16-wide box tests.
    pub packet_nodes: u64,
    /// Active lanes summed over those tests.
    pub packet_lanes: u64,
    /// Single-ray box tests (hybrid tail and single-ray calls).
    pub single_nodes: u64,
}

impl TraceStats {
    pub fn add(&mut self, o: &TraceStats) {
        self.packet_nodes += o.packet_nodes;
        self.packet_lanes += o.packet_lanes;
        self.single_nodes += o.single_nodes;
    }
}

pub struct PacketTracer {
    geometry: Arc<Geometry>,
    nodes: Vec<Node>,
    slot_prim: Vec<u32>,
    isa: Isa,
}

impl PacketTracer {
    /// Builds over the same BVH as [`ObvhsTracer`] (obvhs PLOC, medium preset).
    pub fn build(geometry: Arc<Geometry>, isa: Isa) -> Result<Self> {
        let base = ObvhsTracer::build(geometry.clone());
        let bvh = base.bvh();
        let nodes: Vec<Node> = bvh
            .nodes
            .iter()
            .map(|n| Node {
                min: n.aabb.min.to_array(),
                max: n.aabb.max.to_array(),
                first: n.first_index,
                count: n.prim_count,
            })
            .collect();
        let depth = tree_depth(&nodes);
        if depth >= STACK {
            return Err(Error::Usage(format!(
                "packet backend: BVH depth {depth} exceeds the traversal stack ({STACK})"
            )));
        }
        Ok(PacketTracer {
            geometry,
            nodes,
            slot_prim: bvh.primitive_indices.clone(),
            isa,
        })
    }

    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// Closest hits, with work counters.
    pub fn intersect_packet_stats(
        &self,
        rays: &RayPacket,
        active: LaneMask,
        hits: &mut HitPacket,
        stats: &mut TraceStats,
    ) {
        *hits = HitPacket::default();
        if self.slot_prim.is_empty() || active == 0 {
            return;
        }
        simd::run(
            self.isa,
            kernel::Closest {
                tr: self,
                rays,
                active,
                hits,
                stats,
            },
        );
    }

    /// Occluded lanes, with work counters.
    pub fn occluded_packet_stats(
        &self,
        rays: &RayPacket,
        active: LaneMask,
        stats: &mut TraceStats,
    ) -> LaneMask {
        if self.slot_prim.is_empty() || active == 0 {
            return 0;
        }
        simd::run(
            self.isa,
            kernel::Occluded {
                tr: self,
                rays,
                active,
                stats,
            },
        )
    }
}

fn tree_depth(nodes: &[Node]) -> usize {
    let mut max = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((i, d)) = stack.pop() {
        max = max.max(d);
        let n = nodes[i];
        if n.count == 0 {
            stack.push((n.first as usize, d + 1));
            stack.push((n.first as usize + 1, d + 1));
        }
    }
    max
}

impl Tracer for PacketTracer {
    fn name(&self) -> &'static str {
        "packet"
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if self.slot_prim.is_empty() {
            return None;
        }
        let mut best = single::Best::new(ray.tmax);
        single::closest(self, ray, 0, &mut best, &mut TraceStats::default());
        best.hit()
    }

    fn occluded(&self, ray: &Ray) -> bool {
        !self.slot_prim.is_empty() && single::occluded(self, ray, 0, &mut TraceStats::default())
    }

    fn intersect_packet(&self, rays: &RayPacket, active: LaneMask, hits: &mut HitPacket) {
        self.intersect_packet_stats(rays, active, hits, &mut TraceStats::default());
    }

    fn occluded_packet(&self, rays: &RayPacket, active: LaneMask) -> LaneMask {
        self.occluded_packet_stats(rays, active, &mut TraceStats::default())
    }
}

/// Safe reciprocal for slab tests: a zero direction component gives a huge finite value of the
/// right sign instead of ±∞, so (bound - origin) * inv is never 0 · ∞ = NaN.
#[inline(always)]
pub(crate) fn safe_inv(d: f32) -> f32 {
    const TINY: f32 = 1e-30;
    if d.abs() < TINY {
        (1.0 / TINY).copysign(d)
    } else {
        1.0 / d
    }
}

/// Far-distance scale making the slab test conservative under rounding (Ize, "Robust BVH Ray
/// Traversal", JCGT 2013: 1 + 2γ₃).
pub(crate) const FAR_SCALE: f32 = 1.000_000_8;
