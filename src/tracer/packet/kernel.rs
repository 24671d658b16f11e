//! The 16-ray packet kernels over the wide BVH, generic over [`Lanes`]: per visited node one
//! 16-lane slab test per child for the active lanes, a (child, lane-mask) stack, children
//! pushed far to near by the entry distance of their first active lane, and the watertight
//! triangle test across lanes. A node reached by fewer than [`super::HYBRID_LANES`] lanes (a
//! leaf by fewer than [`super::LEAF_LANES`]) is finished one ray at a time (Benthin et al.
//! 2012).
//!
//! Packet set-up is vectorised, and what the lanes share is used: a shared origin (camera
//! rays) turns `box − origin` into scalar work and lets the packet descend on one interval
//! (frustum) test per node, without per-lane slab tests where it overlaps at most two children
//! or every lane is sure to pass them (Wald et al. 2007; Embree's coherent kernels descend on
//! a frustum too), shared direction signs pick near/far planes without min/max, and a
//! shared axis permutation (most coherent packets) drops the per-lane shuffles of the triangle
//! test. Every variant finds the same hits as the general one: only culling differs, and it
//! stays conservative.

use super::build::{Block, Child, Kind, MAX_ROW, Node, Wide};
use super::leaf::{self, Out, Sheared};
use super::{Best, FAR_SCALE, FAULT_FAR_FIRST, PacketTracer, Ray1, STACK, TraceStats, single};
use crate::geometry::Ray;
use crate::simd::{Kernel, Lanes, Mask, NARROW, Vector, WIDTH};
use crate::tracer::{CULL_SCALE, HitPacket, LaneMask, NO_HIT, RayPacket};
use std::mem::MaybeUninit;

const FULL: u32 = (1 << WIDTH) - 1;

/// Per-packet constants, computed across lanes with the scalar set-up's operations.
struct Prep<V> {
    o: [V; 3],
    inv: [V; 3],
    shear: [V; 3],
    /// `kmask[j][c]`: lanes whose j-th permuted axis (kx, ky, kz) is c (c = 0, 1; else 2).
    kmask: [[u32; 2]; 3],
    /// The permutation when every active lane shares it.
    uniform: Option<[usize; 3]>,
    /// The origin when every active lane shares it (bit for bit).
    origin: [f32; 3],
    /// Lanes whose direction is negative along their dominant axis.
    neg: u32,
    /// Near-plane row per axis when every active lane's direction has the same sign there.
    near_row: [usize; 3],
    /// Per axis, the smallest and largest origin and reciprocal direction over the active
    /// lanes: the interval test of all children at once (set only with shared signs; the
    /// origins' only without a shared origin).
    o_lo: [f32; 3],
    o_hi: [f32; 3],
    i_lo: [f32; 3],
    i_hi: [f32; 3],
    lanes: Lanes16,
}

/// Lane `l`'s j-th permuted axis.
#[inline(always)]
fn axis(kmask: &[[u32; 2]; 3], j: usize, l: usize) -> usize {
    if kmask[j][0] >> l & 1 != 0 {
        0
    } else if kmask[j][1] >> l & 1 != 0 {
        1
    } else {
        2
    }
}

/// Lane arrays of the set-up, for the single-ray tail.
struct Lanes16 {
    inv: [[f32; WIDTH]; 3],
    shear: [[f32; WIDTH]; 3],
}

/// Which shared quantities a packet has (the kernel variant).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Shape {
    /// Shared origin and direction signs.
    Origin,
    /// Shared direction signs.
    Signs,
    General,
}

