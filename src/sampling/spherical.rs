//! Uniform sampling of the solid angle of a triangle (Arvo 1995) and of a rectangle (Ureña,
//! Fajardo & King 2013). Both run in f64: their solid angles come out of sums of angles near π,
//! which cancel in f32 long before the light is small enough to matter (pbrt-v4 #211, Nabla
//! #340). Below [`MIN_SOLID_ANGLE`] callers fall back to area sampling, with the same decision
//! in sampler and pdf.

use crate::math::{acos64, asin64, atan2_64_upper, sin_cos64};
use crate::simd::{
    D3, Vector64, add3, cross3, div3, dot3, neg3, normalize3, scale3, select3, sub3,
};
use glam::DVec3;
use std::f64::consts::PI;

/// Solid angles below this (sr) are sampled by area instead: f64 resolves them to ~1e-9 relative.
pub const MIN_SOLID_ANGLE: f64 = 1e-7;

/// Angle between unit vectors, accurate near 0 and π (pbrt-v4 `AngleBetween`): by the half
/// chord, 2·asin(|b − a|/2) or π − 2·asin(|a + b|/2), whichever is the smaller angle's.
#[inline(always)]
fn angle_between<D: Vector64<N>, const N: usize>(a: D3<D>, b: D3<D>) -> D {
    let c = D::splat;
    let obtuse = dot3(a, b).lt(c(0.0));
    let chord = select3(obtuse, add3(a, b), sub3(b, a));
    let h = asin64(dot3(chord, chord).sqrt().div(c(2.0)).min(c(1.0)));
    let two_h = c(2.0).mul(h);
    D::select(obtuse, c(PI).sub(two_h), two_h)
}

/// v − (v·w)·w.
#[inline(always)]
fn gram_schmidt<D: Vector64<N>, const N: usize>(v: D3<D>, w: D3<D>) -> D3<D> {
    sub3(v, scale3(w, dot3(v, w)))
}

/// Solid angle of the spherical triangle with unit vertices a, b, c, by Van Oosterom &
/// Strackee (1983): Ω = 2·atan2(|a·(b×c)|, 1 + a·b + b·c + c·a). Accurate for tiny triangles.
pub fn triangle_solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    triangle_solid_angle_lanes::<f64, 1>(a.to_array(), b.to_array(), c.to_array())
}

/// [`triangle_solid_angle`] over lanes.
#[inline(always)]
pub fn triangle_solid_angle_lanes<D: Vector64<N>, const N: usize>(
    a: D3<D>,
    b: D3<D>,
    c: D3<D>,
) -> D {
    let one = D::splat(1.0);
    let y = dot3(a, cross3(b, c)).abs();
    let x = one.add(dot3(a, b)).add(dot3(b, c)).add(dot3(c, a));
    D::splat(2.0).mul(atan2_64_upper(y, x))
}

/// Spherical triangle seen from the origin, vertices as unit vectors, for the lanes of `D`
/// (`f64`: one triangle). Written once over lanes, trigonometry included ([`asin64`],
/// [`sin_cos64`]), so sampled over lanes and alone it gives the same bits.
#[derive(Clone, Copy)]
pub struct SphericalTriangle<D = f64> {
    a: D3<D>,
    b: D3<D>,
    c: D3<D>,
    alpha: D,
    area: D,
}

impl SphericalTriangle<f64> {
    /// None for degenerate (zero-area) spherical triangles.
    pub fn new(a: DVec3, b: DVec3, c: DVec3) -> Option<Self> {
        let (t, valid) = Self::lanes(a.to_array(), b.to_array(), c.to_array());
        (valid != 0).then_some(t)
    }

    /// Uniform direction in the triangle (Arvo 1995, in pbrt-v4's formulation): choose the
    /// sub-triangle of area u0·A through vertex a, then a point on its arc b–c'.
    pub fn sample(&self, u: [f64; 2]) -> DVec3 {
        DVec3::from_array(self.sample_lanes(u[0], u[1]))
    }
}

