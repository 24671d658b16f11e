//! The watertight triangle test of Woop, Benthin and Wald (JCGT 2013) over vector lanes, written
//! once for any width: 8 triangles of a leaf block against one ray, or one triangle against 16
//! rays of a packet. Operations mirror [`Triangle::intersect`] one for one (no FMA, the same
//! association), so t and the barycentrics are bit-identical to the scalar test; lanes with an
//! exactly-zero edge function, and lanes whose t lies within the conservative-t error bound
//! (see [`crate::geometry::triangle::conservative_t_bound`]), are returned to the caller, which
//! settles them: the first with the whole scalar test (its edge functions redone in f64); the
//! second, for occlusion, with the scalar test's last step alone, t in f64 ([`f64_t`]), since
//! every f32 value before that step is the scalar test's (a closest hit runs the whole test).

use super::build::Block;
use super::{Best, FAULT_NO_T_BOUND, Ray1};
use crate::geometry::Ray;
use crate::geometry::triangle::Triangle;
use crate::simd::{NARROW, Vector};

/// One triangle per lane in the ray's sheared space: x and y after the shear, z scaled by sz,
/// for the vertices (a, b, c) = (v0, v1, v2) − origin.
pub struct Sheared<V> {
    pub x: [V; 3],
    pub y: [V; 3],
    pub z: [V; 3],
}

/// Per lane (t, b1, b2).
pub type Out<const N: usize> = [[f32; N]; 3];

/// What [`watertight`] decided, per lane.
pub struct Tested {
    /// Hits, with (t, b1, b2) in `out` and 0 < t < tmax.
    pub hit: u32,
    /// Lanes with an exactly-zero edge function: the whole scalar test decides them.
    pub exact: u32,
    /// Lanes whose t is within the error bound: the scalar test's last step, t in f64,
    /// decides them ([`f64_t`] for occlusion; a closest hit, which needs the barycentrics
    /// too, runs the whole scalar test).
    pub t_f64: u32,
}

/// The test on lanes `m` against per-lane `tmax`.
#[inline(always)]
pub fn watertight<V: Vector<N>, const N: usize, const FAULT: u32>(
    s: &Sheared<V>,
    m: u32,
    tmax: V,
    out: &mut Out<N>,
) -> Tested {
    let ([ax, bx, cx], [ay, by, cy], [az, bz, cz]) = (s.x, s.y, s.z);
    let u = cx.mul(by).sub(cy.mul(bx));
    let v = ax.mul(cy).sub(ay.mul(cx));
    let w = bx.mul(ay).sub(by.mul(ax));
    let zero = V::splat(0.0);
    let edge0 = (u.eq(zero) | v.eq(zero) | w.eq(zero)) & m;
    let neg = u.lt(zero) | v.lt(zero) | w.lt(zero);
    let pos = zero.lt(u) | zero.lt(v) | zero.lt(w);
    let mut hit = m & !edge0 & !(neg & pos);
    let mut unsure = 0;
    let det = u.add(v).add(w);
    hit &= !det.eq(zero);
    if hit != 0 {
        let ts = u.mul(az).add(v.mul(bz)).add(w.mul(cz));
        // ts · sign(det): exact, since sign(det) = ±1.
        let tss = det.lt_select(zero, zero.sub(ts), ts);
        hit &= zero.lt(tss) & tss.lt(tmax.mul(det.abs()));
        // t within the test's error bound (pbrt-v4 §6.8.7): same expression, same order as
        // the scalar test, and skipped, as there, for triangles wholly ahead of the origin
        // along the dominant axis.
        let ahead = zero.lt(az) & zero.lt(bz) & zero.lt(cz);
        let check = hit & !ahead;
        if check != 0 && FAULT & FAULT_NO_T_BOUND == 0 {
            // No closures here: they would compile outside the target-feature entry.
            let (max_xt, max_yt) = (amax(ax, bx, cx), amax(ay, by, cy));
            let (max_zt, max_e) = (amax(az, bz, cz), amax(u, v, w));
            let (g2, g3, g5) = (gamma::<V, N>(2), gamma::<V, N>(3), gamma::<V, N>(5));
            let delta_x = g5.mul(max_xt.add(max_zt));
            let delta_y = g5.mul(max_yt.add(max_zt));
            let delta_z = g3.mul(max_zt);
            let delta_e = V::splat(2.0).mul(
                g2.mul(max_xt)
                    .mul(max_yt)
                    .add(delta_y.mul(max_xt))
                    .add(delta_x.mul(max_yt)),
            );
            let bound = V::splat(3.0).mul(
                g3.mul(max_e)
                    .mul(max_zt)
                    .add(delta_e.mul(max_zt))
                    .add(delta_z.mul(max_e)),
            );
            let ambiguous = check & !bound.lt(tss);
            hit &= !ambiguous;
            unsure |= ambiguous;
        }
        if hit != 0 {
            let inv = V::splat(1.0).div(det);
            let t = ts.mul(inv);
            hit &= t.lt(tmax);
            t.store(&mut out[0]);
            v.mul(inv).store(&mut out[1]);
            w.mul(inv).store(&mut out[2]);
        }
    }
    Tested {
        hit,
        exact: edge0,
        t_f64: unsure,
    }
}