impl<V: Vector<WIDTH>> Prep<V> {
    #[inline(always)]
    fn new(p: &RayPacket, active: LaneMask) -> (Self, Shape) {
        let active = active as u32;
        let d = [V::load(&p.dx), V::load(&p.dy), V::load(&p.dz)];
        let (one, zero) = (V::splat(1.0), V::splat(0.0));
        // safe_inv across lanes.
        let tiny = V::splat(1e-30);
        let big = 1.0f32 / 1e-30;
        let (pos_big, neg_big) = (V::splat(big), V::splat(-big));
        let mut inv = [zero; 3];
        let mut inv_a = [[0.0; WIDTH]; 3];
        for a in 0..3 {
            let huge = d[a].sign_select(neg_big, pos_big);
            inv[a] = d[a].abs().lt_select(tiny, huge, one.div(d[a]));
            inv[a].store(&mut inv_a[a]);
        }
        // WatertightRay::new across lanes: kz = the dominant axis, (kx, ky) the next two,
        // swapped for a negative d[kz].
        let ab = [d[0].abs(), d[1].abs(), d[2].abs()];
        let m0 = ab[1].lt(ab[0]) & ab[2].lt(ab[0]);
        let m1 = !ab[1].lt(ab[0]) & ab[2].lt(ab[1]) & FULL;
        let m2 = !(m0 | m1) & FULL;
        let dkz = V::select(m0, d[0], V::select(m1, d[1], d[2]));
        let neg = dkz.lt(zero);
        let pos = !neg & FULL;
        let kx = [(m2 & pos) | (m1 & neg), (m0 & pos) | (m2 & neg)];
        let ky = [(m1 & pos) | (m2 & neg), (m2 & pos) | (m0 & neg)];
        let dkx = V::select(kx[0], d[0], V::select(kx[1], d[1], d[2]));
        let dky = V::select(ky[0], d[0], V::select(ky[1], d[1], d[2]));
        let shear = [dkx.div(dkz), dky.div(dkz), one.div(dkz)];
        let mut shear_a = [[0.0; WIDTH]; 3];
        for j in 0..3 {
            shear[j].store(&mut shear_a[j]);
        }
        let kmask = [kx, ky, [m0, m1]];
        let same = |m: u32| m & active == active || m & active == 0;
        let uniform = (same(m0) && same(m1) && same(m2) && same(neg)).then(|| {
            let l = active.trailing_zeros() as usize;
            [axis(&kmask, 0, l), axis(&kmask, 1, l), axis(&kmask, 2, l)]
        });
        let first = active.trailing_zeros() as usize;
        let origin = [p.ox[first], p.oy[first], p.oz[first]];
        let o = [V::load(&p.ox), V::load(&p.oy), V::load(&p.oz)];
        let (inf, ninf) = (V::splat(f32::INFINITY), V::splat(f32::NEG_INFINITY));
        let (mut o_lo, mut o_hi, mut i_lo, mut i_hi) = ([0.0; 3], [0.0; 3], [0.0; 3], [0.0; 3]);
        let mut shared = true;
        let mut near_row = [0; 3];
        let mut signs = true;
        for a in 0..3 {
            // Bit-for-bit equal: equal as floats with equal sign bits.
            let o0 = V::splat(origin[a]);
            let same = o[a].eq(o0) & !(o[a].sign() ^ o0.sign());
            shared &= same & active == active;
            let s = inv[a].sign() & active;
            signs &= s == 0 || s == active;
            near_row[a] = if s != 0 { a + MAX_ROW } else { a };
        }
        // The hulls only the interval tests read (shared signs), the origins' only without a
        // shared origin (else they are `origin`).
        if signs {
            for a in 0..3 {
                i_lo[a] = V::select(active, inv[a], inf).reduce_min();
                i_hi[a] = V::select(active, inv[a], ninf).reduce_max();
                if !shared {
                    o_lo[a] = V::select(active, o[a], inf).reduce_min();
                    o_hi[a] = V::select(active, o[a], ninf).reduce_max();
                }
            }
        }
        let shape = match (shared, signs) {
            (true, true) => Shape::Origin,
            (_, true) => Shape::Signs,
            _ => Shape::General,
        };
        (
            Prep {
                o,
                inv,
                shear,
                kmask,
                uniform,
                origin,
                neg,
                near_row,
                o_lo,
                o_hi,
                i_lo,
                i_hi,
                lanes: Lanes16 {
                    inv: inv_a,
                    shear: shear_a,
                },
            },
            shape,
        )
    }

    /// Lane `l` as a single ray, from the packet's set-up (no recomputation).
    #[inline(always)]
    fn ray1(&self, p: &RayPacket, l: usize) -> Ray1 {
        // kz from the dominant-axis masks, (kx, ky) from kz and the sign (as WatertightRay).
        const XY: [[[usize; 2]; 2]; 3] = [[[1, 2], [2, 1]], [[2, 0], [0, 2]], [[0, 1], [1, 0]]];
        let (b0, b1) = ((self.kmask[2][0] >> l) & 1, (self.kmask[2][1] >> l) & 1);
        let kz = (2 - 2 * b0 - b1) as usize;
        let [kx, ky] = XY[kz][((self.neg >> l) & 1) as usize];
        let k = [kx, ky, kz];
        let s = [
            self.lanes.shear[0][l],
            self.lanes.shear[1][l],
            self.lanes.shear[2][l],
        ];
        let inv = [
            self.lanes.inv[0][l],
            self.lanes.inv[1][l],
            self.lanes.inv[2][l],
        ];
        Ray1::from_parts(p.get(l), inv, k, s)
    }

