//! Single-ray traversal of the wide BVH: the packet kernel's tail for lanes left alone
//! (Benthin et al. 2012) and the backend's single-ray entry points. One 8-lane slab test covers
//! all children of a node (near/far planes picked by the ray's direction signs, so empty slots
//! miss without a test of their own); closest hit continues into the nearest child and stacks
//! the others far to near with their entry distances, skipping any that the closest hit found
//! since has passed; occlusion returns at the first hit.

use super::build::{Kind, Node};
use super::{Best, FAR_SCALE, FAULT_FAR_FIRST, PacketTracer, Ray1, STACK, TraceStats, leaf};
use crate::geometry::Ray;
use crate::simd::{Lanes, NARROW, Vector};
use crate::tracer::cull_t;
use std::mem::MaybeUninit;

use super::build::Child;

/// The ray's origin and reciprocal direction, splatted once.
struct Splat<W> {
    o: [W; 3],
    inv: [W; 3],
}

impl<W: Vector<NARROW>> Splat<W> {
    #[inline(always)]
    fn new(r: &Ray1) -> Self {
        Splat {
            o: [W::splat(r.o[0]), W::splat(r.o[1]), W::splat(r.o[2])],
            inv: [W::splat(r.inv[0]), W::splat(r.inv[1]), W::splat(r.inv[2])],
        }
    }
}

/// Children whose box the ray meets within (0, cull), with their entry distances.
#[inline(always)]
fn slab<W: Vector<NARROW>>(
    n: &Node,
    r: &Ray1,
    s: &Splat<W>,
    cull: f32,
    near_out: &mut [f32; NARROW],
) -> u32 {
    let mut near = W::splat(0.0);
    let mut far = W::splat(f32::INFINITY);
    for a in 0..3 {
        let lo = r.near[a];
        let hi = if lo < 3 { lo + 3 } else { lo - 3 };
        let t0 = W::load(&n.b[lo]).sub(s.o[a]).mul(s.inv[a]);
        let t1 = W::load(&n.b[hi]).sub(s.o[a]).mul(s.inv[a]);
        near = t0.max(near);
        far = t1.min(far);
    }
    let far = far.mul(W::splat(FAR_SCALE)).min(W::splat(cull));
    near.store(near_out);
    near.le(far)
}

/// A fixed-size stack of (child, entry distance) without initialising its storage.
struct Stack {
    e: [MaybeUninit<(Child, f32)>; STACK],
    sp: usize,
}

impl Stack {
    #[inline(always)]
    fn new() -> Self {
        Stack {
            e: [const { MaybeUninit::uninit() }; STACK],
            sp: 0,
        }
    }

