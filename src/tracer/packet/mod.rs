//! The `packet` backend: our own traversal of an 8-wide BVH collapsed from obvhs's binary tree
//! ([`build`]), through the [`crate::simd`] lane layer.
//!
//! - Single rays ([`single`]): one 8-lane slab test for all children of a node, children
//!   visited near to far for closest hit, occlusion exiting at the first hit; leaves are SoA
//!   blocks of up to 8 triangles tested together ([`leaf`]).
//! - Packets of 16 rays ([`kernel`]): one 16-lane slab test per child for the active lanes
//!   with a (node, lane-mask) stack (Wald et al. 2001, 2007), switching to single-ray
//!   traversal once few lanes remain (Benthin et al. 2012); coherent packets (camera tiles,
//!   shadow rays sharing a direction) stay packets longer.
//!
//! The contract: the same hits as the `obvhs` backend, bit for bit — the closest hit is the
//! smallest (t, primitive id) over the primitives our exact tests hit on (0, tmax), so the
//! traversal order (and the tree) cannot change the answer, ties on shared edges included —
//! and identical results on every ISA.

mod build;
mod kernel;
mod leaf;
mod single;

pub use build::{BRANCH, BuildParams, Wide};

use super::{Geometry, HitPacket, LaneMask, RayPacket, Tracer, cull_t};
use crate::error::{Error, Result};
use crate::geometry::triangle::WatertightRay;
use crate::geometry::{Hit, Ray};
use crate::simd::{self, Isa, Kernel, Lanes};
use crate::tracer::NO_HIT;
use std::sync::Arc;

/// Traversal stack entries (single ray and packet); the build fails clearly (no panic) on a
/// tree that could overflow it.
pub const STACK: usize = 256;

/// Fault injection for the tests' negative controls (a kernel built with a fault must fail the
/// contract tests); production code uses 0, and the flags compile away.
pub const FAULT_NO_T_BOUND: u32 = 1;
/// Visit children far to near (closest hit stays correct, only slower: caught by the
/// visit-order test).
pub const FAULT_FAR_FIRST: u32 = 2;

/// A packet visiting a node with fewer active lanes than this finishes them one ray at a time
/// (single-ray traversal from that node). Chosen from the measured lane occupancy and
/// throughput on bunny and the dragon (docs/tracer.md).
pub const HYBRID_LANES: u32 = 6;

/// The same switch at a leaf: a 16-lane triangle test costs about as much as one ray's test of
/// a whole 8-triangle block, so a packet keeps testing leaves with fewer lanes.
pub const LEAF_LANES: u32 = 3;

/// A camera packet (a shared origin) whose interval test leaves at most this many of a node's
/// children descends into them without per-lane slab tests (into more, only where every lane
/// is sure to pass). Chosen on bunny, the dragon and cornell at 128² and 512²
/// (`DIBENCH_FRUSTUM_SWEEP=1 cargo bench --bench rays`): docs/tracer.md, stop 35.
pub const FRUSTUM_CHILDREN: u32 = 2;

/// Work counters, for the `rays` harness.
#[derive(Clone, Copy, Debug, Default)]
pub struct TraceStats {
    /// 16-lane visits of wide nodes (each tests all children).
    pub packet_nodes: u64,
    /// Active lanes summed over those visits.
    pub packet_lanes: u64,
    /// Single-ray visits of wide nodes (hybrid tail and single-ray calls).
    pub single_nodes: u64,
    /// Leaf blocks (or spheres) tested, by a packet or a single ray.
    pub leaves: u64,
    /// Packet visits that entered some child on the interval test alone (camera packets).
    pub frustum_nodes: u64,
}

impl TraceStats {
    pub fn add(&mut self, o: &TraceStats) {
        self.packet_nodes += o.packet_nodes;
        self.packet_lanes += o.packet_lanes;
        self.single_nodes += o.single_nodes;
        self.leaves += o.leaves;
        self.frustum_nodes += o.frustum_nodes;
    }
}

/// The closest hit so far of one ray, under the contract's rule.
#[derive(Clone, Copy, Debug)]
pub struct Best {
    pub t: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
    /// The ray's own tmax: hits must lie below it.
    pub tmax: f32,
}

impl Best {
    pub fn new(tmax: f32) -> Self {
        Best {
            t: tmax,
            prim: NO_HIT,
            u: 0.0,
            v: 0.0,
            tmax,
        }
    }