    /// Per lane, component `k[j]` of (x, y, z).
    #[inline(always)]
    fn pick(&self, j: usize, v: &[V; 3]) -> V {
        let m = &self.kmask[j];
        V::select(m[0], v[0], V::select(m[1], v[1], v[2]))
    }

    /// Triangle `slot` of a block in every lane's sheared space.
    #[inline(always)]
    fn sheared<const ORIGIN: bool>(&self, blk: &Block, slot: usize) -> Sheared<V> {
        let z = V::splat(0.0);
        let mut s = Sheared {
            x: [z; 3],
            y: [z; 3],
            z: [z; 3],
        };
        for vtx in 0..3 {
            let v = &blk.v[vtx];
            let (px, py, pz) = match self.uniform {
                // The permutation picks rows of the block: no per-lane shuffles.
                Some(k) => (
                    self.rel::<ORIGIN>(v, k[0], slot),
                    self.rel::<ORIGIN>(v, k[1], slot),
                    self.rel::<ORIGIN>(v, k[2], slot),
                ),
                None => {
                    let p = [
                        self.rel::<ORIGIN>(v, 0, slot),
                        self.rel::<ORIGIN>(v, 1, slot),
                        self.rel::<ORIGIN>(v, 2, slot),
                    ];
                    (self.pick(0, &p), self.pick(1, &p), self.pick(2, &p))
                }
            };
            s.x[vtx] = px.sub(self.shear[0].mul(pz));
            s.y[vtx] = py.sub(self.shear[1].mul(pz));
            s.z[vtx] = self.shear[2].mul(pz);
        }
        s
    }

    /// Coordinate `a` of a block vertex relative to every lane's origin.
    #[inline(always)]
    fn rel<const ORIGIN: bool>(&self, v: &[[f32; NARROW]; 3], a: usize, slot: usize) -> V {
        if ORIGIN {
            V::splat(v[a][slot] - self.origin[a])
        } else {
            V::splat(v[a][slot]).sub(self.o_axis(a))
        }
    }

    /// The origin vector of axis `a` (a runtime index: selected, not indexed, so the vectors
    /// stay in registers).
    #[inline(always)]
    fn o_axis(&self, a: usize) -> V {
        match a {
            0 => self.o[0],
            1 => self.o[1],
            _ => self.o[2],
        }
    }

    /// Lanes whose ray meets child `i`'s box within (0, cull); entry distances in `near_out`.
    #[inline(always)]
    fn slab<const SIGNS: bool>(
        &self,
        n: &Node,
        i: usize,
        cull: V,
        near_out: &mut [f32; WIDTH],
    ) -> u32 {
        let mut near = V::splat(0.0);
        let mut far = V::splat(f32::INFINITY);
        for a in 0..3 {
            let (lo, hi) = if SIGNS {
                let lo = self.near_row[a];
                (
                    lo,
                    if lo < MAX_ROW {
                        lo + MAX_ROW
                    } else {
                        lo - MAX_ROW
                    },
                )
            } else {
                (a, a + MAX_ROW)
            };
            let (b0, b1) = (
                V::splat(n.b[lo][i]).sub(self.o[a]),
                V::splat(n.b[hi][i]).sub(self.o[a]),
            );
            let (t0, t1) = (b0.mul(self.inv[a]), b1.mul(self.inv[a]));
            if SIGNS {
                near = t0.max(near);
                far = t1.min(far);
            } else {
                near = t0.min(t1).max(near);
                far = t0.max(t1).min(far);
            }
        }
        let far = far.mul(V::splat(FAR_SCALE)).min(cull);
        near.store(near_out);
        near.le(far)
    }

    /// Children that some lane may hit: the slab test of all 8 children at once (one 8-lane
    /// sequence) on the interval hull of the lanes' origins and reciprocal directions, with
    /// the largest cull distance of the lanes. Rounding is monotone, so the hull's extreme
    /// products bound every lane's computed distances: a child rejected here is rejected by
    /// each lane's own test (Wald et al. 2007's interval culling, exact in floating point).
    /// `near_out` gets each child's hull entry distance, for the same reason at most every
    /// lane's own.
    #[inline(always)]
    fn interval<W: Vector<NARROW>, const ORIGIN: bool>(
        &self,
        n: &Node,
        cull_max: f32,
        near_out: &mut [f32; NARROW],
    ) -> u32 {
        let lo = [W::load(&n.b[0]), W::load(&n.b[1]), W::load(&n.b[2])];
        let hi = [W::load(&n.b[3]), W::load(&n.b[4]), W::load(&n.b[5])];
        self.interval_boxes::<W, ORIGIN>(&lo, &hi, 1.0, cull_max, near_out)
    }

