//! The 16-ray packet kernels over the wide BVH, generic over [`Lanes`]: per visited node one
//! 16-lane slab test per child for the active lanes, a (child, lane-mask) stack, children
//! pushed far to near by the entry distance of their first active lane, and the watertight
//! triangle test across lanes with a per-lane axis permutation. A node (or leaf) reached by
//! few lanes is finished one ray at a time (Benthin et al. 2012).

use super::build::{Block, Child, Kind, Node};
use super::leaf::{self, Sheared};
use super::{
    Best, FAR_SCALE, FAULT_FAR_FIRST, HYBRID_LANES, PacketTracer, Ray1, STACK, TraceStats,
    safe_inv, single,
};
use crate::geometry::Ray;
use crate::geometry::triangle::WatertightRay;
use crate::simd::{Kernel, Lanes, Mask, Vector, WIDTH};
use crate::tracer::{CULL_SCALE, HitPacket, LaneMask, RayPacket};

/// Per-packet constants.
struct Prep<V> {
    o: [V; 3],
    inv: [V; 3],
    shear: [V; 3],
    /// `kmask[j][c]`: lanes whose j-th permuted axis (kx, ky, kz) is c (c = 0, 1; else 2).
    kmask: [[u32; 2]; 3],
    /// The permutation when every lane shares it (a shared direction, most camera tiles).
    uniform: Option<[usize; 3]>,
    wr: [WatertightRay; WIDTH],
    rays: [Ray; WIDTH],
}

impl<V: Vector<WIDTH>> Prep<V> {
    #[inline(always)]
    fn new(p: &RayPacket, active: LaneMask) -> Self {
        let mut shear = [[0.0; WIDTH]; 3];
        let mut kmask = [[0u32; 2]; 3];
        let mut wr = [WatertightRay::new(glam::Vec3::Z); WIDTH];
        let mut rays = [Ray::new(glam::Vec3::ZERO, glam::Vec3::Z, 0.0); WIDTH];
        let mut uniform = None;
        let mut mixed = false;
        for l in 0..WIDTH {
            let ray = p.get(l);
            // Inactive lanes may hold a zero direction; their constants are never used.
            let w = if active & (1 << l) == 0 {
                WatertightRay::new(glam::Vec3::Z)
            } else {
                let w = WatertightRay::new(ray.dir);
                match uniform {
                    None => uniform = Some(w.axes()),
                    Some(k) => mixed |= k != w.axes(),
                }
                w
            };
            let (k, s) = (w.axes(), w.shear());
            for j in 0..3 {
                shear[j][l] = s[j];
                for c in 0..2 {
                    if k[j] == c {
                        kmask[j][c] |= 1 << l;
                    }
                }
            }
            wr[l] = w;
            rays[l] = ray;
        }
        let mut inv = [[0.0; WIDTH]; 3];
        for l in 0..WIDTH {
            inv[0][l] = safe_inv(p.dx[l]);
            inv[1][l] = safe_inv(p.dy[l]);
            inv[2][l] = safe_inv(p.dz[l]);
        }
        Prep {
            o: [V::load(&p.ox), V::load(&p.oy), V::load(&p.oz)],
            inv: [V::load(&inv[0]), V::load(&inv[1]), V::load(&inv[2])],
            shear: [V::load(&shear[0]), V::load(&shear[1]), V::load(&shear[2])],
            kmask,
            uniform: if mixed { None } else { uniform },
            wr,
            rays,
        }
    }

    /// Per lane, component `k[j]` of (x, y, z).
    #[inline(always)]
    fn pick(&self, j: usize, v: &[V; 3]) -> V {
        match self.uniform {
            Some(k) => v[k[j]],
            None => {
                let m = &self.kmask[j];
                V::select(m[0], v[0], V::select(m[1], v[1], v[2]))
            }
        }
    }

    /// One triangle in every lane's sheared space.
    #[inline(always)]
    fn sheared(&self, blk: &Block, slot: usize) -> Sheared<V> {
        let z = V::splat(0.0);
        let mut s = Sheared {
            x: [z; 3],
            y: [z; 3],
            z: [z; 3],
        };
        for vtx in 0..3 {
            let v = &blk.v[vtx];
            let p = [
                V::splat(v[0][slot]).sub(self.o[0]),
                V::splat(v[1][slot]).sub(self.o[1]),
                V::splat(v[2][slot]).sub(self.o[2]),
            ];
            let (px, py, pz) = (self.pick(0, &p), self.pick(1, &p), self.pick(2, &p));
            s.x[vtx] = px.sub(self.shear[0].mul(pz));
            s.y[vtx] = py.sub(self.shear[1].mul(pz));
            s.z[vtx] = self.shear[2].mul(pz);
        }
        s
    }
}

