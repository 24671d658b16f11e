//! What a light-selection heuristic knows of a light without sampling it, and the importance it
//! derives from that at a shading point (Conty Estevez & Kulla 2018, §4; pbrt-v4
//! `LightBounds`). A light at a finite place gives a spatial box, a cone bounding its normals
//! (half-angle θo about an axis), the angle θe beyond those normals it still emits into, and a
//! bound on its radiant intensity; a light at infinity gives the irradiance it delivers.
//!
//! Two departures from pbrt-v4, both about units:
//! - The bound's energy is a peak **intensity** [W/sr] (flat emitter L·A, sphere L·πr², point
//!   and spot I), not a power: intensity·cos/d² is then an irradiance, so a lone small light's
//!   importance is its own irradiance, whatever its shape, and a cluster's compares with a
//!   directional light's E⊥·cos. (pbrt-v4 weighs a point light at 4π·I against a flat one at
//!   π·L·A, so a point light counts 4× more than a quad of the same peak intensity.)
//! - The distance is clamped to the bounding sphere's radius as a squared length against a
//!   squared distance; pbrt-v4 compares d² with the unsquared half-diagonal
//!   (lightsamplers.h:151; found by the pbrt-r4 port, ototoi/pbrt-r4 #57), so its pmf changes
//!   when the scene is scaled. [`DistanceClamp::PbrtV4`] keeps that form for comparison.
//!
//! The importance must be positive wherever the light can reach the point, also after f32
//! rounding: angles are handled as (cos, sin) pairs (no `acos` on the hot path, no sin from
//! 1 − cos² near 0), the bounding sphere is widened by the rounding of the centre offset, and
//! the angular bound by [`ANGLE_PAD`].

use glam::{DVec3, Vec3};
use std::f64::consts::PI;

/// The angle [rad] every angular bound is widened by: far above the f32 rounding of the
/// (cos, sin) arithmetic (≈ 1e-7), far below any angle that changes the importance.
pub const ANGLE_PAD: f32 = 1e-5;

/// How many units of f32 rounding of the larger coordinate widen a bounding sphere: the
/// offset centre − p is computed in f32, and the centre itself is rounded.
pub const SLACK_ULPS: f32 = 4.0;

/// A light at a finite place, as the light BVH bounds it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    /// Axis-aligned box holding every emitting point.
    pub lo: Vec3,
    pub hi: Vec3,
    /// The cone of emitter normals: unit axis and half-angle θo ∈ [0, π] (π: any).
    pub axis: Vec3,
    pub theta_o: f32,
    /// How far beyond its normals a point of the light emits, θe ∈ [0, π]: π/2 for a
    /// Lambertian surface, the falloff band for a spot light.
    pub theta_e: f32,
    /// Bound on the luminance of the radiant intensity in any direction [W/sr].
    pub intensity: f32,
}

/// A light at infinity: the luminance of the irradiance it delivers at normal incidence, and
/// its one direction (directional light) or None (every direction: the environment).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistantBounds {
    pub to_light: Option<Vec3>,
    /// Directional light: E⊥. Environment: ∫ L dω over the sphere (luminance).
    pub irradiance: f32,
}

/// How a light is bounded for selection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bounds {
    Local(LightBounds),
    Distant(DistantBounds),
}

impl LightBounds {
    /// A flat one-sided emitter (quad, triangle) with unit normal `normal` and vertices `pts`.
    pub fn flat(pts: &[Vec3], normal: Vec3, radiance_lum: f32, area: f32) -> Self {
        let (lo, hi) = pts
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        LightBounds {
            lo,
            hi,
            axis: normal,
            theta_o: 0.0,
            theta_e: std::f32::consts::FRAC_PI_2,
            intensity: radiance_lum * area,
        }
    }

    /// A point that emits `intensity` into every direction.
    pub fn point(p: Vec3, intensity: f32) -> Self {
        LightBounds {
            lo: p,
            hi: p,
            axis: Vec3::Z,
            theta_o: std::f32::consts::PI,
            theta_e: std::f32::consts::FRAC_PI_2,
            intensity,
        }
    }

    pub fn centroid(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }
}