    /// Takes a hit if it is below tmax and closer, or as close with a smaller primitive id.
    #[inline(always)]
    pub fn offer(&mut self, t: f32, prim: u32, u: f32, v: f32) {
        if t < self.tmax && super::closer(t, prim, self.t, self.prim) {
            *self = Best {
                t,
                prim,
                u,
                v,
                ..*self
            };
        }
    }

    /// The tmax leaves are tested with: a little past the closest hit, so no hit that could
    /// win (a tie included) is rejected by the test's own t < tmax.
    #[inline(always)]
    pub fn test_tmax(&self) -> f32 {
        let c = cull_t(self.t);
        if c < self.tmax { c } else { self.tmax }
    }

    pub fn hit(&self) -> Option<Hit> {
        (self.prim != NO_HIT).then_some(Hit {
            t: self.t,
            prim: self.prim,
            u: self.u,
            v: self.v,
        })
    }
}

/// Per-ray constants of the single-ray kernels.
#[derive(Clone, Copy, Debug)]
pub struct Ray1 {
    pub ray: Ray,
    pub o: [f32; 3],
    pub inv: [f32; 3],
    /// Row of the near plane per axis in [`build::Node::b`] (min row, or max row if the
    /// direction is negative); the far plane is the other.
    pub near: [usize; 3],
    pub wr: WatertightRay,
    pub k: [usize; 3],
    pub s: [f32; 3],
}

impl Ray1 {
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let d = ray.dir;
        let wr = WatertightRay::new(d);
        Self::from_parts(
            *ray,
            [safe_inv(d.x), safe_inv(d.y), safe_inv(d.z)],
            wr.axes(),
            wr.shear(),
        )
    }

    /// From constants a packet set-up computed (the same values as [`Self::new`]).
    #[inline(always)]
    pub fn from_parts(ray: Ray, inv: [f32; 3], k: [usize; 3], s: [f32; 3]) -> Self {
        let row = |a: usize| a + build::MAX_ROW * (inv[a].to_bits() >> 31) as usize;
        Ray1 {
            ray,
            o: ray.origin.to_array(),
            inv,
            near: [row(0), row(1), row(2)],
            wr: WatertightRay::from_parts(k, s),
            k,
            s,
        }
    }
}

#[derive(Clone)]
pub struct PacketTracer {
    geometry: Arc<Geometry>,
    /// Shared by the variants of [`Self::with_hybrid`] and [`Self::with_frustum_children`].
    wide: Arc<Wide>,
    isa: Isa,
    /// The hybrid switch: (node, leaf) lane counts below which lanes go on alone.
    hybrid: (u32, u32),
    /// A camera packet enters a node's children on the interval test alone when at most this
    /// many overlap it, and those every lane is sure to meet whatever their number
    /// ([`FRUSTUM_CHILDREN`]); None: per-lane tests at every node.
    frustum_children: Option<u32>,
}

impl PacketTracer {
    /// Builds the wide BVH with the default parameters.
    pub fn build(geometry: Arc<Geometry>, isa: Isa) -> Result<Self> {
        Self::build_with(geometry, isa, &BuildParams::default())
    }

    pub fn build_with(geometry: Arc<Geometry>, isa: Isa, p: &BuildParams) -> Result<Self> {
        let wide = Wide::build(&geometry, p)?;
        // Each level pushes at most BRANCH - 1 entries; a packet's node may push all BRANCH.
        if wide.depth * BRANCH + 1 > STACK {
            return Err(Error::Backend(format!(
                "packet backend: BVH depth {} exceeds the traversal stack ({STACK} entries)",
                wide.depth
            )));
        }
        Ok(PacketTracer {
            geometry,
            wide: Arc::new(wide),
            isa,
            hybrid: (HYBRID_LANES, LEAF_LANES),
            frustum_children: Some(FRUSTUM_CHILDREN),
        })
    }

    /// Another hybrid switch (benches that tune it): lanes at a node (a leaf) go on alone
    /// below `node` (`leaf`) active lanes; 0 keeps packets whole, 17 traces every ray alone.
    pub fn with_hybrid(mut self, node: u32, leaf: u32) -> Self {
        self.hybrid = (node, leaf);
        self
    }

    /// Another interval-only switch for camera packets (benches that tune it): None tests every
    /// child per lane, Some(0) only skips the tests that every lane is sure to pass, Some(8)
    /// never tests lanes.
    pub fn with_frustum_children(mut self, children: Option<u32>) -> Self {
        self.frustum_children = children;
        self
    }

    pub fn isa(&self) -> Isa {
        self.isa
    }

    pub fn wide(&self) -> &Wide {
        &self.wide
    }

