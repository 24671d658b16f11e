//! Uniform sampling of the solid angle of a triangle (Arvo 1995) and of a rectangle (Ureña,
//! Fajardo & King 2013). Both run in f64: their solid angles come out of sums of angles near π,
//! which cancel in f32 long before the light is small enough to matter (pbrt-v4 #211, Nabla
//! #340). Below [`MIN_SOLID_ANGLE`] callers fall back to area sampling, with the same decision
//! in sampler and pdf.

use crate::math::{acos64, sin_cos64};
use crate::simd::{D3, Vector64, cross3, div3, dot3, normalize3, scale3};
use glam::DVec3;
use std::f64::consts::PI;

/// Solid angles below this (sr) are sampled by area instead: f64 resolves them to ~1e-9 relative.
pub const MIN_SOLID_ANGLE: f64 = 1e-7;

/// Angle between unit vectors, accurate near 0 and π (pbrt-v4 `AngleBetween`).
fn angle_between(a: DVec3, b: DVec3) -> f64 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * ((a + b).length() / 2.0).min(1.0).asin()
    } else {
        2.0 * ((b - a).length() / 2.0).min(1.0).asin()
    }
}

fn gram_schmidt(v: DVec3, w: DVec3) -> DVec3 {
    v - v.dot(w) * w
}

/// Solid angle of the spherical triangle with unit vertices a, b, c, by Van Oosterom &
/// Strackee (1983): Ω = 2·atan2(|a·(b×c)|, 1 + a·b + b·c + c·a). Accurate for tiny triangles.
pub fn triangle_solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    2.0 * a
        .dot(b.cross(c))
        .abs()
        .atan2(1.0 + a.dot(b) + b.dot(c) + c.dot(a))
}

/// Spherical triangle seen from the origin, vertices as unit vectors.
pub struct SphericalTriangle {
    a: DVec3,
    b: DVec3,
    c: DVec3,
    alpha: f64,
    area: f64,
}

impl SphericalTriangle {
    /// None for degenerate (zero-area) spherical triangles.
    pub fn new(a: DVec3, b: DVec3, c: DVec3) -> Option<Self> {
        let (n_ab, n_bc, n_ca) = (a.cross(b), b.cross(c), c.cross(a));
        if n_ab.length_squared() == 0.0
            || n_bc.length_squared() == 0.0
            || n_ca.length_squared() == 0.0
        {
            return None;
        }
        let (n_ab, n_bc, n_ca) = (n_ab.normalize(), n_bc.normalize(), n_ca.normalize());
        let alpha = angle_between(n_ab, -n_ca);
        let beta = angle_between(n_bc, -n_ab);
        let gamma = angle_between(n_ca, -n_bc);
        let area = alpha + beta + gamma - PI;
        (area > 0.0).then_some(SphericalTriangle {
            a,
            b,
            c,
            alpha,
            area,
        })
    }

    /// The solid angle the sampler is uniform over (Girard: α + β + γ - π).
    pub fn area(&self) -> f64 {
        self.area
    }

    /// Uniform direction in the triangle (Arvo 1995, in pbrt-v4's formulation): choose the
    /// sub-triangle of area u0·A through vertex a, then a point on its arc b–c'.
    pub fn sample(&self, u: [f64; 2]) -> DVec3 {
        let (a, b, c, alpha) = (self.a, self.b, self.c, self.alpha);
        let ap_pi = u[0] * self.area + PI; // A' + π
        let (cos_a, sin_a) = (alpha.cos(), alpha.sin());
        let sin_phi = ap_pi.sin() * cos_a - ap_pi.cos() * sin_a;
        let cos_phi = ap_pi.cos() * cos_a + ap_pi.sin() * sin_a;
        let k1 = cos_phi + cos_a;
        let k2 = sin_phi - sin_a * a.dot(b);
        let cos_bp = ((k2 + (k2 * cos_phi - k1 * sin_phi) * cos_a)
            / ((k2 * sin_phi + k1 * cos_phi) * sin_a))
            .clamp(-1.0, 1.0);
        let sin_bp = (1.0 - cos_bp * cos_bp).max(0.0).sqrt();
        let cp = cos_bp * a + sin_bp * gram_schmidt(c, a).normalize();
        let cos_t = 1.0 - u[1] * (1.0 - cp.dot(b));
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        (cos_t * b + sin_t * gram_schmidt(cp, b).normalize()).normalize()
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
        let cu = clamp(D::select(fu.sign(), inv.neg(), inv), c(-1.0), one);
        let den = one.sub(cu.mul(cu)).max(zero).sqrt();
        let edge = den.eq(zero);
        let xu = clamp(
            cu.mul(self.z0).neg().div(D::select(edge, one, den)),
            self.x0,
            self.x1,
        );
        let xu = D::select(edge, D::select(cu.sign(), self.x0, self.x1), xu);
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