/// A cone of directions in f64 for building: unit axis, half-angle and its cosine.
#[derive(Clone, Copy, Debug)]
pub struct Cone {
    pub axis: DVec3,
    pub theta: f64,
    pub cos: f64,
}

/// The angle between two unit vectors, accurate near 0 and π.
pub fn angle_between(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

impl Cone {
    pub fn new(axis: Vec3, theta: f32) -> Self {
        Self::of(axis.as_dvec3().normalize(), theta as f64)
    }

    /// About a unit axis.
    pub fn of(axis: DVec3, theta: f64) -> Self {
        Cone {
            axis,
            theta,
            cos: theta.cos(),
        }
    }

    /// The smallest cone about a direction between the two axes holding both cones (pbrt-v4
    /// `Union(DirectionCone, DirectionCone)`): half-angle (θa + θab + θb)/2, its axis rotated
    /// from a's towards b's by that minus θa.
    pub fn union(self, b: Cone) -> Cone {
        if self.theta >= PI || b.theta >= PI {
            return Cone::of(self.axis, PI);
        }
        // The common case while building: one more normal inside the cone (no atan2).
        if b.theta == 0.0 && self.axis.dot(b.axis) >= self.cos {
            return self;
        }
        let d = angle_between(self.axis, b.axis);
        if d + b.theta <= self.theta {
            return self;
        }
        if d + self.theta <= b.theta {
            return b;
        }
        let theta = 0.5 * (self.theta + d + b.theta);
        if theta >= PI {
            return Cone::of(self.axis, PI);
        }
        // Rotate a's axis by theta − θa in the plane of both axes (d > 0 here: with d = 0 one
        // cone holds the other). Antiparallel axes (d = π) give θ ≥ π above.
        let rot = theta - self.theta;
        let perp = (b.axis - self.axis * self.axis.dot(b.axis)).normalize_or_zero();
        if perp == DVec3::ZERO {
            // Axes equal to f64 rounding, d tiny: widen a's cone to hold b.
            return Cone::of(self.axis, self.theta.max(d + b.theta));
        }
        let (s, c) = rot.sin_cos();
        Cone::of((self.axis * c + perp * s).normalize(), theta)
    }

    /// Contains direction-cone `b`, with the same padding the importance uses.
    pub fn contains(&self, b: &Cone) -> bool {
        self.theta >= PI || angle_between(self.axis, b.axis) + b.theta <= self.theta
    }
}

/// The orientation measure M_Ω of a bound (Conty Estevez & Kulla 2018, eq. 1): the integral
/// over directions of the cosine-falloff emission profile, 2π∫₀^θo sin θ dθ +
/// 2π∫_θo^θw cos(θ − θo) sin θ dθ with θw = min(θo + θe, π).
pub fn orientation_measure(theta_o: f64, theta_e: f64) -> f64 {
    // The two cases most clusters are in: normals anywhere (4π), or one flat direction (π).
    if theta_o >= PI {
        return 4.0 * PI;
    }
    if theta_o == 0.0 && (theta_e - 0.5 * PI).abs() < 1e-7 {
        return PI;
    }
    let theta_w = (theta_o + theta_e).min(PI);
    let (so, co) = theta_o.sin_cos();
    2.0 * PI * (1.0 - co)
        + 0.5 * PI * (2.0 * (theta_w - theta_o) * so - (2.0 * theta_w - theta_o).cos() + co)
}

/// How the distance is clamped for points near or inside a bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DistanceClamp {
    /// d² ≥ r² with r the bounding sphere's radius: both squared lengths, scale-invariant.
    Radius,
    /// pbrt-v4's d² ≥ r (a squared length against a length): kept to show the defect.
    PbrtV4,
}

/// The importance function's knobs. [`Self::STANDARD`] is what every selector uses; the others
/// exist to show what each safeguard is for (the tests' negative controls).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImportanceModel {
    pub clamp: DistanceClamp,
    /// Widening of every angular bound [rad].
    pub angle_pad: f32,
    /// Widening of the bounding sphere, in f32 rounding units of the larger coordinate.
    pub slack_ulps: f32,
}

