//! The 16-ray packet kernels, generic over [`Lanes`]: one SIMD slab test per visited node
//! for all active lanes, a (node, lane-mask) stack, and the watertight triangle test of Woop
//! et al. (JCGT 2013) evaluated across lanes with a per-lane axis permutation.

use super::single::{self, Best, prim_hit};
use super::{FAR_SCALE, HYBRID_LANES, Node, PacketTracer, STACK, TraceStats, safe_inv};
use crate::geometry::Ray;
use crate::geometry::triangle::{Triangle, WatertightRay};
use crate::simd::{Kernel, Lanes, Mask, WIDTH};
use crate::tracer::{HitPacket, LaneMask, RayPacket};

/// Per-packet constants, computed once per lane in scalar code.
struct Prep {
    o: [[f32; WIDTH]; 3],
    inv: [[f32; WIDTH]; 3],
    shear: [[f32; WIDTH]; 3],
    /// `kmask[j][c]`: lanes whose j-th permuted axis (kx, ky, kz) is c (c = 0, 1; else 2).
    kmask: [[Mask; 2]; 3],
    wr: [WatertightRay; WIDTH],
    rays: [Ray; WIDTH],
}

impl Prep {
    fn new(p: &RayPacket) -> Self {
        let mut prep = Prep {
            o: [p.ox, p.oy, p.oz],
            inv: [p.dx.map(safe_inv), p.dy.map(safe_inv), p.dz.map(safe_inv)],
            shear: [[0.0; WIDTH]; 3],
            kmask: [[0; 2]; 3],
            wr: [WatertightRay::new(glam::Vec3::Z); WIDTH],
            rays: [Ray::new(glam::Vec3::ZERO, glam::Vec3::Z, 0.0); WIDTH],
        };
        for l in 0..WIDTH {
            let ray = p.get(l);
            // Inactive lanes may hold a zero direction; their constants are never used.
            let wr = if ray.dir == glam::Vec3::ZERO {
                WatertightRay::new(glam::Vec3::Z)
            } else {
                WatertightRay::new(ray.dir)
            };
            let (k, s) = (wr.axes(), wr.shear());
            for j in 0..3 {
                prep.shear[j][l] = s[j];
                for c in 0..2 {
                    if k[j] == c {
                        prep.kmask[j][c] |= 1 << l;
                    }
                }
            }
            prep.wr[l] = wr;
            prep.rays[l] = ray;
        }
        prep
    }
}

/// Lanes whose ray meets the node's box within (0, tmax).
#[inline(always)]
fn slab<L: Lanes>(o: &[L::V; 3], inv: &[L::V; 3], n: &Node, tmax: L::V) -> Mask {
    let mut near = L::splat(0.0);
    let mut far = L::splat(f32::INFINITY);
    for a in 0..3 {
        let t0 = L::mul(L::sub(L::splat(n.min[a]), o[a]), inv[a]);
        let t1 = L::mul(L::sub(L::splat(n.max[a]), o[a]), inv[a]);
        near = L::max(L::min(t0, t1), near);
        far = L::min(L::max(t0, t1), far);
    }
    let far = L::min(tmax, L::mul(far, L::splat(FAR_SCALE)));
    L::le(near, far)
}

/// Picks, per lane, component `k` of (x, y, z) by the lane's permutation masks.
#[inline(always)]
fn pick<L: Lanes>(m: &[Mask; 2], v: &[L::V; 3]) -> L::V {
    L::select(m[0], v[0], L::select(m[1], v[1], v[2]))
}