    /// Triangles of a block that some lane may hit: [`Self::interval`] on the triangles'
    /// boxes, widened by 2⁻¹⁶ of the distances, far beyond the rounding by which the
    /// watertight test can accept a ray passing just outside a triangle's box.
    #[inline(always)]
    fn interval_tris<W: Vector<NARROW>, const ORIGIN: bool>(
        &self,
        blk: &Block,
        cull_max: f32,
    ) -> u32 {
        let z = W::splat(0.0);
        let (mut lo, mut hi) = ([z; 3], [z; 3]);
        for a in 0..3 {
            let (p, q, r) = (
                W::load(&blk.v[0][a]),
                W::load(&blk.v[1][a]),
                W::load(&blk.v[2][a]),
            );
            lo[a] = p.min(q).min(r);
            hi[a] = p.max(q).max(r);
        }
        self.interval_boxes::<W, ORIGIN>(
            &lo,
            &hi,
            1.0 + 1.0 / 65536.0,
            cull_max,
            &mut [0.0; NARROW],
        )
    }

    /// The interval slab test of 8 boxes; `widen` ≥ 1 scales the far distances up and the
    /// near ones down.
    #[inline(always)]
    fn interval_boxes<W: Vector<NARROW>, const ORIGIN: bool>(
        &self,
        lo: &[W; 3],
        hi: &[W; 3],
        widen: f32,
        cull_max: f32,
        near_out: &mut [f32; NARROW],
    ) -> u32 {
        let mut near = W::splat(0.0);
        let mut far = W::splat(f32::INFINITY);
        for a in 0..3 {
            let (bn, bf) = self.planes(lo, hi, a);
            let (il, ih) = (W::splat(self.i_lo[a]), W::splat(self.i_hi[a]));
            if ORIGIN {
                let (dn, df) = self.rel_planes(bn, bf, a);
                near = dn.mul(il).min(dn.mul(ih)).max(near);
                far = df.mul(il).max(df.mul(ih)).min(far);
            } else {
                let (ol, oh) = (W::splat(self.o_lo[a]), W::splat(self.o_hi[a]));
                let (n0, n1) = (bn.sub(oh), bn.sub(ol));
                let (f0, f1) = (bf.sub(oh), bf.sub(ol));
                let nmin = n0.mul(il).min(n0.mul(ih)).min(n1.mul(il).min(n1.mul(ih)));
                let fmax = f0.mul(il).max(f0.mul(ih)).max(f1.mul(il).max(f1.mul(ih)));
                near = nmin.max(near);
                far = fmax.min(far);
            }
        }
        let (near, far) = if widen > 1.0 {
            (
                near.div(W::splat(widen)),
                far.mul(W::splat(FAR_SCALE * widen)),
            )
        } else {
            (near, far.mul(W::splat(FAR_SCALE)))
        };
        near.store(near_out);
        near.le(far.min(W::splat(cull_max)))
    }

    /// Axis `a`'s near and far planes of 8 boxes, by the shared direction sign.
    #[inline(always)]
    fn planes<W: Vector<NARROW>>(&self, lo: &[W; 3], hi: &[W; 3], a: usize) -> (W, W) {
        if self.near_row[a] < MAX_ROW {
            (lo[a], hi[a])
        } else {
            (hi[a], lo[a])
        }
    }

    /// Planes relative to the shared origin along axis `a`.
    #[inline(always)]
    fn rel_planes<W: Vector<NARROW>>(&self, bn: W, bf: W, a: usize) -> (W, W) {
        let o = W::splat(self.origin[a]);
        (bn.sub(o), bf.sub(o))
    }

    /// Children that every lane of a shared-origin packet meets within (0, cull_min): the
    /// interval test with the hull's other extremes, the largest entry and smallest exit
    /// distances any lane can have. Rounding is monotone, so each lane's own slab test would
    /// pass it: skipping that test loses nothing.
    #[inline(always)]
    fn every_lane<W: Vector<NARROW>>(&self, n: &Node, cull_min: f32) -> u32 {
        let lo = [W::load(&n.b[0]), W::load(&n.b[1]), W::load(&n.b[2])];
        let hi = [W::load(&n.b[3]), W::load(&n.b[4]), W::load(&n.b[5])];
        let mut near = W::splat(0.0);
        let mut far = W::splat(f32::INFINITY);
        for a in 0..3 {
            let (bn, bf) = self.planes(&lo, &hi, a);
            let (il, ih) = (W::splat(self.i_lo[a]), W::splat(self.i_hi[a]));
            let (dn, df) = self.rel_planes(bn, bf, a);
            near = dn.mul(il).max(dn.mul(ih)).max(near);
            far = df.mul(il).min(df.mul(ih)).min(far);
        }
        near.le(far.mul(W::splat(FAR_SCALE)).min(W::splat(cull_min)))
    }

