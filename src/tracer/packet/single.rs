//! Single-ray traversal of the BVH2: the packet kernel's tail for lanes that are left alone
//! (Benthin et al. 2012), and the backend's single-ray entry points. Same primitive tests and
//! the same conservative slab test as the packet kernel.

use super::{FAR_SCALE, Node, PacketTracer, STACK, TraceStats, safe_inv};
use crate::geometry::triangle::WatertightRay;
use crate::geometry::{Hit, Ray};
use crate::tracer::NO_HIT;

/// Closest hit so far of one ray.
#[derive(Clone, Copy, Debug)]
pub struct Best {
    pub t: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}

impl Best {
    pub fn new(tmax: f32) -> Self {
        Best {
            t: tmax,
            prim: NO_HIT,
            u: 0.0,
            v: 0.0,
        }
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

struct Slab {
    o: [f32; 3],
    inv: [f32; 3],
}

impl Slab {
    fn new(ray: &Ray) -> Self {
        Slab {
            o: ray.origin.to_array(),
            inv: ray.dir.to_array().map(safe_inv),
        }
    }

    /// Entry distance if the ray meets the box within (0, tmax).
    #[inline(always)]
    fn hit(&self, n: &Node, tmax: f32) -> Option<f32> {
        let mut near = 0.0f32;
        let mut far = f32::INFINITY;
        for a in 0..3 {
            let t0 = (n.min[a] - self.o[a]) * self.inv[a];
            let t1 = (n.max[a] - self.o[a]) * self.inv[a];
            let (lo, hi) = if t0 < t1 { (t0, t1) } else { (t1, t0) };
            near = if lo > near { lo } else { near };
            far = if hi < far { hi } else { far };
        }
        let far = far * FAR_SCALE;
        let far = if tmax < far { tmax } else { far };
        (near <= far).then_some(near)
    }
}

/// Tests one primitive; returns (t, u, v) if it is hit in (0, tmax).
#[inline(always)]
pub fn prim_hit(
    tr: &PacketTracer,
    ray: &Ray,
    wr: &WatertightRay,
    prim: u32,
) -> Option<(f32, f32, f32)> {
    match tr.geometry.sphere_index(prim) {
        None => tr.geometry.triangles[prim as usize]
            .intersect(ray, wr)
            .map(|h| (h.t, h.b1, h.b2)),
        Some(s) => tr.geometry.spheres[s].intersect(ray).map(|t| (t, 0.0, 0.0)),
    }
}

/// Closest hit below `best.t` in the subtree at `start`, front to back.
pub fn closest(tr: &PacketTracer, ray: &Ray, start: u32, best: &mut Best, stats: &mut TraceStats) {
    let slab = Slab::new(ray);
    let wr = WatertightRay::new(ray.dir);
    let mut stack = [0u32; STACK];
    let mut sp = 0;
    let Some(_) = slab.hit(&tr.nodes[start as usize], best.t) else {
        stats.single_nodes += 1;
        return;
    };
    stack[0] = start;
    sp += 1;
    while sp > 0 {
        sp -= 1;
        let n = tr.nodes[stack[sp] as usize];
        stats.single_nodes += 1;
        if n.count > 0 {
            for slot in n.first..n.first + n.count {
                let prim = tr.slot_prim[slot as usize];
                let r = Ray::new(ray.origin, ray.dir, best.t);
                if let Some((t, u, v)) = prim_hit(tr, &r, &wr, prim)
                    && t < best.t
                {
                    *best = Best { t, prim, u, v };
                }
            }
            continue;
        }
        let (a, b) = (n.first, n.first + 1);
        let ha = slab.hit(&tr.nodes[a as usize], best.t);
        let hb = slab.hit(&tr.nodes[b as usize], best.t);
        match (ha, hb) {
            (Some(ta), Some(tb)) => {
                let (near, far) = if ta <= tb { (a, b) } else { (b, a) };
                stack[sp] = far;
                stack[sp + 1] = near;
                sp += 2;
            }
            (Some(_), None) => {
                stack[sp] = a;
                sp += 1;
            }
            (None, Some(_)) => {
                stack[sp] = b;
                sp += 1;
            }
            (None, None) => {}
        }
    }
}

/// Whether anything lies on (0, ray.tmax) in the subtree at `start`; exits at the first hit.
pub fn occluded(tr: &PacketTracer, ray: &Ray, start: u32, stats: &mut TraceStats) -> bool {
    let slab = Slab::new(ray);
    let wr = WatertightRay::new(ray.dir);
    let mut stack = [0u32; STACK];
    stack[0] = start;
    let mut sp = 1;
    while sp > 0 {
        sp -= 1;
        let n = tr.nodes[stack[sp] as usize];
        stats.single_nodes += 1;
        if slab.hit(&n, ray.tmax).is_none() {
            continue;
        }
        if n.count > 0 {
            for slot in n.first..n.first + n.count {
                if prim_hit(tr, ray, &wr, tr.slot_prim[slot as usize]).is_some() {
                    return true;
                }
            }
            continue;
        }
        stack[sp] = n.first + 1;
        stack[sp + 1] = n.first;
        sp += 2;
    }
    false
}