/// Watertight triangle test on the lanes in `m`, against per-lane `tmax`. Hit lanes get
/// (t, b1, b2) in `out`. Operations mirror `Triangle::intersect` one for one (no FMA), so
/// t and barycentrics are bit-identical; lanes with an exactly-zero edge function take the
/// scalar path, which redoes them in f64.
#[inline(always)]
fn triangle<L: Lanes>(
    tri: &Triangle,
    prep: &Prep,
    o: &[L::V; 3],
    shear: &[L::V; 3],
    tmax: &[f32; WIDTH],
    m: Mask,
    out: &mut [[f32; WIDTH]; 3],
) -> Mask {
    let rel = |p: glam::Vec3| -> [L::V; 3] {
        [
            L::sub(L::splat(p.x), o[0]),
            L::sub(L::splat(p.y), o[1]),
            L::sub(L::splat(p.z), o[2]),
        ]
    };
    let (a, b, c) = (rel(tri.v0), rel(tri.v1), rel(tri.v2));
    let km = &prep.kmask;
    let (akz, bkz, ckz) = (
        pick::<L>(&km[2], &a),
        pick::<L>(&km[2], &b),
        pick::<L>(&km[2], &c),
    );
    let ax = L::sub(pick::<L>(&km[0], &a), L::mul(shear[0], akz));
    let ay = L::sub(pick::<L>(&km[1], &a), L::mul(shear[1], akz));
    let bx = L::sub(pick::<L>(&km[0], &b), L::mul(shear[0], bkz));
    let by = L::sub(pick::<L>(&km[1], &b), L::mul(shear[1], bkz));
    let cx = L::sub(pick::<L>(&km[0], &c), L::mul(shear[0], ckz));
    let cy = L::sub(pick::<L>(&km[1], &c), L::mul(shear[1], ckz));
    let u = L::sub(L::mul(cx, by), L::mul(cy, bx));
    let v = L::sub(L::mul(ax, cy), L::mul(ay, cx));
    let w = L::sub(L::mul(bx, ay), L::mul(by, ax));
    let zero = L::splat(0.0);
    let edge0 = (L::eq(u, zero) | L::eq(v, zero) | L::eq(w, zero)) & m;
    let neg = L::lt(u, zero) | L::lt(v, zero) | L::lt(w, zero);
    let pos = L::lt(zero, u) | L::lt(zero, v) | L::lt(zero, w);
    let mut hit = m & !edge0 & !(neg & pos);
    let mut unsure: Mask = 0;
    let det = L::add(L::add(u, v), w);
    hit &= !L::eq(det, zero);
    if hit != 0 {
        let az = L::mul(shear[2], akz);
        let bz = L::mul(shear[2], bkz);
        let cz = L::mul(shear[2], ckz);
        let ts = L::add(L::add(L::mul(u, az), L::mul(v, bz)), L::mul(w, cz));
        // ts · sign(det): exact, since sign(det) = ±1.
        let tss = L::select(L::lt(det, zero), L::sub(zero, ts), ts);
        let tm = L::load(tmax);
        hit &= L::lt(zero, tss) & L::lt(tss, L::mul(tm, L::abs(det)));
        // t within the test's error bound (pbrt-v4 §6.8.7): see `conservative_t_bound`, same
        // expression, same order as the scalar test, and skipped, as there, for triangles
        // wholly ahead of the origin along the dominant axis.
        let ahead = L::lt(zero, az) & L::lt(zero, bz) & L::lt(zero, cz);
        let check = hit & !ahead;
        if check != 0 {
            let amax = |p: L::V, q: L::V, r: L::V| L::max(L::max(L::abs(p), L::abs(q)), L::abs(r));
            let (max_xt, max_yt) = (amax(ax, bx, cx), amax(ay, by, cy));
            let (max_zt, max_e) = (amax(az, bz, cz), amax(u, v, w));
            let g = |n: u32| L::splat(crate::math::gamma(n));
            let delta_x = L::mul(g(5), L::add(max_xt, max_zt));
            let delta_y = L::mul(g(5), L::add(max_yt, max_zt));
            let delta_z = L::mul(g(3), max_zt);
            let delta_e = L::mul(
                L::splat(2.0),
                L::add(
                    L::add(
                        L::mul(L::mul(g(2), max_xt), max_yt),
                        L::mul(delta_y, max_xt),
                    ),
                    L::mul(delta_x, max_yt),
                ),
            );
            let bound = L::mul(
                L::splat(3.0),
                L::add(
                    L::add(L::mul(L::mul(g(3), max_e), max_zt), L::mul(delta_e, max_zt)),
                    L::mul(delta_z, max_e),
                ),
            );
            // Lanes inside the bound take the scalar path, which settles them in f64.
            let ambiguous = check & !L::lt(bound, tss);
            hit &= !ambiguous;
            unsure |= ambiguous;
        }
        if hit != 0 {
            let inv = L::div(L::splat(1.0), det);
            let t = L::mul(ts, inv);
            hit &= L::lt(t, tm);
            L::store(t, &mut out[0]);
            L::store(L::mul(v, inv), &mut out[1]);
            L::store(L::mul(w, inv), &mut out[2]);
        }
    }
    let mut rest = edge0 | unsure;
    while rest != 0 {
        let l = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        let r = Ray::new(prep.rays[l].origin, prep.rays[l].dir, tmax[l]);
        if let Some(h) = tri.intersect(&r, &prep.wr[l])
            && h.t < tmax[l]
        {
            out[0][l] = h.t;
            out[1][l] = h.b1;
            out[2][l] = h.b2;
            hit |= 1 << l;
        }
    }
    hit
}