    /// A packet's visit of inner node `i` with the lanes in `m`: counted, its children tested
    /// and the hit ones pushed.
    #[inline(always)]
    fn visit<
        W: Vector<NARROW>,
        const FAULT: u32,
        const ORIGIN: bool,
        const SIGNS: bool,
        const ANY: bool,
    >(
        &self,
        tr: &PacketTracer,
        i: u32,
        m: u32,
        cull: V,
        stack: &mut Stack,
        stats: &mut TraceStats,
    ) {
        stats.packet_nodes += 1;
        stats.packet_lanes += m.count_ones() as u64;
        let n = &tr.wide.nodes[i as usize];
        stats.frustum_nodes += self.push_children::<W, FAULT, ORIGIN, SIGNS, ANY>(
            &tr.wide,
            n,
            m,
            cull,
            stack,
            tr.frustum_children,
        ) as u64;
    }

    /// Tests a node's children for the lanes in `m` and pushes the hit ones, far first by the
    /// entry distance of each child's first lane (of the hull, when the interval test alone
    /// decides: then it returns true).
    #[inline(always)]
    fn push_children<
        W: Vector<NARROW>,
        const FAULT: u32,
        const ORIGIN: bool,
        const SIGNS: bool,
        const ANY: bool,
    >(
        &self,
        wide: &Wide,
        n: &Node,
        m: u32,
        cull: V,
        stack: &mut Stack,
        frustum_children: Option<u32>,
    ) -> bool {
        let mut keys = [(0.0f32, Child::EMPTY, 0 as Mask, 0.0f32); 8];
        let mut k = 0;
        let mut near = [0.0; WIDTH];
        let inf = V::splat(f32::INFINITY);
        let mut hull_near = [0.0; NARROW];
        let mut cand = if SIGNS {
            let cull_max = V::select(m, cull, V::splat(f32::NEG_INFINITY)).reduce_max();
            self.interval::<W, ORIGIN>(n, cull_max, &mut hull_near)
        } else {
            (1 << n.count) - 1
        };
        // Children a shared-origin packet enters on the interval test alone: those every lane
        // is sure to meet (skipping their per-lane tests loses nothing), and all of them when
        // at most `frustum_children` overlap the packet: it then lies (nearly) whole inside
        // them, and per-lane masks would cost more than the leaf tests they save. A packet
        // straddling more children is spreading over geometry finer than itself (docs/tracer.md,
        // stop 35).
        let sure = match frustum_children {
            Some(k) if ORIGIN && cand != 0 => {
                if cand.count_ones() <= k {
                    cand
                } else {
                    let cull_min = V::select(m, cull, V::splat(f32::INFINITY)).reduce_min();
                    self.every_lane::<W>(n, cull_min) & cand
                }
            }
            _ => 0,
        };
        while cand != 0 {
            let i = cand.trailing_zeros() as usize;
            cand &= cand - 1;
            let (hit, entry, key) = if sure >> i & 1 != 0 {
                // The packet descends on the interval test alone, every lane with it, and
                // the leaves' exact tests sort the lanes out. The hull's entry distance bounds
                // every lane's from below, so dropping the lanes whose closest hit has passed
                // it stays conservative. (With different origins the hull is far too loose.)
                (m, hull_near[i], hull_near[i])
            } else {
                let hit = m & self.slab::<SIGNS>(n, i, cull, &mut near);
                if hit == 0 {
                    continue;
                }
                // The smallest entry distance of the child's lanes: lanes whose closest hit
                // is nearer by the time it is popped skip it. Occlusion has no closest hit
                // to cull by, so it skips the reduction.
                let entry = if ANY {
                    0.0
                } else {
                    V::select(hit, V::load(&near), inf).reduce_min()
                };
                // Occlusion orders children by the hull's entry distance where the interval
                // test ran (the near rows then need not be read back).
                let key = if ANY && SIGNS {
                    hull_near[i]
                } else {
                    near[hit.trailing_zeros() as usize]
                };
                (hit, entry, key)
            };
            if hit != 0 {
                let key = if FAULT & FAULT_FAR_FIRST != 0 {
                    -key
                } else {
                    key
                };
                // Insertion by descending key: the nearest ends on top of the stack.
                let mut j = k;
                while j > 0 && keys[j - 1].0 < key {
                    keys[j] = keys[j - 1];
                    j -= 1;
                }
                keys[j] = (key, n.child[i], hit as Mask, entry);
                k += 1;
            }
        }
        for &(_, c, hm, entry) in &keys[..k] {
            wide.prefetch(c);
            stack.push(c, hm, entry);
        }
        sure != 0
    }
}