impl ImportanceModel {
    pub const STANDARD: ImportanceModel = ImportanceModel {
        clamp: DistanceClamp::Radius,
        angle_pad: ANGLE_PAD,
        slack_ulps: SLACK_ULPS,
    };
    /// pbrt-v4's importance: its distance clamp and no rounding safeguards.
    pub const PBRT_V4: ImportanceModel = ImportanceModel {
        clamp: DistanceClamp::PbrtV4,
        angle_pad: 0.0,
        slack_ulps: 0.0,
    };
}

/// A bound as the importance reads it: bounding sphere, normal cone and emission spread as
/// (cos, sin) pairs, intensity. 48 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompactBounds {
    pub center: Vec3,
    /// Radius of the box's bounding sphere (half its diagonal), rounded up.
    pub radius: f32,
    pub axis: Vec3,
    pub cos_o: f32,
    pub sin_o: f32,
    pub cos_e: f32,
    pub sin_e: f32,
    pub intensity: f32,
}

impl CompactBounds {
    pub fn new(b: &LightBounds) -> Self {
        let (lo, hi) = (b.lo.as_dvec3(), b.hi.as_dvec3());
        let center = (0.5 * (lo + hi)).as_vec3();
        let radius = round_up(0.5 * (hi - lo).length());
        let (sin_o, cos_o) = (b.theta_o as f64).sin_cos();
        // θe = π/2 exactly (every Lambertian emitter) must give cos 0, not cos(π/2 in f32).
        let (sin_e, cos_e) = if b.theta_e == std::f32::consts::FRAC_PI_2 {
            (1.0, 0.0)
        } else {
            (b.theta_e as f64).sin_cos()
        };
        CompactBounds {
            center,
            radius,
            axis: b.axis,
            cos_o: cos_o as f32,
            sin_o: sin_o.max(0.0) as f32,
            cos_e: cos_e as f32,
            sin_e: sin_e.max(0.0) as f32,
            intensity: b.intensity,
        }
    }

    /// The importance at `p` with shading normal `n` (zero: no orientation) under the
    /// standard model.
    #[inline]
    pub fn importance(&self, p: Vec3, n: Vec3) -> f64 {
        self.importance_with(p, n, &ImportanceModel::STANDARD)
    }

    /// Conty Estevez & Kulla's importance I·cos θ′·cos θ′ᵢ/d² (their eq. 3; pbrt-v4
    /// `CompactLightBounds::Importance`), with θ′ = max(0, θw − θo − θb) the smallest angle
    /// between an emitter normal in the cone and a direction from the light to p, θb the
    /// half-angle of the cone of directions from p that meet the bounding sphere, and θ′ᵢ =
    /// max(0, θᵢ − θb) at the receiver. Zero only where no point in the bound can emit
    /// towards p (θ′ > θe) or p's hemisphere about n cannot see the bound (θ′ᵢ ≥ π/2):
    /// dibench's surfaces reflect into the hemisphere of the normal flipped to the viewer,
    /// which `n` is.
    #[inline]
    pub fn importance_with(&self, p: Vec3, n: Vec3, m: &ImportanceModel) -> f64 {
        let v = self.center - p;
        let d2 = v.length_squared();
        let r0 = self.radius;
        let clamp2 = match m.clamp {
            DistanceClamp::Radius => r0 * r0,
            DistanceClamp::PbrtV4 => r0,
        };
        let dist2 = d2.max(clamp2) as f64;
        if dist2 == 0.0 {
            return 0.0; // a point light at p: no direction to it
        }
        let slack =
            m.slack_ulps * f32::EPSILON * (self.center.abs().max_element() + p.abs().max_element());
        let r = r0 + slack;
        let value = self.intensity as f64 / dist2;
        if d2 <= r * r {
            return value; // p inside the bounding sphere: every direction is possible
        }
        let d = d2.sqrt();
        let dir = v / d; // p → centre
        // The cone of directions from p meeting the sphere, widened by the pad.
        let sin_b0 = r / d;
        let cos_b0 = (1.0 - sin_b0 * sin_b0).max(0.0).sqrt();
        let (sp, cp) = m.angle_pad.sin_cos();
        let (cos_b, sin_b) = (cos_b0 * cp - sin_b0 * sp, sin_b0 * cp + cos_b0 * sp);
        // Emitter side: θw between the axis and centre → p.
        let (cos_w, sin_w) = (-self.axis.dot(dir), self.axis.cross(dir).length());
        let (cos_x, sin_x) = sub_clamped(cos_w, sin_w, self.cos_o, self.sin_o);
        let (cos_p, sin_p) = sub_clamped(cos_x, sin_x, cos_b, sin_b);
        if angle_exceeds(cos_p, sin_p, self.cos_e, self.sin_e) {
            return 0.0;
        }
        let emit = if self.cos_e >= 0.0 {
            if cos_p <= 0.0 {
                return 0.0; // θ′ = θe = π/2 once padded: no point of the bound faces p
            }
            cos_p
        } else {
            // A spread beyond π/2 (a wide spot light): cos θ′ would reach 0 before θe does.
            // cos(θ′·π/2θe) falls to 0 at θe instead, and is cos θ′ for θe = π/2.
            let theta_e = self.sin_e.atan2(self.cos_e);
            (sin_p.atan2(cos_p) * (std::f32::consts::FRAC_PI_2 / theta_e))
                .cos()
                .max(1e-6)
        };
        if n == Vec3::ZERO {
            return value * emit as f64;
        }
        let (cos_i, sin_i) = (n.dot(dir), n.cross(dir).length());
        let (cos_ip, _) = sub_clamped(cos_i, sin_i, cos_b, sin_b);
        if cos_ip <= 0.0 {
            return 0.0;
        }
        value * (emit * cos_ip) as f64
    }
}