/// Child visit order from the first active lane's direction along the axis that best
/// separates the two child boxes (cheap front-to-back for coherent packets).
#[inline(always)]
fn near_first(tr: &PacketTracer, n: &Node, prep: &Prep, m: Mask) -> (u32, u32) {
    let (a, b) = (&tr.nodes[n.first as usize], &tr.nodes[n.first as usize + 1]);
    let mut axis = 0;
    let mut best = -1.0f32;
    for k in 0..3 {
        let d = ((b.min[k] + b.max[k]) - (a.min[k] + a.max[k])).abs();
        if d > best {
            best = d;
            axis = k;
        }
    }
    let lane = m.trailing_zeros() as usize;
    let d = prep.inv[axis][lane];
    let a_lower = a.min[axis] + a.max[axis] <= b.min[axis] + b.max[axis];
    if (d >= 0.0) == a_lower {
        (n.first, n.first + 1)
    } else {
        (n.first + 1, n.first)
    }
}

pub struct Closest<'a> {
    pub tr: &'a PacketTracer,
    pub rays: &'a RayPacket,
    pub active: LaneMask,
    pub hits: &'a mut HitPacket,
    pub stats: &'a mut TraceStats,
}

impl Kernel for Closest<'_> {
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
        let prep = Prep::new(rays);
        let o = prep.o.map(|x| L::load(&x));
        let inv = prep.inv.map(|x| L::load(&x));
        let shear = prep.shear.map(|x| L::load(&x));
        let mut best_t = rays.tmax;
        let mut tv = L::load(&best_t);
        let mut out = [[0.0f32; WIDTH]; 3];
        let mut stack = [(0u32, 0 as Mask); STACK];
        stack[0] = (0, active);
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let (ni, m_in) = stack[sp];
            let n = tr.nodes[ni as usize];
            stats.packet_nodes += 1;
            stats.packet_lanes += m_in.count_ones() as u64;
            let m = m_in & slab::<L>(&o, &inv, &n, tv);
            if m == 0 {
                continue;
            }
            if m.count_ones() < HYBRID_LANES {
                let mut rest = m;
                while rest != 0 {
                    let l = rest.trailing_zeros() as usize;
                    rest &= rest - 1;
                    let mut b = Best {
                        t: best_t[l],
                        prim: hits.prim[l],
                        u: hits.u[l],
                        v: hits.v[l],
                    };
                    single::closest(tr, &prep.rays[l], ni, &mut b, stats);
                    (best_t[l], hits.prim[l], hits.u[l], hits.v[l]) = (b.t, b.prim, b.u, b.v);
                }
                tv = L::load(&best_t);
                continue;
            }
            if n.count == 0 {
                let (near, far) = near_first(tr, &n, &prep, m);
                stack[sp] = (far, m);
                stack[sp + 1] = (near, m);
                sp += 2;
                continue;
            }
            for slot in n.first..n.first + n.count {
                let prim = tr.slot_prim[slot as usize];
                let mut hit = match tr.geometry.sphere_index(prim) {
                    None => triangle::<L>(
                        &tr.geometry.triangles[prim as usize],
                        &prep,
                        &o,
                        &shear,
                        &best_t,
                        m,
                        &mut out,
                    ),
                    Some(_) => sphere_lanes(tr, &prep, prim, &best_t, m, &mut out),
                };
                while hit != 0 {
                    let l = hit.trailing_zeros() as usize;
                    hit &= hit - 1;
                    (best_t[l], hits.prim[l], hits.u[l], hits.v[l]) =
                        (out[0][l], prim, out[1][l], out[2][l]);
                }
            }
            tv = L::load(&best_t);
        }
        for ((t, &p), &b) in hits.t.iter_mut().zip(&hits.prim).zip(&best_t) {
            *t = if p == crate::tracer::NO_HIT {
                f32::INFINITY
            } else {
                b
            };
        }
    }
}