impl<D: Copy> SphericalTriangle<D> {
    /// [`SphericalTriangle::new`] over lanes: the triangles and the lanes that have one (bit i:
    /// lane i). Lanes without one hold finite values that mean nothing.
    #[inline(always)]
    pub fn lanes<const N: usize>(a: D3<D>, b: D3<D>, c: D3<D>) -> (Self, u32)
    where
        D: Vector64<N>,
    {
        let k = D::splat;
        let (n_ab, n_bc, n_ca) = (cross3(a, b), cross3(b, c), cross3(c, a));
        let (o, l) = (k(0.0), k(1.0));
        let all = (u64::MAX >> (64 - N)) as u32;
        let mut valid =
            all & !(dot3(n_ab, n_ab).eq(o) | dot3(n_bc, n_bc).eq(o) | dot3(n_ca, n_ca).eq(o));
        // Lanes where two vertices are parallel (a zero normal) take three orthogonal normals
        // instead, so that nothing below is 0/0.
        let n_ab = normalize3(select3(valid, n_ab, [l, o, o]));
        let n_bc = normalize3(select3(valid, n_bc, [o, l, o]));
        let n_ca = normalize3(select3(valid, n_ca, [o, o, l]));
        let alpha = angle_between(n_ab, neg3(n_ca));
        let beta = angle_between(n_bc, neg3(n_ab));
        let gamma = angle_between(n_ca, neg3(n_bc));
        let area = alpha.add(beta).add(gamma).sub(k(PI));
        valid &= o.lt(area);
        (
            SphericalTriangle {
                a,
                b,
                c,
                alpha,
                area,
            },
            valid,
        )
    }

    /// The solid angle the sampler is uniform over (Girard: α + β + γ − π).
    pub fn area(&self) -> D {
        self.area
    }

    /// [`SphericalTriangle::sample`] over lanes, for u = (u0, u1).
    #[inline(always)]
    pub fn sample_lanes<const N: usize>(&self, u0: D, u1: D) -> D3<D>
    where
        D: Vector64<N>,
    {
        let k = D::splat;
        let one = k(1.0);
        let (a, b, c, alpha) = (self.a, self.b, self.c, self.alpha);
        let ap_pi = u0.mul(self.area).add(k(PI)); // A' + π
        let (sin_a, cos_a) = sin_cos64(alpha);
        let (sin_ap, cos_ap) = sin_cos64(ap_pi);
        let sin_phi = sin_ap.mul(cos_a).sub(cos_ap.mul(sin_a));
        let cos_phi = cos_ap.mul(cos_a).add(sin_ap.mul(sin_a));
        let k1 = cos_phi.add(cos_a);
        let k2 = sin_phi.sub(sin_a.mul(dot3(a, b)));
        let cos_bp = clamp(
            k2.add(k2.mul(cos_phi).sub(k1.mul(sin_phi)).mul(cos_a))
                .div(k2.mul(sin_phi).add(k1.mul(cos_phi)).mul(sin_a)),
            k(-1.0),
            one,
        );
        let sin_bp = one.sub(cos_bp.mul(cos_bp)).max(k(0.0)).sqrt();
        let cp = add3(
            scale3(a, cos_bp),
            scale3(normalize3(gram_schmidt(c, a)), sin_bp),
        );
        let cos_t = one.sub(u1.mul(one.sub(dot3(cp, b))));
        let sin_t = one.sub(cos_t.mul(cos_t)).max(k(0.0)).sqrt();
        normalize3(add3(
            scale3(b, cos_t),
            scale3(normalize3(gram_schmidt(cp, b)), sin_t),
        ))
    }
}

/// The interior angle at the shared edge of two of the rectangle's planes, by their normals.
/// The clamp keeps acos in its domain under rounding only.
#[inline(always)]
fn angle<D: Vector64<N>, const N: usize>(a: D3<D>, b: D3<D>) -> D {
    acos64(clamp(dot3(a, b).neg(), D::splat(-1.0), D::splat(1.0)))
}

/// `x` clamped to [lo, hi] (lo ≤ hi).
#[inline(always)]
fn clamp<D: Vector64<N>, const N: usize>(x: D, lo: D, hi: D) -> D {
    x.max(lo).min(hi)
}