/// (cos, sin) of max(0, θa − θb) for θa, θb ∈ [0, π] given as (cos, sin) pairs.
#[inline]
fn sub_clamped(cos_a: f32, sin_a: f32, cos_b: f32, sin_b: f32) -> (f32, f32) {
    if cos_a >= cos_b {
        (1.0, 0.0)
    } else {
        (
            cos_a * cos_b + sin_a * sin_b,
            (sin_a * cos_b - cos_a * sin_b).max(0.0),
        )
    }
}

/// θa > θb for θa ∈ [0, π], θb ∈ [0, π], compared where each pair is well conditioned: by sine
/// for a small θb (cos θ rounds to 1 below ~3e-4 rad in f32), by cosine otherwise.
#[inline]
fn angle_exceeds(cos_a: f32, sin_a: f32, cos_b: f32, sin_b: f32) -> bool {
    if cos_b > 0.7 {
        cos_a < 0.0 || sin_a > sin_b
    } else {
        cos_a < cos_b
    }
}

/// x rounded to the next f32 at or above it.
fn round_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x { f.next_up() } else { f }
}

impl DistantBounds {
    /// The luminance of the irradiance at a point with normal n (zero: at normal incidence,
    /// or ∫L dω for the environment): exact for a directional light, with the same f32 dot
    /// product as the estimator's own horizon test, so the two agree on which side is lit;
    /// for the environment, a uniform map's value (π/4π of ∫L dω with a normal).
    #[inline]
    pub fn importance(&self, n: Vec3) -> f64 {
        let e = self.irradiance as f64;
        match (self.to_light, n == Vec3::ZERO) {
            (_, true) => e,
            (Some(l), false) => {
                let c = n.dot(l);
                if c > 0.0 { e * c as f64 } else { 0.0 }
            }
            (None, false) => 0.25 * e,
        }
    }
}

/// Union of bounds for building: box, cone, spread and summed intensity.
#[derive(Clone, Copy, Debug)]
pub struct BoundsSum {
    pub lo: Vec3,
    pub hi: Vec3,
    pub cone: Cone,
    pub theta_e: f64,
    pub intensity: f64,
    pub count: u32,
}

impl Default for BoundsSum {
    fn default() -> Self {
        BoundsSum {
            lo: Vec3::INFINITY,
            hi: Vec3::NEG_INFINITY,
            cone: Cone::of(DVec3::Z, 0.0),
            theta_e: 0.0,
            intensity: 0.0,
            count: 0,
        }
    }
}