/// Spheres are few (lights, analytic shapes): tested per lane with the scalar routine.
#[inline(always)]
fn sphere_lanes(
    tr: &PacketTracer,
    prep: &Prep,
    prim: u32,
    tmax: &[f32; WIDTH],
    m: Mask,
    out: &mut [[f32; WIDTH]; 3],
) -> Mask {
    let mut hit = 0;
    let mut rest = m;
    while rest != 0 {
        let l = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        let r = Ray::new(prep.rays[l].origin, prep.rays[l].dir, tmax[l]);
        if let Some((t, u, v)) = prim_hit(tr, &r, &prep.wr[l], prim)
            && t < tmax[l]
        {
            (out[0][l], out[1][l], out[2][l]) = (t, u, v);
            hit |= 1 << l;
        }
    }
    hit
}

pub struct Occluded<'a> {
    pub tr: &'a PacketTracer,
    pub rays: &'a RayPacket,
    pub active: LaneMask,
    pub stats: &'a mut TraceStats,
}

impl Kernel for Occluded<'_> {
    type Out = LaneMask;
    #[inline(always)]
    fn run<L: Lanes>(self) -> LaneMask {
        let Occluded {
            tr,
            rays,
            active,
            stats,
        } = self;
        let prep = Prep::new(rays);
        let o = prep.o.map(|x| L::load(&x));
        let inv = prep.inv.map(|x| L::load(&x));
        let shear = prep.shear.map(|x| L::load(&x));
        let tmax = rays.tmax;
        let tv = L::load(&tmax);
        let mut out = [[0.0f32; WIDTH]; 3];
        // Lanes still looking for an occluder; a lane retires at its first hit.
        let mut alive = active;
        let mut stack = [(0u32, 0 as Mask); STACK];
        stack[0] = (0, active);
        let mut sp = 1;
        while sp > 0 && alive != 0 {
            sp -= 1;
            let (ni, m_in) = stack[sp];
            let m_in = m_in & alive;
            if m_in == 0 {
                continue;
            }
            let n = tr.nodes[ni as usize];
            stats.packet_nodes += 1;
            stats.packet_lanes += m_in.count_ones() as u64;
            let m = m_in & slab::<L>(&o, &inv, &n, tv);
            if m == 0 {
                continue;
            }
            if m.count_ones() < HYBRID_LANES {
                let mut rest = m;
                while rest != 0 {
                    let l = rest.trailing_zeros() as usize;
                    rest &= rest - 1;
                    if single::occluded(tr, &prep.rays[l], ni, stats) {
                        alive &= !(1 << l);
                    }
                }
                continue;
            }
            if n.count == 0 {
                // Any-hit needs no exact order; still near-first, as it finds occluders sooner.
                let (near, far) = near_first(tr, &n, &prep, m);
                stack[sp] = (far, m);
                stack[sp + 1] = (near, m);
                sp += 2;
                continue;
            }
            let mut m = m;
            for slot in n.first..n.first + n.count {
                let prim = tr.slot_prim[slot as usize];
                let hit = match tr.geometry.sphere_index(prim) {
                    None => triangle::<L>(
                        &tr.geometry.triangles[prim as usize],
                        &prep,
                        &o,
                        &shear,
                        &tmax,
                        m,
                        &mut out,
                    ),
                    Some(_) => sphere_lanes(tr, &prep, prim, &tmax, m, &mut out),
                };
                alive &= !hit;
                m &= !hit;
                if m == 0 {
                    break;
                }
            }
        }
        active & !alive
    }
}