/// A rectangle corner + s·ex·len_x + t·ey·len_y seen from the origin (Ureña et al. 2013, §3),
/// for the lanes of `D` (`f64`: one rectangle). Written once over lanes, trigonometry included
/// ([`acos64`], [`sin_cos64`]), so sampled over lanes and alone it gives the same bits.
#[derive(Clone, Copy)]
pub struct SphericalRectangle<D = f64> {
    x: D3<D>,
    y: D3<D>,
    z: D3<D>,
    x0: D,
    x1: D,
    y0: D,
    y1: D,
    z0: D,
    b0: D,
    b1: D,
    k: D,
    area: D,
}

impl SphericalRectangle<f64> {
    /// `corner` relative to the viewpoint; `ex`, `ey` orthogonal edges. None when the viewpoint
    /// lies in the rectangle's plane (zero solid angle).
    pub fn new(corner: DVec3, ex: DVec3, ey: DVec3) -> Option<Self> {
        let (r, valid) = Self::lanes(corner.to_array(), ex.to_array(), ey.to_array());
        (valid != 0).then_some(r)
    }

    /// The point on the rectangle (relative to the viewpoint) for u ∈ [0,1)², uniform in solid
    /// angle.
    pub fn sample(&self, u: [f64; 2]) -> DVec3 {
        DVec3::from_array(self.sample_lanes(u[0], u[1]))
    }
}

impl<D: Copy> SphericalRectangle<D> {
    /// [`SphericalRectangle::new`] over lanes: the rectangles and the lanes that have one (bit
    /// i: lane i). Lanes without one hold finite values that mean nothing.
    #[inline(always)]
    pub fn lanes<const N: usize>(corner: D3<D>, ex: D3<D>, ey: D3<D>) -> (Self, u32)
    where
        D: Vector64<N>,
    {
        let c = D::splat;
        let (len_x, len_y) = (dot3(ex, ex).sqrt(), dot3(ey, ey).sqrt());
        let (x, y) = (div3(ex, len_x), div3(ey, len_y));
        let z = cross3(x, y);
        let z0 = dot3(corner, z);
        let flip = c(0.0).lt(z0);
        let z = scale3(z, D::select(flip, c(-1.0), c(1.0)));
        let z0 = D::select(flip, z0.neg(), z0);
        let mut valid = !z0.eq(c(0.0));
        // A lane in the plane takes z0 = −1 instead, so that no normal below is 0/0.
        let z0 = D::select(valid, z0, c(-1.0));
        let (x0, y0) = (dot3(corner, x), dot3(corner, y));
        let (x1, y1) = (x0.add(len_x), y0.add(len_y));
        let v00 = [x0, y0, z0];
        let v01 = [x0, y1, z0];
        let v10 = [x1, y0, z0];
        let v11 = [x1, y1, z0];
        let n0 = normalize3(cross3(v00, v10));
        let n1 = normalize3(cross3(v10, v11));
        let n2 = normalize3(cross3(v11, v01));
        let n3 = normalize3(cross3(v01, v00));
        let (g0, g1, g2, g3) = (angle(n0, n1), angle(n1, n2), angle(n2, n3), angle(n3, n0));
        let k = c(2.0 * PI).sub(g2).sub(g3);
        let area = g0.add(g1).sub(k);
        valid &= c(0.0).lt(area);
        let r = SphericalRectangle {
            x,
            y,
            z,
            x0,
            x1,
            y0,
            y1,
            z0,
            b0: n0[2],
            b1: n2[2],
            k,
            area,
        };
        (r, valid)
    }

    /// The solid angle the sampler is uniform over.
    pub fn area(&self) -> D {
        self.area
    }

