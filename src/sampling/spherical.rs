//! Uniform sampling of the solid angle of a triangle (Arvo 1995) and of a rectangle (Ureña,
//! Fajardo & King 2013). Both run in f64: their solid angles come out of sums of angles near π,
//! which cancel in f32 long before the light is small enough to matter (pbrt-v4 #211, Nabla
//! #340). Below [`MIN_SOLID_ANGLE`] callers fall back to area sampling, with the same decision
//! in sampler and pdf.

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

/// A rectangle corner + s·ex·len_x + t·ey·len_y seen from the origin (Ureña et al. 2013, §3).
pub struct SphericalRectangle {
    x: DVec3,
    y: DVec3,
    z: DVec3,
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    z0: f64,
    b0: f64,
    b1: f64,
    k: f64,
    area: f64,
}

impl SphericalRectangle {
    /// `corner` relative to the viewpoint; `ex`, `ey` orthogonal edges. None when the viewpoint
    /// lies in the rectangle's plane (zero solid angle).
    pub fn new(corner: DVec3, ex: DVec3, ey: DVec3) -> Option<Self> {
        let (len_x, len_y) = (ex.length(), ey.length());
        let (x, y) = (ex / len_x, ey / len_y);
        let mut z = x.cross(y);
        let mut z0 = corner.dot(z);
        if z0 > 0.0 {
            z = -z;
            z0 = -z0;
        }
        if z0 == 0.0 {
            return None;
        }
        let (x0, y0) = (corner.dot(x), corner.dot(y));
        let (x1, y1) = (x0 + len_x, y0 + len_y);
        let v00 = DVec3::new(x0, y0, z0);
        let v01 = DVec3::new(x0, y1, z0);
        let v10 = DVec3::new(x1, y0, z0);
        let v11 = DVec3::new(x1, y1, z0);
        let n0 = v00.cross(v10).normalize();
        let n1 = v10.cross(v11).normalize();
        let n2 = v11.cross(v01).normalize();
        let n3 = v01.cross(v00).normalize();
        let g0 = (-n0.dot(n1)).clamp(-1.0, 1.0).acos();
        let g1 = (-n1.dot(n2)).clamp(-1.0, 1.0).acos();
        let g2 = (-n2.dot(n3)).clamp(-1.0, 1.0).acos();
        let g3 = (-n3.dot(n0)).clamp(-1.0, 1.0).acos();
        let k = 2.0 * PI - g2 - g3;
        let area = g0 + g1 - k;
        (area > 0.0).then_some(SphericalRectangle {
            x,
            y,
            z,
            x0,
            x1,
            y0,
            y1,
            z0,
            b0: n0.z,
            b1: n2.z,
            k,
            area,
        })
    }

    pub fn area(&self) -> f64 {
        self.area
    }

    /// The point on the rectangle (relative to the viewpoint) for u ∈ [0,1)², uniform in solid
    /// angle. The clamps keep the inverse trigonometry in its domain under rounding only.
    pub fn sample(&self, u: [f64; 2]) -> DVec3 {
        let au = u[0] * self.area + self.k;
        let fu = (au.cos() * self.b0 - self.b1) / au.sin();
        let cu = (1.0 / (fu * fu + self.b0 * self.b0).sqrt())
            .copysign(fu)
            .clamp(-1.0, 1.0);
        let xu = (-(cu * self.z0) / (1.0 - cu * cu).max(0.0).sqrt()).clamp(self.x0, self.x1);
        let d = (xu * xu + self.z0 * self.z0).sqrt();
        let h0 = self.y0 / (d * d + self.y0 * self.y0).sqrt();
        let h1 = self.y1 / (d * d + self.y1 * self.y1).sqrt();
        let hv = h0 + u[1] * (h1 - h0);
        let hv2 = hv * hv;
        let yv = if hv2 < 1.0 - 1e-12 {
            hv * d / (1.0 - hv2).sqrt()
        } else {
            self.y1
        };
        xu * self.x + yv.clamp(self.y0, self.y1) * self.y + self.z0 * self.z
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