    fn empty(&self) -> bool {
        self.wide.root == build::Child::EMPTY
    }

    /// Closest hits, with work counters.
    pub fn intersect_packet_stats(
        &self,
        rays: &RayPacket,
        active: LaneMask,
        hits: &mut HitPacket,
        stats: &mut TraceStats,
    ) {
        self.closest_packet::<0>(rays, active, hits, stats)
    }

    /// Occluded lanes, with work counters.
    pub fn occluded_packet_stats(
        &self,
        rays: &RayPacket,
        active: LaneMask,
        stats: &mut TraceStats,
    ) -> LaneMask {
        self.occluded_packet_fault::<0>(rays, active, stats)
    }

    #[doc(hidden)]
    pub fn closest_packet<const FAULT: u32>(
        &self,
        rays: &RayPacket,
        active: LaneMask,
        hits: &mut HitPacket,
        stats: &mut TraceStats,
    ) {
        *hits = HitPacket::default();
        if self.empty() || active == 0 {
            return;
        }
        simd::run(
            self.isa,
            kernel::Closest::<FAULT> {
                tr: self,
                rays,
                active,
                hits,
                stats,
            },
        );
    }

    #[doc(hidden)]
    pub fn occluded_packet_fault<const FAULT: u32>(
        &self,
        rays: &RayPacket,
        active: LaneMask,
        stats: &mut TraceStats,
    ) -> LaneMask {
        if self.empty() || active == 0 {
            return 0;
        }
        simd::run(
            self.isa,
            kernel::Occluded::<FAULT> {
                tr: self,
                rays,
                active,
                stats,
            },
        )
    }

    /// Single-ray closest hit, with work counters and a fault mask (tests).
    #[doc(hidden)]
    pub fn closest_single<const FAULT: u32>(
        &self,
        ray: &Ray,
        stats: &mut TraceStats,
    ) -> Option<Hit> {
        if self.empty() {
            return None;
        }
        simd::run(
            self.isa,
            One::<FAULT> {
                tr: self,
                ray,
                stats,
                occluded: false,
            },
        )
        .1
    }

    #[doc(hidden)]
    pub fn occluded_single<const FAULT: u32>(&self, ray: &Ray, stats: &mut TraceStats) -> bool {
        !self.empty()
            && simd::run(
                self.isa,
                One::<FAULT> {
                    tr: self,
                    ray,
                    stats,
                    occluded: true,
                },
            )
            .0
    }

    /// Leaves entered by one closest-hit ray, in visit order, with each leaf's entry distance
    /// (for the near-to-far test).
    #[doc(hidden)]
    pub fn visit_order<const FAULT: u32>(&self, ray: &Ray) -> Vec<f32> {
        if self.empty() {
            return vec![];
        }
        simd::run(self.isa, Visits::<FAULT> { tr: self, ray })
    }
}

struct One<'a, const FAULT: u32> {
    tr: &'a PacketTracer,
    ray: &'a Ray,
    stats: &'a mut TraceStats,
    occluded: bool,
}

impl<const FAULT: u32> Kernel for One<'_, FAULT> {
    type Out = (bool, Option<Hit>);
    #[inline(always)]
    fn run<L: Lanes>(self) -> Self::Out {
        let r = Ray1::new(self.ray);
        if self.occluded {
            let hit = single::occluded::<L, FAULT>(self.tr, &r, self.tr.wide.root, self.stats);
            (hit, None)
        } else {
            let mut best = Best::new(self.ray.tmax);
            single::closest::<L, FAULT>(
                self.tr,
                &r,
                self.tr.wide.root,
                &mut best,
                self.stats,
                &mut |_| {},
            );
            (false, best.hit())
        }
    }
}

struct Visits<'a, const FAULT: u32> {
    tr: &'a PacketTracer,
    ray: &'a Ray,
}

impl<const FAULT: u32> Kernel for Visits<'_, FAULT> {
    type Out = Vec<f32>;
    fn run<L: Lanes>(self) -> Vec<f32> {
        let r = Ray1::new(self.ray);
        let mut best = Best::new(self.ray.tmax);
        let mut order = vec![];
        single::closest::<L, FAULT>(
            self.tr,
            &r,
            self.tr.wide.root,
            &mut best,
            &mut TraceStats::default(),
            &mut |t| order.push(t),
        );
        order
    }
}

impl Tracer for PacketTracer {
    fn name(&self) -> &'static str {
        "packet"
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.closest_single::<0>(ray, &mut TraceStats::default())
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.occluded_single::<0>(ray, &mut TraceStats::default())
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