/// Lanes whose ray meets child `i`'s box within (0, cull); entry distances in `near_out`.
#[inline(always)]
fn slab<V: Vector<WIDTH>>(
    n: &Node,
    i: usize,
    p: &Prep<V>,
    cull: V,
    near_out: &mut [f32; WIDTH],
) -> u32 {
    let mut near = V::splat(0.0);
    let mut far = V::splat(f32::INFINITY);
    for a in 0..3 {
        let t0 = V::splat(n.b[a][i]).sub(p.o[a]).mul(p.inv[a]);
        let t1 = V::splat(n.b[3 + a][i]).sub(p.o[a]).mul(p.inv[a]);
        near = t0.min(t1).max(near);
        far = t0.max(t1).min(far);
    }
    let far = far.mul(V::splat(FAR_SCALE)).min(cull);
    near.store(near_out);
    near.le(far)
}

/// A (child, lane-mask) stack.
struct Stack {
    e: [(Child, Mask); STACK],
    sp: usize,
}

impl Stack {
    #[inline(always)]
    fn push(&mut self, c: Child, m: Mask) {
        self.e[self.sp] = (c, m);
        self.sp += 1;
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<(Child, Mask)> {
        if self.sp == 0 {
            return None;
        }
        self.sp -= 1;
        Some(self.e[self.sp])
    }
}

/// Tests a node's children for the lanes in `m` and pushes the hit ones, far first by the
/// entry distance of each child's first lane.
#[inline(always)]
fn push_children<V: Vector<WIDTH>, const FAULT: u32>(
    n: &Node,
    p: &Prep<V>,
    m: u32,
    cull: V,
    stack: &mut Stack,
) {
    let mut keys = [(0.0f32, Child::EMPTY, 0 as Mask); 8];
    let mut k = 0;
    let mut near = [0.0; WIDTH];
    for i in 0..n.count as usize {
        let hit = m & slab(n, i, p, cull, &mut near);
        if hit != 0 {
            let key = near[hit.trailing_zeros() as usize];
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
            keys[j] = (key, n.child[i], hit as Mask);
            k += 1;
        }
    }
    for &(_, c, hm) in &keys[..k] {
        stack.push(c, hm);
    }
}

/// Closest hits so far, per lane.
struct Bests {
    t: [f32; WIDTH],
    prim: [u32; WIDTH],
    u: [f32; WIDTH],
    v: [f32; WIDTH],
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
    #[inline(always)]
    fn offer(&mut self, l: usize, t: f32, prim: u32, u: f32, v: f32) {
        let mut b = self.get(l);
        b.offer(t, prim, u, v);
        self.put(l, &b);
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
        let Closest {
            tr,
            rays,
            active,
            hits,
            stats,
        } = self;
        let g = &*tr.geometry;
        let p = Prep::<L::V>::new(rays, active);
        let mut best = Bests {
            t: rays.tmax,
            prim: [crate::tracer::NO_HIT; WIDTH],
            u: [0.0; WIDTH],
            v: [0.0; WIDTH],
            tmax: rays.tmax,
        };
        let mut stack = Stack {
            e: [(Child::EMPTY, 0); STACK],
            sp: 0,
        };
        stack.push(tr.wide.root, active);
        let mut out = [[0.0f32; WIDTH]; 3];
        while let Some((c, m)) = stack.pop() {
            let m = m as u32;
            if m.count_ones() < HYBRID_LANES {
                let mut rest = m;
                while rest != 0 {
                    let l = rest.trailing_zeros() as usize;
                    rest &= rest - 1;
                    let mut b = best.get(l);
                    let r = Ray1::new(&p.rays[l]);
                    single::closest::<L, FAULT>(tr, &r, c, &mut b, stats, &mut |_| {});
                    best.put(l, &b);
                }
                continue;
            }
            match c.kind() {
                Kind::Inner(i) => {
                    let n = &tr.wide.nodes[i as usize];
                    stats.packet_nodes += 1;
                    stats.packet_lanes += m.count_ones() as u64;
                    let cull = L::V::load(&best.t).mul(L::V::splat(CULL_SCALE));
                    push_children::<L::V, FAULT>(n, &p, m, cull, &mut stack);
                }
                Kind::Block(b, count) => {
                    stats.leaves += 1;
                    let blk = &tr.wide.blocks[b as usize];
                    let tm = best.test_tmax::<L::V>();
                    let mut tmv = [0.0; WIDTH];
                    tm.store(&mut tmv);
                    for slot in 0..count as usize {
                        let s = p.sheared(blk, slot);
                        let prim = blk.prim[slot];
                        let (mut hit, mut rest) =
                            leaf::watertight::<L::V, WIDTH, FAULT>(&s, m, tm, &mut out);
                        while hit != 0 {
                            let l = hit.trailing_zeros() as usize;
                            hit &= hit - 1;
                            best.offer(l, out[0][l], prim, out[1][l], out[2][l]);
                        }
                        while rest != 0 {
                            let l = rest.trailing_zeros() as usize;
                            rest &= rest - 1;
                            let r = Ray::new(p.rays[l].origin, p.rays[l].dir, tmv[l]);
                            if let Some(h) = g.triangles[prim as usize].intersect(&r, &p.wr[l]) {
                                best.offer(l, h.t, prim, h.b1, h.b2);
                            }
                        }
                    }
                }
                Kind::Sphere(prim) => {
                    stats.leaves += 1;
                    let sphere = &g.spheres[g.sphere_index(prim).unwrap()];
                    let mut rest = m;
                    while rest != 0 {
                        let l = rest.trailing_zeros() as usize;
                        rest &= rest - 1;
                        let b = best.get(l);
                        let r = Ray::new(p.rays[l].origin, p.rays[l].dir, b.test_tmax());
                        if let Some(t) = sphere.intersect(&r) {
                            best.offer(l, t, prim, 0.0, 0.0);
                        }
                    }
                }
                Kind::Empty => {}
            }
        }
        for l in 0..WIDTH {
            if best.prim[l] != crate::tracer::NO_HIT {
                hits.t[l] = best.t[l];
                hits.prim[l] = best.prim[l];
                hits.u[l] = best.u[l];
                hits.v[l] = best.v[l];
            }
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
        let Occluded {
            tr,
            rays,
            active,
            stats,
        } = self;
        let g = &*tr.geometry;
        let p = Prep::<L::V>::new(rays, active);
        let tm = L::V::load(&rays.tmax);
        let cull = tm.mul(L::V::splat(CULL_SCALE));
        let mut out = [[0.0f32; WIDTH]; 3];
        // Lanes still looking for an occluder; a lane retires at its first hit.
        let mut alive = active as u32;
        let mut stack = Stack {
            e: [(Child::EMPTY, 0); STACK],
            sp: 0,
        };
        stack.push(tr.wide.root, active);
        while let Some((c, m)) = stack.pop() {
            let mut m = m as u32 & alive;
            if m == 0 {
                continue;
            }
            if m.count_ones() < HYBRID_LANES {
                while m != 0 {
                    let l = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let r = Ray1::new(&p.rays[l]);
                    if single::occluded::<L, FAULT>(tr, &r, c, stats) {
                        alive &= !(1 << l);
                    }
                }
                if alive == 0 {
                    break;
                }
                continue;
            }
            match c.kind() {
                Kind::Inner(i) => {
                    let n = &tr.wide.nodes[i as usize];
                    stats.packet_nodes += 1;
                    stats.packet_lanes += m.count_ones() as u64;
                    push_children::<L::V, FAULT>(n, &p, m, cull, &mut stack);
                }
                Kind::Block(b, count) => {
                    stats.leaves += 1;
                    let blk = &tr.wide.blocks[b as usize];
                    for slot in 0..count as usize {
                        let s = p.sheared(blk, slot);
                        let prim = blk.prim[slot];
                        let (mut occ, mut rest) =
                            leaf::watertight::<L::V, WIDTH, FAULT>(&s, m, tm, &mut out);
                        while rest != 0 {
                            let l = rest.trailing_zeros() as usize;
                            rest &= rest - 1;
                            if g.triangles[prim as usize]
                                .intersect(&p.rays[l], &p.wr[l])
                                .is_some_and(|h| h.t < p.rays[l].tmax)
                            {
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
                    while m != 0 {
                        let l = m.trailing_zeros() as usize;
                        m &= m - 1;
                        if sphere.intersect(&p.rays[l]).is_some() {
                            alive &= !(1 << l);
                        }
                    }
                }
                Kind::Empty => {}
            }
            if alive == 0 {
                break;
            }
        }
        (active as u32 & !alive) as LaneMask
    }
}