    #[inline(always)]
    fn push(&mut self, c: Child, t: f32) {
        // The build bounds depth · BRANCH by STACK, so this never overflows; indexing checks.
        self.e[self.sp] = MaybeUninit::new((c, t));
        self.sp += 1;
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<(Child, f32)> {
        if self.sp == 0 {
            return None;
        }
        self.sp -= 1;
        // SAFETY: entries below sp were written by push.
        Some(unsafe { self.e[self.sp].assume_init() })
    }

    #[inline(always)]
    fn get(&self, i: usize) -> (Child, f32) {
        debug_assert!(i < self.sp);
        // SAFETY: i < sp, written by push.
        unsafe { self.e[i].assume_init() }
    }

    #[inline(always)]
    fn set(&mut self, i: usize, e: (Child, f32)) {
        self.e[i] = MaybeUninit::new(e);
    }
}

/// Closest hit in the subtree `start`, improving `best`. `visit` sees the entry distance of
/// every leaf entered, in order (the visit-order test; a no-op elsewhere).
#[inline(always)]
pub fn closest<L: Lanes, const FAULT: u32>(
    tr: &PacketTracer,
    r: &Ray1,
    start: Child,
    best: &mut Best,
    stats: &mut TraceStats,
    visit: &mut impl FnMut(f32),
) {
    let s = Splat::<L::W>::new(r);
    let g = &*tr.geometry;
    let mut stack = Stack::new();
    let (mut cur, mut cur_t) = (start, 0.0f32);
    loop {
        match cur.kind() {
            Kind::Inner(i) => {
                let n = &tr.wide.nodes[i as usize];
                stats.single_nodes += 1;
                let mut near = [0.0; NARROW];
                let mut m = slab(n, r, &s, cull_t(best.t), &mut near);
                if m != 0 {
                    let first = m.trailing_zeros() as usize;
                    m &= m - 1;
                    if m == 0 {
                        (cur, cur_t) = (n.child[first], near[first]);
                        continue;
                    }
                    // Insert the hit children into the top of the stack, farthest deepest.
                    let base = stack.sp;
                    let far_first = FAULT & FAULT_FAR_FIRST != 0;
                    let add = |slot: usize, stack: &mut Stack| {
                        let e = (n.child[slot], near[slot]);
                        tr.wide.prefetch(e.0);
                        let mut j = stack.sp;
                        stack.push(e.0, e.1);
                        while j > base {
                            let below = stack.get(j - 1);
                            let deeper = if far_first {
                                below.1 > e.1
                            } else {
                                below.1 < e.1
                            };
                            if !deeper {
                                break;
                            }
                            stack.set(j, below);
                            j -= 1;
                        }
                        stack.set(j, e);
                    };
                    add(first, &mut stack);
                    while m != 0 {
                        let slot = m.trailing_zeros() as usize;
                        m &= m - 1;
                        add(slot, &mut stack);
                    }
                    (cur, cur_t) = stack.pop().unwrap();
                    continue;
                }
            }
            Kind::Block(b, count) => {
                stats.leaves += 1;
                visit(cur_t);
                leaf::block_closest::<L::W, FAULT>(
                    &g.triangles,
                    &tr.wide.blocks[b as usize],
                    count,
                    r,
                    best,
                );
            }
            Kind::Sphere(p) => {
                stats.leaves += 1;
                visit(cur_t);
                let sphere = &g.spheres[g.sphere_index(p).unwrap()];
                let tmax = best.test_tmax();
                if let Some(t) = sphere.intersect(&Ray::new(r.ray.origin, r.ray.dir, tmax)) {
                    best.offer(t, p, 0.0, 0.0);
                }
            }
            Kind::Empty => {}
        }
        loop {
            let Some((c, t)) = stack.pop() else { return };
            if t <= cull_t(best.t) {
                (cur, cur_t) = (c, t);
                break;
            }
        }
    }
}

/// Whether anything in the subtree `start` lies on (0, tmax); returns at the first hit.
#[inline(always)]
pub fn occluded<L: Lanes, const FAULT: u32>(
    tr: &PacketTracer,
    r: &Ray1,
    start: Child,
    stats: &mut TraceStats,
) -> bool {
    let s = Splat::<L::W>::new(r);
    let g = &*tr.geometry;
    let cull = cull_t(r.ray.tmax);
    let mut stack = Stack::new();
    let mut cur = start;
    loop {
        match cur.kind() {
            Kind::Inner(i) => {
                let n = &tr.wide.nodes[i as usize];
                stats.single_nodes += 1;
                let mut near = [0.0; NARROW];
                let mut m = slab(n, r, &s, cull, &mut near);
                if m != 0 {
                    cur = n.child[m.trailing_zeros() as usize];
                    m &= m - 1;
                    while m != 0 {
                        let slot = m.trailing_zeros() as usize;
                        m &= m - 1;
                        tr.wide.prefetch(n.child[slot]);
                        stack.push(n.child[slot], 0.0);
                    }
                    continue;
                }
            }
            Kind::Block(b, count) => {
                stats.leaves += 1;
                if leaf::block_any::<L::W, FAULT>(
                    &g.triangles,
                    &tr.wide.blocks[b as usize],
                    count,
                    r,
                ) {
                    return true;
                }
            }
            Kind::Sphere(p) => {
                stats.leaves += 1;
                if g.spheres[g.sphere_index(p).unwrap()]
                    .intersect(&r.ray)
                    .is_some()
                {
                    return true;
                }
            }
            Kind::Empty => {}
        }
        match stack.pop() {
            Some((c, _)) => cur = c,
            None => return false,
        }
    }
}