/// A (child, lane mask, smallest entry distance) stack without initialising its storage.
struct Stack {
    e: [MaybeUninit<(Child, Mask, f32)>; STACK],
    sp: usize,
}

impl Stack {
    #[inline(always)]
    fn new(root: Child, active: LaneMask) -> Self {
        let mut s = Stack {
            e: [const { MaybeUninit::uninit() }; STACK],
            sp: 0,
        };
        s.push(root, active, 0.0);
        s
    }
    #[inline(always)]
    fn push(&mut self, c: Child, m: Mask, entry: f32) {
        // The build bounds depth · BRANCH by STACK; indexing checks anyway.
        self.e[self.sp] = MaybeUninit::new((c, m, entry));
        self.sp += 1;
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<(Child, u32, f32)> {
        if self.sp == 0 {
            return None;
        }
        self.sp -= 1;
        // SAFETY: entries below sp were written by push.
        let (c, m, t) = unsafe { self.e[self.sp].assume_init() };
        Some((c, m as u32, t))
    }
}

/// Closest hits so far, per lane.
struct Bests {
    t: [f32; WIDTH],
    u: [f32; WIDTH],
    v: [f32; WIDTH],
    prim: [u32; WIDTH],
    tmax: [f32; WIDTH],
}

impl Bests {
    #[inline(always)]
    fn get(&self, l: usize) -> Best {
        Best {
            t: self.t[l],
            prim: self.prim[l],
            u: self.u[l],
            v: self.v[l],
            tmax: self.tmax[l],
        }
    }

    #[inline(always)]
    fn put(&mut self, l: usize, b: &Best) {
        (self.t[l], self.prim[l], self.u[l], self.v[l]) = (b.t, b.prim, b.u, b.v);
    }

    /// [`Best::offer`] for the hit lanes of one triangle (their t is below the tmax they
    /// were tested with, which is at most the ray's).
    #[inline(always)]
    fn offer<V: Vector<WIDTH>>(&mut self, hit: u32, out: &Out<WIDTH>, prim: u32) {
        let t = V::load(&out[0]);
        let bt = V::load(&self.t);
        let mut take = hit & t.lt(bt);
        let mut tie = hit & t.eq(bt);
        while tie != 0 {
            let l = tie.trailing_zeros() as usize;
            tie &= tie - 1;
            if prim < self.prim[l] {
                take |= 1 << l;
            }
        }
        if take == 0 {
            return;
        }
        V::select(take, t, bt).store(&mut self.t);
        V::select(take, V::load(&out[1]), V::load(&self.u)).store(&mut self.u);
        V::select(take, V::load(&out[2]), V::load(&self.v)).store(&mut self.v);
        while take != 0 {
            let l = take.trailing_zeros() as usize;
            take &= take - 1;
            self.prim[l] = prim;
        }
    }

    /// Per lane `min(tmax, best · CULL_SCALE)`: see [`Best::test_tmax`].
    #[inline(always)]
    fn test_tmax<V: Vector<WIDTH>>(&self) -> V {
        V::load(&self.t)
            .mul(V::splat(CULL_SCALE))
            .min(V::load(&self.tmax))
    }
}

pub struct Closest<'a, const FAULT: u32> {
    pub tr: &'a PacketTracer,
    pub rays: &'a RayPacket,
    pub active: LaneMask,
    pub hits: &'a mut HitPacket,
    pub stats: &'a mut TraceStats,
}