/// The scalar test's answer for a lane [`watertight`] left to t in f64 (`Tested::t_f64`): its
/// f32 values up to there are [`Triangle::intersect`]'s, so only that test's last step remains
/// (the same t, or no hit, as the whole test). Used for occlusion, where shadow rays leaving
/// walls with no error along their normal met it at every wall: redoing the whole test was
/// 3 % of a cornell `light` pass (docs/tracer.md, stop 36).
#[inline(always)]
pub fn f64_t(tri: &Triangle, r: &Ray1, tmax: f32) -> Option<f32> {
    tri.provable_t_f64(&r.ray, &r.wr).filter(|&t| t < tmax)
}

#[inline(always)]
fn amax<V: Vector<N>, const N: usize>(p: V, q: V, r: V) -> V {
    p.abs().max(q.abs()).max(r.abs())
}

#[inline(always)]
fn gamma<V: Vector<N>, const N: usize>(n: u32) -> V {
    V::splat(crate::math::gamma(n))
}

/// The 8 triangles of a block in one ray's sheared space (the ray's axis permutation picks the
/// rows, so no per-lane shuffles).
#[inline(always)]
fn block_sheared<W: Vector<NARROW>>(blk: &Block, r: &Ray1) -> Sheared<W> {
    let [kx, ky, kz] = r.k;
    let (sx, sy, sz) = (W::splat(r.s[0]), W::splat(r.s[1]), W::splat(r.s[2]));
    let z = W::splat(0.0);
    let mut s = Sheared {
        x: [z; 3],
        y: [z; 3],
        z: [z; 3],
    };
    for vtx in 0..3 {
        let v = &blk.v[vtx];
        let px = W::load(&v[kx]).sub(W::splat(r.o[kx]));
        let py = W::load(&v[ky]).sub(W::splat(r.o[ky]));
        let pz = W::load(&v[kz]).sub(W::splat(r.o[kz]));
        s.x[vtx] = px.sub(sx.mul(pz));
        s.y[vtx] = py.sub(sy.mul(pz));
        s.z[vtx] = sz.mul(pz);
    }
    s
}

/// The scalar test for the lanes the vector test returned.
#[inline(always)]
fn scalar(tri: &Triangle, r: &Ray1, tmax: f32) -> Option<(f32, f32, f32)> {
    tri.intersect(&Ray::new(r.ray.origin, r.ray.dir, tmax), &r.wr)
        .map(|h| (h.t, h.b1, h.b2))
}

/// Offers every triangle of a block (`count` lanes) to the closest hit so far.
#[inline(always)]
pub fn block_closest<W: Vector<NARROW>, const FAULT: u32>(
    tris: &[Triangle],
    blk: &Block,
    count: u32,
    r: &Ray1,
    best: &mut Best,
) {
    let s = block_sheared::<W>(blk, r);
    let tmax = best.test_tmax();
    let mut out = [[0.0; NARROW]; 3];
    let Tested {
        mut hit,
        exact,
        t_f64,
    } = watertight::<W, NARROW, FAULT>(&s, (1 << count) - 1, W::splat(tmax), &mut out);
    while hit != 0 {
        let l = hit.trailing_zeros() as usize;
        hit &= hit - 1;
        best.offer(out[0][l], blk.prim[l], out[1][l], out[2][l]);
    }
    let mut rest = exact | t_f64;
    while rest != 0 {
        let l = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        let prim = blk.prim[l];
        if let Some((t, u, v)) = scalar(&tris[prim as usize], r, tmax) {
            best.offer(t, prim, u, v);
        }
    }
}

/// Whether any triangle of a block hits on (0, tmax).
#[inline(always)]
pub fn block_any<W: Vector<NARROW>, const FAULT: u32>(
    tris: &[Triangle],
    blk: &Block,
    count: u32,
    r: &Ray1,
) -> bool {
    let s = block_sheared::<W>(blk, r);
    let tmax = r.ray.tmax;
    let mut out = [[0.0; NARROW]; 3];
    let Tested {
        hit,
        mut exact,
        mut t_f64,
    } = watertight::<W, NARROW, FAULT>(&s, (1 << count) - 1, W::splat(tmax), &mut out);
    if hit != 0 {
        return true;
    }
    while exact != 0 {
        let l = exact.trailing_zeros() as usize;
        exact &= exact - 1;
        if scalar(&tris[blk.prim[l] as usize], r, tmax).is_some_and(|h| h.0 < tmax) {
            return true;
        }
    }
    while t_f64 != 0 {
        let l = t_f64.trailing_zeros() as usize;
        t_f64 &= t_f64 - 1;
        if f64_t(&tris[blk.prim[l] as usize], r, tmax).is_some() {
            return true;
        }
    }
    false
}