impl BoundsSum {
    /// One light's bounds as a sum.
    pub fn of(b: &LightBounds) -> Self {
        let mut s = BoundsSum::default();
        s.add(b);
        s
    }

    pub fn add(&mut self, b: &LightBounds) {
        let cone = Cone::new(b.axis, b.theta_o);
        self.cone = if self.count == 0 {
            cone
        } else {
            self.cone.union(cone)
        };
        self.lo = self.lo.min(b.lo);
        self.hi = self.hi.max(b.hi);
        self.theta_e = self.theta_e.max(b.theta_e as f64);
        self.intensity += b.intensity as f64;
        self.count += 1;
    }

    pub fn merge(&mut self, o: &BoundsSum) {
        if o.count == 0 {
            return;
        }
        self.cone = if self.count == 0 {
            o.cone
        } else {
            self.cone.union(o.cone)
        };
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
        self.theta_e = self.theta_e.max(o.theta_e);
        self.intensity += o.intensity;
        self.count += o.count;
    }

    pub fn bounds(&self) -> LightBounds {
        LightBounds {
            lo: self.lo,
            hi: self.hi,
            axis: self.cone.axis.as_vec3(),
            theta_o: round_up_angle(self.cone.theta),
            theta_e: round_up_angle(self.theta_e),
            intensity: self.intensity as f32,
        }
    }

    /// The box's surface area plus 1 % of its squared diagonal: the plain surface area is 0
    /// for collinear lights, which would make every split of them cost nothing.
    pub fn area_measure(&self) -> f64 {
        let e = (self.hi - self.lo).as_dvec3().max(DVec3::ZERO);
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x) + 0.01 * e.length_squared()
    }
}

/// An angle rounded up to f32, at most π.
fn round_up_angle(x: f64) -> f32 {
    round_up(x).min(std::f32::consts::PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed form of M_Ω matches the integral it stands for, and θe = π/2 with θo = 0
    /// gives π (a flat Lambertian emitter's ∫cos dω).
    #[test]
    fn orientation_measure_is_its_integral() {
        for (o, e) in [
            (0.0, PI / 2.0),
            (0.4, 0.9),
            (1.2, 0.3),
            (2.5, 1.5),
            (3.1, 0.2),
        ] {
            let w = f64::min(o + e, PI);
            let n = 200_000;
            let mut sum = 0.0;
            for k in 0..n {
                let t = (k as f64 + 0.5) / n as f64 * w;
                let profile = if t <= o { 1.0 } else { (t - o).cos() };
                sum += 2.0 * PI * profile * t.sin() * w / n as f64;
            }
            let m = orientation_measure(o, e);
            assert!(
                (m - sum).abs() < 1e-6 * sum.max(1.0),
                "θo {o} θe {e}: {m} vs {sum}"
            );
        }
        assert!((orientation_measure(0.0, PI / 2.0) - PI).abs() < 1e-12);
    }

    /// A union holds both cones, and is no wider than needed when one holds the other.
    #[test]
    fn cone_union_contains_both() {
        let mut rng = crate::sampling::stream::SampleStream::new(1, 2, 3, 4);
        let mut dir = || {
            crate::sampling::warp::sample_uniform_sphere(rng.next_2d())
                .as_dvec3()
                .normalize()
        };
        for k in 0..2000 {
            let a = Cone::of(dir(), (k % 7) as f64 * 0.3);
            let b = Cone::of(dir(), (k % 5) as f64 * 0.2);
            let u = a.union(b);
            for c in [a, b] {
                assert!(
                    u.theta >= PI || angle_between(u.axis, c.axis) + c.theta <= u.theta + 1e-12,
                    "{a:?} ∪ {b:?} = {u:?}"
                );
            }
        }
        let wide = Cone::of(DVec3::Z, 1.0);
        let narrow = Cone::of(DVec3::new(0.0, 0.1f64.sin(), 0.1f64.cos()), 0.2);
        assert_eq!(wide.union(narrow).theta, 1.0);
        assert_eq!(narrow.union(wide).theta, 1.0);
    }
}