impl<const FAULT: u32> Kernel for Closest<'_, FAULT> {
    type Out = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        let (p, shape) = Prep::<L::V>::new(self.rays, self.active);
        let mut best = Bests {
            t: self.rays.tmax,
            u: [0.0; WIDTH],
            v: [0.0; WIDTH],
            prim: [NO_HIT; WIDTH],
            tmax: self.rays.tmax,
        };
        let (tr, rays, active, stats) = (self.tr, self.rays, self.active, self.stats);
        match shape {
            Shape::Origin => {
                closest::<L, FAULT, true, true>(tr, &p, rays, active, &mut best, stats)
            }
            Shape::Signs => {
                closest::<L, FAULT, false, true>(tr, &p, rays, active, &mut best, stats)
            }
            Shape::General => {
                closest::<L, FAULT, false, false>(tr, &p, rays, active, &mut best, stats)
            }
        }
        // Lanes without a hit hold NO_HIT and u = v = 0 in `best` as in a missed lane of
        // `HitPacket::default()`; only t differs (their tmax against ∞). Whole rows, no
        // branch per lane.
        let mut hit = 0u32;
        for (l, &prim) in best.prim.iter().enumerate() {
            hit |= ((prim != NO_HIT) as u32) << l;
        }
        let hits = self.hits;
        L::V::select(hit, L::V::load(&best.t), L::V::splat(f32::INFINITY)).store(&mut hits.t);
        (hits.prim, hits.u, hits.v) = (best.prim, best.u, best.v);
    }
}

#[inline(always)]
fn closest<L: Lanes, const FAULT: u32, const ORIGIN: bool, const SIGNS: bool>(
    tr: &PacketTracer,
    p: &Prep<L::V>,
    rays: &RayPacket,
    active: LaneMask,
    best: &mut Bests,
    stats: &mut TraceStats,
) {
    let g = &*tr.geometry;
    let mut stack = Stack::new(tr.wide.root, active);
    let mut out = [[0.0f32; WIDTH]; 3];
    while let Some((c, m, entry)) = stack.pop() {
        // Drop the lanes whose closest hit now lies before the child (as their slab test
        // would: conservative, since entry is the smallest of the lanes' entry distances).
        let passed = L::V::load(&best.t)
            .mul(L::V::splat(CULL_SCALE))
            .lt(L::V::splat(entry));
        let m = m & !passed;
        if m == 0 {
            continue;
        }
        if m.count_ones()
            < if c.is_inner() {
                tr.hybrid.0
            } else {
                tr.hybrid.1
            }
        {
            let mut rest = m;
            while rest != 0 {
                let l = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                let mut b = best.get(l);
                let r = p.ray1(rays, l);
                single::closest::<L, FAULT>(tr, &r, c, &mut b, stats, &mut |_| {});
                best.put(l, &b);
            }
            continue;
        }
        match c.kind() {
            Kind::Inner(i) => {
                let cull = L::V::load(&best.t).mul(L::V::splat(CULL_SCALE));
                p.visit::<L::W, FAULT, ORIGIN, SIGNS, false>(tr, i, m, cull, &mut stack, stats);
            }
            Kind::Block(b, count) => {
                stats.leaves += 1;
                let blk = &tr.wide.blocks[b as usize];
                let tm = best.test_tmax::<L::V>();
                let mut cand = (1u32 << count) - 1;
                if SIGNS {
                    let cull_max = L::V::select(m, tm, L::V::splat(f32::NEG_INFINITY)).reduce_max();
                    cand &= p.interval_tris::<L::W, ORIGIN>(blk, cull_max);
                }
                while cand != 0 {
                    let slot = cand.trailing_zeros() as usize;
                    cand &= cand - 1;
                    let s = p.sheared::<ORIGIN>(blk, slot);
                    let prim = blk.prim[slot];
                    let leaf::Tested { hit, exact, t_f64 } =
                        leaf::watertight::<L::V, WIDTH, FAULT>(&s, m, tm, &mut out);
                    if hit != 0 {
                        best.offer::<L::V>(hit, &out, prim);
                    }
                    let mut rest = exact | t_f64;
                    if rest != 0 {
                        let mut tmv = [0.0; WIDTH];
                        tm.store(&mut tmv);
                        while rest != 0 {
                            let l = rest.trailing_zeros() as usize;
                            rest &= rest - 1;
                            let r = p.ray1(rays, l);
                            let ray = Ray::new(r.ray.origin, r.ray.dir, tmv[l]);
                            if let Some(h) = g.triangles[prim as usize].intersect(&ray, &r.wr) {
                                let mut b = best.get(l);
                                b.offer(h.t, prim, h.b1, h.b2);
                                best.put(l, &b);
                            }
                        }
                    }
                }
            }
            Kind::Sphere(prim) => {
                stats.leaves += 1;
                let sphere = &g.spheres[g.sphere_index(prim).unwrap()];
                let mut tmax = [0.0f32; WIDTH];
                best.test_tmax::<L::V>().store(&mut tmax);
                let (mut rest, t) = sphere.intersect_lanes::<L::D>(rays, &tmax, m);
                while rest != 0 {
                    let l = rest.trailing_zeros() as usize;
                    rest &= rest - 1;
                    let mut b = best.get(l);
                    b.offer(t[l], prim, 0.0, 0.0);
                    best.put(l, &b);
                }
            }
            Kind::Empty => {}
        }
    }
}