    /// [`SphericalRectangle::sample`] over lanes, for u = (u0, u1). The clamps keep the inverse
    /// trigonometry in its domain under rounding only; where the cosine of the u-edge's angle
    /// rounds to ±1, its point is the edge's end (the limit), not ±∞ clamped.
    #[inline(always)]
    pub fn sample_lanes<const N: usize>(&self, u0: D, u1: D) -> D3<D>
    where
        D: Vector64<N>,
    {
        let c = D::splat;
        let (one, zero) = (c(1.0), c(0.0));
        let au = u0.mul(self.area).add(self.k);
        let (sin_au, cos_au) = sin_cos64(au);
        let fu = cos_au.mul(self.b0).sub(self.b1).div(sin_au);
        let inv = one.div(fu.mul(fu).add(self.b0.mul(self.b0)).sqrt());
        let cu = clamp(fu.sign_select(inv.neg(), inv), c(-1.0), one);
        let den = one.sub(cu.mul(cu)).max(zero).sqrt();
        let edge = den.eq(zero);
        let xu = clamp(
            cu.mul(self.z0).neg().div(D::select(edge, one, den)),
            self.x0,
            self.x1,
        );
        let xu = D::select(edge, cu.sign_select(self.x0, self.x1), xu);
        let d = xu.mul(xu).add(self.z0.mul(self.z0)).sqrt();
        let h0 = self.y0.div(d.mul(d).add(self.y0.mul(self.y0)).sqrt());
        let h1 = self.y1.div(d.mul(d).add(self.y1.mul(self.y1)).sqrt());
        let hv = h0.add(u1.mul(h1.sub(h0)));
        let hv2 = hv.mul(hv);
        let inside = hv2.lt(c(1.0 - 1e-12));
        let yv = D::select(
            inside,
            hv.mul(d).div(D::select(inside, one.sub(hv2), one).sqrt()),
            self.y1,
        );
        let yv = clamp(yv, self.y0, self.y1);
        let (a, b, e) = (
            scale3(self.x, xu),
            scale3(self.y, yv),
            scale3(self.z, self.z0),
        );
        [
            a[0].add(b[0]).add(e[0]),
            a[1].add(b[1]).add(e[1]),
            a[2].add(b[2]).add(e[2]),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solid_angles_agree_between_formulas() {
        // A quad = two triangles: the rectangle's Girard area equals the two triangles' sum.
        let corner = DVec3::new(-0.3, 1.0, -0.2);
        let (ex, ey) = (DVec3::new(0.8, 0.0, 0.0), DVec3::new(0.0, 0.0, 0.5));
        let rect = SphericalRectangle::new(corner, ex, ey).unwrap();
        let v = [corner, corner + ex, corner + ex + ey, corner + ey].map(|p| p.normalize());
        let tri = triangle_solid_angle(v[0], v[1], v[2]) + triangle_solid_angle(v[0], v[2], v[3]);
        assert!(
            (rect.area() - tri).abs() < 1e-12,
            "{} vs {tri}",
            rect.area()
        );
        let girard = SphericalTriangle::new(v[0], v[1], v[2]).unwrap().area();
        assert!((girard - triangle_solid_angle(v[0], v[1], v[2])).abs() < 1e-12);
    }

    #[test]
    fn samples_land_inside_and_on_the_plane() {
        let corner = DVec3::new(-0.3, 1.0, -0.2);
        let (ex, ey) = (DVec3::new(0.8, 0.0, 0.0), DVec3::new(0.0, 0.0, 0.5));
        let rect = SphericalRectangle::new(corner, ex, ey).unwrap();
        let (a, b, c) = (
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.5, 1.0, 0.1).normalize(),
            DVec3::new(0.1, 1.0, 0.6).normalize(),
        );
        let tri = SphericalTriangle::new(a, b, c).unwrap();
        for i in 0..32 {
            for j in 0..32 {
                let u = [(i as f64 + 0.5) / 32.0, (j as f64 + 0.5) / 32.0];
                let q = rect.sample(u) - corner;
                let (s, t) = (
                    q.dot(ex) / ex.length_squared(),
                    q.dot(ey) / ey.length_squared(),
                );
                assert!(
                    (-1e-9..=1.0 + 1e-9).contains(&s)
                        && (-1e-9..=1.0 + 1e-9).contains(&t)
                        && q.dot(ex.cross(ey)).abs() < 1e-9
                );
                let w = tri.sample(u);
                // Inside the spherical triangle: on the inner side of all three great circles.
                for (p, q, r) in [(a, b, c), (b, c, a), (c, a, b)] {
                    assert!(p.cross(q).dot(w) * p.cross(q).dot(r) >= -1e-12);
                }
            }
        }
    }
}