pub struct Occluded<'a, const FAULT: u32> {
    pub tr: &'a PacketTracer,
    pub rays: &'a RayPacket,
    pub active: LaneMask,
    pub stats: &'a mut TraceStats,
}

impl<const FAULT: u32> Kernel for Occluded<'_, FAULT> {
    type Out = LaneMask;
    #[inline(always)]
    fn run<L: Lanes>(self) -> LaneMask {
        let (p, shape) = Prep::<L::V>::new(self.rays, self.active);
        let (tr, rays, active, stats) = (self.tr, self.rays, self.active, self.stats);
        match shape {
            Shape::Origin => occluded::<L, FAULT, true, true>(tr, &p, rays, active, stats),
            Shape::Signs => occluded::<L, FAULT, false, true>(tr, &p, rays, active, stats),
            Shape::General => occluded::<L, FAULT, false, false>(tr, &p, rays, active, stats),
        }
    }
}

#[inline(always)]
fn occluded<L: Lanes, const FAULT: u32, const ORIGIN: bool, const SIGNS: bool>(
    tr: &PacketTracer,
    p: &Prep<L::V>,
    rays: &RayPacket,
    active: LaneMask,
    stats: &mut TraceStats,
) -> LaneMask {
    let g = &*tr.geometry;
    let tm = L::V::load(&rays.tmax);
    let cull = tm.mul(L::V::splat(CULL_SCALE));
    let mut out = [[0.0f32; WIDTH]; 3];
    // Lanes still looking for an occluder; a lane retires at its first hit.
    let mut alive = active as u32;
    let mut stack = Stack::new(tr.wide.root, active);
    while let Some((c, m, _)) = stack.pop() {
        let mut m = m & alive;
        if m == 0 {
            continue;
        }
        if m.count_ones()
            < if c.is_inner() {
                tr.hybrid.0
            } else {
                tr.hybrid.1
            }
        {
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                if single::occluded::<L, FAULT>(tr, &p.ray1(rays, l), c, stats) {
                    alive &= !(1 << l);
                }
            }
        } else {
            match c.kind() {
                Kind::Inner(i) => {
                    p.visit::<L::W, FAULT, ORIGIN, SIGNS, true>(tr, i, m, cull, &mut stack, stats);
                }
                Kind::Block(b, count) => {
                    stats.leaves += 1;
                    let blk = &tr.wide.blocks[b as usize];
                    let mut cand = (1u32 << count) - 1;
                    if SIGNS {
                        let cull_max =
                            L::V::select(m, tm, L::V::splat(f32::NEG_INFINITY)).reduce_max();
                        cand &= p.interval_tris::<L::W, ORIGIN>(blk, cull_max);
                    }
                    while cand != 0 {
                        let slot = cand.trailing_zeros() as usize;
                        cand &= cand - 1;
                        let s = p.sheared::<ORIGIN>(blk, slot);
                        let prim = blk.prim[slot];
                        let leaf::Tested {
                            hit: mut occ,
                            mut exact,
                            mut t_f64,
                        } = leaf::watertight::<L::V, WIDTH, FAULT>(&s, m, tm, &mut out);
                        let tri = &g.triangles[prim as usize];
                        while exact != 0 {
                            let l = exact.trailing_zeros() as usize;
                            exact &= exact - 1;
                            let r = p.ray1(rays, l);
                            if tri
                                .intersect(&r.ray, &r.wr)
                                .is_some_and(|h| h.t < r.ray.tmax)
                            {
                                occ |= 1 << l;
                            }
                        }
                        while t_f64 != 0 {
                            let l = t_f64.trailing_zeros() as usize;
                            t_f64 &= t_f64 - 1;
                            let r = p.ray1(rays, l);
                            if leaf::f64_t(tri, &r, r.ray.tmax).is_some() {
                                occ |= 1 << l;
                            }
                        }
                        m &= !occ;
                        alive &= !occ;
                        if m == 0 {
                            break;
                        }
                    }
                }
                Kind::Sphere(prim) => {
                    stats.leaves += 1;
                    let sphere = &g.spheres[g.sphere_index(prim).unwrap()];
                    alive &= !sphere.intersect_lanes::<L::D>(rays, &rays.tmax, m).0;
                }
                Kind::Empty => {}
            }
        }
        if alive == 0 {
            break;
        }
    }
    (active as u32 & !alive) as LaneMask
}
